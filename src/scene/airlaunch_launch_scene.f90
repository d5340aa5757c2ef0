!> The air-launch scene (the paper's scenario, §4-§5.2): build the system from
!> the inputs, trim it, integrate the four phases with event location, record
!> the output contract (docs/output.md) and the milestones.
module airlaunch_launch_scene
  use airlaunch_kinds, only: dp, pi, g0, rad2deg, deg2rad
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_atmosphere, only: isa, air_state
  use airlaunch_rotation, only: quat_from_euler
  use airlaunch_cvode, only: cvode_solver, cvode_options, cvode_stats, add_stats
  use airlaunch_linalg, only: solve_banded
  use airlaunch_run_config, only: run_config
  use airlaunch_ncwrite, only: nc_writer
  use airlaunch_output_meta, only: write_run_metadata
  use airlaunch_scenario_config, only: scenario_config
  use airlaunch_trim, only: trim_problem, trim_result, trim_case0
  use airlaunch_rigid_body, only: rigid_body, new_rigid_body
  use airlaunch_force_source, only: gravity_source
  use airlaunch_cut_joint, only: cut_joint_geometry, cut_joint_options, phase_name, phase_free, &
    phase_preparation
  use airlaunch_line_model, only: line_params
  use airlaunch_launch_loads, only: launch_loads
  use airlaunch_launch_system, only: launch_system, launch_nroots, rigid_size
  use airlaunch_launch_history, only: launch_result, launch_sample, launch_history, sample_launch, &
    record_milestones, write_milestones, event_or_minus, segment_distance, handle_launch_event
  implicit none
  private
  public :: launch_result, run_launch, setup_launch


  interface
    !> The scene with coupling (a), `&line coupling = 'rigidized'`: the line as
    !> the virtual rigid body of the Kane chain (submodule airlaunch_launch_rigidized).
    module subroutine run_rigidized(run, cfg, echo, res, error)
      type(run_config), intent(in) :: run
      type(scenario_config), intent(in) :: cfg
      character(len=*), intent(in) :: echo
      type(launch_result), intent(inout) :: res
      type(error_type), allocatable, intent(inout) :: error
    end subroutine run_rigidized
  end interface

contains

  !> Build the system, trim it and fill its initial state y0 (relative
  !> variables, see airlaunch_launch_system).
  subroutine setup_launch(cfg, sys, y0, res, error)
    type(scenario_config), intent(in) :: cfg
    type(launch_system), intent(inout) :: sys
    real(dp), allocatable, intent(out) :: y0(:)
    type(launch_result), intent(inout) :: res
    type(error_type), allocatable, intent(inout) :: error
    type(air_state) :: air
    type(trim_problem) :: tp
    type(trim_result) :: tr
    type(rigid_body) :: b0, b1
    type(cut_joint_geometry) :: geo
    type(cut_joint_options) :: jopt
    type(launch_loads) :: loads
    type(line_params) :: lp
    real(dp) :: v0, radius, r_rocket(3), r_tie(3), pull
    integer :: n, i, status

    air = isa(cfg%flight%altitude)
    v0 = cfg%flight%mach*air%sound_speed
    radius = cfg%rocket%aero%diameter/2
    sys%has_line = cfg%line%enabled
    if (sys%has_line) then
      ! the line: weight and drag on, ISA density along it
      lp = line_params(length=cfg%line%length, n_seg=cfg%line%n_seg, ea=cfg%line%ea, &
        mass_per_length=cfg%line%mass_per_length, damping=cfg%line%damping, diameter=cfg%line%diameter, &
        cd_normal=cfg%line%cd_normal, cd_tangential=cfg%line%cd_tangential, gravity=.true., air=.true.)
      call sys%line%init(lp, error)
      if (allocated(error)) return
      sys%chute = cfg%chute
      if (sys%chute%deploy_time >= 0.0_dp) sys%chute%fill_time = &
        sys%chute%fill_constant*sqrt(4*sys%chute%drag_area/(pi*sys%chute%cd0))/v0
    end if

    ! --- trim of the Case 0 system (aircraft + locked rocket + parachute pull)
    r_rocket = [cfg%bay%ramp_edge_x + cfg%bay%l0, cfg%bay%floor_y + radius, 0.0_dp]
    r_tie = r_rocket + [cfg%rocket%aero%cg_from_nose - cfg%rocket%tie_down_from_nose, 0.0_dp, 0.0_dp]
    ! steady pull: the canopy's drag and the skin friction of the trailing line
    pull = 0.5_dp*air%density*v0**2*(sys%chute%drag_area + cfg%line%cd_tangential*pi*cfg%line%diameter &
      *cfg%line%length)
    if (sys%chute%deploy_time >= 0.0_dp) pull = 0.5_dp*air%density*v0**2*sys%chute%packed_drag_area
    if (.not. sys%has_line) pull = 0.0_dp
    tp = trim_problem(aircraft_mass=cfg%aircraft%mass, rocket_mass=cfg%rocket%mass, r_rocket=r_rocket, &
      r_tie=r_tie, pull=pull, density=air%density, speed=v0, mode=cfg%flight%trim_mode, &
      alpha_target=cfg%flight%trim_alpha)
    loads%aircraft = cfg%aircraft%aero
    call trim_case0(tp, loads%aircraft, tr, error)
    if (allocated(error)) return
    res%trim_alpha_deg = tr%alpha*rad2deg
    res%trim_elevator_deg = tr%delta_e*rad2deg
    res%trim_thrust_n = tr%thrust
    res%trim_cl0 = tr%cl0
    res%trim_cm0 = tr%cm0

    ! --- bodies: aircraft in trimmed level flight, rocket locked on the rail
    b0 = new_rigid_body("aircraft", cfg%aircraft%mass, diag(cfg%aircraft%inertia), error)
    if (allocated(error)) return
    b0%r = [0.0_dp, cfg%flight%altitude, 0.0_dp]
    b0%v = [v0, 0.0_dp, 0.0_dp]
    call b0%set_attitude(quat_from_euler([0.0_dp, tr%alpha, 0.0_dp]))
    b1 = new_rigid_body("rocket", cfg%rocket%mass, diag(cfg%rocket%inertia), error)
    if (allocated(error)) return
    geo = cut_joint_geometry(rail_direction=[-1.0_dp, 0.0_dp, 0.0_dp], &
      floor_point=[0.0_dp, cfg%bay%floor_y, 0.0_dp], edge_point=[cfg%bay%ramp_edge_x, cfg%bay%floor_y, 0.0_dp], &
      contact_point=[0.0_dp, -radius, 0.0_dp], nose_x=cfg%rocket%aero%cg_from_nose, &
      rocket_length=cfg%rocket%aero%length, rocket_radius=radius)
    jopt = cut_joint_options(mu_rail=cfg%bay%friction, mu_edge=cfg%bay%friction)
    sys%tie_down = [cfg%rocket%aero%cg_from_nose - cfg%rocket%tie_down_from_nose, 0.0_dp, 0.0_dp]
    call sys%sep%init(b0, b1, sys%tie_down, 1, geo, jopt, cfg%bay%release_time, error, &
      aircraft_prescribed=cfg%aircraft%dynamics == "prescribed")
    if (allocated(error)) return
    sys%sep%edge_bilateral = cfg%bay%edge_contact == "bilateral"
    call sys%sep%joint%place_on_rail(sys%sep%bodies(0), cfg%bay%l0, 0.0_dp, sys%sep%bodies(1))
    call sys%sep%add_source(gravity_source())
    loads%rocket = cfg%rocket%aero
    loads%edge_point = geo%edge_point
    loads%tie_down = sys%tie_down
    loads%aircraft_aero_on = cfg%aircraft%dynamics /= "prescribed"
    loads%line_on = sys%has_line
    call sys%sep%add_source(loads)
    sys%iloads = size(sys%sep%sources)

    ! --- state: reference frame at V0, h0; the line trails straight aft from
    !     the tie-down point, stretched by the steady pull
    sys%v_ref = v0
    sys%h_ref = cfg%flight%altitude
    n = merge(sys%line%n, 0, sys%has_line)
    allocate(y0(rigid_size + 6*n), sys%yabs(rigid_size + 6*n), sys%ydabs(rigid_size + 6*n))
    call sys%sep%pack_state(y0(1:rigid_size))
    do i = 0, 1
      y0(13*i+1:13*i+3) = y0(13*i+1:13*i+3) - [0.0_dp, sys%h_ref, 0.0_dp]
      y0(13*i+4) = y0(13*i+4) - v0
    end do
    if (sys%has_line) then
      allocate(sys%x(3, 0:n), sys%v(3, 0:n), sys%f(3, 0:n), sys%tension(n))
      call place_line(sys, cfg, pull, y0, error)
      if (allocated(error)) return
    end if
    call sys%prepare(0.0_dp, y0, status)
    call sys%sep%start(0.0_dp, sys%yabs(1:rigid_size), phase_preparation, error)
  contains
    pure function diag(d) result(m)
      real(dp), intent(in) :: d(3)
      real(dp) :: m(3, 3)
      m = 0
      m(1, 1) = d(1); m(2, 2) = d(2); m(3, 3) = d(3)
    end function diag
  end subroutine setup_launch

  !> The line's nodes in y: trailing straight aft from the tie-down point,
  !> stretched by the steady pull, then settled to their static equilibrium.
  subroutine place_line(sys, cfg, pull, y0, error)
    type(launch_system), intent(inout) :: sys
    type(scenario_config), intent(in) :: cfg
    real(dp), intent(in) :: pull   !< steady pull of the parachute and line drag [N]
    real(dp), intent(inout) :: y0(:)
    type(error_type), allocatable, intent(inout) :: error
    real(dp) :: seg, dir(3)
    integer :: n, k, i
    n = sys%line%n
    seg = sys%line%l0*(1.0_dp + pull/cfg%line%ea)
    dir = [-1.0_dp, 0.0_dp, 0.0_dp]
    do k = 1, n
      i = rigid_size + 6*(k - 1)
      y0(i+1:i+3) = sys%sep%bodies(1)%point_position(sys%tie_down) + k*seg*dir - [0.0_dp, sys%h_ref, 0.0_dp]
      y0(i+4:i+6) = 0.0_dp
    end do
    call settle_line(sys, y0, error)
  end subroutine place_line

  !> Static equilibrium of the trailing line in the trimmed flight: every node
  !> moves with the aircraft at V0, node 0 is the tie-down point, and the node
  !> positions (1..N, node N the parachute) are found by Newton's method with a
  !> finite-difference block-tridiagonal Jacobian (3-colouring of the nodes,
  !> LAPACK band solve).  Starting in equilibrium removes the transient that a
  !> straight initial line would ring with (weight and drag sag it).
  subroutine settle_line(sys, y, error)
    type(launch_system), intent(inout) :: sys
    real(dp), intent(inout) :: y(:)
    type(error_type), allocatable, intent(inout) :: error
    integer :: n, m, it, color, k, c, i, j, row, col
    real(dp), allocatable :: r(:), r2(:), ab(:, :), du(:, :)
    real(dp) :: scale, h
    integer, parameter :: kl = 5, ku = 5
    n = sys%line%n
    m = 3*n
    allocate(r(m), r2(m), ab(2*kl + ku + 1, m), du(m, 1))
    h = 1.0e-5_dp
    call residual(y, r)
    ! forces are judged against the line's tension (round-off of EA eps sets the floor)
    scale = max(1.0_dp, maxval(abs(r)), maxval(sys%tension))
    do it = 1, 30
      if (maxval(abs(r)) <= 1.0e-9_dp*scale) exit
      ab = 0.0_dp
      do color = 0, 2
        do c = 1, 3
          do k = 1 + color, n, 3
            i = rigid_size + 6*(k - 1) + c
            y(i) = y(i) + h
          end do
          call residual(y, r2)
          do k = 1 + color, n, 3
            i = rigid_size + 6*(k - 1) + c
            y(i) = y(i) - h
            col = 3*(k - 1) + c
            do row = max(1, 3*(k - 2) + 1), min(m, 3*k + 3)
              ab(kl + ku + 1 + row - col, col) = (r2(row) - r(row))/h
            end do
          end do
        end do
      end do
      du(:, 1) = -r
      call solve_banded(ab, kl, ku, du, error, "static line equilibrium")
      if (allocated(error)) return
      do k = 1, n
        j = rigid_size + 6*(k - 1)
        y(j+1:j+3) = y(j+1:j+3) + du(3*k-2:3*k, 1)
      end do
      call residual(y, r)
    end do
    if (maxval(abs(r)) > 1.0e-6_dp*scale) call fatal_error(error, "the trailing line has no static " // &
      "equilibrium in the trimmed flight (residual " // str(maxval(abs(r))) // " N)")
  contains
    !> Node accelerations times masses in the steady flight (zero at equilibrium).
    subroutine residual(yy, res)
      real(dp), intent(in) :: yy(:)
      real(dp), intent(out) :: res(:)
      real(dp) :: ydot(size(yy))
      integer :: kk, status, ii
      call sys%prepare(0.0_dp, yy, status)
      ! nodes move with the aircraft: relative velocity zero
      call sys%rhs(0.0_dp, yy, ydot, status)
      do kk = 1, n
        ii = rigid_size + 6*(kk - 1)
        res(3*kk-2:3*kk) = ydot(ii+4:ii+6)*sys%line%node_mass(kk)
      end do
    end subroutine residual
  end subroutine settle_line

  !> Run the scene and write its output (unless run%trajectory is false).
  subroutine run_launch(run, cfg, echo, res, error)
    type(run_config), intent(in) :: run
    type(scenario_config), intent(in) :: cfg
    character(len=*), intent(in) :: echo
    type(launch_result), intent(out) :: res
    type(error_type), allocatable, intent(inout) :: error
    type(launch_system), target :: sys
    type(cvode_solver) :: solver
    type(cvode_options) :: opts
    type(error_type), allocatable :: run_error
    real(dp), allocatable :: y0(:)
    type(launch_history) :: hist
    integer :: nmax, n
    real(dp) :: tout, last_record_of_extremum
    integer :: k

    if (cfg%line%coupling == "rigidized") then
      call run_rigidized(run, cfg, echo, res, error)
      return
    end if
    last_record_of_extremum = 0.0_dp
    call setup_launch(cfg, sys, y0, res, error)
    if (allocated(error)) return
    n = sys%line%n
    opts%rtol = run%rtol
    opts%atol = run%atol
    opts%linear_solver = "band"
    ! The band holds the stiff couplings: the line's node chain and node 1 with
    ! the rocket's position and attitude (offsets up to 18).  The aircraft-rocket
    ! coupling through the CFA (offsets to 25) and aircraft-node 1 (31) are soft
    ! and left out of the Newton matrix (a modified Newton iteration): measured
    ! 27 % faster than the full band with the same milestones (docs/performance.md).
    opts%upper_bandwidth = 18
    opts%lower_bandwidth = 18
    opts%atol_vector = atol_scaling(run%atol, size(y0))
    ! BDF orders above 2 are not A-stable: on the line's lightly damped axial
    ! modes they force tiny steps (measured: 6.2k steps at order 2, 40k at 4,
    ! 72k at 3 for the paper scenario, same milestones), so the scene default
    ! is order 2 (&run max_order = 0).
    opts%max_order = run%max_order
    if (opts%max_order == 0) opts%max_order = 2
    if (.not. sys%has_line) call rigid_only_options(run, opts)
    call solver%init(sys, 0.0_dp, y0, opts, error)
    if (allocated(error)) return

    res%has_line = sys%has_line
    nmax = ceiling(run%t_end/run%output_dt + 1.0e-9_dp) + 1
    if (run%trajectory) call hist%init(nmax, n, sys%has_line)
    call record()
    do k = 1, nmax - 1
      tout = min(k*run%output_dt, run%t_end)
      call advance_to(tout, run_error)
      if (allocated(run_error)) exit
      call record()
      if (tout >= run%t_end) exit
      if (run%stop_when_final .and. milestones_final()) exit
    end do
    call add_stats(res%stats, solver%stats())
    res%end_time = solver%t
    res%release_time = event_or_minus(sys%sep%event_time(1))
    res%edge_time = event_or_minus(sys%sep%event_time(2))
    res%separation_time = event_or_minus(sys%sep%event_time(3))
    res%early_separation = sys%sep%early_separation
    res%edge_pull_time = event_or_minus(sys%sep%edge_pull_time)
    if (allocated(run_error)) then
      res%status = "failed"
      res%failure = run_error%message
    end if
    call solver%free()
    if (run%trajectory) call write_output()
    if (allocated(run_error)) call move_alloc(run_error, error)
  contains

    !> Integrate to tout, handling the events on the way.
    subroutine advance_to(t_target, err)
      real(dp), intent(in) :: t_target
      type(error_type), allocatable, intent(inout) :: err
      logical :: event, changed
      integer :: which(launch_nroots), guard, status

      do guard = 1, 100
        call solver%advance(t_target, err, event, which)
        if (allocated(err)) then
          err%message = phase_name(sys%sep%phase) // ": " // err%message
          return
        end if
        if (.not. event) return
        call sys%prepare(solver%t, solver%y, status)
        call handle_launch_event(res, solver%t, sys%sep, sys%yabs(1:rigid_size), which(1:launch_nroots-1), &
          which(launch_nroots), sys%find_pitch_max, changed, err)
        if (allocated(err)) return
        if (changed) then
          ! the constraint set changed: restart CVODE from the event (its
          ! counters restart too, so keep the totals)
          call add_stats(res%stats, solver%stats())
          call solver%reinit(solver%t, solver%y, err)
          if (allocated(err)) return
        end if
        if (solver%t >= t_target) return
      end do
      call fatal_error(err, phase_name(sys%sep%phase) // ", t = " // str(solver%t) // &
        " s: too many events before the output time")
    end subroutine advance_to

    !> The milestones cannot change any more (for &run stop_when_final): the
    !> rocket is free, its first pitch maximum is found, and 1 s has passed
    !> since both, during which the rocket-empennage clearance only grew (so its
    !> minimum is behind) and the aircraft's pitch excursion and load factor did
    !> not set a new maximum.  A later snatch of the line is not waited for.
    logical function milestones_final()
      milestones_final = .false.
      if (sys%sep%phase /= phase_free .or. res%pitch_max_time < 0.0_dp) return
      if (solver%t < max(res%pitch_max_time, res%separation_time) + 1.0_dp) return
      milestones_final = solver%t >= last_record_of_extremum + 1.0_dp
    end function milestones_final

    !> Sample the state at the solver's time (outputs and milestones).
    subroutine record()
      integer :: status
      type(error_type), allocatable :: eval_error
      type(launch_sample) :: smp
      call sys%prepare(solver%t, solver%y, status)
      call sys%sep%evaluate(solver%t, sys%yabs(1:rigid_size), eval_error)
      smp = sample_launch(cfg, sys%sep, sys%iloads)
      if (sys%has_line) then
        if (record_milestones(res, solver%t, smp, sys%sep, sys%tension)) last_record_of_extremum = solver%t
      else
        if (record_milestones(res, solver%t, smp, sys%sep)) last_record_of_extremum = solver%t
      end if
      res%max_quaternion_norm_error = max(res%max_quaternion_norm_error, abs(norm2(solver%y(7:10)) - 1.0_dp), &
        abs(norm2(solver%y(20:23)) - 1.0_dp))
      if (.not. run%trajectory) return
      if (sys%has_line) then
        call hist%append(solver%t, smp, sys%sep, sys%x, sys%tension, sys%x(:, n))
      else
        call hist%append(solver%t, smp, sys%sep)
      end if
    end subroutine record

    subroutine write_output()
      type(nc_writer) :: w
      type(error_type), allocatable :: werr
      call w%create(run%output, werr)
      call hist%write_contract(w, "parachute (the line's last node), earth frame", "", werr)
      if (sys%has_line) then
        call write_run_metadata(w, "airlaunch", "airlaunch: aircraft-rocket-line-parachute separation " // &
          "(Zheng & Zhang 2018, §5.2)", echo, werr)
      else
        call write_run_metadata(w, "airlaunch", "airlaunch: aircraft-rocket separation without line or " // &
          "parachute (gravity drop, rail release)", echo, werr)
      end if
      call write_milestones(w, res, werr)
      call w%finish(werr)
      if (allocated(werr) .and. .not. allocated(run_error)) call move_alloc(werr, run_error)
    end subroutine write_output
  end subroutine run_launch




  !> Solver settings of a scene without a line (26 rigid states): a dense
  !> Newton matrix (the band of the line is gone; 26 x 26 costs nothing), and
  !> BDF up to order 5 unless &run max_order says otherwise (the order-2
  !> default exists for the line's lightly damped axial modes).
  subroutine rigid_only_options(run, opts)
    type(run_config), intent(in) :: run
    type(cvode_options), intent(inout) :: opts
    opts%linear_solver = "dense"
    if (run%max_order == 0 .and. opts%method == "bdf") opts%max_order = 5
  end subroutine rigid_only_options

  !> Per-component absolute tolerances: positions and velocities in m and
  !> m/s (relative variables, small numbers), quaternions and rates tighter.
  pure function atol_scaling(atol, n) result(a)
    real(dp), intent(in) :: atol
    integer, intent(in) :: n
    real(dp) :: a(n)
    integer :: i
    a = atol*1.0e2_dp
    do i = 0, 1
      a(13*i+7:13*i+10) = atol
      a(13*i+11:13*i+13) = atol*10
    end do
  end function atol_scaling

end module airlaunch_launch_scene
