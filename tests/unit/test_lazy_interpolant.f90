!> The step observer (airlaunch_step_maxima) reads CVODE's whole interpolant
!> only for the stretches a bracket may use (a sequence rising into their
!> end, a bracket now, a sample inside): its maxima must be those of the
!> observer shown every stretch whole (the behaviour before, reproduced here
!> by a forwarder that reads each stretch whole before showing it), bit for
!> bit - the values, their times, the first times within the band, and the
!> very times the quantities were evaluated at.  Two oscillators, one growing
!> (every peak a new maximum: each one refined, across two steps) and one
!> decaying (peaks that cannot beat the first: rising stretches read for
!> nothing), with stop times, re-initialisations (a sequence closed on the
!> stretch before) and a stop time 1e-6 s after one (a short sequence); the
!> rates (needs_rate) both ways.  And a single quantity's observer reads at
!> most 3/4 of the stretches whole (the saving: about half of them rise).
module lazy_interpolant_systems
  use airlaunch_kinds, only: dp, pi
  use airlaunch_ode, only: ode_system, rhs_ok
  use airlaunch_cvode, only: step_observer, step_polynomial
  use airlaunch_step_maxima, only: maxima_observer
  implicit none
  private
  public :: two_oscillators, probe, whole_forwarder

  !> [x1, v1, x2, v2]: x1'' = -w1^2 x1 + 2 z w1 x1' (growing), x2'' = -w2^2 x2 - 2 z w2 x2'.
  type, extends(ode_system) :: two_oscillators
    real(dp) :: w1 = 2*pi, w2 = 2*pi*1.37_dp, z = 0.03_dp
  contains
    procedure :: rhs => oscillators_rhs
  end type two_oscillators

  !> q1 = x1 + 0.3 x2, q2 = x2, q3 = v1^2 (with rates: the acceleration x1'' squared);
  !> counts its evaluations and sums their times.
  type, extends(maxima_observer) :: probe
    integer :: pick(3) = [1, 2, 3]   !< quantity m is q_pick(m) (as many as trackers)
    integer :: evaluations = 0
    real(dp) :: time_sum = 0.0_dp
  contains
    procedure :: values => probe_values
  end type probe

  !> Shows `inner` every stretch read whole (every coefficient off CVODE).
  type, extends(step_observer) :: whole_forwarder
    type(probe) :: inner
    type(step_polynomial) :: whole
    integer :: stretches = 0
  contains
    procedure :: observe => forward
  end type whole_forwarder

contains

  subroutine oscillators_rhs(self, t, y, ydot, status)
    class(two_oscillators), intent(inout) :: self
    real(dp), intent(in) :: t, y(:)
    real(dp), intent(out) :: ydot(:)
    integer, intent(out) :: status
    ydot(1) = y(2)
    ydot(2) = -self%w1**2*y(1) + 2*self%z*self%w1*y(2)
    ydot(3) = y(4)
    ydot(4) = -self%w2**2*y(3) - 2*self%z*self%w2*y(4) + 0.0_dp*t
    status = rhs_ok
  end subroutine oscillators_rhs

  subroutine probe_values(self, t, q, ok)
    class(probe), intent(inout) :: self
    real(dp), intent(in) :: t
    real(dp), intent(out) :: q(:)
    logical, intent(out) :: ok
    real(dp) :: all(3)
    integer :: m
    self%evaluations = self%evaluations + 1
    self%time_sum = self%time_sum + t
    all(1) = self%y(1) + 0.3_dp*self%y(3)
    all(2) = self%y(3)
    all(3) = self%y(2)**2
    if (self%needs_rate) all(3) = self%dy(2)**2
    do m = 1, size(self%trk)
      q(m) = all(self%pick(m))
    end do
    ok = .true.
  end subroutine probe_values

  subroutine forward(self, poly, t_start, t_end, restart, last)
    class(whole_forwarder), intent(inout) :: self
    type(step_polynomial), intent(in) :: poly
    real(dp), intent(in) :: t_start, t_end
    logical, intent(in) :: restart, last
    self%stretches = self%stretches + 1
    call self%whole%copy(poly)
    call self%whole%fill(from=poly)
    call self%inner%observe(self%whole, t_start, t_end, restart, last)
  end subroutine forward
end module lazy_interpolant_systems

program test_lazy_interpolant
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type
  use airlaunch_strings, only: str
  use airlaunch_cvode, only: cvode_solver, cvode_options, cvode_stats, step_observer
  use airlaunch_peak_search, only: peak_tracker
  use lazy_interpolant_systems, only: two_oscillators, probe, whole_forwarder
  use testing
  implicit none

  call section("one quantity, growing peaks (each refined): lazily and whole")
  call compare([1], .false., .true.)
  call section("one quantity, decaying peaks (the first the largest): lazily and whole")
  call compare([2], .false., .true.)
  call section("three quantities, values only: lazily and whole")
  call compare([1, 2, 3], .false., .false.)
  call section("three quantities with the rates (needs_rate): lazily and whole")
  call compare([3, 1, 2], .true., .false.)
  call finish()

