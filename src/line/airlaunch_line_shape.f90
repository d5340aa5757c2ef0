!> Initial shapes of a line between its two end positions: straight (uniform
!> strain, possibly negative = slack) or sagged (a parabola of given midspan sag
!> below the chord, nodes at equal arc-length spacing).  The parabola's length
!> is fixed by chord and sag, not by the line's length: its strain is
!> parabola_length/L - 1 (the caller checks it).  The nodes sit on the
!> parabola, so for even N node N/2 is its vertex and the sag is met exactly;
!> for odd N the middle segment's chord spans the vertex and lies above it by
!> about sag/N^2 (exactly: the nodes at arc fraction 1/2 -+ 1/(2N)).
module airlaunch_line_shape
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  implicit none
  private
  public :: straight_shape, sagged_shape, parabola_length, parabola_sag_for_length

contains

  !> Nodes x(3,0:n) evenly spaced on the segment from xa to xb.
  pure subroutine straight_shape(n, xa, xb, x)
    integer, intent(in) :: n               !< number of segments
    real(dp), intent(in) :: xa(3), xb(3)   !< end positions [m]
    real(dp), intent(out) :: x(:, 0:)      !< node positions (3, 0:n) [m]
    integer :: k
    do k = 0, n
      x(:, k) = xa + (xb - xa)*(real(k, dp)/n)
    end do
  end subroutine straight_shape

  !> Arc length [m] of the parabola over a chord c [m] with midspan sag f [m]:
  !> (c/2) sqrt(1 + 16 r^2) + c asinh(4 r)/(8 r), r = f/c (c for f = 0).
  pure real(dp) function parabola_length(chord, sag) result(s)
    real(dp), intent(in) :: chord   !< chord length c > 0 [m]
    real(dp), intent(in) :: sag     !< midspan sag f >= 0 [m]
    real(dp) :: r
    r = sag/chord
    if (r < 1.0e-6_dp) then
      s = chord*(1.0_dp + 8.0_dp/3.0_dp*r*r)   ! the series: the closed form cancels
    else
      s = 0.5_dp*chord*sqrt(1.0_dp + 16.0_dp*r*r) + chord*asinh(4.0_dp*r)/(8.0_dp*r)
    end if
  end function parabola_length

  !> Sag [m] of the parabola of arc length `length` over a chord c (bisection;
  !> the length grows with the sag); 0 if length <= c.
  pure real(dp) function parabola_sag_for_length(chord, length) result(f)
    real(dp), intent(in) :: chord    !< chord length c > 0 [m]
    real(dp), intent(in) :: length   !< arc length [m]
    real(dp) :: lo, hi
    integer :: i
    f = 0.0_dp
    if (length <= chord) return
    lo = 0.0_dp
    hi = length
    do i = 1, 200
      f = 0.5_dp*(lo + hi)
      if (parabola_length(chord, f) > length) then
        hi = f
      else
        lo = f
      end if
    end do
  end function parabola_sag_for_length

  !> Nodes x(3,0:n) at equal arc length on the parabola through xa and xb with
  !> midspan sag `sag` [m] perpendicular to the chord, downwards (towards -y) in
  !> the vertical plane of the chord (towards -x if the chord is vertical).
  subroutine sagged_shape(n, xa, xb, sag, x, error)
    integer, intent(in) :: n                               !< number of segments
    real(dp), intent(in) :: xa(3), xb(3)                   !< end positions [m]
    real(dp), intent(in) :: sag                            !< midspan sag [m]
    real(dp), intent(out) :: x(:, 0:)                      !< node positions (3, 0:n) [m]
    type(error_type), allocatable, intent(inout) :: error  !< set if the chord is zero
    integer, parameter :: per_seg = 40
    integer :: m, i, k
    real(dp) :: e(3), down(3), chord, target, frac
    real(dp), allocatable :: p(:, :), s(:)
    chord = norm2(xb - xa)
    if (chord <= 0.0_dp) then
      call fatal_error(error, "line_scene: initial_shape = 'sag' needs two distinct end positions " // &
        "(chord = " // str(chord) // " m)")
      return
    end if
    e = (xb - xa)/chord
    down = [0.0_dp, -1.0_dp, 0.0_dp]
    if (abs(e(2)) > 1.0_dp - 1.0e-9_dp) down = [-1.0_dp, 0.0_dp, 0.0_dp]
    down = down - dot_product(down, e)*e
    down = down/norm2(down)
    m = per_seg*n
    allocate(p(3, 0:m), s(0:m))
    s(0) = 0.0_dp
    do i = 0, m
      frac = real(i, dp)/m
      p(:, i) = xa + frac*(xb - xa) + 4.0_dp*sag*frac*(1.0_dp - frac)*down
      if (i > 0) s(i) = s(i-1) + norm2(p(:, i) - p(:, i-1))
    end do
    x(:, 0) = xa
    x(:, n) = xb
    i = 1
    do k = 1, n - 1
      target = s(m)*real(k, dp)/n
      do while (s(i) < target)
        i = i + 1
      end do
      frac = (target - s(i-1))/(s(i) - s(i-1))
      x(:, k) = p(:, i-1) + frac*(p(:, i) - p(:, i-1))
    end do
  end subroutine sagged_shape
end module airlaunch_line_shape
