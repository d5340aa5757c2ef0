!> The air-launch scene with coupling (a), `&line coupling = 'rigidized'`:
!> the paper's equivalent rigidization (§2.4 Steps 1-6) inside the Kane chain
!> rocket - virtual line - parachute (§4.2), see airlaunch_rigidized_coupling.
!>
!> Same set-up as the direct scene (trim of the Case 0 system, the line in its
!> static equilibrium: `setup_launch`), same aircraft, rocket, cut joint, CFA,
!> phases and events; the same output contract (docs/output.md), with
!> line_nodes and the tensions from the sub-stepped flexible line and
!> parachute_position = B3 of the chain, plus the virtual body over time.
submodule (airlaunch_launch_scene) airlaunch_launch_rigidized
  use airlaunch_multibody, only: separation_system, separation_nroots
  use airlaunch_rigidized_coupling, only: rigidized_settings, rigidized_coupling, rigidized_loads, &
    rigidized_nroots, virtual_line, virtual_line_body
  implicit none

contains

  !> Run the scene with the rigidized line (see the submodule header).
  module subroutine run_rigidized(run, cfg, echo, res, error)
    type(run_config), intent(in) :: run
    type(scenario_config), intent(in) :: cfg
    character(len=*), intent(in) :: echo
    type(launch_result), intent(inout) :: res
    type(error_type), allocatable, intent(inout) :: error
    type(launch_system), target :: dsys
    type(separation_system) :: sep
    type(rigidized_coupling) :: cpl
    type(rigidized_settings) :: ropt
    type(rigidized_loads) :: rl
    type(error_type), allocatable :: run_error
    real(dp), allocatable :: y0(:), xl(:, :), vl_(:, :), ten(:)
    integer :: nmax, nrec, n, k, status, nout, iout
    real(dp), allocatable :: time(:), phase(:), ac_pos(:, :), ac_eul(:, :), ac_alpha(:), ac_q(:), elev(:), &
      load_factor(:), rk_pos(:, :), rk_vel(:, :), rk_eul(:, :), rk_rate(:), rk_elev(:), pc_pos(:, :), &
      t_rocket(:), t_chute(:), nodes(:, :, :), cforce(:, :), normal(:), friction(:), clearance(:), residual(:), &
      edge_clearance(:), m_rig(:), j_rig(:), d_rig(:), f_rig(:, :), mismatch(:)
    real(dp) :: min_rigid_tension, max_mismatch
    real(dp), allocatable :: t_out(:)

    ! --- the direct scene's set-up gives the trimmed bodies and the settled line
    call setup_launch(cfg, dsys, y0, res, error)
    if (allocated(error)) return
    n = dsys%line%n
    allocate(xl(3, 0:n), vl_(3, 0:n), ten(n))
    call dsys%prepare(0.0_dp, y0, status)
    xl = dsys%x
    vl_ = dsys%v

    ! --- the chain: same aircraft, rocket, cut joint and loads, three bodies
    call sep%init(dsys%sep%bodies(0), dsys%sep%bodies(1), dsys%tie_down, 3, dsys%sep%joint%geo, &
      dsys%sep%joint%opt, dsys%sep%t0, error, aircraft_prescribed=dsys%sep%aircraft_prescribed)
    if (allocated(error)) return
    sep%edge_bilateral = dsys%sep%edge_bilateral
    sep%quat_gain = dsys%sep%quat_gain
    ! gravity on the aircraft and the rocket; B2 and B3 get their weights from
    ! rigidized_loads (the line's true weight; no weight on the apparent mass)
    call sep%add_source(gravity_source(first=0, last=1))
    call sep%add_source(dsys%sep%sources(dsys%iloads)%source)
    select type (s => sep%sources(2)%source)
    type is (launch_loads)
      s%line_force = 0.0_dp   ! not applied: the chain's B2 carries the line
    end select
    rl%line_mass = dsys%line%total_mass()
    rl%diameter = cfg%line%diameter
    rl%cd_normal = cfg%line%cd_normal
    rl%cd_tangential = cfg%line%cd_tangential
    rl%chute = dsys%chute
    call sep%add_source(rl)

    ropt%outer_dt = cfg%line%outer_dt
    ropt%far_end = cfg%line%far_end
    ropt%chain_rtol = run%rtol
    ropt%chain_atol = run%atol
    ropt%inner_rtol = run%rtol
    if (cfg%line%inner_rtol > 0.0_dp) ropt%inner_rtol = cfg%line%inner_rtol
    ropt%inner_atol = 100.0_dp*run%atol   ! as the direct scene's line nodes (atol_scaling)
    ropt%chain_max_order = 2
    ropt%inner_max_order = 2
    if (run%max_order > 0) then
      ropt%chain_max_order = run%max_order
      ropt%inner_max_order = run%max_order
    end if
    call cpl%init(sep, 2, 3, dsys%line, dsys%chute, xl, vl_, dsys%v_ref, dsys%h_ref, 0.0_dp, &
      phase_preparation, ropt, error)
    if (allocated(error)) then
      error%message = phase_name(phase_preparation) // ", t = 0 s: " // error%message
      return
    end if

    nmax = ceiling(run%t_end/run%output_dt + 1.0e-9_dp) + 1
    if (run%trajectory) then
      allocate(time(nmax), phase(nmax), ac_pos(3, nmax), ac_eul(3, nmax), ac_alpha(nmax), ac_q(nmax), &
        elev(nmax), load_factor(nmax), rk_pos(3, nmax), rk_vel(3, nmax), rk_eul(3, nmax), rk_rate(nmax), &
        rk_elev(nmax), pc_pos(3, nmax), t_rocket(nmax), t_chute(nmax), nodes(3, 0:n, nmax), &
        cforce(6, nmax), normal(nmax), friction(nmax), clearance(nmax), residual(nmax), edge_clearance(nmax), &
        m_rig(nmax), j_rig(nmax), d_rig(nmax), f_rig(3, nmax), mismatch(nmax))
    end if
    nrec = 0
    min_rigid_tension = huge(1.0_dp)
    max_mismatch = 0.0_dp
    ! the output times (as the direct scene's)
    allocate(t_out(nmax))
    nout = 0
    do k = 1, nmax - 1
      nout = nout + 1
      t_out(nout) = min(k*run%output_dt, run%t_end)
      if (t_out(nout) >= run%t_end) exit
    end do
    iout = 1
    call record_at(0.0_dp, cpl%chain_solver%y, run_error)
    call run_outer_steps(run_error)
    res%stats = cpl%stats()
    res%end_time = cpl%t
    res%release_time = event_or_minus(cpl%chain%sep%event_time(1))
    res%edge_time = event_or_minus(cpl%chain%sep%event_time(2))
    res%separation_time = event_or_minus(cpl%chain%sep%event_time(3))
    res%early_separation = cpl%chain%sep%early_separation
    res%edge_pull_time = event_or_minus(cpl%chain%sep%edge_pull_time)
    if (allocated(run_error)) then
      res%status = "failed"
      res%failure = run_error%message
    end if
    if (run%trajectory) call write_output()
    call cpl%free()
    if (allocated(run_error)) call move_alloc(run_error, error)
  contains

    !> Outer steps (§2.4 Steps 3-6) to the end of the run, the events on the way;
    !> the outputs are recorded by `record_at` from inside the steps.
    subroutine run_outer_steps(err)
      type(error_type), allocatable, intent(inout) :: err
      logical :: event, changed
      integer :: which(rigidized_nroots), n_events, j
      real(dp) :: t_target, e(3), eps, t_last
      eps = 1.0e-12_dp*max(1.0_dp, run%t_end)
      n_events = 0
      t_last = cpl%t
      do while (run%t_end - cpl%t > eps)
        t_target = min(cpl%t + ropt%outer_dt, run%t_end)
        if (run%t_end - t_target < 1.0e-6_dp*ropt%outer_dt) t_target = run%t_end
        ! end on an output time when the step reaches it (no round-off slivers)
        if (iout <= nout) then
          if (abs(t_out(iout) - t_target) < 1.0e-6_dp*ropt%outer_dt) t_target = t_out(iout)
        end if
        call cpl%begin_step(t_target, event, which, err, t_out(iout:nout))
        do j = 1, cpl%n_saved
          if (allocated(err)) exit
          call cpl%line_to(cpl%saved_t(j), err)
          if (.not. allocated(err)) call record_at(cpl%saved_t(j), cpl%saved_y(:, j), err)
        end do
        if (.not. allocated(err)) call cpl%end_step(err)
        if (allocated(err)) then
          if (index(err%message, "phase ") /= 1) err%message = phase_name(cpl%chain%sep%phase) // ": " // err%message
          return
        end if
        if (.not. event) then
          call skip_recorded()
          cycle
        end if
        ! several events within one output interval are allowed, not a cascade
        if (cpl%t - t_last > run%output_dt) n_events = 0
        t_last = cpl%t
        n_events = n_events + 1
        if (n_events > 100) then
          call fatal_error(err, phase_name(cpl%chain%sep%phase) // ", t = " // str(cpl%t) // &
            " s: too many events before the output time")
          return
        end if
        associate(c => cpl%chain)
          call c%prepare(cpl%t, cpl%chain_solver%y)
          if (which(rigidized_nroots) < 0 .and. c%sep%phase == phase_free .and. c%find_pitch_max) then
            e = dcm_to_euler(c%sep%bodies(1)%c)
            res%pitch_max_time = cpl%t
            res%pitch_max_deg = e(2)*rad2deg
            res%nose_elevation_at_max_deg = nose_elevation(c%sep%bodies(1)%q)*rad2deg
            c%find_pitch_max = .false.
          end if
          call c%sep%handle_event(cpl%t, c%yabs, which(1:separation_nroots), changed, err)
          if (allocated(err)) then
            err%message = phase_name(c%sep%phase) // ", t = " // str(cpl%t) // " s: " // err%message
            return
          end if
          if (changed .and. c%sep%phase == phase_free .and. res%separation_time < 0.0_dp) then
            e = dcm_to_euler(c%sep%bodies(1)%c)
            res%pitch_at_separation_deg = e(2)*rad2deg
            res%pitch_rate_at_separation_deg_s = c%euler_pitch_rate()*rad2deg
            res%separation_time = cpl%t
          end if
        end associate
        ! every event restarts the chain at its time (the outer step ended there)
        call cpl%restart_chain(err)
        if (allocated(err)) return
        ! an output time that coincides with the event
        if (iout <= nout) then
          if (abs(t_out(iout) - cpl%t) <= eps) call record_at(cpl%t, cpl%chain_solver%y, err)
          if (allocated(err)) return
        end if
        call skip_recorded()
      end do
    end subroutine run_outer_steps

    !> The next output time is the first one after the coupling's time.
    subroutine skip_recorded()
      do while (iout <= nout)
        if (t_out(iout) > cpl%t + 1.0e-12_dp*max(1.0_dp, run%t_end)) exit
        iout = iout + 1
      end do
    end subroutine skip_recorded

    !> Sample the state at time t (outputs and milestones): the chain's state
    !> y (relative frame), the line's from the coupling's line solver at t.
    subroutine record_at(t, y, err)
      real(dp), intent(in) :: t, y(:)
      type(error_type), allocatable, intent(inout) :: err
      real(dp) :: ea(3), er(3), rate, nz, cl, ecl, edge(3), tail(3), nose(3), aft(3), frig(3), axis(3), mm
      integer :: j, o
      type(error_type), allocatable :: eval_error
      type(virtual_line) :: vb
      if (allocated(err)) return
      call cpl%line_state(xl, vl_, ten)
      call cpl%chain%prepare(t, y)
      call cpl%chain%sep%evaluate(t, cpl%chain%yabs, eval_error)
      associate(sp => cpl%chain%sep, b0 => cpl%chain%sep%bodies(0), b1 => cpl%chain%sep%bodies(1), &
          b3 => cpl%chain%sep%bodies(3))
        ea = dcm_to_euler(b0%c)
        er = dcm_to_euler(b1%c)
        rate = cpl%chain%euler_pitch_rate()
        nz = dot_product(b0%c(:, 2), sp%a0 + [0.0_dp, g0, 0.0_dp])/g0
        nose = b1%point_position([cfg%rocket%aero%cg_from_nose, 0.0_dp, 0.0_dp])
        aft = b1%point_position([cfg%rocket%aero%cg_from_nose - cfg%rocket%aero%length, 0.0_dp, 0.0_dp])
        edge = b0%r + matmul(b0%c, [cfg%bay%ramp_edge_x, cfg%bay%floor_y, 0.0_dp])
        tail = b0%r + matmul(b0%c, [cfg%bay%tail_x, cfg%bay%tail_y, 0.0_dp])
        cl = segment_distance(tail, nose, aft) - cfg%rocket%aero%diameter/2
        ecl = segment_distance(edge, nose, aft) - cfg%rocket%aero%diameter/2
        if (sp%phase /= phase_free) ecl = 0.0_dp
        if (sp%phase == phase_free) res%min_clearance = min(res%min_clearance, cl)
        if (maxval(ten) > res%peak_tension) then
          res%peak_tension = maxval(ten)
          res%peak_tension_time = t
        end if
        res%max_aircraft_pitch_excursion_deg = max(res%max_aircraft_pitch_excursion_deg, &
          abs(ea(2)*rad2deg - res%trim_alpha_deg))
        res%max_load_factor_excursion = max(res%max_load_factor_excursion, abs(nz - 1.0_dp))
        if (sp%phase /= phase_free) res%max_constraint_residual = max(res%max_constraint_residual, &
          sp%js%res_position)
        do j = 0, 3   ! aircraft, rocket, line body, parachute
          o = merge(7 + 13*j, 27 + 7*(j - 2), j < 2)
          res%max_quaternion_norm_error = max(res%max_quaternion_norm_error, &
            abs(norm2(y(o:o+3)) - 1.0_dp))
        end do
        ! the rigidized model's own quantities
        frig = cpl%chain%line_force()
        axis = b3%r - b1%point_position(sp%tie_down)
        min_rigid_tension = min(min_rigid_tension, dot_product(frig, axis)/norm2(axis))
        mm = norm2(xl(:, n) - b3%r)
        max_mismatch = max(max_mismatch, mm)
        if (.not. run%trajectory) return
        vb = virtual_line_body(cpl%line%model, xl, vl_, ropt%guard_band)
        nrec = nrec + 1
        time(nrec) = t
        phase(nrec) = sp%phase
        ac_pos(:, nrec) = b0%r
        ac_eul(:, nrec) = ea*rad2deg
        select type (s => sp%sources(2)%source)
        type is (launch_loads)
          ac_alpha(nrec) = s%aircraft_out%alpha*rad2deg
          elev(nrec) = s%aircraft_out%delta_e*rad2deg
        end select
        ac_q(nrec) = b0%w(3)*rad2deg
        load_factor(nrec) = nz
        rk_pos(:, nrec) = b1%r
        rk_vel(:, nrec) = b1%v
        rk_eul(:, nrec) = er*rad2deg
        rk_rate(nrec) = rate*rad2deg
        rk_elev(nrec) = nose_elevation(b1%q)*rad2deg
        pc_pos(:, nrec) = b3%r
        t_rocket(nrec) = ten(1)
        t_chute(nrec) = ten(n)
        nodes(:, :, nrec) = xl
        cforce(1:3, nrec) = sp%rh_force
        cforce(4:6, nrec) = sp%rh_moment
        normal(nrec) = sp%normal_force
        friction(nrec) = sp%friction_force
        clearance(nrec) = cl
        edge_clearance(nrec) = ecl
        residual(nrec) = sp%js%res_position
        m_rig(nrec) = vb%mass
        j_rig(nrec) = vb%inertia
        d_rig(nrec) = vb%length
        f_rig(:, nrec) = frig
        mismatch(nrec) = mm
      end associate
    end subroutine record_at

    subroutine write_output()
      type(nc_writer) :: w
      type(error_type), allocatable :: werr
      real(dp) :: node_index(0:n)
      integer :: j
      do j = 0, n
        node_index(j) = j
      end do
      call w%create(run%output, werr)
      call w%add_dim("time", time(1:nrec), "s", "time since the start (trimmed flight)", werr)
      call w%add_dim("xyz", [0.0_dp, 1.0_dp, 2.0_dp], "1", &
        "earth-frame component: 0 = x forward, 1 = y up, 2 = z right", werr)
      call w%add_dim("angle", [0.0_dp, 1.0_dp, 2.0_dp], "1", "Euler angle: 0 = yaw, 1 = pitch, 2 = roll", werr)
      call w%add_dim("node", node_index, "1", "line node: 0 = rocket tie-down, N = parachute", werr)
      call w%add_dim("wrench", [0.0_dp, 1.0_dp, 2.0_dp, 3.0_dp, 4.0_dp, 5.0_dp], "1", &
        "0-2 force on the rocket (earth x, y, z), 3-5 moment on the rocket about its CG (rocket axes)", werr)
      call w%add_var_1d("phase", ["time"], phase(1:nrec), "1", "phase: 0 locked, 1 rail extraction, " // &
        "2 rotation on the ramp edge, 3 free flight", werr)
      call w%add_var_2d("aircraft_position", ["xyz ", "time"], ac_pos(:, 1:nrec), "m", "aircraft CG, earth frame", werr)
      call w%add_var_2d("aircraft_euler_deg", ["angle", "time "], ac_eul(:, 1:nrec), "degree", &
        "aircraft yaw, pitch, roll", werr)
      call w%add_var_1d("aircraft_alpha_deg", ["time"], ac_alpha(1:nrec), "degree", "aircraft angle of attack", werr)
      call w%add_var_1d("aircraft_pitch_rate_deg_s", ["time"], ac_q(1:nrec), "degree s-1", &
        "aircraft body pitch rate", werr)
      call w%add_var_1d("elevator_deg", ["time"], elev(1:nrec), "degree", "elevator deflection", werr)
      call w%add_var_1d("aircraft_load_factor", ["time"], load_factor(1:nrec), "1", &
        "aircraft normal load factor (specific force along body y / g)", werr)
      call w%add_var_2d("rocket_position", ["xyz ", "time"], rk_pos(:, 1:nrec), "m", "rocket CG, earth frame", werr)
      call w%add_var_2d("rocket_velocity", ["xyz ", "time"], rk_vel(:, 1:nrec), "m s-1", &
        "rocket CG velocity, earth frame", werr)
      call w%add_var_2d("rocket_euler_deg", ["angle", "time "], rk_eul(:, 1:nrec), "degree", &
        "rocket yaw, pitch, roll (the paper's Euler convention; pitch in [-90, 90])", werr)
      call w%add_var_1d("rocket_pitch_rate_deg_s", ["time"], rk_rate(1:nrec), "degree s-1", &
        "rocket Euler pitch rate", werr)
      call w%add_var_1d("rocket_nose_elevation_deg", ["time"], rk_elev(1:nrec), "degree", &
        "rocket nose elevation, continuous through the vertical (0 level forward, 90 up, 180 level aft)", werr)
      call w%add_var_2d("parachute_position", ["xyz ", "time"], pc_pos(:, 1:nrec), "m", &
        "parachute (chain body B3), earth frame", werr)
      call w%add_var_1d("line_tension_rocket_end_N", ["time"], t_rocket(1:nrec), "N", &
        "line tension at the rocket end (sub-stepped flexible line)", werr)
      call w%add_var_1d("line_tension_parachute_end_N", ["time"], t_chute(1:nrec), "N", &
        "line tension at the parachute end (sub-stepped flexible line)", werr)
      call w%add_var_3d("line_nodes", ["xyz ", "node", "time"], nodes(:, :, 1:nrec), "m", &
        "line node positions (sub-stepped flexible line), earth frame", werr)
      call w%add_var_2d("constraint_force", ["wrench", "time  "], cforce(:, 1:nrec), "N or N m", &
        "cut-joint constraint wrench R_H on the rocket (CFA)", werr)
      call w%add_var_1d("edge_normal_force_N", ["time"], normal(1:nrec), "N", &
        "contact normal force of the rail / ramp edge on the rocket", werr)
      call w%add_var_1d("friction_force_N", ["time"], friction(1:nrec), "N", &
        "friction on the rocket along the exit direction", werr)
      call w%add_var_1d("clearance_m", ["time"], clearance(1:nrec), "m", &
        "distance from the rocket's surface to the aircraft's empennage (&bay tail_x, tail_y)", werr)
      call w%add_var_1d("edge_clearance_m", ["time"], edge_clearance(1:nrec), "m", &
        "distance from the rocket's surface to the ramp edge after separation (0 before)", werr)
      call w%add_var_1d("constraint_residual_m", ["time"], residual(1:nrec), "m", &
        "position residual of the cut-joint constraints", werr)
      call w%add_var_1d("m_rigid_kg", ["time"], m_rig(1:nrec), "kg", &
        "virtual line body: mass m_rigid (Eq. (31), kinetic-energy equivalent, guarded)", werr)
      call w%add_var_1d("j_rigid_kg_m2", ["time"], j_rig(1:nrec), "kg m2", &
        "virtual line body: transverse moment of inertia J_rigid (Eq. (32), guarded)", werr)
      call w%add_var_1d("d_rigid_m", ["time"], d_rig(1:nrec), "m", &
        "virtual line body: length d_rigid (Eq. (20), chord of the flexible line)", werr)
      call w%add_var_2d("rigid_line_force_N", ["xyz ", "time"], f_rig(:, 1:nrec), "N", &
        "force of the virtual line body on the rocket at the tie-down point (chain joint force), earth frame", werr)
      call w%add_var_1d("line_end_mismatch_m", ["time"], mismatch(1:nrec), "m", &
        "distance between the flexible line's node N and the chain's parachute B3", werr)
      call write_run_metadata(w, "airlaunch", "airlaunch: aircraft-rocket-line-parachute separation " // &
        "(Zheng & Zhang 2018, §5.2), line by equivalent rigidization (§2.4)", echo, werr)
      call write_milestones(w, res, werr)
      call w%add_text_att("/", "line_coupling", "rigidized", werr)
      call w%add_real_att("/", "outer_dt_s", ropt%outer_dt, werr)
      call w%add_real_att("/", "refreshes", real(cpl%n_refresh, dp), werr)
      call w%add_real_att("/", "guarded_mass_refreshes", real(cpl%n_guard_mass, dp), werr)
      call w%add_real_att("/", "guarded_inertia_refreshes", real(cpl%n_guard_inertia, dp), werr)
      call w%add_real_att("/", "min_rigid_line_tension_N", min_rigid_tension, werr)
      call w%add_real_att("/", "max_line_end_mismatch_m", max_mismatch, werr)
      call w%finish(werr)
      if (allocated(werr) .and. .not. allocated(run_error)) call move_alloc(werr, run_error)
    end subroutine write_output
  end subroutine run_rigidized
end submodule airlaunch_launch_rigidized