contains

  !> Runs the same integration twice, once observed lazily and once through
  !> the forwarder, and compares the trackers and the evaluations.
  subroutine compare(pick, with_rate, saves)
    integer, intent(in) :: pick(:)      !< the quantities (probe%pick)
    logical, intent(in) :: with_rate    !< needs_rate
    logical, intent(in) :: saves        !< check that a quarter of the stretches or more is not read whole
    type(peak_tracker), pointer :: lazy_trk(:), whole_trk(:)
    type(probe), target :: lazy
    type(whole_forwarder), target :: fwd
    integer :: m, steps
    allocate(lazy_trk(size(pick)), whole_trk(size(pick)))
    lazy%pick(1:size(pick)) = pick
    fwd%inner%pick(1:size(pick)) = pick
    lazy_trk(:)%band = 1.0e-6_dp
    whole_trk(:)%band = 1.0e-6_dp
    lazy%trk => lazy_trk
    lazy%needs_rate = with_rate
    fwd%inner%trk => whole_trk
    fwd%inner%needs_rate = with_rate
    call run(lazy, steps)
    call run(fwd, steps)
    do m = 1, size(pick)
      call check(lazy_trk(m)%best == whole_trk(m)%best .and. lazy_trk(m)%t_best == whole_trk(m)%t_best, &
        "quantity " // str(m) // ": maximum " // str(lazy_trk(m)%best) // " at " // str(lazy_trk(m)%t_best) // &
        " s, read whole " // str(whole_trk(m)%best) // " at " // str(whole_trk(m)%t_best) // " s")
      call check(lazy_trk(m)%first_time() == whole_trk(m)%first_time() .and. lazy_trk(m)%n_rec == whole_trk(m)%n_rec, &
        "quantity " // str(m) // ": first time within the band " // str(lazy_trk(m)%first_time()) // " s (" // &
        str(whole_trk(m)%first_time()) // " s)")
      if (lazy_trk(m)%n_rec == whole_trk(m)%n_rec) call check(all(lazy_trk(m)%rec_t == whole_trk(m)%rec_t) .and. &
        all(lazy_trk(m)%rec_q == whole_trk(m)%rec_q), "quantity " // str(m) // ": the same candidates")
    end do
    call check(lazy%evaluations == fwd%inner%evaluations .and. lazy%time_sum == fwd%inner%time_sum, &
      "the same evaluations: " // str(lazy%evaluations) // " (" // str(fwd%inner%evaluations) // "), at the same times")
    if (saves) call check(lazy%whole_reads < (3*fwd%stretches)/4, "stretches read whole: " // &
      str(lazy%whole_reads) // " of " // str(fwd%stretches) // " (" // str(steps) // " steps)")
    if (any(pick == 1)) call check(lazy%evaluations > fwd%stretches + 30, "brackets refined: " // str(lazy%evaluations) // &
      " evaluations for " // str(fwd%stretches) // " stretches")
    deallocate(lazy_trk, whole_trk)
  end subroutine compare

  !> 0 .. 6 s (stop times at 2.05 and 4.3 s, then a re-initialisation each;
  !> a stop time 1e-6 s after the second: a short sequence), output every 0.1 s.
  subroutine run(obs, stretches)
    class(step_observer), intent(inout) :: obs
    integer, intent(out) :: stretches
    type(two_oscillators), target :: sys
    type(cvode_solver) :: solver
    type(cvode_options) :: opts
    type(cvode_stats) :: stats
    type(error_type), allocatable :: error
    real(dp) :: tout, stops(3)
    integer :: k, i
    stops = [2.05_dp, 4.3_dp, 4.300001_dp]
    opts = cvode_options(rtol=1.0e-7_dp, atol=1.0e-9_dp, t_final=6.0_dp)
    call solver%init(sys, 0.0_dp, [1.0_dp, 0.0_dp, 0.5_dp, 0.0_dp], opts, error)
    call check(.not. allocated(error), "init")
    k = 1
    call solver%set_stop_time(stops(k), error)
    do i = 1, 60
      tout = 0.1_dp*i
      do while (solver%t < tout .and. .not. allocated(error))
        call solver%advance(tout, error, observer=obs)   ! (it returns at a stop time before tout)
        if (k > 3 .or. allocated(error)) cycle
        if (solver%t >= stops(k)) then
          if (k <= 2) call solver%reinit(solver%t, solver%y, error)
          k = k + 1
          if (k <= 3 .and. .not. allocated(error)) call solver%set_stop_time(stops(k), error)
        end if
      end do
    end do
    call check(.not. allocated(error), "the run to 6 s")
    stats = solver%stats()
    stretches = int(stats%steps)
    call solver%free()
  end subroutine run
end program test_lazy_interpolant
