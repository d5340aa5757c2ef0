!> Clearance of the rocket from the carrier's empennage (or the ramp edge): the
!> smallest distance from the aircraft's horizontal tail to the rocket's
!> surface, and its rate of change, whose rising zero is a local minimum of the
!> clearance (an event of the launch scene's integrators, so that the minimum is
!> exact and not the smallest of the sampled outputs).
!>
!> The tail is the segment across the aircraft's z axis through the empennage
!> point (`&bay tail_x, tail_y`), `tail_half_span` each way (0: the point
!> alone).  The rocket is its body cylinder (the axis segment, less the radius)
!> and its fins, each a flat trapezoid (the planform of `&rocket fin_*`) in the
!> plane of the axis at its roll angle: four fins in X at 45, 135, 225, 315 deg
!> from the rocket's y axis towards z, three at 0, 120, 240 deg (one along +y).
!> The clearance is the least of the pieces' distances (each exact: the
!> closest points of two segments, of a segment and a convex plate); its rate
!> is (p - q).(v_p - v_q)/|p - q| of the nearest piece, p and q its closest
!> points as material points of the aircraft and the rocket (the distance is
!> stationary in their positions on their pieces).  Where the nearest piece
!> changes the least has a kink, and its rate jumps down (the piece that takes
!> over was approaching faster): a kink is never a local minimum, so every
!> minimum is a rising zero of the rate of one piece.
module airlaunch_clearance
  use airlaunch_kinds, only: dp, pi
  use airlaunch_rigid_body, only: rigid_body
  implicit none
  private
  public :: clearance_geometry, clearance, clearance_rate, segment_distance, set_fins, max_fins
  public :: segment_segment, point_trapezoid, segment_trapezoid

  integer, parameter :: max_fins = 4

  !> Where the tail and the rocket's surface are, in their bodies' axes.
  type :: clearance_geometry
    real(dp) :: point(3) = 0.0_dp   !< the tail's centre (empennage point), aircraft axes [m]
    real(dp) :: half_span = 0.0_dp  !< the tail's half span along the aircraft's z axis [m]
    real(dp) :: nose(3) = 0.0_dp    !< the rocket's nose on its axis, rocket axes [m]
    real(dp) :: aft(3) = 0.0_dp     !< the rocket's aft end on its axis, rocket axes [m]
    real(dp) :: radius = 0.0_dp     !< the rocket's radius [m]
    integer :: fin_count = 0        !< 0 (no fins), 3 or 4
    !> a fin's planform in its plane: (x rocket axes, distance from the axis)
    !> of its root's leading and trailing edges, its tip's trailing and leading edges [m]
    real(dp) :: fin(2, 4) = 0.0_dp
    real(dp) :: roll(2, max_fins) = 0.0_dp  !< each fin's span direction, (y, z) rocket axes
  end type clearance_geometry

