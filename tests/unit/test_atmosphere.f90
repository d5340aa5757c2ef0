!> ISA 1976 against the U.S. Standard Atmosphere 1976 tables (geometric
!> altitude; NOAA-S/T 76-1562, Table I).  The table prints 5 significant
!> digits, so the tolerance is 5e-5 relative (1e-4 on the printed pressure).
!> Then the whole documented range, -2 km to 47 km (model.md), against the
!> standard's closed forms written out here (an audit's reference): layer
!> temperatures T_b + L (H - H_b), the hydrostatic pressure (T/T_b)^(-g0/(R L))
!> or exp(-g0 (H - H_b)/(R T_b)) chained from 101 325 Pa at sea level, rho = p/(R T),
!> a = sqrt(gamma R T), with H = r0 z/(r0 + z); the same operations in another
!> order, so 1e-12 relative (round-off of the powers; measured 2e-16).  The
!> profile is continuous at the layer bases (1e-12 across +-1e-9 m of geopotential
!> height, where the smooth profile changes by 3e-13) and flagged outside the range.
program test_atmosphere
  use airlaunch_kinds, only: dp
  use airlaunch_atmosphere
  use testing
  implicit none
  real(dp), parameter :: z(6) = [0.0_dp, 5000.0_dp, 10000.0_dp, 11000.0_dp, 15000.0_dp, 20000.0_dp]
  real(dp), parameter :: t(6) = [288.150_dp, 255.676_dp, 223.252_dp, 216.774_dp, 216.650_dp, 216.650_dp]
  real(dp), parameter :: p(6) = [101325.0_dp, 54048.0_dp, 26500.0_dp, 22700.0_dp, 12111.0_dp, 5529.3_dp]
  real(dp), parameter :: rho(6) = [1.2250_dp, 0.73643_dp, 0.41351_dp, 0.36480_dp, 0.19476_dp, 0.088910_dp]
  real(dp), parameter :: a(6) = [340.294_dp, 320.545_dp, 299.532_dp, 295.154_dp, 295.070_dp, 295.070_dp]
  real(dp), parameter :: r0 = 6356766.0_dp, rg = 287.05287_dp, g = 9.80665_dp, gam = 1.4_dp
  real(dp), parameter :: h_base(5) = [0.0_dp, 11000.0_dp, 20000.0_dp, 32000.0_dp, 47000.0_dp]
  real(dp), parameter :: lapse(4) = [-6.5e-3_dp, 0.0_dp, 1.0e-3_dp, 2.8e-3_dp]
  real(dp) :: t_base(5), p_base(5), zz, hh, tt, pp, worst
  type(air_state) :: air, below, above
  integer :: i, k
  character(len=8) :: tag
  do i = 1, 6
    write(tag, '(i0," m")') nint(z(i))
    call section("ISA at " // trim(tag))
    air = isa(z(i))
    call check(air%in_range, "altitude in range")
    call check_close(air%temperature, t(i), "temperature [K]", rel=5e-6_dp)
    call check_close(air%pressure, p(i), "pressure [Pa]", rel=1e-4_dp)
    call check_close(air%density, rho(i), "density [kg/m3]", rel=1e-4_dp)
    call check_close(air%sound_speed, a(i), "speed of sound [m/s]", rel=5e-6_dp)
  end do
  call section("closed forms, -2 km to 47 km")
  t_base(1) = 288.15_dp
  p_base(1) = 101325.0_dp
  do k = 1, 4
    t_base(k + 1) = t_base(k) + lapse(k)*(h_base(k + 1) - h_base(k))
    if (lapse(k) == 0.0_dp) then
      p_base(k + 1) = p_base(k)*exp(-g*(h_base(k + 1) - h_base(k))/(rg*t_base(k)))
    else
      p_base(k + 1) = p_base(k)*(t_base(k + 1)/t_base(k))**(-g/(rg*lapse(k)))
    end if
  end do
  worst = 0.0_dp
  do i = -2000, 47000, 125
    zz = real(i, dp)
    hh = r0*zz/(r0 + zz)
    k = 1
    do while (k < 4 .and. hh >= h_base(k + 1))
      k = k + 1
    end do
    tt = t_base(k) + lapse(k)*(hh - h_base(k))
    if (lapse(k) == 0.0_dp) then
      pp = p_base(k)*exp(-g*(hh - h_base(k))/(rg*t_base(k)))
    else
      pp = p_base(k)*(tt/t_base(k))**(-g/(rg*lapse(k)))
    end if
    air = isa(zz)
    call check(air%in_range, "in range")
    worst = max(worst, abs(air%temperature/tt - 1), abs(air%pressure/pp - 1), &
      abs(air%density/(pp/(rg*tt)) - 1), abs(air%sound_speed/sqrt(gam*rg*tt) - 1))
  end do
  call check(worst < 1e-12_dp, "T, p, rho, a within 1e-12 of the closed forms")
  call section("continuity at the layer bases")
  do k = 2, 4
    below = isa(r0*(h_base(k) - 1e-9_dp)/(r0 - (h_base(k) - 1e-9_dp)))
    above = isa(r0*(h_base(k) + 1e-9_dp)/(r0 - (h_base(k) + 1e-9_dp)))
    call check_close(above%temperature, below%temperature, "temperature", rel=1e-12_dp)
    call check_close(above%pressure, below%pressure, "pressure", rel=1e-12_dp)
    call check_close(above%density, below%density, "density", rel=1e-12_dp)
  end do
  call section("outside the range")
  below = isa(-2000.001_dp)
  above = isa(47000.001_dp)
  call check(.not. below%in_range, "below -2 km is flagged out of range")
  call check(.not. above%in_range, "above 47 km is flagged out of range")
  air = isa(60000.0_dp)
  call check(.not. air%in_range, "60 km is flagged out of range")
  call finish()
end program test_atmosphere
