!> Clearance of the rocket from a point of the carrier (its empennage, the
!> ramp edge): the distance of the point from the rocket's axis segment less
!> the rocket's radius, and its rate of change, whose rising zero is a local
!> minimum of the clearance (an event of the launch scene's integrators, so
!> that the minimum is exact and not the smallest of the sampled outputs).
module airlaunch_clearance
  use airlaunch_kinds, only: dp
  use airlaunch_rigid_body, only: rigid_body
  implicit none
  private
  public :: clearance_geometry, clearance, clearance_rate, segment_distance

  !> Where the point and the rocket's axis are, in their bodies' axes.
  type :: clearance_geometry
    real(dp) :: point(3) = 0.0_dp   !< the carrier's point, aircraft axes [m]
    real(dp) :: nose(3) = 0.0_dp    !< the rocket's nose on its axis, rocket axes [m]
    real(dp) :: aft(3) = 0.0_dp     !< the rocket's aft end on its axis, rocket axes [m]
    real(dp) :: radius = 0.0_dp     !< the rocket's radius [m]
  end type clearance_geometry

contains

  !> Clearance [m] of the rocket (body `rocket`) from the point of `aircraft`.
  pure real(dp) function clearance(geom, aircraft, rocket) result(c)
    type(clearance_geometry), intent(in) :: geom
    type(rigid_body), intent(in) :: aircraft, rocket
    c = segment_distance(aircraft%point_position(geom%point), rocket%point_position(geom%nose), &
      rocket%point_position(geom%aft)) - geom%radius
  end function clearance

  !> Its rate [m/s]: (p - q).(v_p - v_q)/|p - q|, q the axis point nearest to p
  !> (the distance is stationary in q's position along the axis, or q is an
  !> end), v_q the rocket's velocity at that material point.
  pure real(dp) function clearance_rate(geom, aircraft, rocket) result(rate)
    type(clearance_geometry), intent(in) :: geom
    type(rigid_body), intent(in) :: aircraft, rocket
    real(dp) :: p(3), a(3), b(3), s, q_body(3), d(3)
    p = aircraft%point_position(geom%point)
    a = rocket%point_position(geom%nose)
    b = rocket%point_position(geom%aft)
    s = segment_fraction(p, a, b)
    q_body = geom%nose + s*(geom%aft - geom%nose)
    d = p - rocket%point_position(q_body)
    rate = 0.0_dp
    if (norm2(d) > 0.0_dp) rate = dot_product(d, aircraft%point_velocity(geom%point) - &
      rocket%point_velocity(q_body))/norm2(d)
  end function clearance_rate

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
