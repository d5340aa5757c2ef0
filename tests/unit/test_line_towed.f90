!> Validation of the end body's drag and the line's skin friction (issue 3,
!> "distributed loads" and "end conditions"): the steady towed line.
!>
!> The paper's line (L = 60 m, EA = 1 MN, d = 25 mm, Cd_t = 0.01) is tied at
!> node 0 and trails the canopy (a point mass with drag area CdS = 10 m^2) in
!> the 10 km, Mach 0.65 stream (rho = 0.41351 kg/m^3, U = 194.7 m/s along -x),
!> without weight, and settles from the straight unstretched line.
!>
!> Analytic steady state (derived here).  The line streams straight along the
!> flow; the canopy pulls T_end = 1/2 rho U^2 CdS, and the skin friction adds
!> f = 1/2 rho Cd_t pi d U^2 per stretched length (the wetted area pi d ell).
!> With u the unstretched coordinate from the canopy, dT/du = f (1 + T/EA), so
!>   T(u) = (T_end + EA) exp(f u/EA) - EA,
!> the support carries T(L), and the stretched length is
!>   L_s = int_0^L (1 + T/EA) du = (T_end + EA)/f (exp(f L/EA) - 1).
!> T_end = 78 377 N, f = 6.16 N/m, T(L) = 78 775 N (the paper scenario's settled
!> tow, with the line's weight: 78.77 kN), L_s = 64.7146 m.
!>
!> Checks (N = 20 and 60; CVODE, and the marching scheme at N = 20).  In a
!> straight line the lumped chain is exact up to the rule that puts half of
!> each segment's friction on each node: the support reaction is the sum of
!> all loads, the canopy's position is the sum of the segment lengths, and
!> segment k carries the canopy and the friction beyond its midpoint.  Each
!> equals the continuum's to second order in the segment, ~(l0 f/EA)^2 =
!> 3e-10 at N = 20, so the bound is 1e-7 relative, above that and the settling
!> residual (measured: reaction 1e-13, canopy position 3e-11, segment tensions
!> 5.9e-10 at N = 20 and 6.5e-11 at N = 60).  Friction on the material length pi d l0 instead
!> of the stretched one would move T(L) by f L eps = 29 N (3.7e-4), the canopy
!> drag on any other area by far more.
program test_line_towed
  use airlaunch_kinds, only: dp, pi
  use airlaunch_error, only: error_type
  use airlaunch_strings, only: str
  use airlaunch_line
  use airlaunch_line_scene
  use testing
  implicit none
  real(dp), parameter :: length = 60.0_dp, ea = 1.0e6_dp, rho_line = 0.3_dp, diameter = 0.025_dp
  real(dp), parameter :: cd_t = 0.01_dp, cds = 10.0_dp, rho_air = 0.41351_dp, u_air = 194.7_dp
  real(dp) :: q, t_end, f, t_support, l_s

  q = 0.5_dp*rho_air*u_air**2
  t_end = q*cds
  f = q*cd_t*pi*diameter
  t_support = tension_at(length)
  l_s = (t_end + ea)/f*(exp(f*length/ea) - 1.0_dp)
  call section("the towed line: L = 60 m, EA = 1 MN, canopy CdS = 10 m^2, U = 194.7 m/s, no weight")
  print '(a, f12.3, a, f8.4, a, f12.3, a, f10.5, a)', "  analytic: canopy drag ", t_end, " N, friction ", f, &
    " N/m; support ", t_support, " N, stretched length ", l_s, " m"
  call towed(20, "cvode")
  call towed(60, "cvode")
  call towed(20, "marching")
  call finish()

contains

  !> The continuum tension at unstretched distance u from the canopy [N].
  real(dp) function tension_at(u) result(t)
    real(dp), intent(in) :: u
    t = (t_end + ea)*exp(f*u/ea) - ea
  end function tension_at

  !> Settle the towed line with n segments by `scheme` and check it.
  subroutine towed(n, scheme)
    integer, intent(in) :: n
    character(len=*), intent(in) :: scheme
    type(line_scene_config) :: c
    type(line_scene) :: sc
    type(error_type), allocatable :: err
    real(dp) :: l0, worst
    integer :: m, k
    character(len=:), allocatable :: tag
    tag = scheme // ", N = " // str(n)
    l0 = length/n
    c%line = line_params(length=length, n_seg=n, ea=ea, mass_per_length=rho_line, damping=1000.0_dp, &
      settling_damping=5.0_dp, diameter=diameter, cd_normal=1.2_dp, cd_tangential=cd_t, gravity=.false., &
      air=.true., wind=[-u_air, 0.0_dp, 0.0_dp], air_density=rho_air)
    c%end_a = line_end(kind=end_fixed, position=[0.0_dp, 0.0_dp, 0.0_dp])
    c%end_b = line_end(kind=end_point_mass, mass=10.0_dp, drag_area=cds, position=[-length, 0.0_dp, 0.0_dp])
    c%t_end = 10.0_dp
    c%output_interval = 1.0_dp
    c%record_tensions = .true.
    c%integration%scheme = scheme
    c%integration%rtol = 1.0e-6_dp
    c%integration%atol = 1.0e-6_dp
    if (scheme == "marching") c%integration%dt = 0.9_dp*marching_stable_step(ea, rho_line, l0, 1000.0_dp, 5.0_dp)
    call sc%init(c, err)
    if (.not. allocated(err)) call sc%run(err)
    call check(.not. allocated(err), tag // ": run to 10 s")
    if (allocated(err)) then
      print '(a)', err%message
      return
    end if
    m = sc%n_out
    call check(maxval(abs(sc%nodes(:, :, m) - sc%nodes(:, :, m-1))) < 1.0e-8_dp, tag // &
      ": settled (node motion in the last second < 1e-8 m)")
    call check_close(-sc%end_force(1, 1, m), t_support, tag // ": support reaction [N]", rel=1.0e-7_dp)
    call check_close(maxval(abs(sc%end_force(2:3, 1, m))), 0.0_dp, tag // ": no side force at the support [N]", &
      abs=1.0e-7_dp*t_support)
    call check_close(-sc%nodes(1, n, m), l_s, tag // ": canopy position = stretched length [m]", rel=1.0e-7_dp)
    worst = 0.0_dp
    do k = 1, n   ! segment k's midpoint lies (n - k + 1/2) l0 from the canopy
      worst = max(worst, abs(sc%tensions(k, m)/tension_at((n - k + 0.5_dp)*l0) - 1.0_dp))
    end do
    call check_close(worst, 0.0_dp, tag // ": largest relative error of a segment tension against T at " // &
      "its midpoint", abs=1.0e-7_dp)
    call sc%free()
  end subroutine towed
end program test_line_towed
