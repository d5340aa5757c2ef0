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
!>
!> A lifting surface of chord c builds its lift in a gust over a few chords
!> travelled (Küssner): the lift of the gust velocity w is that of the
!> effective velocity
!>
!>   w_K(s) = integral_0^s w'(s') psi(2 (s - s')/c) ds',
!>   psi(sigma) = 1 - a1 exp(-b1 sigma) - a2 exp(-b2 sigma)
!>
!> (Jones' approximation of Küssner's function: a1 = a2 = 1/2, b1 = 0.13,
!> b2 = 1; sigma the distance travelled in half-chords), a function of the
!> surface's distance s into the frozen gust alone.  For the 1 - cosine shape
!> the integral has a closed form (`lagged_gust_velocity`); behind the gust
!> w_K decays as exp(-2 b_i (s - 2H)/c).
module airlaunch_gust
  use airlaunch_kinds, only: dp, pi
  implicit none
  private
  public :: gust_field, gust_velocity, lagged_gust_velocity, make_gust, air_relative_velocity

  !> Jones' approximation of Küssner's function: weights and rates [1/half-chord].
  real(dp), parameter :: kussner_a(2) = [0.5_dp, 0.5_dp], kussner_b(2) = [0.13_dp, 1.0_dp]

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

  !> The gust velocity whose lift a surface of chord `chord` at x, flying
  !> along +x through the frozen gust, has built (Küssner, Jones'
  !> approximation; module header) [m/s].  With s = x_1 - x_front the distance
  !> into the gust and p = pi/H, w' = (U/2) p sin(p s), and each exponential of
  !> psi contributes -a_i (U/2) p J_i with
  !>   J_i(s) = integral_0^s sin(p s') exp(-k_i (s - s')) ds'
  !>          = (k_i sin(p s) - p cos(p s) + p exp(-k_i s))/(k_i^2 + p^2),
  !> k_i = 2 b_i/c; behind the gust (s > 2H) w' = 0: J_i(2H) exp(-k_i (s - 2H)).
  pure function lagged_gust_velocity(g, x, chord) result(w)
    type(gust_field), intent(in) :: g
    real(dp), intent(in) :: x(3)           !< earth frame [m]
    real(dp), intent(in) :: chord          !< the surface's chord [m], > 0
    real(dp) :: w(3)
    real(dp) :: s, se, p, k, lag
    integer :: i
    w = 0.0_dp
    if (.not. g%active) return
    s = x(1) - g%x_front
    if (s <= 0.0_dp) return
    p = pi/g%gradient
    se = min(s, 2.0_dp*g%gradient)
    lag = 0.0_dp
    do i = 1, 2
      k = 2.0_dp*kussner_b(i)/chord
      lag = lag + kussner_a(i)*(k*sin(p*se) - p*cos(p*se) + p*exp(-k*se))/(k*k + p*p)*exp(-k*(s - se))
    end do
    w = (0.5_dp*(1.0_dp - cos(p*se)) - 0.5_dp*p*lag)*g%amplitude
  end function lagged_gust_velocity

  !> The velocity v of a point at x relative to the air: v - w(x) [m/s]; with
  !> `chord` > 0, relative to the air whose lift a surface of that chord has
  !> built (lagged_gust_velocity).
  pure function air_relative_velocity(g, x, v, chord) result(u)
    type(gust_field), intent(in) :: g
    real(dp), intent(in) :: x(3)           !< earth frame [m]
    real(dp), intent(in) :: v(3)           !< earth frame [m/s]
    real(dp), intent(in), optional :: chord   !< [m]; absent or 0: the gust itself
    real(dp) :: u(3)
    if (present(chord)) then
      if (chord > 0.0_dp) then
        u = v - lagged_gust_velocity(g, x, chord)
        return
      end if
    end if
    u = v - gust_velocity(g, x)
  end function air_relative_velocity
end module airlaunch_gust
