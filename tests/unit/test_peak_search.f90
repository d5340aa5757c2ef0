!> The running maximum between samples (airlaunch_peak_search) against an
!> analytic function, f(t) = exp(-t) cos(5 (t - 1)): its largest value on
!> [0, 3] is at t1 = 1 - atan(0.2)/5, f(t1) = exp(-t1) 5/sqrt(26), between the
!> samples of an uneven grid (as a solver's steps): the largest sample is
!> 1e-4 below it (what the output records gave), the tracker finds it to
!> rounding; a sequence that ends rising (the function may jump after it) or
!> starts falling keeps its end value.
!>
!> The step observer (airlaunch_step_maxima) on synthetic steps whose
!> interpolants are given: a bracket over two steps whose junction sample is a
!> valley between a peak in each step (1.2 at t = 1.5 in the first, 2.0 at
!> t = 2.4 in the second; samples 0.9, 0.9, -0.475 at t = 1, 2, 3).  Each
!> step is searched on its own interpolant, so the larger peak is found; one
!> Brent search over the whole bracket followed the samples' parabola to the
!> first step and returned 1.2.
!>
!> The peak's first time (`first_time`): a tension held at its maximum over a
!> plateau (a drift of 1e-10 relative, rising then falling: the largest
!> sample at t = 0.26 s, the plateau from t = 0) is reported at the plateau's
!> start, not where round-off put the largest sample; against a brute force
!> over every value offered (random values and times, offered in random
!> order, as refined maxima come after the samples that bracket them): the
!> earliest time of a value within the band of the maximum, exactly while
!> the records fit (32), never earlier beyond.
module peak_search_test_observer
  use airlaunch_kinds, only: dp
  use airlaunch_step_maxima, only: maxima_observer
  implicit none
  private
  public :: state_observer

  !> The quantity is the (one-component) state itself.
  type, extends(maxima_observer) :: state_observer
  contains
    procedure :: values => state_values
  end type state_observer

contains

  subroutine state_values(self, t, q, ok)
    class(state_observer), intent(inout) :: self
    real(dp), intent(in) :: t
    real(dp), intent(out) :: q(:)
    logical, intent(out) :: ok
    q(1) = self%y(1) + 0.0_dp*t
    ok = .true.
  end subroutine state_values
end module peak_search_test_observer

program test_peak_search
  use airlaunch_kinds, only: dp
  use airlaunch_strings, only: str
  use airlaunch_peak_search
  use airlaunch_cvode, only: step_polynomial
  use peak_search_test_observer, only: state_observer
  use testing
  implicit none
  real(dp) :: t1, f1, t, sample_max
  type(peak_tracker) :: trk
  type(max_search) :: search
  type(peak_bracket) :: br
  integer :: k, refinements

  t1 = 1.0_dp - atan(0.2_dp)/5
  f1 = exp(-t1)*5/sqrt(26.0_dp)

  call section("the maximum between samples")
  refinements = 0
  sample_max = -huge(1.0_dp)
  t = 0.0_dp
  k = 0
  do while (t <= 3.0_dp)
    sample_max = max(sample_max, f(t))
    ! the piece numbers stand for the steps' interpolants (here all f itself)
    if (trk%push(t, f(t), k, br)) call refine(br)
    k = k + 1
    t = t + 0.05_dp + 0.08_dp*modulo(0.37_dp*k, 1.0_dp)   ! uneven steps of 0.05-0.13
  end do
  if (trk%close(br)) call refine(br)
  call check(sample_max < f1 - 1.0e-5_dp, "the samples miss the peak by " // str(f1 - sample_max) // &
    " (the test needs a peak between samples)")
  call check_close(trk%best, f1, "largest value", rel=1.0e-13_dp)
  call check_close(trk%t_best, t1, "its time", abs=1.0e-7_dp)
  call check(trk%best >= sample_max, "not below any sample")
  call check(refinements >= 1 .and. refinements <= 3, "refinements: " // str(refinements) // &
    " (the local maxima that could beat the running one)")

  call section("a sequence that ends rising keeps its end")
  trk = peak_tracker()
  t = 0.2_dp
  do while (t <= 0.9_dp + 1.0e-12_dp)
    if (trk%push(t, f(t), 1, br)) call refine(br)
    t = t + 0.1_dp
  end do
  if (trk%close(br)) call refine(br)
  call check_close(trk%best, f(0.9_dp), "largest value at the end", rel=1.0e-15_dp)
  ! f still rises into the end: one probe just inside settles it (a golden-
  ! section search towards the end took ~30 evaluations, at every end of the
  ! rigidized coupling's outer steps)
  call check(search%evaluations == 1, "settled by one probe inside the end (" // &
    str(search%evaluations) // " evaluations)")

  call section("a peak just inside the end of a sequence is still found")
  ! samples at 0.9 and at tb, the peak t1 a 0.003 of the interval before tb:
  ! the probe (a 0.001 inside) sees f rise, and the search goes on to t1
  trk = peak_tracker()
  t = (t1 - 0.0027_dp)/0.997_dp
  call check(f(t) > f(0.9_dp) .and. t > t1, "tb = " // str(t) // " past the peak, its sample the larger")
  if (trk%push(0.9_dp, f(0.9_dp), 1, br)) call refine(br)
  if (trk%push(t, f(t), 1, br)) call refine(br)
  if (trk%close(br)) call refine(br)
  call check_close(trk%best, f1, "largest value: the peak", rel=1.0e-13_dp)
  call check(trk%best > f(t), "above the end's sample by " // str(trk%best - f(t)))

  call section("a sequence that starts falling keeps its start")
  trk = peak_tracker()
  t = 1.0_dp
  do while (t <= 1.5_dp)
    if (trk%push(t, f(t), 1, br)) call refine(br)
    t = t + 0.1_dp
  end do
  if (trk%close(br)) call refine(br)
  call check_close(trk%best, f(1.0_dp), "largest value at the start", rel=1.0e-15_dp)
  call check(search%evaluations == 1, "settled by one probe inside the start (" // &
    str(search%evaluations) // " evaluations)")

  call section("a maximum inside a single interval")
  ! two samples and the middle one (the first and last step of a sequence)
  trk = peak_tracker()
  if (trk%push(0.9_dp, f(0.9_dp), 1, br)) call refine(br)
  if (trk%push(0.99_dp, f(0.99_dp), 1, br)) call refine(br)
  if (trk%push(1.08_dp, f(1.08_dp), 1, br)) call refine(br)
  if (trk%close(br)) call refine(br)
  call check_close(trk%best, f1, "largest value", rel=1.0e-13_dp)

  call section("the step observer: a peak in each of a bracket's two steps")
  call two_peaks()

  call section("the first time within the band: a plateau")
  call plateau()

  call section("the first time within the band: against a brute force")
  call first_time_brute_force()

  call finish()

contains

  !> Four steps [0,1], [1,2], [2,3], [3,4]: y = 0.9 t, 1.2 - 1.2 (t - 1.5)^2,
  !> 2 - 6.875 (t - 2.4)^2, then linear to -1 (each interpolant as CVODE's:
  !> Taylor coefficients at its step's end).
  subroutine two_peaks()
    type(state_observer) :: obs
    type(step_polynomial) :: p
    type(peak_tracker), pointer :: trk2(:)
    allocate(trk2(1))
    obs%trk => trk2
    obs%needs_rate = .false.
    allocate(p%c(1, 0:2))
    p%order = 2
    call show(obs, p, 1.0_dp, [0.9_dp, 0.9_dp, 0.0_dp], 0.0_dp, .true., .false.)
    call show(obs, p, 2.0_dp, [0.9_dp, -1.2_dp, -1.2_dp], 1.0_dp, .false., .false.)
    call show(obs, p, 3.0_dp, [-0.475_dp, -8.25_dp, -6.875_dp], 2.0_dp, .false., .false.)
    call show(obs, p, 4.0_dp, [-1.0_dp, -0.525_dp, 0.0_dp], 3.0_dp, .false., .true.)
    call check_close(trk2(1)%best, 2.0_dp, "the larger peak, in the second step", rel=1.0e-12_dp)
    call check_close(trk2(1)%t_best, 2.4_dp, "its time", abs=1.0e-6_dp)
    deallocate(trk2)
  end subroutine two_peaks

  !> Samples every 20 ms of a plateau at 78 770 N drifting by 1e-10 relative
  !> (up to t = 0.26 s, then down), then a fall after t = 0.72 s; band 1e-5
  !> (an integration tolerance).  The largest sample is at 0.26 s; the first
  !> within the band at 0: reported there.  With band 0 the largest sample's
  !> time.  A record (not a candidate) cannot move the time.
  subroutine plateau()
    type(peak_tracker) :: p
    real(dp) :: tt, q
    integer :: i
    p%band = 1.0e-5_dp
    do i = 0, 60
      tt = 0.02_dp*i
      q = 78770.0_dp*(1 + 1.0e-10_dp*(0.26_dp - abs(tt - 0.26_dp)))
      if (tt > 0.72_dp) q = 78770.0_dp - 2000*(tt - 0.72_dp)
      call p%offer(tt, q)
    end do
    call p%offer(0.1234_dp, 78770.0_dp, candidate=.false.)   ! an output record
    call check_close(p%t_best, 0.26_dp, "the largest sample at 0.26 s", abs=1.0e-12_dp)
    call check(p%first_time() == 0.0_dp, "the plateau's first time: " // str(p%first_time()) // " s")
    ! the rising samples 0 .. 0.26 s form the staircase; the falling ones are
    ! later and lower, the record no candidate
    call check(p%n_rec == 14, "records kept: " // str(p%n_rec) // " (the 14 rising samples)")
    p%band = 0.0_dp
    call check_close(p%first_time(), 0.26_dp, "band 0: the largest sample's time", abs=1.0e-12_dp)
    ! a later peak above the band moves the time to it
    p%band = 1.0e-5_dp
    call p%offer(1.5_dp, 78770.0_dp*(1 + 2.0e-5_dp))
    call check(p%first_time() == 1.5_dp, "a later peak 2e-5 higher: at its time (" // str(p%first_time()) // ")")
  end subroutine plateau

  !> Random offers (values in [0, 1], or within 1e-3 of 1 to crowd the band;
  !> times in [0, 1], offered in random order) against the earliest time of a
  !> value within band 1e-3 of the maximum: equal while at most 32 records were
  !> needed (with 40 offers), never earlier and never past the maximum's time
  !> with 400.
  subroutine first_time_brute_force()
    integer, parameter :: n_max = 400
    type(peak_tracker) :: p
    real(dp) :: ts(n_max), qs(n_max), r(2), exact, floor, got
    integer :: trial, i, n, bad_small, bad_large, differ
    call fixed_seed()
    bad_small = 0
    bad_large = 0
    differ = 0
    do trial = 1, 400
      n = merge(40, n_max, trial <= 200)
      p = peak_tracker()
      p%band = 1.0e-3_dp
      do i = 1, n
        call random_number(r)
        ts(i) = r(1)
        qs(i) = merge(1 - 1.0e-3_dp*r(2)*2, r(2), mod(i, 2) == 0)
        call p%offer(ts(i), qs(i))
      end do
      floor = maxval(qs(1:n))*(1 - 1.0e-3_dp)
      exact = minval(ts(1:n), mask=qs(1:n) >= floor)
      got = p%first_time()
      if (n <= 40) then
        if (got /= exact) bad_small = bad_small + 1
      else
        if (got < exact .or. got > ts(maxloc(qs(1:n), 1))) bad_large = bad_large + 1
        if (got /= exact) differ = differ + 1
      end if
    end do
    call check(bad_small == 0, "40 offers: the brute force's first time in every trial (" // str(bad_small) // &
      " of 200 differ)")
    call check(bad_large == 0, "400 offers: never before it nor after the maximum (" // str(bad_large) // &
      " of 200 outside; " // str(differ) // " later than it)")
    ! a staircase longer than the records: values i at times i (i = 1 .. 100), band
    ! 0.495 (floor 50.5): the first within is 51; kept records are merged, so a
    ! later one may answer, never an earlier one
    p = peak_tracker()
    p%band = 0.495_dp
    do i = 1, 100
      call p%offer(real(i, dp), real(i, dp))
    end do
    got = p%first_time()
    call check(p%n_rec <= max_records .and. got >= 51.0_dp .and. got <= 100.0_dp, &
      "a staircase of 100 in 32 records: first time " // str(got) // " (exact 51; records " // str(p%n_rec) // ")")
  end subroutine first_time_brute_force

  !> Show the observer the step [t_start, tn] with Taylor coefficients c at tn.
  subroutine show(obs, p, tn, c, t_start, restart, last)
    type(state_observer), intent(inout) :: obs
    type(step_polynomial), intent(inout) :: p
    real(dp), intent(in) :: tn, c(0:2), t_start
    logical, intent(in) :: restart, last
    p%tn = tn
    p%c(1, :) = c
    call obs%observe(p, t_start, tn, restart, last)
  end subroutine show

  pure real(dp) function f(t)
    real(dp), intent(in) :: t
    f = exp(-t)*cos(5*(t - 1))
  end function f

  subroutine refine(br)
    type(peak_bracket), intent(in) :: br
    real(dp) :: u
    refinements = refinements + 1
    call search%start(br, 1.0e-12_dp)
    do while (search%next(u))
      call check(u >= br%lo .and. u <= br%hi, "inside the bracket")
      call search%tell(f(u))
    end do
    call check(search%evaluations < 40, "evaluations: " // str(search%evaluations))
    call trk%offer(search%x, search%maximum())
  end subroutine refine

end program test_peak_search
