!> The air-launch scene's run with its two line couplings (DESIGN §4) as two
!> engines over one set of records, and the hand-over between them:
!>  * direct (b): the launch_system (bodies + line nodes) in one CVODE;
!>  * rigidized (a): the paper's equivalent rigidization (§2.4 Steps 1-6, the
!>    Kane chain rocket - virtual line - parachute and the sub-stepped flexible
!>    line, airlaunch_rigidized_coupling).
!> Both start from the same set-up (`setup_launch`: trim of the Case 0 system,
!> the line in its static equilibrium), share the milestones (`res`), the
!> output times and the history of the output contract (docs/output.md).
!>
!> The plan (airlaunch_coupling_choice) says which engine runs: one for the
!> whole run ('direct', 'rigidized'), one per phase ('per_phase': the switch
!> happens at the event that changes the phase), or the automatic choice
!> ('auto': checked every outer step H = `&line outer_dt`).  A switch hands
!> over the state at one instant t: the aircraft and the rocket (r, v, q, w),
!> the line's nodes 1..N (positions and velocities; node N carries the
!> parachute in both couplings), the phase machine (phase, event times, the
!> cut joint's references of the run's start) and the pitch-maximum search;
!> the new engine's CVODE starts there (as after every event).  The records
!> continue: output times before t were recorded by the old engine, the rest
!> by the new one; counters are summed.
submodule (airlaunch_launch_scene) airlaunch_launch_coupled
  use airlaunch_multibody, only: separation_system, separation_nroots
  use airlaunch_rigidized_coupling, only: rigidized_settings, rigidized_coupling, rigidized_loads, &
    rigidized_nroots, rigidized_pitch_root, rigidized_clearance_root, virtual_line, virtual_line_body, &
    continue_phase_machine
  use airlaunch_coupling_choice, only: auto_switch, line_indicator, line_indicator_of, coupling_name
  use airlaunch_rigidized_coupling, only: rigidized_chain, rigidized_line
  use airlaunch_step_maxima, only: maxima_observer
  use airlaunch_peak_search, only: peak_tracker
  use airlaunch_clearance, only: clearance
  use airlaunch_rotation, only: dcm_to_euler
  implicit none

  !> The safety maxima taken over the integrators' steps (docs/output.md):
  !> the largest segment tension, |aircraft pitch - trim|, |n - n_trim|.
  !> (m_line_gap: minus the line's clearance from the empennage point, so that
  !> its smallest value is a maximum; tracked by the direct coupling only;
  !> m_exit_gap: minus the rocket's clearance from the empennage (the records'
  !> `clearance`), from the release on, in the direct coupling and the
  !> rigidized coupling's chain: min_exit_clearance_m)
  integer, parameter :: m_tension = 1, m_pitch = 2, m_load = 3, m_line_gap = 4, m_exit_gap = 5
  !> the trackers that stop_when_final waits for (not m_exit_gap: its minimum
  !> after the separation is the records' min_clearance, already waited for)
  integer, parameter :: n_final = m_line_gap
  !> Which integrator an observer watches: the direct system (all three), the
  !> rigidized coupling's chain (pitch and load factor) or its line (tension).
  integer, parameter :: src_direct = 1, src_chain = 2, src_line = 3

  !> The safety maxima over every internal step of one integrator
  !> (airlaunch_step_maxima), each evaluation the same function of the state
  !> as an output record's; the load factor's step-end samples are estimates
  !> (the interpolant's derivative as the aircraft's acceleration).
  type, extends(maxima_observer) :: metric_observer
    integer :: source = 0
    type(launch_system), pointer :: dsys => null()
    type(rigidized_chain), pointer :: chain => null()
    type(rigidized_line), pointer :: line => null()
    real(dp) :: trim_deg = 0.0_dp                     !< the aircraft's trimmed pitch [deg]
    real(dp) :: trim_load_factor = 1.0_dp             !< its load factor then, cos(trim pitch)
  contains
    procedure :: watches
    procedure :: values => metric_values
  end type metric_observer

  !> One run: the two engines, the choice between them and the records.
  type :: coupled_run
    type(coupling_plan) :: plan                       !< how the coupling is chosen
    integer :: active = coupling_direct               !< the engine in use
    ! --- the direct coupling (b)
    type(launch_system), pointer :: dsys => null()    !< on the heap: CVODE keeps its address
    type(cvode_solver) :: dsolver                     !< its integrator
    type(cvode_options) :: dopts                      !< its settings
    logical :: dsolver_started = .false.              !< dsolver was initialised
    ! --- the rigidized coupling (a)
    type(separation_system) :: chain                  !< the configured chain (bodies set at each start)
    type(rigidized_settings) :: ropt                  !< outer step and sub-step settings
    type(rigidized_coupling) :: cpl                   !< both subsystems while it runs
    integer :: n_refresh = 0, n_guard_mass = 0, n_guard_inertia = 0   !< over all its stints
    real(dp) :: min_rigid_tension = huge(1.0_dp)      !< smallest axial force of the rigid line [N]
    real(dp) :: max_mismatch = 0.0_dp                 !< largest node N - B3 distance [m]
    ! --- the automatic choice and the switches
    type(auto_switch) :: auto                         !< hysteresis state
    real(dp) :: next_check = 0.0_dp                   !< next check of the indicator (direct engine) [s]
    real(dp) :: chk_steps = 0.0_dp, chk_t = 0.0_dp    !< line-carrying steps and time at the last check
    real(dp) :: rec_steps = 0.0_dp, rec_t = 0.0_dp    !< the same at the last record
    integer :: switches = 0                           !< hand-overs so far
    character(len=:), allocatable :: switch_log       !< "t s: from -> to; ..."
    logical :: done = .false.                         !< the run reached its end
    ! --- output times and records
    real(dp), allocatable :: t_out(:)                 !< output times after 0
    integer :: nout = 0, iout = 1                     !< their number, the next one to record
    type(launch_history) :: hist                      !< the output contract
    real(dp) :: last_record_of_extremum = 0.0_dp      !< for stop_when_final [s]
    logical :: extras = .false.                       !< record the coupling's own variables
    real(dp), allocatable :: m_rig(:), j_rig(:), d_rig(:), f_rig(:, :), mismatch(:)
    real(dp), allocatable :: active_rec(:), strain_rec(:), change_rec(:), steps_rec(:)
    ! --- work arrays: the line's state of the rigidized engine
    real(dp), allocatable :: xl(:, :), vl(:, :), ten(:)
    ! --- the safety maxima over every step (on the heap: the observers point to them)
    type(peak_tracker), pointer :: trk(:) => null()
    type(metric_observer) :: dobs, cobs, lobs         !< direct, chain, line
  end type coupled_run

contains

  !> Run the scene (see the submodule header).
  !> (interface in airlaunch_launch_scene)
  module procedure run_coupled
    type(coupled_run) :: r
    type(error_type), allocatable :: run_error, output_error
    real(dp), allocatable :: y0(:)
    logical :: switch

    r%plan = plan
    allocate(r%dsys)
    call setup_launch(cfg, r%dsys, y0, res, error)
    if (.not. allocated(error)) call prepare_run(r, run, cfg, size(y0), error)
    if (.not. allocated(error)) call init_observers(r, res, run%rtol)
    if (.not. allocated(error)) call start_engine(r, y0, error)
    if (allocated(error)) then
      call release(r)
      return
    end if
    res%has_line = r%dsys%has_line
    call record_now(r, run, cfg, res, run_error)
    switch = .false.
    if (r%plan%mode == "auto" .and. .not. allocated(run_error)) call auto_check(r, 0.0_dp, switch)
    do while (.not. (r%done .or. allocated(run_error)))
      if (switch) then
        call hand_over(r, res, run_error)
        if (allocated(run_error)) exit
      end if
      if (r%active == coupling_direct) then
        call direct_segment(r, run, cfg, res, switch, run_error)
      else
        call rigidized_segment(r, run, cfg, res, switch, run_error)
      end if
    end do
    call finish_result(r, res)
    call take_maxima(r, res)
    if (allocated(run_error)) then
      res%status = run_status(run_error)
      res%failure = run_error%message
    end if
    if (run%trajectory) then
      call write_output(r, run, echo, res, output_error)
      if (allocated(output_error)) res%output_error = output_error%message
      call add_output_error(run_error, output_error)
    end if
    call release(r)
    if (allocated(run_error)) call move_alloc(run_error, error)
  end procedure run_coupled

  ! ------------------------------------------------------------ set-up

  !> Output times, records, solver settings and (if the plan may use it) the
  !> rigidized coupling's chain.
  subroutine prepare_run(r, run, cfg, n_state, error)
    type(coupled_run), intent(inout) :: r
    type(run_config), intent(in) :: run
    type(scenario_config), intent(in) :: cfg
    integer, intent(in) :: n_state
    type(error_type), allocatable, intent(inout) :: error
    integer :: nmax, k, n, st
    n = r%dsys%line%n
    call set_direct_options(run, n_state, r%dsys%has_line, r%dopts)
    ! one wall-time budget for the run, whichever integrators share it
    if (run%max_wall_time > 0.0_dp) r%dopts%wall_deadline = wall_clock() + run%max_wall_time
    ! with a &gust, a quarter of its passage 2H/V0 (launch_system%gust_max_step):
    ! CVODE reads the right-hand side only at the points of its steps, so a
    ! longer step (the trimmed flight before the gust takes steps of seconds)
    ! could step over the whole gust and never see it.  The direct coupling
    ! lifts the cap once every point has passed the gust (event
    ! launch_gust_root); the rigidized coupling's integrators keep it.
    r%dopts%max_step = r%dsys%gust_max_step
    nmax = ceiling(run%t_end/run%output_dt + 1.0e-9_dp) + 1
    allocate(r%t_out(nmax))
    r%nout = 0
    do k = 1, nmax - 1
      r%nout = r%nout + 1
      r%t_out(r%nout) = min(k*run%output_dt, run%t_end)
      if (r%t_out(r%nout) >= run%t_end) exit
    end do
    r%iout = 1
    r%extras = r%plan%mode /= "direct"
    if (run%trajectory) then
      call r%hist%init(nmax, n, r%dsys%has_line, st)
      if (st == 0 .and. r%extras) allocate(r%m_rig(nmax), r%j_rig(nmax), r%d_rig(nmax), r%f_rig(3, nmax), &
        r%mismatch(nmax), r%active_rec(nmax), r%strain_rec(nmax), r%change_rec(nmax), r%steps_rec(nmax), stat=st)
      if (st /= 0) then
        call refuse_records(error, run%output_dt, nmax, history_bytes(nmax, n, r%dsys%has_line) + &
          merge(8.0_dp*11*nmax, 0.0_dp, r%extras))
        return
      end if
    end if
    r%active = r%plan%initial()
    r%auto%active = r%active
    if (.not. r%plan%uses_rigidized()) return
    allocate(r%xl(3, 0:n), r%vl(3, 0:n), r%ten(n))
    r%ropt = rigidized_options(run, cfg)
    r%ropt%max_step = r%dsys%gust_max_step
    r%ropt%wall_deadline = r%dopts%wall_deadline
    call build_chain(cfg, r%dsys, r%chain, error)
  end subroutine prepare_run

  !> Settings of the rigidized coupling from &run and &line.
  function rigidized_options(run, cfg) result(ropt)
    type(run_config), intent(in) :: run
    type(scenario_config), intent(in) :: cfg
    type(rigidized_settings) :: ropt
    ropt%outer_dt = cfg%line%outer_dt
    ropt%far_end = cfg%line%far_end
    ropt%inner_scheme = cfg%line%inner_scheme
    ropt%inner_dt = cfg%line%inner_dt
    ropt%chain_rtol = run%rtol
    ropt%chain_atol = run%atol
    ropt%inner_rtol = run%rtol
    if (cfg%line%inner_rtol > 0.0_dp) ropt%inner_rtol = cfg%line%inner_rtol
    ropt%inner_atol = 100.0_dp*run%atol   ! as the direct scene's line nodes (atol_scaling)
    ropt%chain_max_order = 2
    ropt%inner_max_order = 2
    ropt%max_steps = run%max_steps
    ropt%max_wall_time = run%max_wall_time
    ropt%t_end = run%t_end
    if (run%max_order > 0) then
      ropt%chain_max_order = run%max_order
      ropt%inner_max_order = run%max_order
    end if
  end function rigidized_options

  !> The chain of the rigidized coupling: the same aircraft, rocket, cut joint
  !> and loads as the direct system `dsys`, three bodies (rocket, virtual
  !> line, parachute).  The line's end force is not applied (the chain's B2
  !> carries the line).
  subroutine build_chain(cfg, dsys, sep, error)
    type(scenario_config), intent(in) :: cfg
    type(launch_system), intent(in) :: dsys
    type(separation_system), intent(out) :: sep
    type(error_type), allocatable, intent(inout) :: error
    type(rigidized_loads) :: rl
    call sep%init(dsys%sep%bodies(0), dsys%sep%bodies(1), dsys%tie_down, 3, dsys%sep%joint%geo, &
      dsys%sep%joint%opt, dsys%sep%t0, error, aircraft_prescribed=dsys%sep%aircraft_prescribed)
    if (allocated(error)) return
    sep%edge_bilateral = dsys%sep%edge_bilateral
    sep%quat_gain = dsys%sep%quat_gain
    sep%ground_altitude = dsys%sep%ground_altitude
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
  end subroutine build_chain

  !> The first engine at t = 0 from the set-up state y0.
  subroutine start_engine(r, y0, error)
    type(coupled_run), intent(inout) :: r
    real(dp), intent(in) :: y0(:)
    type(error_type), allocatable, intent(inout) :: error
    integer :: status
    if (r%active == coupling_direct) then
      call r%dsolver%init(r%dsys, 0.0_dp, y0, r%dopts, error)
      r%dsolver_started = .true.
      if (.not. allocated(error)) call stop_at_next_kink(r, 0.0_dp, error)
      return
    end if
    call r%dsys%prepare(0.0_dp, y0, status)
    call r%cpl%init(r%chain, 2, 3, r%dsys%line, r%dsys%chute, r%dsys%x, r%dsys%v, r%dsys%v_ref, r%dsys%h_ref, &
      0.0_dp, phase_preparation, r%ropt, error)
    r%cpl%chain%clr = r%dsys%clr
    if (allocated(error)) error%message = phase_name(phase_preparation) // ", t = 0 s: " // error%message
  end subroutine start_engine

  ! ------------------------------------------------------------ direct engine

  !> CVODE settings of the direct coupling (the whole system in one solver).
  subroutine set_direct_options(run, n_state, has_line, opts)
    type(run_config), intent(in) :: run
    integer, intent(in) :: n_state
    logical, intent(in) :: has_line
    type(cvode_options), intent(out) :: opts
    opts%rtol = run%rtol
    opts%atol = run%atol
    opts%max_total_steps = run%max_steps
    opts%max_wall_time = run%max_wall_time
    opts%t_final = run%t_end   ! the steps do not depend on the output times
    ! Newton's band system with the positions (bodies' and nodes', x' = v)
    ! eliminated: 65 of the paper scenario's 116 unknowns, and LAPACK's partial
    ! pivoting no longer swaps the line's rows (airlaunch_lapack_band;
    ! docs/performance.md, "The position-reduced Newton solve")
    opts%linear_solver = "position_reduced_band"
    ! The band holds the stiff couplings: the line's node chain and node 1 with
    ! the rocket's position and attitude (offsets up to 18).  The aircraft-rocket
    ! coupling through the CFA (offsets to 25) and aircraft-node 1 (31) are soft
    ! and left out of the Newton matrix (a modified Newton iteration): measured
    ! 27 % faster than the full band with the same milestones (docs/performance.md).
    opts%upper_bandwidth = 18
    opts%lower_bandwidth = 18
    allocate(opts%atol_vector(n_state))
    opts%atol_vector(:) = atol_scaling(run%atol, n_state)
    ! BDF orders above 2 are not A-stable: on the line's lightly damped axial
    ! modes they force many more steps (measured on input/airlaunch_paper.nml:
    ! 678 steps at order 2, 12 140 at 3, 8 132 at 4, 7 760 at 5, every milestone
    ! within 6e-4 of the converged reference), so the scene default is order 2
    ! (&run max_order = 0).
    opts%max_order = run%max_order
    if (opts%max_order == 0) opts%max_order = 2
    if (.not. has_line) call rigid_only_options(run, opts)
  end subroutine set_direct_options

  !> Solver settings of a scene without a line (26 rigid states): a dense
  !> Newton matrix (the band of the line is gone; 26 x 26 costs nothing), and
  !> BDF up to order 5 unless &run max_order says otherwise (the order-2
  !> default exists for the line's lightly damped axial modes).
  subroutine rigid_only_options(run, opts)
    type(run_config), intent(in) :: run
    type(cvode_options), intent(inout) :: opts
    ! a full band: the scene's own difference quotients (launch_jacobian), whose
    ! increments stay above the rounding of V0 + v (CVODE's dense ones did not)
    opts%linear_solver = "band"
    opts%upper_bandwidth = rigid_size - 1
    opts%lower_bandwidth = rigid_size - 1
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

  !> The direct coupling from the next output time on, until the run ends or
  !> the plan switches (`switch`: the state at the solver's time is handed over).
  subroutine direct_segment(r, run, cfg, res, switch, err)
    type(coupled_run), intent(inout) :: r
    type(run_config), intent(in) :: run
    type(scenario_config), intent(in) :: cfg
    type(launch_result), intent(inout) :: res
    logical, intent(out) :: switch
    type(error_type), allocatable, intent(inout) :: err
    real(dp) :: tout, t_stop
    switch = .false.
    do while (r%iout <= r%nout)
      tout = r%t_out(r%iout)
      t_stop = tout
      if (r%plan%mode == "auto") t_stop = min(tout, r%next_check)
      call direct_advance(r, t_stop, res, switch, err)
      if (allocated(err)) return
      if (r%dsys%sep%landed()) then
        call record_landing(r, run, cfg, res, r%dsolver%t, err)
        return
      end if
      call direct_output(r, run, cfg, res, err)
      if (r%done) return
      if (switch) return
      if (r%plan%mode == "auto" .and. r%dsolver%t >= r%next_check) then
        call auto_check(r, r%dsolver%t, switch)
        if (switch) then
          call direct_to_seen_end(r, run, cfg, res, err)
          return
        end if
      end if
    end do
    r%done = .true.
  end subroutine direct_segment

  !> An automatic switch decided at a check time inside the direct solver's
  !> last step: the safety maxima have already seen that step to its end
  !> (dsolver%t_seen), so the run keeps the direct solution that far - its
  !> records and events on the way, no new step - and hands over there.
  subroutine direct_to_seen_end(r, run, cfg, res, err)
    type(coupled_run), intent(inout) :: r
    type(run_config), intent(in) :: run
    type(scenario_config), intent(in) :: cfg
    type(launch_result), intent(inout) :: res
    type(error_type), allocatable, intent(inout) :: err
    real(dp) :: tout
    logical :: leave
    do while (r%dsolver%t < r%dsolver%t_seen)
      tout = r%dsolver%t_seen
      if (r%iout <= r%nout) tout = min(tout, r%t_out(r%iout))
      leave = .false.
      call direct_advance(r, tout, res, leave, err)
      if (allocated(err)) return
      if (r%dsys%sep%landed()) then
        call record_landing(r, run, cfg, res, r%dsolver%t, err)
        return
      end if
      call direct_output(r, run, cfg, res, err)
      if (r%done) return
    end do
    call set_next_check(r, r%dsolver%t)
  end subroutine direct_to_seen_end

  !> Record the direct engine if it has reached the next output time; the run
  !> is done (r%done) after the record at t_end or once its metrics are final.
  subroutine direct_output(r, run, cfg, res, err)
    type(coupled_run), intent(inout) :: r
    type(run_config), intent(in) :: run
    type(scenario_config), intent(in) :: cfg
    type(launch_result), intent(inout) :: res
    type(error_type), allocatable, intent(inout) :: err
    real(dp) :: tout
    if (r%iout > r%nout) return
    tout = r%t_out(r%iout)
    if (r%dsolver%t < tout) return
    call record_now(r, run, cfg, res, err)
    r%iout = r%iout + 1
    if (tout >= run%t_end .or. stop_now(r, run, res, r%dsys%sep%phase, r%dsolver%t)) r%done = .true.
  end subroutine direct_output

  !> Integrate the direct system to t_target, handling the events on the way;
  !> stops early (`switch`) at a phase change the plan gives to the other coupling.
  subroutine direct_advance(r, t_target, res, switch, err)
    type(coupled_run), intent(inout) :: r
    real(dp), intent(in) :: t_target
    type(launch_result), intent(inout) :: res
    logical, intent(inout) :: switch
    type(error_type), allocatable, intent(inout) :: err
    logical :: event, changed
    integer :: which(launch_nroots), guard, status
    logical :: lower
    real(dp), allocatable :: y(:)
    do guard = 1, 100
      call r%dsolver%advance(t_target, err, event, which, r%dobs)
      if (allocated(err)) then
        err%message = phase_name(r%dsys%sep%phase) // ": " // err%message
        return
      end if
      if (break_is_due(r%dsys, r%dsolver%t)) then
        ! the scheduled cut (the solver stopped at break_time: stop_at_next_kink)
        call part_line(r, r%dsys%break_segment, res, err)
        if (allocated(err)) return
        if (.not. event) then
          if (r%dsolver%t >= t_target) return
          cycle
        end if
      end if
      if (.not. event) then
        if (r%dsolver%t >= t_target) return
        ! stopped at a scheduled kink (stop_at_next_kink): restart there, so that
        ! no BDF step carries history across it, and stop at the next one
        y = r%dsolver%y
        call r%dsolver%reinit(r%dsolver%t, y, err)
        if (.not. allocated(err)) call stop_at_next_kink(r, r%dsolver%t, err)
        if (allocated(err)) return
        cycle
      end if
      if (which(launch_break_root) /= 0) then
        ! a segment's tension reached its strength: it parts
        call part_line(r, 0, res, err)
        if (allocated(err)) return
      end if
      if (which(launch_gust_root) /= 0) then
        ! every point of the scene is past the gust: its step cap goes
        call lift_gust_cap(r, err)
        if (allocated(err)) return
      end if
      if (all(which(:launch_gust_root - 1) == 0)) then
        ! the line's break or the gust's passing alone: the phases are as they were
        if (r%dsolver%t >= t_target) return
        cycle
      end if
      call r%dsys%prepare(r%dsolver%t, r%dsolver%y, status)
      call handle_launch_event(res, r%dsolver%t, r%dsys%sep, r%dsys%yabs(1:rigid_size), &
        which(1:separation_nroots), which(launch_pitch_root), r%dsys%find_pitch_max, which(launch_clearance_root), &
        r%dsys%clr, changed, lower, err)
      if (allocated(err)) return
      if (lower) r%last_record_of_extremum = r%dsolver%t
      if (r%dsys%sep%landed()) return   ! a body reached the ground: the run ends there
      if (changed) then
        if (leaves_at_phase(r, coupling_direct, r%dsys%sep%phase)) then
          switch = .true.
          return
        end if
        ! the constraint set changed: restart CVODE from the event (the
        ! solver keeps its counters' totals over the restart)
        y = r%dsolver%y
        call r%dsolver%reinit(r%dsolver%t, y, err)
        if (.not. allocated(err)) call stop_at_next_kink(r, r%dsolver%t, err)
        if (allocated(err)) return
      end if
      if (r%dsolver%t >= t_target) return
    end do
    call fatal_error(err, phase_name(r%dsys%sep%phase) // ", t = " // str(r%dsolver%t) // &
      " s: too many events before the output time")
  end subroutine direct_advance

  !> The scheduled cut of the line (&line break_time) is due at time t: it
  !> has not been made, and its time has come.
  logical function break_is_due(sys, t)
    type(launch_system), intent(in) :: sys
    real(dp), intent(in) :: t
    break_is_due = sys%break_time > 0.0_dp .and. t >= sys%break_time
  end function break_is_due

  !> The line parts at the direct solver's time: at segment k (the scheduled
  !> cut), or, for k = 0 (a breaking-strength event), at the segment of the
  !> smallest margin to its strength and at any other that has reached its
  !> strength with it (line_model%part_reached).
  !> From now on those segments carry nothing (line_model%part), and CVODE
  !> restarts there, its right-hand side having jumped.
  subroutine part_line(r, k, res, err)
    type(coupled_run), intent(inout) :: r
    integer, intent(in) :: k
    type(launch_result), intent(inout) :: res
    type(error_type), allocatable, intent(inout) :: err
    real(dp), allocatable :: y(:)
    integer :: status, j, first
    allocate(y, source=r%dsolver%y)
    associate(s => r%dsys)
      if (k > 0) then
        first = k
        call s%line%part(k)
        s%break_time = -1.0_dp   ! done
      else
        call s%load_bodies(r%dsolver%t, y)
        call s%line_tensions(r%dsolver%t, status)
        if (status /= 0) then   ! rhs_fatal: a tension not finite
          call fatal_error(err, phase_name(s%sep%phase) // ": " // s%failure)
          return
        end if
        call s%line%part_reached(s%strength, s%tension, first)
      end if
      ! a break is a change of the scene: stop_when_final watches 1 s past it
      r%last_record_of_extremum = max(r%last_record_of_extremum, r%dsolver%t)
      if (res%line_breaks == 0) then
        res%line_break_time = r%dsolver%t
        res%line_break_segment = first
      end if
      res%line_breaks = s%line%n_parted
      res%parted_segments = pack([(j, j = 1, s%line%n)], s%line%parted)
    end associate
    call r%dsolver%reinit(r%dsolver%t, y, err)
    if (.not. allocated(err)) call stop_at_next_kink(r, r%dsolver%t, err)
  end subroutine part_line

  !> The gust has passed every point of the direct system (event
  !> launch_gust_root, or found at a resumption): no more watching, and
  !> CVODE's step is free again.  Its passing is a change of the scene, like
  !> a break: stop_when_final watches 1 s past it.
  subroutine lift_gust_cap(r, err)
    type(coupled_run), intent(inout) :: r
    type(error_type), allocatable, intent(inout) :: err
    r%dsys%gust_watch = .false.
    r%last_record_of_extremum = max(r%last_record_of_extremum, r%dsolver%t)
    r%dopts%max_step = 0.0_dp
    call r%dsolver%set_max_step(0.0_dp, err)
  end subroutine lift_gust_cap

  !> The direct coupling resumes at time t: the aircraft and the rocket from
  !> `machine` (bodies loaded, absolute), its phase machine, the line nodes
  !> x, v (0:N, absolute) and the pitch-maximum search.
  subroutine direct_resume(r, t, machine, x, v, find_pitch_max, err)
    type(coupled_run), intent(inout) :: r
    real(dp), intent(in) :: t
    type(separation_system), intent(in) :: machine
    real(dp), intent(in) :: x(:, 0:), v(:, 0:)
    logical, intent(in) :: find_pitch_max
    type(error_type), allocatable, intent(inout) :: err
    real(dp), allocatable :: y(:)
    integer :: i, k, n, status
    n = r%dsys%line%n
    allocate(y(rigid_size + 6*n))
    associate(s => r%dsys)
      s%sep%bodies(0) = machine%bodies(0)
      s%sep%bodies(1) = machine%bodies(1)
      call s%sep%pack_state(y(1:rigid_size))
      do i = 0, 1
        y(13*i+1:13*i+3) = y(13*i+1:13*i+3) - [s%v_ref*t, s%h_ref, 0.0_dp]
        y(13*i+4) = y(13*i+4) - s%v_ref
      end do
      do k = 1, n
        i = rigid_size + 6*(k - 1)
        y(i+1:i+3) = x(:, k) - [s%v_ref*t, s%h_ref, 0.0_dp]
        y(i+4:i+6) = v(:, k) - [s%v_ref, 0.0_dp, 0.0_dp]
      end do
      call continue_phase_machine(s%sep, machine)
      s%find_pitch_max = find_pitch_max
      call s%prepare(t, y, status)
      call s%sep%evaluate(t, s%yabs(1:rigid_size), err)
      if (allocated(err)) return
    end associate
    if (r%dsolver_started) then
      call r%dsolver%reinit(t, y, err)
    else
      call r%dsolver%init(r%dsys, t, y, r%dopts, err)
      r%dsolver_started = .true.
    end if
    ! the gust passed while the rigidized coupling ran
    if (.not. allocated(err) .and. r%dsys%gust_watch) then
      if (r%dsys%gust_clearance() > 0.0_dp) call lift_gust_cap(r, err)
    end if
    if (.not. allocated(err)) call stop_at_next_kink(r, t, err)
  end subroutine direct_resume

  !> The direct solver stops at the next time after t at which its right-hand
  !> side jumps or kinks on a schedule: the release t0 in Case 0 (the event is
  !> then at t0 itself, not at CVODE's root estimate a rounding after it,
  !> whatever the output times), the canopy's deployment and the end of its
  !> filling (the apparent mass's momentum force starts and stops there).
  subroutine stop_at_next_kink(r, t, err)
    type(coupled_run), intent(inout) :: r
    real(dp), intent(in) :: t
    type(error_type), allocatable, intent(inout) :: err
    real(dp) :: next
    next = huge(1.0_dp)
    if (r%dsys%sep%phase == phase_preparation .and. r%dsys%sep%t0 > t) next = r%dsys%sep%t0
    if (r%dsys%has_line) then
      associate(c => r%dsys%chute)
        if (c%deploy_time > t) next = min(next, c%deploy_time)
        if (c%deploy_time >= 0.0_dp .and. c%fill_time > 0.0_dp .and. c%deploy_time + c%fill_time > t) &
          next = min(next, c%deploy_time + c%fill_time)
      end associate
      if (r%dsys%break_time > t) next = min(next, r%dsys%break_time)
    end if
    if (next < huge(1.0_dp)) call r%dsolver%set_stop_time(next, err)
  end subroutine stop_at_next_kink

  ! ------------------------------------------------------------ rigidized engine

  !> Outer steps of the rigidized coupling (§2.4 Steps 3-6) until the run ends
  !> or the plan switches; the outputs are recorded from inside the steps.
  subroutine rigidized_segment(r, run, cfg, res, switch, err)
    type(coupled_run), intent(inout) :: r
    type(run_config), intent(in) :: run
    type(scenario_config), intent(in) :: cfg
    type(launch_result), intent(inout) :: res
    logical, intent(out) :: switch
    type(error_type), allocatable, intent(inout) :: err
    logical :: event, leave
    integer :: which(rigidized_nroots), n_events, j
    real(dp) :: t_target, eps, t_last, h
    switch = .false.
    h = r%ropt%outer_dt
    eps = 1.0e-12_dp*max(1.0_dp, run%t_end)
    n_events = 0
    t_last = r%cpl%t
    do while (run%t_end - r%cpl%t > eps)
      ! outer steps end on the grid k*h (an event's short step realigns the next)
      t_target = min(next_grid_time(r%cpl%t, h), run%t_end)
      if (run%t_end - t_target < 1.0e-6_dp*h) t_target = run%t_end
      ! (the steps end on the grid, not on output times a rounding away from it:
      ! an output that close is recorded at the step's end; the steps then do not
      ! depend on the output times)
      r%cobs%chain => r%cpl%chain
      r%lobs%line => r%cpl%line
      call r%cpl%begin_step(t_target, event, which, err, r%t_out(r%iout:r%nout), r%cobs)
      do j = 1, r%cpl%n_saved
        if (allocated(err)) exit
        call r%cpl%line_to(r%cpl%saved_t(j), err, r%lobs)
        if (.not. allocated(err)) call rigidized_record(r, run, cfg, res, r%cpl%saved_t(j), r%cpl%saved_y(:, j), err)
      end do
      if (.not. allocated(err)) call r%cpl%end_step(err, r%lobs)
      if (allocated(err)) then
        if (index(err%message, "phase ") /= 1) err%message = phase_name(r%cpl%chain%sep%phase) // ": " // err%message
        return
      end if
      leave = .false.
      if (event) then
        ! several events within one output interval are allowed, not a cascade
        if (r%cpl%t - t_last > run%output_dt) n_events = 0
        t_last = r%cpl%t
        n_events = n_events + 1
        if (n_events > 100) then
          call fatal_error(err, phase_name(r%cpl%chain%sep%phase) // ", t = " // str(r%cpl%t) // &
            " s: too many events before the output time")
          return
        end if
        call rigidized_event(r, run, cfg, res, which, leave, err)
        if (allocated(err)) return
        if (r%cpl%chain%sep%landed()) then
          call record_landing(r, run, cfg, res, r%cpl%t, err)
          return
        end if
      end if
      call skip_recorded(r, run)
      if (stop_now(r, run, res, r%cpl%chain%sep%phase, r%cpl%t)) exit
      switch = leave
      if (r%plan%mode == "auto" .and. r%cpl%t >= r%next_check - 1.0e-6_dp*h) call auto_check(r, r%cpl%t, switch)
      if (switch) return
    end do
    r%done = .true.
  end subroutine rigidized_segment

  !> An event of the chain at the coupling's time (CVODE root info `which`):
  !> milestones and phase change; `leave` if the plan gives the new phase to
  !> the direct coupling, else the chain restarts there; an output time that
  !> coincides with the event is recorded.
  subroutine rigidized_event(r, run, cfg, res, which, leave, err)
    type(coupled_run), intent(inout) :: r
    type(run_config), intent(in) :: run
    type(scenario_config), intent(in) :: cfg
    type(launch_result), intent(inout) :: res
    integer, intent(in) :: which(:)
    logical, intent(out) :: leave
    type(error_type), allocatable, intent(inout) :: err
    logical :: changed, lower
    leave = .false.
    associate(c => r%cpl%chain)
      call c%prepare(r%cpl%t, r%cpl%chain_solver%y)
      call handle_launch_event(res, r%cpl%t, c%sep, c%yabs, which(1:separation_nroots), &
        which(rigidized_pitch_root), c%find_pitch_max, which(rigidized_clearance_root), c%clr, changed, lower, err)
      if (allocated(err)) return
      if (lower) r%last_record_of_extremum = r%cpl%t
    end associate
    leave = changed .and. leaves_at_phase(r, coupling_rigidized, r%cpl%chain%sep%phase)
    ! every event restarts the chain at its time (the outer step ended there)
    if (.not. leave) call r%cpl%restart_chain(err)
    if (allocated(err)) return
    ! the output times before the event were recorded inside the outer step
    ! (with output_dt < outer_dt, several): the event's own is after them
    do while (r%iout <= r%nout)
      if (r%t_out(r%iout) >= r%cpl%t - 1.0e-12_dp*max(1.0_dp, run%t_end)) exit
      r%iout = r%iout + 1
    end do
    if (r%iout > r%nout) return
    if (abs(r%t_out(r%iout) - r%cpl%t) <= 1.0e-12_dp*max(1.0_dp, run%t_end)) &
      call rigidized_record(r, run, cfg, res, r%cpl%t, r%cpl%chain_solver%y, err)
  end subroutine rigidized_event

  !> A body reached the ground at time t (the active engine is there): the run
  !> ends with a record at t unless that output time was just recorded.
  subroutine record_landing(r, run, cfg, res, t, err)
    type(coupled_run), intent(inout) :: r
    type(run_config), intent(in) :: run
    type(scenario_config), intent(in) :: cfg
    type(launch_result), intent(inout) :: res
    real(dp), intent(in) :: t
    type(error_type), allocatable, intent(inout) :: err
    r%done = .true.
    if (r%hist%nrec > 0) then
      if (r%hist%time(r%hist%nrec) >= t) return
    end if
    call record_now(r, run, cfg, res, err)
  end subroutine record_landing

  !> The next output time is the first one after the rigidized coupling's time.
  subroutine skip_recorded(r, run)
    type(coupled_run), intent(inout) :: r
    type(run_config), intent(in) :: run
    do while (r%iout <= r%nout)
      if (r%t_out(r%iout) > r%cpl%t + 1.0e-12_dp*max(1.0_dp, run%t_end)) exit
      r%iout = r%iout + 1
    end do
  end subroutine skip_recorded

  !> The rigidized coupling (re)starts at time t from the direct system's
  !> state (bodies, nodes and phase machine loaded by its `prepare`).
  subroutine rigidized_resume(r, t, err)
    type(coupled_run), intent(inout) :: r
    real(dp), intent(in) :: t
    type(error_type), allocatable, intent(inout) :: err
    associate(s => r%dsys)
      r%chain%bodies(0) = s%sep%bodies(0)
      r%chain%bodies(1) = s%sep%bodies(1)
      call r%cpl%init(r%chain, 2, 3, s%line, s%chute, s%x, s%v, s%v_ref, s%h_ref, t, s%sep%phase, r%ropt, err, &
        machine=s%sep)
      if (allocated(err)) return
      r%cpl%chain%find_pitch_max = s%find_pitch_max
      r%cpl%chain%clr = s%clr
    end associate
  end subroutine rigidized_resume

  !> Add the rigidized coupling's counters of its present stint to the run's.
  subroutine add_rigidized_counts(r, res)
    type(coupled_run), intent(inout) :: r
    type(launch_result), intent(inout) :: res
    call add_stats(res%stats, r%cpl%stats())
    r%n_refresh = r%n_refresh + r%cpl%n_refresh
    r%n_guard_mass = r%n_guard_mass + r%cpl%n_guard_mass
    r%n_guard_inertia = r%n_guard_inertia + r%cpl%n_guard_inertia
  end subroutine add_rigidized_counts

  ! ------------------------------------------------------------ the choice

  !> The engine `from` hands over at the phase change into `phase` (per_phase).
  pure logical function leaves_at_phase(r, from, phase) result(leave)
    type(coupled_run), intent(in) :: r
    integer, intent(in) :: from, phase
    leave = r%plan%mode == "per_phase" .and. r%plan%for_phase(phase) /= from
  end function leaves_at_phase

  !> The automatic choice at time t from the active engine's line state and
  !> step rate; `switch` if it wants the other coupling.  Sets the next check time.
  subroutine auto_check(r, t, switch)
    type(coupled_run), intent(inout) :: r
    real(dp), intent(in) :: t
    logical, intent(inout) :: switch
    type(line_indicator) :: ind
    ind = current_indicator(r, t)
    ind%steps = steps_per_outer_step(r, r%chk_steps, r%chk_t, t)
    r%chk_steps = line_steps(r)
    r%chk_t = t
    call r%auto%decide(r%plan%auto, t, ind)
    switch = switch .or. r%auto%active /= r%active
    call set_next_check(r, t)
  end subroutine auto_check

  !> The next check of the indicator: the next time k*interval after t (checks
  !> keep to one grid, so with interval = output_dt every record is a check),
  !> on an output time if it falls within round-off of one (no slivers of a step).
  subroutine set_next_check(r, t)
    type(coupled_run), intent(inout) :: r
    real(dp), intent(in) :: t
    real(dp) :: tol
    integer :: j
    r%next_check = next_grid_time(t, r%plan%auto%interval)
    tol = 1.0e-6_dp*r%plan%auto%interval
    do j = r%iout, r%nout
      if (r%t_out(j) > r%next_check + tol) exit
      if (abs(r%t_out(j) - r%next_check) <= tol) r%next_check = r%t_out(j)
    end do
  end subroutine set_next_check

  !> Steps taken so far by the integrator that carries the line: the direct
  !> coupling's (over its restarts) or the rigidized coupling's line sub-steps.
  function line_steps(r) result(n)
    type(coupled_run), intent(in) :: r
    real(dp) :: n
    if (r%active == coupling_direct) then
      n = real(r%dsolver%steps_taken(), dp)
    else
      n = real(r%cpl%line_steps(), dp)
    end if
  end function line_steps

  !> Steps per outer step of the line-carrying integrator since (n0, t0).
  function steps_per_outer_step(r, n0, t0, t) result(rate)
    type(coupled_run), intent(in) :: r
    real(dp), intent(in) :: n0, t0, t
    real(dp) :: rate
    real(dp) :: outer
    rate = 0.0_dp
    if (t <= t0) return
    ! over a whole number of outer steps (within round-off) the rate is exact:
    ! a check and a record of the same interval then agree (not 4 - 1e-15
    ! against 4 + 1e-15 on either side of a threshold)
    outer = (t - t0)/r%plan%auto%interval
    if (anint(outer) >= 1.0_dp .and. abs(outer - anint(outer)) <= 1.0e-6_dp*outer) outer = anint(outer)
    rate = (line_steps(r) - n0)/outer
  end function steps_per_outer_step

  !> The first time k*h (k integer) after t >= 0, more than 1e-6 h after it
  !> (real arithmetic: t/h may exceed the default integer range).
  pure function next_grid_time(t, h) result(tn)
    real(dp), intent(in) :: t   !< time [s], >= 0
    real(dp), intent(in) :: h   !< grid step [s]
    real(dp) :: tn
    tn = (aint(t/h) + 1.0_dp)*h
    if (tn - t <= 1.0e-6_dp*h) tn = tn + h
  end function next_grid_time

  !> The indicator of the active engine's line at its present time t.
  function current_indicator(r, t) result(ind)
    type(coupled_run), intent(inout) :: r
    real(dp), intent(in) :: t
    type(line_indicator) :: ind
    integer :: status
    if (r%active == coupling_direct) then
      call r%dsys%prepare(t, r%dsolver%y, status)
      ind = line_indicator_of(r%dsys%x, r%dsys%v, r%dsys%line%l0, r%plan%auto)
    else
      call r%cpl%line_state(r%xl, r%vl, r%ten)
      ind = line_indicator_of(r%xl, r%vl, r%dsys%line%l0, r%plan%auto)
    end if
  end function current_indicator

  !> Hand the state over to the other engine at the active one's time.
  subroutine hand_over(r, res, err)
    type(coupled_run), intent(inout) :: r
    type(launch_result), intent(inout) :: res
    type(error_type), allocatable, intent(inout) :: err
    real(dp) :: t
    integer :: status, from
    from = r%active
    call finish_observers(r)   ! the maxima so far, on the outgoing engine's steps
    if (from == coupling_direct) then
      t = r%dsolver%t
      ! the direct solver's counters go into the result once, at the end
      ! (finish_result): it keeps them over its restarts and stints
      call r%dsys%prepare(t, r%dsolver%y, status)
      call rigidized_resume(r, t, err)
      r%active = coupling_rigidized
    else
      t = r%cpl%t
      call add_rigidized_counts(r, res)
      call r%cpl%chain%prepare(t, r%cpl%chain_solver%y)
      call r%cpl%line_state(r%xl, r%vl, r%ten)
      call direct_resume(r, t, r%cpl%chain%sep, r%xl, r%vl, r%cpl%chain%find_pitch_max, err)
      call r%cpl%free()
      r%active = coupling_direct
    end if
    if (allocated(err)) then
      err%message = phase_name(r%dsys%sep%phase) // ", t = " // str(t) // " s: switching from the " // &
        coupling_name(from) // " to the " // coupling_name(1 - from) // " coupling: " // err%message
      return
    end if
    r%auto%active = r%active
    call set_next_check(r, t)
    r%chk_steps = line_steps(r)
    r%chk_t = t
    r%rec_steps = r%chk_steps
    r%rec_t = t
    r%switches = r%switches + 1
    if (.not. allocated(r%switch_log)) r%switch_log = ""
    if (r%switches > 1) r%switch_log = r%switch_log // "; "
    r%switch_log = r%switch_log // str(t) // " s: " // coupling_name(from) // " -> " // coupling_name(r%active)
  end subroutine hand_over

  !> &run stop_when_final: the milestones cannot change any more (the rocket
  !> is free, its first pitch maximum found, and 1 s has passed since both,
  !> during which no extremum moved: the clearance and line-clearance minima,
  !> the aircraft excursions, the peak tension).  A later snatch of the line is not
  !> waited for, but a line that can still part (a scheduled cut to come, or
  !> an intact segment with a strength: launch_system%may_still_part) keeps
  !> the run going, so that its break is recorded, and a break counts as a
  !> change (part_line): the run goes on for 1 s after it.  So does a &gust
  !> that some point of the scene has still to pass (launch_system%gust_watch,
  !> lifted by the direct coupling's event launch_gust_root): a gust met after
  !> the milestones looked final would otherwise never be flown into (a run
  !> that the rigidized coupling ends keeps watching: it runs to t_end).
  logical function stop_now(r, run, res, phase, t)
    type(coupled_run), intent(in) :: r
    type(run_config), intent(in) :: run
    type(launch_result), intent(in) :: res
    integer, intent(in) :: phase
    real(dp), intent(in) :: t
    stop_now = .false.
    if (.not. run%stop_when_final) return
    if (phase /= phase_free .or. res%pitch_max_time < 0.0_dp) return
    if (r%dsys%may_still_part()) return
    if (r%dsys%gust_watch) return
    if (t < max(res%pitch_max_time, res%separation_time) + 1.0_dp) return
    stop_now = t >= max(r%last_record_of_extremum, maxval(r%trk(1:n_final)%t_best)) + 1.0_dp
  end function stop_now

  ! ------------------------------------------------------------ records

  !> Sample the active engine at its present time.
  subroutine record_now(r, run, cfg, res, err)
    type(coupled_run), intent(inout) :: r
    type(run_config), intent(in) :: run
    type(scenario_config), intent(in) :: cfg
    type(launch_result), intent(inout) :: res
    type(error_type), allocatable, intent(inout) :: err
    if (r%active == coupling_direct) then
      call direct_record(r, run, cfg, res)
    else
      call rigidized_record(r, run, cfg, res, r%cpl%t, r%cpl%chain_solver%y, err)
    end if
  end subroutine record_now

  !> Sample the direct system at the solver's time (outputs and milestones).
  !> Without the trajectory output only what the record's milestones need is
  !> computed (the bodies and the joint: no loads, no line forces), the same
  !> values as the full record's, so that a sweep's row is the single run's.
  subroutine direct_record(r, run, cfg, res)
    type(coupled_run), intent(inout) :: r
    type(run_config), intent(in) :: run
    type(scenario_config), intent(in) :: cfg
    type(launch_result), intent(inout) :: res
    integer :: status
    real(dp) :: t
    type(error_type), allocatable :: eval_error
    type(launch_sample) :: smp
    t = r%dsolver%t
    associate(s => r%dsys, y => r%dsolver%y)
      res%max_quaternion_norm_error = max(res%max_quaternion_norm_error, abs(norm2(y(7:10)) - 1.0_dp), &
        abs(norm2(y(20:23)) - 1.0_dp))
      if (.not. run%trajectory) then
        call s%to_absolute(t, y)
        call s%sep%evaluate_joint(s%yabs(1:rigid_size))
        if (record_milestones(res, clearance(s%clr, s%sep%bodies(0), s%sep%bodies(1)), s%sep)) &
          r%last_record_of_extremum = t
        return
      end if
      call s%prepare(t, y, status)
      call s%sep%evaluate(t, s%yabs(1:rigid_size), eval_error)
      smp = sample_launch(cfg, s%sep, s%iloads)
      if (record_milestones(res, smp%clearance, s%sep)) r%last_record_of_extremum = t
      if (s%has_line) then
        call r%hist%append(t, smp, s%sep, s%x, s%tension, s%x(:, s%line%n))
      else
        call r%hist%append(t, smp, s%sep)
      end if
      if (r%extras) call record_extras(r, s%x, s%v, s%f(:, 0), 0.0_dp)
    end associate
  end subroutine direct_record

  !> Sample the rigidized coupling at time t (outputs and milestones): the
  !> chain's state y (relative frame), the line's from its sub-stepping solver
  !> at t (without the trajectory output: the milestones' part alone, as
  !> direct_record).
  subroutine rigidized_record(r, run, cfg, res, t, y, err)
    type(coupled_run), intent(inout) :: r
    type(run_config), intent(in) :: run
    type(scenario_config), intent(in) :: cfg
    type(launch_result), intent(inout) :: res
    real(dp), intent(in) :: t, y(:)
    type(error_type), allocatable, intent(inout) :: err
    real(dp) :: frig(3), axis(3), mm
    integer :: j, o
    type(error_type), allocatable :: eval_error
    type(launch_sample) :: smp
    if (allocated(err)) return
    do j = 0, 3   ! aircraft, rocket, line body, parachute
      o = merge(7 + 13*j, 27 + 7*(j - 2), j < 2)
      res%max_quaternion_norm_error = max(res%max_quaternion_norm_error, abs(norm2(y(o:o+3)) - 1.0_dp))
    end do
    associate(c => r%cpl%chain, sp => r%cpl%chain%sep, b1 => r%cpl%chain%sep%bodies(1), &
        b3 => r%cpl%chain%sep%bodies(3))
      call c%prepare(t, y)
      if (.not. run%trajectory) then
        call sp%evaluate_joint(c%yabs)
        if (record_milestones(res, clearance(c%clr, sp%bodies(0), b1), sp)) r%last_record_of_extremum = t
        return
      end if
      call r%cpl%line_state(r%xl, r%vl, r%ten)
      call sp%evaluate(t, c%yabs, eval_error)
      smp = sample_launch(cfg, sp, 2)
      if (record_milestones(res, smp%clearance, sp)) r%last_record_of_extremum = t
      ! the rigidized model's own quantities
      frig = c%line_force()
      axis = b3%r - b1%point_position(sp%tie_down)
      r%min_rigid_tension = min(r%min_rigid_tension, dot_product(frig, axis)/norm2(axis))
      mm = norm2(r%xl(:, r%dsys%line%n) - b3%r)
      r%max_mismatch = max(r%max_mismatch, mm)
      call r%hist%append(t, smp, sp, r%xl, r%ten, b3%r)
      call record_extras(r, r%xl, r%vl, frig, mm)
    end associate
  end subroutine rigidized_record

  !> The coupling's own variables of the last history record: the virtual
  !> line body of the line state x, v, the line's force on the rocket, the
  !> node N - B3 distance and (mixed plans) the active coupling and the indicator.
  subroutine record_extras(r, x, v, force, mismatch)
    type(coupled_run), intent(inout) :: r
    real(dp), intent(in) :: x(:, 0:), v(:, 0:), force(3), mismatch
    type(virtual_line) :: vb
    type(line_indicator) :: ind
    integer :: k
    k = r%hist%nrec
    vb = virtual_line_body(r%dsys%line, x, v, r%ropt%guard_band)
    r%m_rig(k) = vb%mass
    r%j_rig(k) = vb%inertia
    r%d_rig(k) = vb%length
    r%f_rig(:, k) = force
    r%mismatch(k) = mismatch
    ind = line_indicator_of(x, v, r%dsys%line%l0, r%plan%auto)
    r%active_rec(k) = r%active
    r%strain_rec(k) = ind%min_strain
    r%change_rec(k) = ind%strain_change
    r%steps_rec(k) = steps_per_outer_step(r, r%rec_steps, r%rec_t, r%hist%time(k))
    r%rec_steps = line_steps(r)
    r%rec_t = r%hist%time(k)
  end subroutine record_extras

  ! ------------------------------------------------------------ the safety maxima

  !> The run's trackers and the observers of its three integrators; values
  !> within `band` (relative: the run's rtol) of a maximum are the same peak,
  !> whose time is the first of them.
  subroutine init_observers(r, res, band)
    type(coupled_run), intent(inout) :: r
    type(launch_result), intent(in) :: res
    real(dp), intent(in) :: band
    allocate(r%trk(m_exit_gap))
    r%trk%band = band
    r%dobs%source = src_direct
    r%dobs%dsys => r%dsys
    r%cobs%source = src_chain
    r%lobs%source = src_line
    r%dobs%trk => r%trk
    r%cobs%trk => r%trk
    r%lobs%trk => r%trk
    r%dobs%trim_deg = res%trim_alpha_deg
    r%cobs%trim_deg = res%trim_alpha_deg
    ! the trimmed level flight (no acceleration, pitch = alpha) loads the body's
    ! y axis with g cos(alpha): the excursion is from that, not from 1 g
    r%dobs%trim_load_factor = cos(res%trim_alpha_deg*deg2rad)
    r%cobs%trim_load_factor = r%dobs%trim_load_factor
    r%dobs%estimated(m_load) = .true.
    r%cobs%estimated(m_load) = .true.
  end subroutine init_observers

  !> Close the open sequences of the active engine's observers (refining a
  !> maximum at their end): before a switch and at the end of the run.
  subroutine finish_observers(r)
    type(coupled_run), intent(inout) :: r
    if (.not. associated(r%trk)) return
    if (r%active == coupling_direct) then
      call r%dobs%finish()
    else
      if (associated(r%cpl%chain)) call r%cobs%finish()
      if (associated(r%cpl%line)) call r%lobs%finish()
    end if
  end subroutine finish_observers

  !> The maxima into the milestones: the trackers' (every step, refined
  !> between steps; the output records do not take them, so that they are the
  !> same with and without the trajectory).  The peak tension's time is the first time the steps'
  !> tension came within the band (rtol) of it: on a plateau (the steady tow
  !> before release) the place of the largest value is round-off and
  !> integrator noise.
  subroutine take_maxima(r, res)
    type(coupled_run), intent(inout) :: r
    type(launch_result), intent(inout) :: res
    if (.not. associated(r%trk)) return
    call finish_observers(r)
    if (res%has_line) then
      associate (trk => r%trk(m_tension))
        ! (max with 0: a run that failed before its first sample)
        res%peak_tension = max(trk%best, 0.0_dp)
        if (trk%t_best >= 0.0_dp) res%peak_tension_time = trk%first_time(res%peak_tension)
      end associate
    end if
    res%max_aircraft_pitch_excursion_deg = max(r%trk(m_pitch)%best, 0.0_dp)
    res%max_load_factor_excursion = max(r%trk(m_load)%best, 0.0_dp)
    ! the direct coupling's steps and the rigidized coupling's line sub-steps
    ! (with the chain's empennage point) both offer the line's clearance
    if (res%has_line .and. r%trk(m_line_gap)%t_best >= 0.0_dp) &
      res%min_line_clearance = min(res%min_line_clearance, -r%trk(m_line_gap)%best)
    ! the rocket's clearance over the whole exit: every step from the release on
    if (r%trk(m_exit_gap)%t_best >= 0.0_dp) then
      res%min_exit_clearance = -r%trk(m_exit_gap)%best
      res%min_exit_clearance_time = r%trk(m_exit_gap)%t_best
    end if
  end subroutine take_maxima

  !> Whether the observer's integrator carries metric m (the rocket's
  !> clearance from the release on: the phase is constant over a sequence of
  !> steps, which ends at each event).
  logical function watches(self, m)
    class(metric_observer), intent(in) :: self
    integer, intent(in) :: m
    select case (self%source)
    case (src_direct)
      if (m == m_exit_gap) then
        watches = self%dsys%sep%phase /= phase_preparation
      else
        watches = (m /= m_tension .and. m /= m_line_gap) .or. self%dsys%has_line
      end if
    case (src_chain)
      watches = m == m_pitch .or. m == m_load .or. &
        (m == m_exit_gap .and. self%chain%sep%phase /= phase_preparation)
    case default
      ! (the line's sub-steps: its tension, and its clearance from the empennage
      ! point interpolated between the chain's samples like the tie-down's)
      watches = m == m_tension .or. m == m_line_gap
    end select
  end function watches

  !> The metrics at time t from the interpolated state self%y (self%only > 0:
  !> that one is enough; the others are then -huge): the same functions of the
  !> state as the records'.  A step-end sample takes the load factor (an
  !> `estimated` quantity) from the interpolant's derivative instead of the
  !> forces (the aircraft's acceleration: the rate of its velocity states 4:6
  !> in both integrators; a sample that only brackets its maxima, at a
  !> fraction of an evaluation of the forces).
  subroutine metric_values(self, t, q, ok)
    class(metric_observer), intent(inout) :: self
    real(dp), intent(in) :: t
    real(dp), intent(out) :: q(:)
    logical, intent(out) :: ok
    type(error_type), allocatable :: eval_error
    integer :: status, only
    logical :: estimate
    only = self%only
    estimate = self%step_end_sample
    ok = .true.
    select case (self%source)
    case (src_direct)
      associate(s => self%dsys)
        if (only == m_exit_gap) then
          call s%load_bodies(t, self%y)
          q(m_exit_gap) = -clearance(s%clr, s%sep%bodies(0), s%sep%bodies(1))
          return
        else if (only == m_pitch) then
          call s%load_bodies(t, self%y)
        else
          call s%prepare(t, self%y, status)
          ok = status == 0
          if (.not. ok) return
          q(m_exit_gap) = -clearance(s%clr, s%sep%bodies(0), s%sep%bodies(1))
          if (s%has_line) then
            q(m_tension) = maxval(s%tension)
            q(m_line_gap) = -s%line_clearance()
          end if
          if (only == m_tension .or. only == m_line_gap) return
          if (.not. estimate) call s%sep%evaluate(t, s%yabs(1:rigid_size), eval_error)
          ok = .not. allocated(eval_error)
          if (.not. ok) return
        end if
        call aircraft_metrics(s%sep, self%trim_deg, self%trim_load_factor, only, q, estimate, self%dy(4:6))
      end associate
    case (src_chain)
      associate(c => self%chain)
        call c%prepare(t, self%y)
        q(m_exit_gap) = -clearance(c%clr, c%sep%bodies(0), c%sep%bodies(1))
        if (only == m_exit_gap) return
        if (only /= m_pitch .and. .not. estimate) then
          call c%sep%evaluate(t, c%yabs, eval_error)
          ok = .not. allocated(eval_error)
          if (.not. ok) return
        end if
        call aircraft_metrics(c%sep, self%trim_deg, self%trim_load_factor, only, q, estimate, self%dy(4:6))
      end associate
    case default
      associate(l => self%line)
        call l%unpack(t, self%y)
        call l%model%tensions(l%x, l%v, l%tension, status)
        ok = status == 0
        if (.not. ok) return
        q(m_tension) = maxval(l%tension)
        q(m_line_gap) = -l%tail_clearance(t)
      end associate
    end select
  end subroutine metric_values

  !> The aircraft's pitch excursion |theta - theta_trim| [deg] and (unless
  !> only the pitch is asked for; needs sep%evaluate) its load factor
  !> excursion |n - n_trim| (n as sample_launch records it, n_trim =
  !> cos(theta_trim) that of the trimmed level flight).
  subroutine aircraft_metrics(sep, trim_deg, trim_load_factor, only, q, estimate, a0)
    type(separation_system), intent(in) :: sep
    real(dp), intent(in) :: trim_deg
    real(dp), intent(in) :: trim_load_factor
    integer, intent(in) :: only
    real(dp), intent(inout) :: q(3)
    logical, intent(in) :: estimate   !< the acceleration a0 instead of sep%a0 (no evaluation)
    real(dp), intent(in) :: a0(3)
    real(dp) :: e(3), n
    associate(b0 => sep%bodies(0))
      e = dcm_to_euler(b0%c)
      q(m_pitch) = abs(e(2)*rad2deg - trim_deg)
      if (only == m_pitch) return
      if (estimate) then
        n = dot_product(b0%c(:, 2), a0 + [0.0_dp, g0, 0.0_dp])/g0
      else
        n = dot_product(b0%c(:, 2), sep%a0 + [0.0_dp, g0, 0.0_dp])/g0
      end if
      q(m_load) = abs(n - trim_load_factor)
    end associate
  end subroutine aircraft_metrics

  ! ------------------------------------------------------------ end of the run

  !> The event times, end time and counters of the engine the run ended in.
  subroutine finish_result(r, res)
    type(coupled_run), intent(inout) :: r
    type(launch_result), intent(inout) :: res
    ! the direct solver's totals over all its stints (it is initialised once)
    if (r%dsolver_started) call add_stats(res%stats, r%dsolver%stats())
    if (r%active == coupling_direct) then
      res%end_time = r%dsolver%t
      call events_of(r%dsys%sep)
    else
      call add_rigidized_counts(r, res)
      res%end_time = r%cpl%t
      call events_of(r%cpl%chain%sep)
    end if
  contains
    subroutine events_of(sep)
      type(separation_system), intent(in) :: sep
      res%release_time = event_or_minus(sep%event_time(1))
      res%edge_time = event_or_minus(sep%event_time(2))
      res%separation_time = event_or_minus(sep%event_time(3))
      res%early_separation = sep%early_separation
      res%edge_pull_time = event_or_minus(sep%edge_pull_time)
      res%ground_time = event_or_minus(sep%ground_time)
      res%ground_body = sep%ground_body
      res%ground_point = sep%ground_point
      res%ground_speed = sep%ground_speed
    end subroutine events_of
  end subroutine finish_result

  !> Free both engines.
  subroutine release(r)
    type(coupled_run), intent(inout) :: r
    if (associated(r%trk)) deallocate(r%trk)
    nullify(r%trk, r%dobs%trk, r%cobs%trk, r%lobs%trk, r%dobs%dsys, r%cobs%chain, r%lobs%line)
    call r%dsolver%free()
    call r%cpl%free()
    if (associated(r%dsys)) deallocate(r%dsys)
    nullify(r%dsys)
  end subroutine release

  !> The output file: the contract, and the coupling's own variables and
  !> attributes (docs/output.md).
  subroutine write_output(r, run, echo, res, run_error)
    type(coupled_run), intent(in) :: r
    type(run_config), intent(in) :: run
    character(len=*), intent(in) :: echo
    type(launch_result), intent(in) :: res
    type(error_type), allocatable, intent(inout) :: run_error
    type(nc_writer) :: w
    type(error_type), allocatable :: werr
    call w%create(run%output, werr)
    select case (r%plan%mode)
    case ("direct")
      call r%hist%write_contract(w, "parachute (the line's last node), earth frame", "", werr)
      if (r%dsys%has_line) then
        call write_run_metadata(w, "airlaunch", "airlaunch: aircraft-rocket-line-parachute separation " // &
          "(Zheng & Zhang 2018, §5.2)", echo, werr)
      else
        call write_run_metadata(w, "airlaunch", "airlaunch: aircraft-rocket separation without line or " // &
          "parachute (gravity drop, rail release)", echo, werr)
      end if
      call write_milestones(w, res, werr)
    case ("rigidized")
      call r%hist%write_contract(w, "parachute (chain body B3), earth frame", " (sub-stepped flexible line)", werr)
      call write_rigidized_variables(r, w, .false., werr)
      call write_run_metadata(w, "airlaunch", "airlaunch: aircraft-rocket-line-parachute separation " // &
        "(Zheng & Zhang 2018, §5.2), line by equivalent rigidization (§2.4)", echo, werr)
      call write_milestones(w, res, werr)
      call write_rigidized_attributes(r, w, werr)
    case default
      call r%hist%write_contract(w, "parachute: the line's last node (direct coupling) or the chain's body B3 " // &
        "(rigidized coupling), earth frame", "", werr)
      call write_rigidized_variables(r, w, .true., werr)
      call write_choice_variables(r, w, werr)
      call write_run_metadata(w, "airlaunch", "airlaunch: aircraft-rocket-line-parachute separation " // &
        "(Zheng & Zhang 2018, §5.2), line coupling chosen " // &
        trim(merge("per phase    ", "automatically", r%plan%mode == "per_phase")), echo, werr)
      call write_milestones(w, res, werr)
      call write_rigidized_attributes(r, w, werr)
      call write_choice_attributes(r, w, werr)
    end select
    call w%finish(werr)
    if (allocated(werr) .and. .not. allocated(run_error)) call move_alloc(werr, run_error)
  end subroutine write_output

  !> The virtual line body over time (`mixed`: also in the direct coupling's
  !> records, from its line nodes).
  subroutine write_rigidized_variables(r, w, mixed, werr)
    type(coupled_run), intent(in) :: r
    type(nc_writer), intent(inout) :: w
    logical, intent(in) :: mixed
    type(error_type), allocatable, intent(inout) :: werr
    integer :: nrec
    character(len=:), allocatable :: force_text
    nrec = r%hist%nrec
    force_text = "force of the virtual line body on the rocket at the tie-down point (chain joint force), earth frame"
    if (mixed) force_text = "force of the line on the rocket at the tie-down point: the virtual body's joint " // &
      "force (rigidized coupling) or the line's end force (direct coupling), earth frame"
    call w%add_var_1d("m_rigid_kg", ["time"], r%m_rig(1:nrec), "kg", &
      "virtual line body: mass m_rigid (Eq. (31), kinetic-energy equivalent, guarded)", werr)
    call w%add_var_1d("j_rigid_kg_m2", ["time"], r%j_rig(1:nrec), "kg m2", &
      "virtual line body: transverse moment of inertia J_rigid (Eq. (32), guarded)", werr)
    call w%add_var_1d("d_rigid_m", ["time"], r%d_rig(1:nrec), "m", &
      "virtual line body: length d_rigid (Eq. (20), chord of the flexible line)", werr)
    call w%add_var_2d("rigid_line_force_N", ["xyz ", "time"], r%f_rig(:, 1:nrec), "N", force_text, werr)
    call w%add_var_1d("line_end_mismatch_m", ["time"], r%mismatch(1:nrec), "m", &
      "distance between the flexible line's node N and the chain's parachute B3" // &
      trim(merge(" (0 in the direct coupling)", "                           ", mixed)), werr)
  end subroutine write_rigidized_variables

  !> The rigidized coupling's attributes (over all its stints).
  subroutine write_rigidized_attributes(r, w, werr)
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    type(coupled_run), intent(in) :: r
    type(nc_writer), intent(inout) :: w
    type(error_type), allocatable, intent(inout) :: werr
    call w%add_text_att("/", "line_coupling", trim(r%plan%mode), werr)
    call w%add_real_att("/", "outer_dt_s", r%ropt%outer_dt, werr)
    call w%add_text_att("/", "line_inner_scheme", trim(r%ropt%inner_scheme), werr)
    if (r%ropt%inner_scheme == "marching" .and. associated(r%cpl%line)) &
      call w%add_real_att("/", "line_inner_dt_s", r%cpl%marcher%dt, werr)
    call w%add_int_att("/", "refreshes", [r%n_refresh], werr)
    call w%add_int_att("/", "guarded_mass_refreshes", [r%n_guard_mass], werr)
    call w%add_int_att("/", "guarded_inertia_refreshes", [r%n_guard_inertia], werr)
    ! NaN when no record came from the rigidized engine ('auto' that never switched)
    call w%add_real_att("/", "min_rigid_line_tension_N", merge(r%min_rigid_tension, &
      ieee_value(1.0_dp, ieee_quiet_nan), r%min_rigid_tension < huge(1.0_dp)), werr)
    call w%add_real_att("/", "max_line_end_mismatch_m", r%max_mismatch, werr)
  end subroutine write_rigidized_attributes

  !> Which coupling each record comes from, and the indicator there.
  subroutine write_choice_variables(r, w, werr)
    type(coupled_run), intent(in) :: r
    type(nc_writer), intent(inout) :: w
    type(error_type), allocatable, intent(inout) :: werr
    integer :: nrec
    nrec = r%hist%nrec
    call w%add_var_1d("line_coupling_active", ["time"], r%active_rec(1:nrec), "1", &
      "line coupling of the record: 0 direct, 1 rigidized", werr)
    call w%add_var_1d("line_min_strain", ["time"], r%strain_rec(1:nrec), "1", &
      "automatic choice, taut indicator: smallest segment strain of the flexible line", werr)
    call w%add_var_1d("line_strain_change", ["time"], r%change_rec(1:nrec), "1", &
      "automatic choice, slow indicator: largest segment strain rate times the outer step, over the mean " // &
      "strain (at least auto_min_strain)", werr)
    call w%add_var_1d("line_steps_per_outer_step", ["time"], r%steps_rec(1:nrec), "1", &
      "automatic choice, busy indicator: steps of the integrator that carries the line (the direct coupling's, " // &
      "or the rigidized coupling's line sub-steps) per outer step since the previous record", werr)
  end subroutine write_choice_variables

  !> The plan and the switches.
  subroutine write_choice_attributes(r, w, werr)
    type(coupled_run), intent(in) :: r
    type(nc_writer), intent(inout) :: w
    type(error_type), allocatable, intent(inout) :: werr
    integer :: k
    character(len=:), allocatable :: by_phase
    if (r%plan%mode == "per_phase") then
      by_phase = coupling_name(r%plan%by_phase(0))
      do k = 1, 3
        by_phase = by_phase // ", " // coupling_name(r%plan%by_phase(k))
      end do
      call w%add_text_att("/", "coupling_by_phase", by_phase, werr)
    else
      call w%add_real_att("/", "auto_min_strain", r%plan%auto%min_strain, werr)
      call w%add_real_att("/", "auto_max_strain_change", r%plan%auto%max_strain_change, werr)
      call w%add_real_att("/", "auto_dwell_s", r%plan%auto%dwell, werr)
      call w%add_real_att("/", "auto_min_steps", r%plan%auto%min_steps, werr)
    end if
    call w%add_int_att("/", "coupling_switches", [r%switches], werr)
    if (r%switches > 0) call w%add_text_att("/", "coupling_switch_log", r%switch_log, werr)
  end subroutine write_choice_attributes
end submodule airlaunch_launch_coupled
