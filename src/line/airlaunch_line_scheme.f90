!> The role every time integrator of a standalone line plays (STYLE.md habit 3):
!> advance to an output time, give the node state, release resources.
!> Implementations: `line_cvode` (default; CVODE BDF with a band linear solver,
!> airlaunch_line_cvode) and `line_marching` (the paper's explicit marching with
!> the end-force iteration, Eqs. (12)–(17), airlaunch_line_marching).
module airlaunch_line_scheme
  use airlaunch_kinds, only: dp, i8
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_peak_search, only: peak_tracker
  use airlaunch_line_ends, only: line_end
  implicit none
  private
  public :: line_scheme, line_scheme_options, line_scheme_stats, check_scheme_options, scheme_peak_tension
  public :: check_fill_target

  !> How to integrate a line (namelist group `&line_scene`, scheme part).
  type :: line_scheme_options
    character(len=16) :: scheme = "cvode"   !< "cvode" (default) or "marching" (the paper's)
    ! cvode
    real(dp) :: rtol = 1.0e-5_dp            !< cvode: relative tolerance
    real(dp) :: atol = 1.0e-5_dp            !< cvode: absolute tolerance [m, m/s]
    real(dp) :: max_step = 0.0_dp           !< cvode: largest step [s], 0 = unlimited
    !> cvode: largest BDF order (1..5).  2 by default: BDF2 is A-stable, and the
    !> line's lightly damped transverse and axial modes make orders 3-5 step-size
    !> limited by their stability (measured 2.4x more steps, see docs/line.md).
    integer :: max_order = 2
    !> cvode: the line's analytic Jacobian (default) or CVODE's difference
    !> quotients (.false.; for comparison: same answers, 20 force evaluations
    !> per Jacobian)
    logical :: analytic_jacobian = .true.
    !> cvode: steps allowed over the whole run (`&run max_steps`); 0 = no limit
    integer :: max_steps = 0
    !> cvode: the run's wall-time budget (`&run max_wall_time`) [s]; 0 = no limit
    real(dp) :: max_wall_time = 0.0_dp
    !> cvode: wall_clock() at which it is spent (0: max_wall_time from the scheme's start)
    real(dp) :: wall_deadline = 0.0_dp
    !> cvode: end of the run [s]; the first step's estimate looks that far, not
    !> to the first output time, so the steps do not depend on the output times
    !> (0: the first output time)
    real(dp) :: t_final = 0.0_dp
    ! marching
    real(dp) :: dt = 1.0e-4_dp              !< marching: fixed time step [s]
    real(dp) :: force_tol = 1.0e-6_dp       !< marching: e0, far-end force tolerance [N]
    integer :: max_iterations = 20          !< marching: far-end iterations per step
    !> take the largest segment tension over every step (line_scheme%peak; its
    !> time is the first within rtol of it, for either scheme):
    !> cvode refines it between steps (its cost on input/line_parachute.nml
    !> with the lumped mass, whole process: +13 % instructions at N = 8, +16 %
    !> at N = 60); the benchmarks turn it off for both schemes
    logical :: peak_tension = .true.
  end type line_scheme_options

  !> Work counters of an integration.
  type :: line_scheme_stats
    integer(i8) :: steps = 0        !< time steps taken
    integer(i8) :: rhs_evals = 0    !< force evaluations of the whole line
    integer(i8) :: jac_evals = 0    !< cvode: Jacobian evaluations
    integer(i8) :: iterations = 0   !< marching: far-end force iterations (all steps)
    integer(i8) :: failures = 0     !< cvode: error-test and convergence failures
  end type line_scheme_stats

  !> A line time integrator.
  type, abstract :: line_scheme
    real(dp) :: t = 0.0_dp   !< time of the current state [s]
    !> (1): the largest segment tension over every step of the scheme (on the
    !> heap: an observer of the integrator points to it)
    type(peak_tracker), pointer :: peak(:) => null()
    !> the largest segment tension evaluated so far [N] (every value the peak
    !> tracker is offered is one of these) and the segment carrying it, 1..N
    !> (0: none yet): the place of `peak`'s value
    real(dp) :: peak_seen = -huge(1.0_dp)
    integer :: peak_segment = 0
    !> the last advance stopped where a segment's tension reached its strength
    !> (set_strength): the owner parts it (part) and goes on
    logical :: strength_reached = .false.
    !> the last advance stopped where the lowest integrated node reached the
    !> ground (set_ground): the owner ends the run there
    logical :: ground_reached = .false.
  contains
    procedure :: peak_tension => scheme_peak_tension
    procedure :: set_strength => scheme_set_strength
    procedure :: set_ground => scheme_set_ground
    procedure :: part => scheme_part
    procedure :: start_peak => scheme_start_peak
    procedure :: note_peak_segment => scheme_note_peak_segment
    procedure :: release_peak => scheme_release_peak
    procedure(advance_interface), deferred :: advance
    procedure(state_interface), deferred :: get_state
    procedure(stats_interface), deferred :: stats
    procedure(body_interface), deferred :: set_body_motion
    procedure(stop_interface), deferred :: set_stop_time
    procedure(fill_interface), deferred :: set_fill_time
    procedure(free_interface), deferred :: free
  end type line_scheme

  abstract interface
    !> Integrate to t_out (>= t); on failure `error` names the time and the quantity.
    subroutine advance_interface(self, t_out, error)
      import :: line_scheme, dp, error_type
      implicit none
      class(line_scheme), intent(inout) :: self
      real(dp), intent(in) :: t_out
      type(error_type), allocatable, intent(inout) :: error
    end subroutine advance_interface
    !> Node positions x(3,0:N) and velocities v(3,0:N) at the current time,
    !> kinematic ends included.
    subroutine state_interface(self, x, v)
      import :: line_scheme, dp
      implicit none
      class(line_scheme), intent(inout) :: self
      real(dp), intent(out) :: x(:, 0:), v(:, 0:)
    end subroutine state_interface
    !> Work counters so far.
    function stats_interface(self) result(s)
      import :: line_scheme, line_scheme_stats
      implicit none
      class(line_scheme), intent(in) :: self
      type(line_scheme_stats) :: s
    end function stats_interface
    !> Give end `which` (1 = node 0, 2 = node N) the motion of a body between
    !> two samples (the owner's outer step); the integrator restarts there.
    subroutine body_interface(self, which, t1, x1, v1, t2, x2, v2, error)
      import :: line_scheme, dp, error_type
      implicit none
      class(line_scheme), intent(inout) :: self
      integer, intent(in) :: which
      real(dp), intent(in) :: t1, t2, x1(3), v1(3), x2(3), v2(3)
      type(error_type), allocatable, intent(inout) :: error
    end subroutine body_interface
    !> Do not step past t_stop (> t): a change of the system known in advance.
    subroutine stop_interface(self, t_stop, error)
      import :: line_scheme, dp, error_type
      implicit none
      class(line_scheme), intent(inout) :: self
      real(dp), intent(in) :: t_stop
      type(error_type), allocatable, intent(inout) :: error
    end subroutine stop_interface
    !> The canopy at end `which` (1 = node 0, 2 = node N) deploys at the current
    !> time and fills in `fill_time` [s]; the integrator restarts there.
    subroutine fill_interface(self, which, fill_time, error)
      import :: line_scheme, dp, error_type
      implicit none
      class(line_scheme), intent(inout) :: self
      integer, intent(in) :: which
      real(dp), intent(in) :: fill_time
      type(error_type), allocatable, intent(inout) :: error
    end subroutine fill_interface
    !> Release resources (safe to call twice).
    subroutine free_interface(self)
      import :: line_scheme
      implicit none
      class(line_scheme), intent(inout) :: self
    end subroutine free_interface
  end interface

contains

  !> Segment j parts when its tension reaches strength(j) [N]: the integrator
  !> watches the smallest margin (airlaunch_line_model's weakest_segment) as an
  !> event and stops where it reaches 0 (strength_reached).  A scheme without
  !> event location cannot (the default: an error).
  subroutine scheme_set_strength(self, strength, error)
    class(line_scheme), intent(inout) :: self              !< scheme
    real(dp), intent(in) :: strength(:)                    !< per segment [N]
    type(error_type), allocatable, intent(inout) :: error  !< set: not supported
    call fatal_error(error, "line: a breaking strength needs a scheme that locates events (cvode); " // &
      "this scheme has none (" // str(size(strength)) // " segment strengths given)")
    if (.false.) self%t = self%t
  end subroutine scheme_set_strength

  !> The run ends where the lowest node that is a state (not a kinematic end)
  !> reaches the geometric altitude `ground` [m]: the integrator watches it as
  !> an event and stops there (ground_reached).  A scheme without event
  !> location cannot (the default: an error).
  subroutine scheme_set_ground(self, ground, error)
    class(line_scheme), intent(inout) :: self              !< scheme
    real(dp), intent(in) :: ground                         !< [m]
    type(error_type), allocatable, intent(inout) :: error  !< set: not supported
    call fatal_error(error, "line: a ground (at " // str(ground) // " m) needs a scheme that locates " // &
      "events (cvode); this scheme has none")
    if (.false.) self%t = self%t
  end subroutine scheme_set_ground

  !> Segment k parts now (line_model%part): it carries nothing from here on,
  !> and the integrator restarts here, the forces having jumped.  The default:
  !> an error (a scheme that cannot restart on a changed line).
  subroutine scheme_part(self, k, error)
    class(line_scheme), intent(inout) :: self              !< scheme
    integer, intent(in) :: k                               !< segment 1..N
    type(error_type), allocatable, intent(inout) :: error  !< set: not supported
    call fatal_error(error, "line: parting segment " // str(k) // " needs the cvode scheme; this " // &
      "scheme cannot part its line")
    if (.false.) self%t = self%t
  end subroutine scheme_part

  !> The largest segment tension of the computed solution so far [N] and its
  !> time t_peak [s]: the first time the tension came within the tracker's
  !> band (the scheme's rtol) of it (0 and -1 before any step).
  function scheme_peak_tension(self, t_peak) result(tmax)
    class(line_scheme), intent(inout) :: self   !< scheme
    real(dp), intent(out) :: t_peak             !< its time [s]
    real(dp) :: tmax
    tmax = 0.0_dp
    t_peak = -1.0_dp
    if (.not. associated(self%peak)) return
    if (self%peak(1)%t_best < 0.0_dp) return
    tmax = self%peak(1)%best
    t_peak = self%peak(1)%first_time()
  end function scheme_peak_tension

  !> A fresh tracker of the peak tension; tensions within `band` (relative)
  !> of the peak are the same peak, reported at the first of them.
  subroutine scheme_start_peak(self, band)
    class(line_scheme), intent(inout) :: self   !< scheme
    real(dp), intent(in) :: band                !< relative band of the peak
    call self%release_peak()
    allocate(self%peak(1))
    self%peak(1)%band = band
    self%peak_seen = -huge(1.0_dp)
    self%peak_segment = 0
  end subroutine scheme_start_peak

  !> A segment tension `value` evaluated at segment k: the segment of the
  !> largest one so far is the peak's place (the first of equal values).
  subroutine scheme_note_peak_segment(self, value, k)
    class(line_scheme), intent(inout) :: self   !< scheme
    real(dp), intent(in) :: value               !< the tension [N]
    integer, intent(in) :: k                    !< its segment, 1..N (0: none)
    if (k < 1) return
    if (value > self%peak_seen) then
      self%peak_seen = value
      self%peak_segment = k
    end if
  end subroutine scheme_note_peak_segment

  !> Free the tracker.
  subroutine scheme_release_peak(self)
    class(line_scheme), intent(inout) :: self   !< scheme
    if (associated(self%peak)) deallocate(self%peak)
    nullify(self%peak)
  end subroutine scheme_release_peak

  !> An error unless end `which` of `ends` (1 = node 0, 2 = node N) is a
  !> deploying canopy and `fill_time` > 0 (set_fill_time's arguments).
  subroutine check_fill_target(ends, which, fill_time, error)
    type(line_end), intent(in) :: ends(2)                  !< the scheme's ends
    integer, intent(in) :: which                           !< the end
    real(dp), intent(in) :: fill_time                      !< its filling time [s]
    type(error_type), allocatable, intent(inout) :: error  !< set if not
    if (which < 1 .or. which > 2) then
      call fatal_error(error, "line: end index " // str(which) // " is not allowed: 1 (node 0) or 2 (node N)")
    else if (.not. ends(which)%inflating()) then
      call fatal_error(error, "line: end " // str(which) // " is not a deploying canopy: no filling time to set")
    else if (.not. (fill_time > 0.0_dp .and. fill_time <= huge(1.0_dp))) then
      call fatal_error(error, "line: a filling time of " // str(fill_time) // " s is not allowed: must be > 0 " // &
        "and finite")
    end if
  end subroutine check_fill_target

  !> Validate the scheme options (one line naming the variable, its value and
  !> what is allowed).
  subroutine check_scheme_options(opts, error)
    type(line_scheme_options), intent(in) :: opts          !< options
    type(error_type), allocatable, intent(inout) :: error  !< set on bad input
    select case (trim(opts%scheme))
    case ("cvode")
      if (.not. (opts%rtol > 0.0_dp)) then
        call fatal_error(error, "line_scene: rtol = " // str(opts%rtol) // " is not allowed: the relative " // &
          "tolerance must be > 0")
      else if (.not. (opts%atol > 0.0_dp)) then
        call fatal_error(error, "line_scene: atol = " // str(opts%atol) // " is not allowed: the absolute " // &
          "tolerance must be > 0")
      else if (.not. (opts%max_step >= 0.0_dp)) then
        call fatal_error(error, "line_scene: max_step = " // str(opts%max_step) // " s is not allowed: " // &
          "must be > 0, or 0 for no limit")
      else if (opts%max_order < 0 .or. opts%max_order > 5) then
        call fatal_error(error, "line_scene: max_order = " // str(opts%max_order) // " is not allowed: " // &
          "BDF order 1..5 (0 = CVODE's default 5)")
      end if
    case ("marching")
      if (.not. (opts%dt > 0.0_dp)) then
        call fatal_error(error, "line_scene: dt = " // str(opts%dt) // " s is not allowed: the marching " // &
          "time step must be > 0")
      else if (.not. (opts%force_tol > 0.0_dp)) then
        call fatal_error(error, "line_scene: force_tol = " // str(opts%force_tol) // " N is not allowed: " // &
          "the far-end force tolerance e0 must be > 0")
      else if (opts%max_iterations < 1) then
        call fatal_error(error, "line_scene: max_iterations = " // str(opts%max_iterations) // &
          " is not allowed: must be >= 1")
      end if
    case default
      call fatal_error(error, "line_scene: scheme = '" // trim(opts%scheme) // "' is not allowed: use " // &
        "'cvode' (default) or 'marching'")
    end select
  end subroutine check_scheme_options
end module airlaunch_line_scheme