contains

  !> The rocket's fins in `geom`: `count` (0, 3, 4) trapezoids, root chord
  !> `root_chord` at the radius with its leading edge at x = `root_le_x` (rocket
  !> axes), tip chord `tip_chord` at `semi_span` further out, its leading edge
  !> `sweep` aft of the root's.
  pure subroutine set_fins(geom, count, root_le_x, root_chord, tip_chord, sweep, semi_span)
    type(clearance_geometry), intent(inout) :: geom
    integer, intent(in) :: count
    real(dp), intent(in) :: root_le_x, root_chord, tip_chord, sweep, semi_span
    real(dp) :: phi0
    integer :: k
    geom%fin_count = 0
    if (count /= 3 .and. count /= 4) return
    geom%fin_count = count
    geom%fin(:, 1) = [root_le_x, geom%radius]
    geom%fin(:, 2) = [root_le_x - root_chord, geom%radius]
    geom%fin(:, 3) = [root_le_x - sweep - tip_chord, geom%radius + semi_span]
    geom%fin(:, 4) = [root_le_x - sweep, geom%radius + semi_span]
    phi0 = merge(pi/4, 0.0_dp, count == 4)
    do k = 1, count
      geom%roll(:, k) = [cos(phi0 + 2*pi*(k - 1)/count), sin(phi0 + 2*pi*(k - 1)/count)]
    end do
  end subroutine set_fins

  !> Clearance [m] of the rocket (body `rocket`) from the tail of `aircraft`.
  pure real(dp) function clearance(geom, aircraft, rocket) result(c)
    type(clearance_geometry), intent(in) :: geom
    type(rigid_body), intent(in) :: aircraft, rocket
    real(dp) :: pa(3), qr(3)
    call nearest(geom, aircraft, rocket, c, pa, qr)
  end function clearance

  !> Its rate [m/s]: (p - q).(v_p - v_q)/|p - q| of the nearest piece, p and
  !> q its closest points (q on the axis for the body), v_p, v_q the bodies'
  !> velocities at those material points.
  pure real(dp) function clearance_rate(geom, aircraft, rocket) result(rate)
    type(clearance_geometry), intent(in) :: geom
    type(rigid_body), intent(in) :: aircraft, rocket
    real(dp) :: c, pa(3), qr(3), d(3)
    call nearest(geom, aircraft, rocket, c, pa, qr)
    d = aircraft%point_position(pa) - rocket%point_position(qr)
    rate = 0.0_dp
    if (norm2(d) > 0.0_dp) rate = dot_product(d, aircraft%point_velocity(pa) - &
      rocket%point_velocity(qr))/norm2(d)
  end function clearance_rate

  !> The clearance `c` and the nearest piece's closest points: `pa` on the
  !> tail (aircraft axes), `qr` on the rocket (rocket axes; on the axis when
  !> the body is nearest).
  pure subroutine nearest(geom, aircraft, rocket, c, pa, qr)
    type(clearance_geometry), intent(in) :: geom
    type(rigid_body), intent(in) :: aircraft, rocket
    real(dp), intent(out) :: c, pa(3), qr(3)
    real(dp) :: a(3), b(3), e1(3), e2(3), s, t, x1(3), x2(3), y1(3), y2(3), d, qu, qw
    integer :: k
    a = rocket%point_position(geom%nose)
    b = rocket%point_position(geom%aft)
    ! the tail's ends, earth frame (one point without a span)
    e1 = aircraft%point_position(geom%point - [0.0_dp, 0.0_dp, geom%half_span])
    e2 = aircraft%point_position(geom%point + [0.0_dp, 0.0_dp, geom%half_span])
    ! the body: the tail's distance from the axis, less the radius
    if (geom%half_span > 0.0_dp) then
      call segment_segment(e1, e2, a, b, t, s)
      c = norm2(e1 + t*(e2 - e1) - (a + s*(b - a))) - geom%radius
    else
      t = 0.5_dp
      s = segment_fraction(e1, a, b)
      c = norm2(e1 - (a + s*(b - a))) - geom%radius
    end if
    pa = geom%point + [0.0_dp, 0.0_dp, (2*t - 1)*geom%half_span]
    qr = geom%nose + s*(geom%aft - geom%nose)
    if (geom%fin_count == 0) return
    ! the fins: the tail's ends in rocket axes, then in each fin's plane
    ! (along the axis, along the span, normal to the fin)
    y1 = in_rocket_axes(e1, rocket)
    y2 = in_rocket_axes(e2, rocket)
    do k = 1, geom%fin_count
      x1 = in_fin_plane(y1, geom%roll(:, k))
      x2 = in_fin_plane(y2, geom%roll(:, k))
      call segment_trapezoid(x1, x2, geom%fin, d, t, qu, qw)
      if (d < c) then
        c = d
        pa = geom%point + [0.0_dp, 0.0_dp, (2*t - 1)*geom%half_span]
        qr = [qu, qw*geom%roll(1, k), qw*geom%roll(2, k)]
      end if
    end do
  end subroutine nearest

  !> An earth point `x` in the axes of `body`, from its CG (C^T (x - r),
  !> written out: matmul of a transpose allocated a temporary here).
  pure function in_rocket_axes(x, body) result(y)
    real(dp), intent(in) :: x(3)
    type(rigid_body), intent(in) :: body
    real(dp) :: y(3), d(3)
    d = x - body%r
    y = [dot_product(body%c(:, 1), d), dot_product(body%c(:, 2), d), dot_product(body%c(:, 3), d)]
  end function in_rocket_axes

  !> A point `y` of rocket axes in the plane of a fin whose span runs along
  !> (0, e): (along the axis, along the span, normal to the fin).
  pure function in_fin_plane(y, e) result(x)
    real(dp), intent(in) :: y(3), e(2)
    real(dp) :: x(3)
    x = [y(1), e(1)*y(2) + e(2)*y(3), -e(2)*y(2) + e(1)*y(3)]
  end function in_fin_plane

  !> Distance `d` of the segment [x1, x2] from the convex quadrilateral plate
  !> `v` (vertices in order, in the plane z = 0; a zero-length side allowed),
  !> the segment's parameter `t` in [0, 1] and the plate's point (qu, qw) of
  !> the closest pair.  The least over the segment's ends against the plate,
  !> the segment against the plate's sides, and 0 where it pierces the plate.
  pure subroutine segment_trapezoid(x1, x2, v, d, t, qu, qw)
    real(dp), intent(in) :: x1(3), x2(3), v(2, 4)
    real(dp), intent(out) :: d, t, qu, qw
    real(dp) :: dk, u, w, s, tk, x(3), a(3), b(3)
    integer :: i
    call point_trapezoid(x1, v, d, qu, qw)
    t = 0.0_dp
    if (all(x2 == x1)) return
    call point_trapezoid(x2, v, dk, u, w)
    if (dk < d) then
      d = dk; t = 1.0_dp; qu = u; qw = w
    end if
    do i = 1, 4
      a = [v(:, i), 0.0_dp]
      b = [v(:, modulo(i, 4) + 1), 0.0_dp]
      call segment_segment(x1, x2, a, b, tk, s)
      dk = norm2(x1 + tk*(x2 - x1) - (a + s*(b - a)))
      if (dk < d) then
        d = dk; t = tk; qu = a(1) + s*(b(1) - a(1)); qw = a(2) + s*(b(2) - a(2))
      end if
    end do
    if (x1(3)*x2(3) <= 0.0_dp .and. x1(3) /= x2(3)) then
      tk = x1(3)/(x1(3) - x2(3))
      x = x1 + tk*(x2 - x1)
      if (inside(x(1:2), v)) then
        d = 0.0_dp; t = tk; qu = x(1); qw = x(2)
      end if
    end if
  end subroutine segment_trapezoid

  !> Distance `d` of the point `x` from the plate `v` (segment_trapezoid) and
  !> the plate's nearest point (qu, qw): its projection where that is inside,
  !> else the nearest point of its sides.
  pure subroutine point_trapezoid(x, v, d, qu, qw)
    real(dp), intent(in) :: x(3), v(2, 4)
    real(dp), intent(out) :: d, qu, qw
    real(dp) :: dk, s, a(3), b(3), q(3)
    integer :: i
    if (inside(x(1:2), v)) then
      d = abs(x(3)); qu = x(1); qw = x(2)
      return
    end if
    d = huge(1.0_dp); qu = v(1, 1); qw = v(2, 1)
    do i = 1, 4
      a = [v(:, i), 0.0_dp]
      b = [v(:, modulo(i, 4) + 1), 0.0_dp]
      s = segment_fraction(x, a, b)
      q = a + s*(b - a)
      dk = norm2(x - q)
      if (dk < d) then
        d = dk; qu = q(1); qw = q(2)
      end if
    end do
  end subroutine point_trapezoid

  !> The plane point `x` is inside the convex polygon `v` (or on its sides):
  !> on the inner side of every side (a zero-length side passes).
  pure logical function inside(x, v) result(yes)
    real(dp), intent(in) :: x(2), v(2, 4)
    real(dp) :: area, side
    integer :: i, j
    area = 0.0_dp
    do i = 1, 4
      j = modulo(i, 4) + 1
      area = area + v(1, i)*v(2, j) - v(1, j)*v(2, i)
    end do
    yes = area /= 0.0_dp
    do i = 1, 4
      j = modulo(i, 4) + 1
      side = (v(1, j) - v(1, i))*(x(2) - v(2, i)) - (v(2, j) - v(2, i))*(x(1) - v(1, i))
      if (side*area < 0.0_dp) yes = .false.
    end do
  end function inside

  !> Parameters s, t in [0, 1] of the closest points p1 + s (q1 - p1), p2 +
  !> t (q2 - p2) of two segments (Ericson, Real-Time Collision Detection,
  !> 5.1.9; parallel segments: one closest pair of the many).
  pure subroutine segment_segment(p1, q1, p2, q2, s, t)
    real(dp), intent(in) :: p1(3), q1(3), p2(3), q2(3)
    real(dp), intent(out) :: s, t
    real(dp) :: d1(3), d2(3), r(3), a, e, f, b, c, denom
    d1 = q1 - p1; d2 = q2 - p2; r = p1 - p2
    a = dot_product(d1, d1); e = dot_product(d2, d2); f = dot_product(d2, r)
    s = 0.0_dp; t = 0.0_dp
    if (a <= 0.0_dp .and. e <= 0.0_dp) return
    if (a <= 0.0_dp) then
      t = clamp01(f/e)
      return
    end if
    c = dot_product(d1, r)
    if (e <= 0.0_dp) then
      s = clamp01(-c/a)
      return
    end if
    b = dot_product(d1, d2)
    denom = a*e - b*b
    if (denom > 0.0_dp) s = clamp01((b*f - c*e)/denom)
    t = (b*s + f)/e
    if (t < 0.0_dp) then
      t = 0.0_dp; s = clamp01(-c/a)
    else if (t > 1.0_dp) then
      t = 1.0_dp; s = clamp01((b - c)/a)
    end if
  end subroutine segment_segment

  pure real(dp) function clamp01(x) result(y)
    real(dp), intent(in) :: x
    y = max(0.0_dp, min(1.0_dp, x))
  end function clamp01

  !> Distance of p from the segment [a, b].
  pure real(dp) function segment_distance(p, a, b) result(dist)
    real(dp), intent(in) :: p(3), a(3), b(3)
    dist = norm2(p - (a + segment_fraction(p, a, b)*(b - a)))
  end function segment_distance

  !> The parameter s in [0, 1] of the point of [a, b] nearest to p (0 if the
  !> segment is a point, e.g. a geometry left unset).
  pure real(dp) function segment_fraction(p, a, b) result(s)
    real(dp), intent(in) :: p(3), a(3), b(3)
    real(dp) :: ab2
    s = 0.0_dp
    ab2 = dot_product(b - a, b - a)
    if (ab2 > 0.0_dp) s = max(0.0_dp, min(1.0_dp, dot_product(p - a, b - a)/ab2))
  end function segment_fraction
end module airlaunch_clearance
