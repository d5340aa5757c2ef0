!> The largest value of a function of time known on a sequence of intervals
!> (the solver's internal steps, each with its interpolant), not only at the
!> samples: a running maximum over the intervals' ends that brackets each
!> discrete local maximum and refines it on the interpolants with Brent's
!> minimiser (golden section and parabolic steps; R. P. Brent, Algorithms for
!> Minimization without Derivatives, 1973, ch. 5), by reverse communication:
!> the caller evaluates the function where the search asks (library code
!> holds no function pointers and no state of its own).
!>
!>     if (tracker%push(t, q, piece, br)) then       ! a bracket worth refining
!>       call search%start(br, tol)
!>       do while (search%next(t))
!>         call search%tell(f(t))                     ! on piece br%left or br%right
!>       end do
!>       call tracker%offer(search%x, search%fx)
!>     end if
!>
!> The peak's time is reported as the first time the function came within the
!> tracker's `band` (relative; the owner's integration tolerance) of its
!> maximum (`first_time`): where a function holds its maximum over a plateau
!> (a steady tow tension before release), the place of the largest sample is
!> decided by round-off and the integrator's noise, the first time is not.
module airlaunch_peak_search
  use airlaunch_kinds, only: dp
  implicit none
  private
  public :: peak_bracket, max_search, peak_tracker, max_records

  !> A local maximum between samples: x (the largest sample) in [lo, hi], the
  !> samples' values, and the pieces (interpolants) left and right of x.
  type :: peak_bracket
    real(dp) :: lo = 0.0_dp, x = 0.0_dp, hi = 0.0_dp
    real(dp) :: flo = 0.0_dp, fx = 0.0_dp, fhi = 0.0_dp
    integer :: left = 0, right = 0   !< piece of [lo, x] and of [x, hi]
  end type peak_bracket

  !> Brent's one-dimensional search for the maximum of f on [a, b], one
  !> evaluation per `next`/`tell`.
  type :: max_search
    real(dp) :: a = 0.0_dp, b = 0.0_dp      !< the bracket
    real(dp) :: x = 0.0_dp, fx = 0.0_dp     !< the best point so far and -f there (Brent minimises -f)
    real(dp) :: w = 0.0_dp, fw = 0.0_dp     !< the second best
    real(dp) :: v = 0.0_dp, fv = 0.0_dp     !< the previous w
    real(dp) :: d = 0.0_dp, e = 0.0_dp      !< the last step and the one before
    real(dp) :: u = 0.0_dp                  !< the point asked for
    real(dp) :: tol = 0.0_dp                !< absolute tolerance on x
    integer :: evaluations = 0              !< f evaluations asked for
    !> the sample x at an end of the bracket (+1: at b, -1: at a, 0: inside):
    !> f is first probed just inside it, and if it is not larger there the
    !> end is the maximum (a function still rising into the end of a
    !> sequence of steps; golden sections towards an end take ~30 evaluations)
    integer :: edge = 0
    logical :: done = .false.               !< the edge probe settled it
  contains
    procedure :: start => search_start
    procedure :: next => search_next
    procedure :: tell => search_tell
    procedure :: maximum => search_maximum
  end type max_search

  !> At most this many candidates for a peak's first time are kept (work
  !> arrays of fixed size: no allocation per step); beyond, the two closest in
  !> value merge and a later time may answer, never an earlier one.
  integer, parameter :: max_records = 32

  !> Running maximum of samples at the ends of consecutive intervals; a
  !> sequence of intervals ends where the function may jump (`close`).
  type :: peak_tracker
    real(dp) :: best = -huge(1.0_dp)   !< the largest value offered
    real(dp) :: t_best = -1.0_dp       !< its time
    !> relative band of the peak: values within band*|best| of best are the
    !> same peak, whose time is the first of them (`first_time`)
    real(dp) :: band = 0.0_dp
    !> the values offered that may still be the first within the band: none
    !> is both later and not larger than another (times and values rise together)
    integer :: n_rec = 0
    real(dp) :: rec_t(max_records) = 0.0_dp, rec_q(max_records) = 0.0_dp
    integer :: n = 0                   !< samples of the open sequence (0: none)
    real(dp) :: ts(2) = 0.0_dp, qs(2) = 0.0_dp  !< its last two samples (2: the latest)
    integer :: piece(2) = 0            !< piece of the interval ending at each (0: none)
  contains
    procedure :: offer => tracker_offer
    procedure :: first_time => tracker_first_time
    procedure :: push => tracker_push
    procedure :: close => tracker_close
    procedure :: rises_into => tracker_rises_into
  end type peak_tracker

  !> golden-section fraction (3 - sqrt(5))/2
  real(dp), parameter :: cgold = 0.3819660112501051_dp
  !> relative resolution of x: sqrt(epsilon), the best a maximum's place allows
  real(dp), parameter :: xrel = 1.4901161193847656e-8_dp
  integer, parameter :: max_evaluations = 60

