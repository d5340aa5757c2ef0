!> Maxima of functions of an integrator's state over every internal step, not
!> only at the output times: a step observer (airlaunch_cvode) that samples
!> each quantity at the steps' ends, brackets each discrete local maximum that
!> could beat the running one (airlaunch_peak_search's trackers) and refines it
!> on the CVODE interpolants of the two steps around it (Brent's search).  A
!> sequence of steps ends where the quantities may jump (an event, a stop time,
!> a restart, the end of the run); its first and last step also get a sample
!> at their middle (a sequence may be a single step with its maximum inside).
!> A bracket over two steps is searched on each step's interpolant apart.
!> A step's interpolant is read off CVODE whole (every CVodeGetDky) only if a
!> bracket may use it: a sample inside the step, a bracket at its end, or a
!> quantity rising into its end (the next sample or the sequence's close may
!> then bracket a maximum on it; a falling one never does); the other steps
!> are sampled at their end from its value (and rate) there alone - the same
!> samples, brackets and maxima bit for bit (test_lazy_interpolant).
!>
!> An extension says which quantities its integrator carries (`watches`) and
!> evaluates them at a time from the interpolated state self%y and its rate
!> self%dy (`values`); a quantity whose step-end samples are only estimates
!> that bracket its maxima (`estimated`: e.g. a load factor from the
!> interpolant's derivative) enters the maximum through refined values only.  The trackers (one per quantity) are the owner's: several observers
!> (integrators) may share them.
module airlaunch_step_maxima
  use airlaunch_kinds, only: dp
  use airlaunch_cvode, only: step_observer, step_polynomial
  use airlaunch_peak_search, only: peak_tracker, peak_bracket, max_search
  implicit none
  private
  public :: maxima_observer

  !> At most this many quantities per observer (work arrays of fixed size: an
  !> automatic array of unknown size would be a heap allocation every step)
  integer, parameter :: max_quantities = 8

  type, abstract, extends(step_observer) :: maxima_observer
    type(peak_tracker), pointer :: trk(:) => null()   !< one per quantity (the owner's)
    type(step_polynomial) :: piece(2)                 !< the last two stretches' interpolants
    integer :: cur = 2                                !< the latest piece
    real(dp), allocatable :: y(:), dy(:)              !< the state at the time asked for, its rate
    logical :: needs_rate = .true.                    !< `values` reads self%dy
    !> quantities whose step-end samples are estimates (only bracketing their maxima)
    logical :: estimated(max_quantities) = .false.
    !> what the evaluation under way is for: quantity `only` (0: all), and
    !> whether it is a step-end sample (an `estimated` quantity may be estimated)
    integer :: only = 0
    logical :: step_end_sample = .false.
    !> stretches whose whole interpolant was read off CVODE (a count: the others
    !> were sampled at their end only)
    integer :: whole_reads = 0
  contains
    procedure :: observe => maxima_observe
    procedure :: finish => maxima_finish
    procedure :: watches => maxima_watches
    procedure(values_interface), deferred :: values
  end type maxima_observer

  abstract interface
    !> The quantities q(m) at time t from the state self%y (rate self%dy) for
    !> every m the observer watches (self%only > 0: that one is enough, the
    !> others may be left -huge; self%step_end_sample: an `estimated` quantity
    !> may be estimated).  ok = .false. if the state cannot be evaluated.
    subroutine values_interface(self, t, q, ok)
      import :: maxima_observer, dp
      implicit none
      class(maxima_observer), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), intent(out) :: q(:)
      logical, intent(out) :: ok
    end subroutine values_interface
  end interface

contains

  !> Whether this observer's integrator carries quantity m (default: all).
  logical function maxima_watches(self, m)
    class(maxima_observer), intent(in) :: self
    integer, intent(in) :: m
    maxima_watches = m >= 1 .and. m <= size(self%trk)
  end function maxima_watches

  !> The quantities this observer's trackers hold (at most max_quantities:
  !> the work arrays are of that size).
  pure integer function n_quantities(self)
    class(maxima_observer), intent(in) :: self
    n_quantities = min(size(self%trk), max_quantities)
  end function n_quantities

  !> A stretch of the solution (airlaunch_cvode's step_observer): its end is
  !> the next sample of each quantity; a bracketed local maximum is refined.
  !> The stretch's whole interpolant is read off CVODE (fill) only where it is
  !> sampled inside, refined on, or may be later: a sample at its start or
  !> middle or an end before the step's, a bracket now, or a sequence that
  !> rises into its end (the next sample or the sequence's close may bracket
  !> a maximum there, on this piece).  The samples at a step's end need its
  !> value there (and its rate: the first derivative) only.
  subroutine maxima_observe(self, poly, t_start, t_end, restart, last)
    class(maxima_observer), intent(inout) :: self
    type(step_polynomial), intent(in) :: poly
    real(dp), intent(in) :: t_start, t_end
    logical, intent(in) :: restart, last
    real(dp) :: q(max_quantities), t
    type(peak_bracket) :: br
    logical :: ok, starts, est
    integer :: m, j, nq
    nq = n_quantities(self)
    if (restart) call self%finish()   ! the state may jump at a (re)start
    self%cur = 3 - self%cur
    if (.not. allocated(self%y)) allocate(self%y(size(poly%c, 1)), self%dy(size(poly%c, 1)))
    starts = .false.
    do m = 1, nq
      if (self%watches(m) .and. self%trk(m)%n == 0) starts = .true.
    end do
    call self%piece(self%cur)%copy(poly)
    if (starts .or. last .or. t_end /= poly%tn) then
      call whole_piece(self, poly)
    else if (self%needs_rate) then
      call self%piece(self%cur)%fill(1, from=poly)
    end if
    ! an `estimated` quantity is evaluated in full where the interpolant's
    ! derivative cannot bracket its maxima: a first-order stretch (a constant
    ! derivative) and the first stretch of a sequence, the first step after a
    ! (re)start, taken at order 1 (CVODE reports the next order for its
    ! interpolant, but the derivative is still about a secant there: in the
    ! rigidized coupling's snatch, estimates 3e-4 low hid a peak 1e-5 high)
    est = poly%order >= 2 .and. .not. starts
    if (starts) then
      ! a new sequence starts with the stretch's start
      call evaluate(self, t_start, self%cur, 0, est, q(1:nq), ok)
      if (ok) then
        do m = 1, nq
          if (self%watches(m) .and. self%trk(m)%n == 0) ok = self%trk(m)%push(t_start, q(m), self%cur, br, &
            value=.not. (est .and. self%estimated(m)))
        end do
      end if
    end if
    ! the sample at the stretch's end; in the first and the last stretch of a
    ! sequence also one at its middle (a sequence may be a single step - the
    ! rigidized coupling's outer steps -, with its maximum inside)
    do j = 1, 2
      t = t_end
      if (j == 1) t = 0.5_dp*(t_start + t_end)
      if (j == 1 .and. .not. (t > t_start .and. (starts .or. last))) cycle
      call evaluate(self, t, self%cur, 0, est, q(1:nq), ok)
      if (.not. ok) cycle
      do m = 1, nq
        if (.not. self%watches(m)) cycle
        if (self%trk(m)%push(t, q(m), self%cur, br, value=.not. (est .and. self%estimated(m)))) then
          call whole_piece(self, poly)
          call refine(self, m, br)
        end if
      end do
    end do
    do m = 1, nq
      if (.not. self%watches(m)) cycle
      if (self%trk(m)%rises_into(self%cur)) then
        call whole_piece(self, poly)
        exit
      end if
    end do
    if (last) call self%finish()
  end subroutine maxima_observe

  !> The current piece whole: the rest of its coefficients read off CVODE
  !> (`poly`, the step shown).
  subroutine whole_piece(self, poly)
    class(maxima_observer), intent(inout) :: self
    type(step_polynomial), intent(in) :: poly
    if (self%piece(self%cur)%whole()) return
    self%whole_reads = self%whole_reads + 1
    call self%piece(self%cur)%fill(from=poly)
  end subroutine whole_piece

  !> Close the observer's sequences (the quantities may jump after their end),
  !> refining a maximum at their end: at a (re)start, an event, a switch of
  !> integrator, the end of the run.
  subroutine maxima_finish(self)
    class(maxima_observer), intent(inout) :: self
    type(peak_bracket) :: br
    integer :: m
    if (.not. associated(self%trk)) return
    do m = 1, n_quantities(self)
      if (.not. self%watches(m)) cycle
      if (self%trk(m)%close(br)) call refine(self, m, br)
    end do
  end subroutine maxima_finish

  !> The maximum of quantity m in the bracket br, on the stretches' interpolants.
  !> A bracket over two steps (its best sample at their junction) is searched
  !> step by step, each on its own interpolant: a maximum inside each step is
  !> found, not only the one Brent's parabolas over the whole bracket reach.
  subroutine refine(self, m, br)
    class(maxima_observer), intent(inout) :: self
    integer, intent(in) :: m
    type(peak_bracket), intent(in) :: br
    type(peak_bracket) :: b
    real(dp) :: q(max_quantities)
    integer :: k, nq
    logical :: ok
    nq = n_quantities(self)
    b = br
    if (self%estimated(m)) then
      ! the samples only estimate it: its value at the bracket's best sample
      k = br%right
      if (k == 0) k = br%left
      call evaluate(self, br%x, k, m, .false., q(1:nq), ok)
      if (.not. ok) return
      b%fx = q(m)
    end if
    if (b%left /= b%right .and. b%lo < b%x .and. b%x < b%hi) then
      call search_piece(self, m, peak_bracket(lo=b%lo, x=b%x, hi=b%x, flo=b%flo, fx=b%fx, fhi=b%fx, &
        left=b%left, right=b%left))
      call search_piece(self, m, peak_bracket(lo=b%x, x=b%x, hi=b%hi, flo=b%fx, fx=b%fx, fhi=b%fhi, &
        left=b%right, right=b%right))
    else
      call search_piece(self, m, b)
    end if
  end subroutine refine

  !> Brent's search for the maximum of quantity m in the bracket b (piece
  !> b%left before b%x, b%right after), offered to its tracker.
  subroutine search_piece(self, m, b)
    class(maxima_observer), intent(inout) :: self
    integer, intent(in) :: m
    type(peak_bracket), intent(in) :: b
    type(max_search) :: search
    real(dp) :: t, q(max_quantities)
    integer :: k, nq
    logical :: ok
    nq = n_quantities(self)
    call search%start(b, 1.0e-12_dp)
    do while (search%next(t))
      k = b%right
      if (t < b%x .or. k == 0) k = b%left
      call evaluate(self, t, k, m, .false., q(1:nq), ok)
      if (.not. ok) return
      call search%tell(q(m))
    end do
    call self%trk(m)%offer(search%x, search%maximum())
  end subroutine search_piece

  !> The quantities at time t on piece k.
  subroutine evaluate(self, t, k, only, estimate, q, ok)
    class(maxima_observer), intent(inout) :: self
    real(dp), intent(in) :: t
    integer, intent(in) :: k, only
    logical, intent(in) :: estimate
    real(dp), intent(out) :: q(:)
    logical, intent(out) :: ok
    q = -huge(1.0_dp)
    if (self%needs_rate) then
      call self%piece(k)%eval(t, self%y, self%dy)
    else
      call self%piece(k)%eval(t, self%y)
    end if
    self%only = only
    self%step_end_sample = estimate
    call self%values(t, q, ok)
  end subroutine evaluate

end module airlaunch_step_maxima
