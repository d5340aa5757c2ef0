!> Working precision and physical constants used everywhere (SI units).
module airlaunch_kinds
  use, intrinsic :: iso_fortran_env, only: real64, int64
  implicit none
  private
  public :: dp, i8, pi, deg2rad, rad2deg, g0, r_air, gamma_air

  !> Working precision: IEEE double.
  integer, parameter :: dp = real64
  !> 64-bit integer for counters.
  integer, parameter :: i8 = int64
  real(dp), parameter :: pi = 3.141592653589793238462643383279502884_dp
  real(dp), parameter :: deg2rad = pi/180.0_dp
  real(dp), parameter :: rad2deg = 180.0_dp/pi
  !> Standard gravity [m/s^2] (ISA 1976, also used as constant gravity).
  real(dp), parameter :: g0 = 9.80665_dp
  !> Specific gas constant of dry air [J/(kg K)] (ISA 1976: R*/M0).
  real(dp), parameter :: r_air = 287.05287_dp
  !> Ratio of specific heats of air.
  real(dp), parameter :: gamma_air = 1.4_dp
end module airlaunch_kinds
