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
    integer :: nmax, n, k, status, nout, iout
    type(launch_history) :: hist
    real(dp), allocatable :: m_rig(:), j_rig(:), d_rig(:), f_rig(:, :), mismatch(:)
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
      call hist%init(nmax, n)
      allocate(m_rig(nmax), j_rig(nmax), d_rig(nmax), f_rig(3, nmax), mismatch(nmax))
    end if
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
      real(dp) :: t_target, eps, t_last
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
          call handle_launch_event(res, cpl%t, c%sep, c%yabs, which(1:separation_nroots), &
            which(rigidized_nroots), c%find_pitch_max, changed, err)
          if (allocated(err)) return
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
      real(dp) :: frig(3), axis(3), mm
      integer :: j, o
      type(error_type), allocatable :: eval_error
      type(virtual_line) :: vb
      type(launch_sample) :: smp
      if (allocated(err)) return
      call cpl%line_state(xl, vl_, ten)
      call cpl%chain%prepare(t, y)
      call cpl%chain%sep%evaluate(t, cpl%chain%yabs, eval_error)
      associate(sp => cpl%chain%sep, b1 => cpl%chain%sep%bodies(1), b3 => cpl%chain%sep%bodies(3))
        smp = sample_launch(cfg, sp, 2)
        ! the milestones (stop_when_final is not offered by this coupling)
        if (record_milestones(res, t, smp, sp, ten)) continue
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
        call hist%append(t, smp, sp, xl, ten, b3%r)
        m_rig(hist%nrec) = vb%mass
        j_rig(hist%nrec) = vb%inertia
        d_rig(hist%nrec) = vb%length
        f_rig(:, hist%nrec) = frig
        mismatch(hist%nrec) = mm
      end associate
    end subroutine record_at

    subroutine write_output()
      type(nc_writer) :: w
      type(error_type), allocatable :: werr
      integer :: nrec
      nrec = hist%nrec
      call w%create(run%output, werr)
      call hist%write_contract(w, "parachute (chain body B3), earth frame", " (sub-stepped flexible line)", werr)
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
