!> The specification: a right-hand side allocates nothing (issue 7: no
!> allocation or I/O in right-hand sides).
!>
!> The paper scenario (input/airlaunch_paper.nml, its default direct line
!> coupling) is built as the program builds it (read_scenario_config,
!> setup_launch) and integrated by CVODE through the four phases; at snapshots
!> in each phase the launch system's right-hand side and event functions are
!> called at the snapshot state and at perturbed states (other times, faster
!> bodies and nodes, a line pushed slack), and every heap allocation of the
!> process during these calls is counted (tests/unit/malloc_counter.c replaces
!> malloc, calloc and realloc).  The count must not change: the solver's own
!> work between the snapshots is not counted, the calls are.  A positive control
!> first shows that the counter sees an allocation.
program test_rhs_allocations
  use, intrinsic :: iso_c_binding, only: c_int64_t
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type
  use airlaunch_strings, only: str
  use airlaunch_namelist, only: nml_file
  use airlaunch_scenario_config, only: scenario_config, read_scenario_config
  use airlaunch_launch_system, only: launch_system, launch_nroots, rigid_size, launch_pitch_root, launch_clearance_root
  use airlaunch_launch_scene, only: setup_launch
  use airlaunch_launch_history, only: launch_result, handle_launch_event
  use airlaunch_cvode, only: cvode_solver, cvode_options
  use airlaunch_ode, only: rhs_ok
  use airlaunch_cut_joint, only: phase_preparation, phase_free
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use testing
  use heap_counter, only: heap_allocations, check_counter_sees_allocation
  implicit none

  !> Snapshot times [s]: two in each phase of the paper run (release 0.72 s,
  !> edge 3.0 s, separation 3.9 s).
  real(dp), parameter :: t_snap(8) = [0.3_dp, 0.6_dp, 1.5_dp, 2.5_dp, 3.3_dp, 3.7_dp, 4.5_dp, 6.0_dp]
  !> Calls per snapshot: right-hand sides (half with a slack line) and event functions.
  integer, parameter :: n_rhs = 13, n_roots = 2

  type(scenario_config) :: cfg
  type(launch_system), target :: sys
  type(launch_result) :: res
  type(cvode_solver) :: solver
  type(cvode_options) :: opts
  type(nml_file) :: f
  type(error_type), allocatable :: error
  character(len=:), allocatable :: echo, path
  real(dp), allocatable :: y0(:), y(:), ydot(:)
  real(dp) :: g(launch_nroots)
  integer(c_int64_t) :: before, delta, counted, in_phase(0:3)
  integer :: i, k, status, n_calls, phase
  logical :: ok, phase_seen(0:3), taut_seen, slack_seen

  call check_counter_sees_allocation()

  call section("the paper scenario, direct coupling")
  path = paper_input()
  call f%load(path, error)
  if (.not. allocated(error)) call read_scenario_config(f, cfg, echo, error)
  if (.not. allocated(error)) call setup_launch(cfg, sys, y0, res, error)
  call check(.not. allocated(error), "read " // path // " and set up the launch system")
  if (allocated(error)) then
    write(*, '(a)') error%message
    call finish()
  end if
  call check(sys%has_line .and. sys%line%n == cfg%line%n_seg, "the line with " // str(sys%line%n) // " segments")
  opts = cvode_options(linear_solver="band", upper_bandwidth=18, lower_bandwidth=18, rtol=1.0e-5_dp, &
    atol=1.0e-6_dp, max_order=2)
  call solver%init(sys, 0.0_dp, y0, opts, error)
  call check(.not. allocated(error), "CVODE set up")
  if (allocated(error)) call finish()
  allocate(y(size(y0)), ydot(size(y0)))

  ! warm-up, not counted: the first calls may size what is sized once
  do k = 1, 3
    call sys%rhs(0.0_dp, y0, ydot, status)
    call sys%roots(0.0_dp, y0, g, status)
  end do

  call section("right-hand sides and event functions at snapshots of the run")
  counted = 0
  in_phase = 0
  n_calls = 0
  phase_seen = .false.
  taut_seen = .false.
  slack_seen = .false.
  ok = .true.
  do i = 1, size(t_snap)
    call integrate_to(t_snap(i))
    if (allocated(error)) exit
    phase = sys%sep%phase
    phase_seen(phase) = .true.
    before = heap_allocations()
    call calls_at_snapshot(solver%t, solver%y)
    delta = heap_allocations() - before
    in_phase(phase) = in_phase(phase) + delta
    counted = counted + delta
    write(*, '(a)') "  t = " // str(solver%t) // " s, phase " // str(phase) // ": " // str(int(delta)) // &
      " allocations in " // str(n_rhs) // " right-hand sides and " // str(n_roots) // " event evaluations"
  end do
  call check(.not. allocated(error), "the run reached t = " // str(t_snap(size(t_snap))) // " s")
  if (allocated(error)) write(*, '(a)') error%message
  call check(all(phase_seen), "snapshots in phases 0 (locked), 1 (rail), 2 (edge) and 3 (free)")
  call check(taut_seen .and. slack_seen, "states with the line taut and with slack segments")
  call check(ok, "every call returned rhs_ok with finite derivatives")
  do phase = phase_preparation, phase_free
    call check(in_phase(phase) == 0, "phase " // str(phase) // ": " // str(int(in_phase(phase))) // " allocations")
  end do
  call check(counted == 0, "the specification: a right-hand side allocates nothing (" // str(int(counted)) // &
    " heap allocations in " // str(n_calls) // " calls of rhs and roots)")
  call solver%free()
  call finish()

contains

  !> Integrate to tout, switching the phase at the events (as the program's
  !> direct coupling does).
  subroutine integrate_to(tout)
    real(dp), intent(in) :: tout
    logical :: event, changed, lower
    integer :: which(launch_nroots), guard, st
    do guard = 1, 100
      call solver%advance(tout, error, event, which)
      if (allocated(error) .or. .not. event) return
      call sys%prepare(solver%t, solver%y, st)
      call handle_launch_event(res, solver%t, sys%sep, sys%yabs(1:rigid_size), which(1:launch_pitch_root-1), &
        which(launch_pitch_root), sys%find_pitch_max, which(launch_clearance_root), sys%clr, changed, lower, error)
      if (allocated(error)) return
      if (changed) then
        y = solver%y
        call solver%reinit(solver%t, y, error)
        if (allocated(error)) return
      end if
      if (solver%t >= tout) return
    end do
  end subroutine integrate_to

  !> n_rhs right-hand sides and n_roots event evaluations around the state ys
  !> at ts: later times, velocities scaled up, and (second half) the line's
  !> nodes pulled 10 % towards the rocket's tie-down point, so that every
  !> segment is slack.  Allocates nothing itself (y, ydot, g exist).
  subroutine calls_at_snapshot(ts, ys)
    real(dp), intent(in) :: ts, ys(:)
    real(dp) :: t, tie(3), scale
    integer :: k, j, o, st
    do k = 0, n_rhs - 1
      t = ts + 1.0e-4_dp*k
      scale = 1.0_dp + 1.0e-3_dp*k
      y = ys
      y(4:6) = scale*ys(4:6)        ! aircraft velocity (relative frame)
      y(17:19) = scale*ys(17:19)    ! rocket velocity
      do j = 1, sys%line%n
        o = rigid_size + 6*(j - 1)
        y(o+4:o+6) = scale*ys(o+4:o+6)
      end do
      if (2*k >= n_rhs) then
        call sys%prepare(t, y, st)
        tie = sys%x(:, 0)
        tie(1) = tie(1) - sys%v_ref*t
        tie(2) = tie(2) - sys%h_ref
        do j = 1, sys%line%n
          o = rigid_size + 6*(j - 1)
          y(o+1:o+3) = tie + 0.9_dp*(y(o+1:o+3) - tie)
        end do
      end if
      call sys%rhs(t, y, ydot, st)
      n_calls = n_calls + 1
      ok = ok .and. st == rhs_ok .and. all(ieee_is_finite(ydot))
      if (all(sys%tension > 0.0_dp)) taut_seen = .true.
      if (any(sys%tension == 0.0_dp)) slack_seen = .true.
    end do
    do k = 1, n_roots
      call sys%roots(ts + 1.0e-4_dp*k, ys, g, st)
      n_calls = n_calls + 1
      ok = ok .and. st == rhs_ok
    end do
  end subroutine calls_at_snapshot
end program test_rhs_allocations
