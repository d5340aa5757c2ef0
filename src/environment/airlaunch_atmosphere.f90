!> The U.S. Standard Atmosphere 1976 (ISA) from -2 km to 47 km geometric altitude.
!>
!> Altitude in airlaunch is the earth-frame y coordinate, a geometric height.
!> It is converted to geopotential height H = r0 z / (r0 + z) (r0 = 6 356 766 m),
!> in which the standard defines its layers; the standard's tables at geometric
!> heights are therefore reproduced (10 km: rho = 0.41351 kg/m^3, a = 299.53 m/s).
module airlaunch_atmosphere
  use airlaunch_kinds, only: dp, g0, r_air, gamma_air
  implicit none
  private
  public :: air_state, isa, isa_min_altitude, isa_max_altitude

  !> Lowest and highest geometric altitude covered [m].
  real(dp), parameter :: isa_min_altitude = -2000.0_dp
  real(dp), parameter :: isa_max_altitude = 47000.0_dp

  !> Effective earth radius of the standard [m].
  real(dp), parameter :: r0 = 6356766.0_dp
  !> Layer bases (geopotential [m]), base temperatures [K], lapse rates [K/m].
  real(dp), parameter :: hb(4) = [0.0_dp, 11000.0_dp, 20000.0_dp, 32000.0_dp]
  real(dp), parameter :: tb(4) = [288.15_dp, 216.65_dp, 216.65_dp, 228.65_dp]
  real(dp), parameter :: lb(4) = [-0.0065_dp, 0.0_dp, 0.001_dp, 0.0028_dp]
  real(dp), parameter :: p_sl = 101325.0_dp

  !> Thermodynamic state of the air at one altitude.
  type :: air_state
    real(dp) :: temperature = 0.0_dp   !< [K]
    real(dp) :: pressure = 0.0_dp      !< [Pa]
    real(dp) :: density = 0.0_dp       !< [kg/m^3]
    real(dp) :: sound_speed = 0.0_dp   !< [m/s]
    logical :: in_range = .false.      !< altitude inside the covered range
  end type air_state

contains

  !> Air at geometric altitude z [m].  Outside [isa_min_altitude,
  !> isa_max_altitude] the state is evaluated at the nearest limit and
  !> `in_range` is false, so the caller can report it.
  pure function isa(z) result(air)
    real(dp), intent(in) :: z   !< geometric altitude [m]
    type(air_state) :: air
    real(dp) :: zc, h, pb, t
    integer :: k, i
    air%in_range = z >= isa_min_altitude .and. z <= isa_max_altitude
    zc = min(max(z, isa_min_altitude), isa_max_altitude)
    h = r0*zc/(r0 + zc)
    k = 1
    do i = 2, 4
      if (h >= hb(i)) k = i
    end do
    ! pressure at the base of layer k, layer by layer from sea level
    pb = p_sl
    do i = 1, k - 1
      pb = layer_pressure(pb, tb(i), lb(i), hb(i+1) - hb(i))
    end do
    t = tb(k) + lb(k)*(h - hb(k))
    air%temperature = t
    air%pressure = layer_pressure(pb, tb(k), lb(k), h - hb(k))
    air%density = air%pressure/(r_air*t)
    air%sound_speed = sqrt(gamma_air*r_air*t)
  end function isa

  !> Hydrostatic pressure dh above a layer base (pressure pb, temperature t_b, lapse l).
  pure function layer_pressure(pb, t_b, l, dh) result(p)
    real(dp), intent(in) :: pb, t_b, l, dh
    real(dp) :: p
    if (l == 0.0_dp) then
      p = pb*exp(-g0*dh/(r_air*t_b))
    else
      p = pb*((t_b + l*dh)/t_b)**(-g0/(r_air*l))
    end if
  end function layer_pressure
end module airlaunch_atmosphere
