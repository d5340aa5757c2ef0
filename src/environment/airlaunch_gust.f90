!> A discrete "1 - cosine" gust, frozen in the air (the earth frame of the
!> air-launch scene is the still air's frame): the air velocity
!>
!>   w(x) = (U/2) (1 - cos(pi s / H)),  s = x_1 - x_front,  0 <= s <= 2H,
!>
!> and zero outside, with U the peak gust velocity (a vector across the flight
!> path: vertical and lateral components), H the gust gradient distance (the
!> gust is 2H long along the flight path, the earth's x) and x_front the plane
!> the aircraft, flying along +x, meets first.  This is the shape of the
!> certification gust of CS-25.341(a) / 14 CFR 25.341(a) (there H runs from
!> 9 m to 107 m and U from the reference gust velocity); w is continuous with a
!> continuous first derivative at both edges, so CVODE's error control steps
!> across them without an event.
!>
!> Every point of the scene (the aircraft's and the rocket's centres of mass,
!> the line's segment midpoints, the parachute) reads the gust at its own
!> position: the rocket and the trailing line and canopy meet it later than the
!> aircraft, by their distance behind it over the flight speed.
module airlaunch_gust
  use airlaunch_kinds, only: dp, pi
  implicit none
  private
  public :: gust_field, gust_velocity, make_gust, air_relative_velocity

  !> One discrete gust (inactive by default: zero everywhere).
  type :: gust_field
    logical :: active = .false.            !< false: no gust (w = 0 everywhere)
    real(dp) :: amplitude(3) = 0.0_dp      !< peak gust velocity U, earth frame [m/s]
    real(dp) :: gradient = 1.0_dp          !< gust gradient distance H [m]
    real(dp) :: x_front = 0.0_dp           !< earth x of the gust's first edge [m]
  end type gust_field

contains

  !> The gust of peak velocity `amplitude` (earth frame) and gradient distance
  !> `gradient` whose first edge is at earth x = `x_front`; inactive when the
  !> amplitude is zero.
  pure function make_gust(amplitude, gradient, x_front) result(g)
    real(dp), intent(in) :: amplitude(3)   !< peak gust velocity [m/s]
    real(dp), intent(in) :: gradient       !< H > 0 [m]
    real(dp), intent(in) :: x_front        !< [m]
    type(gust_field) :: g
    g%active = any(amplitude /= 0.0_dp)
    g%amplitude = amplitude
    g%gradient = gradient
    g%x_front = x_front
  end function make_gust

  !> Air velocity of the gust at the earth-frame point x [m/s].
  pure function gust_velocity(g, x) result(w)
    type(gust_field), intent(in) :: g
    real(dp), intent(in) :: x(3)           !< earth frame [m]
    real(dp) :: w(3)
    real(dp) :: s
    w = 0.0_dp
    if (.not. g%active) return
    s = x(1) - g%x_front
    if (s <= 0.0_dp .or. s >= 2.0_dp*g%gradient) return
    w = (0.5_dp*(1.0_dp - cos(pi*s/g%gradient)))*g%amplitude
  end function gust_velocity

  !> The velocity v of a point at x relative to the air: v - w(x) [m/s].
  pure function air_relative_velocity(g, x, v) result(u)
    type(gust_field), intent(in) :: g
    real(dp), intent(in) :: x(3)           !< earth frame [m]
    real(dp), intent(in) :: v(3)           !< earth frame [m/s]
    real(dp) :: u(3)
    u = v - gust_velocity(g, x)
  end function air_relative_velocity
end module airlaunch_gust