contains

  !> Search the maximum in [br%lo, br%hi] from the sample br%x (f = br%fx there;
  !> the end values seed the first parabola); tol: absolute tolerance on x.
  pure subroutine search_start(self, br, tol)
    class(max_search), intent(inout) :: self
    type(peak_bracket), intent(in) :: br
    real(dp), intent(in) :: tol
    ! Brent minimises: f enters negated
    self%a = br%lo
    self%b = br%hi
    self%x = br%x
    self%fx = -br%fx
    self%tol = max(tol, 0.0_dp)
    ! the ends as the second and third points (a parabola through the three samples first)
    if (br%flo >= br%fhi .and. br%lo < br%x) then
      self%w = br%lo; self%fw = -br%flo; self%v = br%hi; self%fv = -br%fhi
    else
      self%w = br%hi; self%fw = -br%fhi; self%v = br%lo; self%fv = -br%flo
    end if
    if (self%w == self%x) then
      self%w = self%v; self%fw = self%fv
    end if
    if (self%v == self%x) then
      self%v = self%w; self%fv = self%fw
    end if
    self%d = 0.0_dp
    self%e = br%hi - br%lo   ! a parabolic step is allowed at once
    self%evaluations = 0
    self%done = .false.
    self%edge = 0
    if (br%hi > br%lo) then
      if (br%x >= br%hi) self%edge = 1
      if (br%x <= br%lo) self%edge = -1
    end if
  end subroutine search_start

  !> The next point t to evaluate; false when the maximum is located
  !> (then x, fx: the maximum and f there).
  logical function search_next(self, t) result(more)
    class(max_search), intent(inout) :: self
    real(dp), intent(out) :: t
    real(dp) :: xm, tol1, tol2, p, q, r, etemp
    logical :: golden
    t = self%x
    more = .false.
    if (self%done .or. self%evaluations >= max_evaluations .or. .not. (self%b > self%a)) return
    if (self%edge /= 0 .and. self%evaluations == 0) then
      ! the probe just inside the end (a thousandth of the bracket, at least
      ! twice the resolution of x)
      self%u = self%x - self%edge*max(1.0e-3_dp*(self%b - self%a), 2*(xrel*abs(self%x) + self%tol/3))
      self%u = min(max(self%u, self%a), self%b)
      t = self%u
      self%evaluations = 1
      more = .true.
      return
    end if
    xm = 0.5_dp*(self%a + self%b)
    tol1 = xrel*abs(self%x) + self%tol/3
    tol2 = 2*tol1
    if (abs(self%x - xm) <= tol2 - 0.5_dp*(self%b - self%a)) return
    golden = .true.
    if (abs(self%e) > tol1) then
      r = (self%x - self%w)*(self%fx - self%fv)
      q = (self%x - self%v)*(self%fx - self%fw)
      p = (self%x - self%v)*q - (self%x - self%w)*r
      q = 2*(q - r)
      if (q > 0.0_dp) p = -p
      q = abs(q)
      etemp = self%e
      if (.not. (abs(p) >= abs(0.5_dp*q*etemp) .or. p <= q*(self%a - self%x) .or. p >= q*(self%b - self%x))) then
        golden = .false.
        self%e = self%d
        self%d = p/q
        self%u = self%x + self%d
        if (self%u - self%a < tol2 .or. self%b - self%u < tol2) self%d = sign(tol1, xm - self%x)
      end if
    end if
    if (golden) then
      if (self%x >= xm) then
        self%e = self%a - self%x
      else
        self%e = self%b - self%x
      end if
      self%d = cgold*self%e
    end if
    if (abs(self%d) >= tol1) then
      self%u = self%x + self%d
    else
      self%u = self%x + sign(tol1, self%d)
    end if
    self%u = min(max(self%u, self%a), self%b)
    t = self%u
    self%evaluations = self%evaluations + 1
    more = .true.
  end function search_next

  !> f at the point `next` asked for.
  pure subroutine search_tell(self, f)
    class(max_search), intent(inout) :: self
    real(dp), intent(in) :: f
    real(dp) :: fu
    fu = -f
    if (self%edge /= 0 .and. self%evaluations == 1 .and. fu >= self%fx) then
      self%done = .true.   ! not larger inside: the end is the maximum
      return
    end if
    if (fu <= self%fx) then
      if (self%u >= self%x) then
        self%a = self%x
      else
        self%b = self%x
      end if
      self%v = self%w; self%fv = self%fw
      self%w = self%x; self%fw = self%fx
      self%x = self%u; self%fx = fu
    else
      if (self%u < self%x) then
        self%a = self%u
      else
        self%b = self%u
      end if
      if (fu <= self%fw .or. self%w == self%x) then
        self%v = self%w; self%fv = self%fw
        self%w = self%u; self%fw = fu
      else if (fu <= self%fv .or. self%v == self%x .or. self%v == self%w) then
        self%v = self%u; self%fv = fu
      end if
    end if
  end subroutine search_tell

  !> The largest f found (at x).
  pure real(dp) function search_maximum(self) result(f)
    class(max_search), intent(in) :: self
    f = -self%fx
  end function search_maximum

  !> A value of the function at time t: the running maximum (the first of
  !> equal ones) and, unless `candidate` is false (a value that may only raise
  !> the maximum, e.g. an output record, whose times vary with the output
  !> cadence), a candidate for the first time within the band.  Offers may
  !> come in any time order (a refined maximum lies before the sample that
  !> bracketed it).
  pure subroutine tracker_offer(self, t, f, candidate)
    class(peak_tracker), intent(inout) :: self
    real(dp), intent(in) :: t, f
    logical, intent(in), optional :: candidate
    logical :: cand
    if (f > self%best) then
      self%best = f
      self%t_best = t
    end if
    cand = .true.
    if (present(candidate)) cand = candidate
    if (cand) call remember(self, t, f)
  end subroutine tracker_offer

  !> The lower edge of the peak's band for the peak value `top`.
  pure real(dp) function band_floor(self, top) result(floor)
    class(peak_tracker), intent(in) :: self
    real(dp), intent(in) :: top
    floor = top - self%band*abs(top)
  end function band_floor

  !> Keep (t, f) among the records if it may be the first value within the
  !> band of the final maximum: records form a staircase, each later and
  !> larger than the one before; a value below the band of the maximum so far
  !> never enters it again (the maximum only rises).
  pure subroutine remember(self, t, f)
    class(peak_tracker), intent(inout) :: self
    real(dp), intent(in) :: t, f
    real(dp) :: floor
    integer :: i, k, pos
    floor = band_floor(self, self%best)
    if (f < floor) return
    ! an earlier record at least as large makes (t, f) useless
    do i = 1, self%n_rec
      if (self%rec_t(i) <= t .and. self%rec_q(i) >= f) return
    end do
    ! drop the records below the band and those (t, f) makes useless
    k = 0
    pos = 0
    do i = 1, self%n_rec
      if (self%rec_q(i) < floor) cycle
      if (self%rec_t(i) >= t .and. self%rec_q(i) <= f) cycle
      k = k + 1
      self%rec_t(k) = self%rec_t(i)
      self%rec_q(k) = self%rec_q(i)
      if (self%rec_t(k) < t) pos = k
    end do
    self%n_rec = k
    ! full: merge the two neighbours closest in value (the later one goes; a
    ! threshold between them then finds the later time)
    if (self%n_rec == max_records) then
      k = 2
      do i = 3, self%n_rec
        if (self%rec_q(i) - self%rec_q(i - 1) < self%rec_q(k) - self%rec_q(k - 1)) k = i
      end do
      self%rec_t(k:self%n_rec - 1) = self%rec_t(k + 1:self%n_rec)
      self%rec_q(k:self%n_rec - 1) = self%rec_q(k + 1:self%n_rec)
      self%n_rec = self%n_rec - 1
      if (pos >= k) pos = pos - 1
    end if
    ! insert after the last earlier record
    self%rec_t(pos + 2:self%n_rec + 1) = self%rec_t(pos + 1:self%n_rec)
    self%rec_q(pos + 2:self%n_rec + 1) = self%rec_q(pos + 1:self%n_rec)
    self%rec_t(pos + 1) = t
    self%rec_q(pos + 1) = f
    self%n_rec = self%n_rec + 1
  end subroutine remember

  !> The first time a candidate value came within the band of the peak value
  !> `top` (default: the running maximum; an owner may hold a larger one, e.g.
  !> from its records); t_best if no candidate did (-1 before any offer).
  pure real(dp) function tracker_first_time(self, top) result(t)
    class(peak_tracker), intent(in) :: self
    real(dp), intent(in), optional :: top
    real(dp) :: floor
    integer :: i
    floor = band_floor(self, self%best)
    if (present(top)) floor = band_floor(self, max(top, self%best))
    t = self%t_best
    do i = 1, self%n_rec
      if (self%rec_q(i) >= floor) then
        t = self%rec_t(i)
        return
      end if
    end do
  end function tracker_first_time

  !> The next sample q at time t, the end of an interval on `piece` (the
  !> first sample of a sequence: its start, piece unused).  True with `br` if
  !> the sample before it is a local maximum that may exceed the running
  !> maximum between the samples.
  logical function tracker_push(self, t, q, piece, br, value) result(want)
    class(peak_tracker), intent(inout) :: self
    real(dp), intent(in) :: t, q
    integer, intent(in) :: piece
    type(peak_bracket), intent(out) :: br
    !> q is a value of the function (default), not only an estimate that
    !> brackets its maxima (then only refined values enter the maximum)
    logical, intent(in), optional :: value
    logical :: take
    want = .false.
    take = .true.
    if (present(value)) take = value
    if (take) call self%offer(t, q)
    select case (self%n)
    case (0)
      self%n = 1
      self%ts(2) = t; self%qs(2) = q; self%piece(2) = 0
      return
    case (1)
      ! the sequence's first sample, larger than the next: a maximum at its start
      if (self%qs(2) > q .and. t > self%ts(2)) then
        br = peak_bracket(lo=self%ts(2), x=self%ts(2), hi=t, flo=self%qs(2), fx=self%qs(2), fhi=q, &
          left=piece, right=piece)
        want = worth(self, br)
      end if
    case default
      if (self%qs(2) >= self%qs(1) .and. self%qs(2) > q) then
        br = peak_bracket(lo=self%ts(1), x=self%ts(2), hi=t, flo=self%qs(1), fx=self%qs(2), fhi=q, &
          left=self%piece(2), right=piece)
        want = worth(self, br)
      end if
    end select
    self%ts(1) = self%ts(2); self%qs(1) = self%qs(2); self%piece(1) = self%piece(2)
    self%ts(2) = t; self%qs(2) = q; self%piece(2) = piece
    self%n = 2
  end function tracker_push

  !> Whether the open sequence rises into its latest sample, the end of an
  !> interval on `piece` (piece > 0): then the next sample (push) or the
  !> sequence's close may bracket a maximum on that piece; otherwise no later
  !> bracket reaches into it.
  pure logical function tracker_rises_into(self, piece) result(rises)
    class(peak_tracker), intent(in) :: self
    integer, intent(in) :: piece
    rises = .false.
    if (self%n >= 2 .and. self%piece(2) == piece) rises = self%qs(2) >= self%qs(1)
  end function tracker_rises_into

  !> The sequence ends (the function may jump after its last sample): true
  !> with `br` if its last interval rises to its end (a maximum at or just
  !> before the end).
  logical function tracker_close(self, br) result(want)
    class(peak_tracker), intent(inout) :: self
    type(peak_bracket), intent(out) :: br
    want = .false.
    if (self%n >= 2) then
      if (self%qs(2) > self%qs(1) .and. self%ts(2) > self%ts(1)) then
        br = peak_bracket(lo=self%ts(1), x=self%ts(2), hi=self%ts(2), flo=self%qs(1), fx=self%qs(2), &
          fhi=self%qs(2), left=self%piece(2), right=self%piece(2))
        want = worth(self, br)
      end if
    end if
    self%n = 0
  end function tracker_close

  !> A bracket is refined if its peak could exceed the running maximum: the
  !> largest sample plus twice its rise over the lower neighbour (a parabola
  !> through three samples peaks less than that above its middle one, unless
  !> they are very unevenly spaced).
  pure logical function worth(self, br)
    class(peak_tracker), intent(in) :: self
    type(peak_bracket), intent(in) :: br
    real(dp) :: reach, h1, h2, s1, s2, curv
    reach = br%fx + 2*(br%fx - min(br%flo, br%fhi))
    ! and the vertex of the parabola through them (unevenly spaced samples)
    h1 = br%x - br%lo
    h2 = br%hi - br%x
    if (h1 > 0.0_dp .and. h2 > 0.0_dp) then
      s1 = (br%fx - br%flo)/h1
      s2 = (br%fhi - br%fx)/h2
      curv = (s2 - s1)/(h1 + h2)      ! half the second derivative
      if (curv < 0.0_dp) reach = max(reach, br%fx - (s1 + curv*h1)**2/(4*curv))
    end if
    worth = reach >= self%best .and. br%hi > br%lo
  end function worth

end module airlaunch_peak_search
