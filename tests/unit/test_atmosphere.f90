!> ISA 1976 against the U.S. Standard Atmosphere 1976 tables (geometric
!> altitude; NOAA-S/T 76-1562, Table I).  The table prints 5 significant
!> digits, so the tolerance is 5e-5 relative (1e-4 on the printed pressure).
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
  type(air_state) :: air
  integer :: i
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
  call section("outside the range")
  air = isa(60000.0_dp)
  call check(.not. air%in_range, "60 km is flagged out of range")
  call finish()
end program test_atmosphere
