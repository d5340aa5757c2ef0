!> The rocket's optional Mach tables (src/aero/airlaunch_rocket_aero.f90):
!> C_dn(M_c) per cross-flow strip and C_A(M) of the free stream, against the
!> module header's force formulas evaluated by hand:
!>  - a table of one point, or of several points all equal to the scalar
!>    coefficient, gives the scalar's forces and moments bit for bit (the same
!>    product in the same order);
!>  - at a table's point, between two points and beyond either end, the force
!>    of a rocket broadside to the air (every strip at M_c = v/a) and of one in
!>    axial flow (C_A at M = v/a) is the formula's with the hand-interpolated
!>    coefficient;
!>  - a pitching rocket in still air: each strip reads C_dn at its own
!>    cross-flow Mach number |w x|/a (two strips, hand computation);
!>  - a NaN Mach number gives a NaN coefficient, not an end point's value.
program test_rocket_mach
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan, ieee_is_nan
  use airlaunch_kinds, only: dp, pi
  use airlaunch_rocket_aero
  use testing
  implicit none
  type(rocket_aero) :: rk, tab
  real(dp), parameter :: rho = 0.41351_dp, a = 300.0_dp
  real(dp) :: f(3), m(3), ft(3), mt(3), v, s_ref, x(2), cdn(2), fy(2), w
  real(dp) :: vbs(3, 3), wbs(3, 3), shields(2)
  integer :: i, j, k

  call section("a one-point or constant table gives the scalar coefficient's forces bit for bit")
  ! three states (broadside with pitch and yaw rates, 30 deg with sideslip,
  ! near-axial) x two shields (fully out, half in the bay); no tolerance:
  ! the table returns the same coefficient and the force the same product
  vbs(:, 1) = [0.0_dp, -150.0_dp, 20.0_dp]
  vbs(:, 2) = [200.0_dp, -100.0_dp, 30.0_dp]
  vbs(:, 3) = [250.0_dp, -1.0_dp, 0.5_dp]
  wbs(:, 1) = [0.1_dp, 0.3_dp, -0.8_dp]
  wbs(:, 2) = [0.0_dp, 0.0_dp, 0.5_dp]
  wbs(:, 3) = [0.0_dp, -0.2_dp, 0.0_dp]
  shields = [1.0e9_dp, 0.0_dp]
  rk%cn_alpha_fin = 10.0_dp; rk%cn_fin_90 = 2.0_dp
  do k = 1, 2
    tab = rk
    if (k == 1) then
      tab%n_c_dn = 1; tab%c_dn_mach(1) = 0.4_dp; tab%c_dn_table(1) = rk%c_dn
      tab%n_c_axial = 1; tab%c_axial_mach(1) = 0.7_dp; tab%c_axial_table(1) = rk%c_axial
    else
      tab%n_c_dn = 4; tab%c_dn_mach(1:4) = [0.0_dp, 0.3_dp, 0.6_dp, 0.9_dp]; tab%c_dn_table(1:4) = rk%c_dn
      tab%n_c_axial = 3; tab%c_axial_mach(1:3) = [0.2_dp, 0.5_dp, 0.8_dp]; tab%c_axial_table(1:3) = rk%c_axial
    end if
    do i = 1, 3
      do j = 1, 2
        call rocket_aero_eval(rk, rho, a, vbs(:, i), wbs(:, i), shields(j), f, m)
        call rocket_aero_eval(tab, rho, a, vbs(:, i), wbs(:, i), shields(j), ft, mt)
        call check(all(ft == f) .and. all(mt == m), "table of " // merge("one point  ", "four points", k == 1) // &
          ", state " // achar(48 + i) // ", shield " // achar(48 + j) // ": forces and moments bit for bit")
      end do
    end do
  end do
  rk%cn_alpha_fin = 0.0_dp; rk%cn_fin_90 = 0.0_dp

  call section("C_dn(M_c) at a point, between points and beyond the ends: broadside rocket")
  ! v_b = (0, -v, 0), no rotation: every strip at M_c = v/a; the force is
  ! F_y = 1/2 rho v^2 eta C_dn d L (module header) plus the slender-body term
  ! sin(2a) cos(a/2) at a = 90 deg, 1e-16 of it (atan2(v, 0) = pi/2 rounded):
  ! 1e-12 relative.  Table (0.2, 1.2), (0.6, 1.6), (1.0, 2.2); a constant
  ! C_dn would give 1.2 throughout.
  tab = rk
  tab%n_c_dn = 3; tab%c_dn_mach(1:3) = [0.2_dp, 0.6_dp, 1.0_dp]; tab%c_dn_table(1:3) = [1.2_dp, 1.6_dp, 2.2_dp]
  call broadside(180.0_dp, 1.6_dp, "at the point M_c = 0.6: C_dn = 1.6")
  call broadside(240.0_dp, 1.9_dp, "at the midpoint M_c = 0.8: C_dn = (1.6 + 2.2)/2 = 1.9")
  call broadside(120.0_dp, 1.4_dp, "at M_c = 0.4 (midpoint of the first interval): C_dn = 1.4")
  call broadside(330.0_dp, 2.2_dp, "beyond the last point, M_c = 1.1: C_dn = 2.2 (held)")
  call broadside(30.0_dp, 1.2_dp, "below the first point, M_c = 0.1: C_dn = 1.2 (held)")

  call section("C_A(M) at a point and at a midpoint: axial flow")
  ! v_b = (v, 0, 0): no cross-flow, no normal force; F_x = -1/2 rho v^2 S_ref C_A(v/a)
  ! (one product: 1e-14 relative).  Table (0.3, 0.30), (0.9, 0.60).
  tab = rk
  tab%n_c_axial = 2; tab%c_axial_mach(1:2) = [0.3_dp, 0.9_dp]; tab%c_axial_table(1:2) = [0.30_dp, 0.60_dp]
  s_ref = pi*rk%diameter**2/4
  v = 90.0_dp
  call rocket_aero_eval(tab, rho, a, [v, 0.0_dp, 0.0_dp], [0.0_dp, 0.0_dp, 0.0_dp], 1.0e9_dp, f, m)
  call check_close(f(1), -0.5_dp*rho*v*v*s_ref*0.30_dp, "at the point M = 0.3: C_A = 0.30", rel=1e-14_dp)
  v = 180.0_dp
  call rocket_aero_eval(tab, rho, a, [v, 0.0_dp, 0.0_dp], [0.0_dp, 0.0_dp, 0.0_dp], 1.0e9_dp, f, m)
  call check_close(f(1), -0.5_dp*rho*v*v*s_ref*0.45_dp, "at the midpoint M = 0.6: C_A = 0.45", rel=1e-14_dp)
  v = 240.0_dp
  call rocket_aero_eval(tab, rho, a, [v, 0.0_dp, 0.0_dp], [0.0_dp, 0.0_dp, 0.0_dp], 1.0e9_dp, f, m)
  call check_close(f(1), -0.5_dp*rho*v*v*s_ref*0.55_dp, "at M = 0.8: C_A = 0.30 + 0.30 (5/6) = 0.55", rel=1e-14_dp)

  call section("a pitching rocket: each strip at its own cross-flow Mach number")
  ! Still air, pitch rate w about body z, two strips: with the CG 12 m aft of
  ! the nose (length 18.5 m) the strips span [-6.5, 2.75] and [2.75, 12] m,
  ! centres x = -1.875 and 7.375 m.  Strip i moves with (0, w x_i, 0): M_c =
  ! |w x_i|/a, and with the table C_dn = 1 + M_c (points (0, 1), (2, 3))
  !   F_y,i = -1/2 rho eta C_dn,i d dx |w x_i| w x_i,  M_z = sum x_i F_y,i.
  ! The CG's or the free stream's Mach number (0 here) would give C_dn = 1 on
  ! both.  Two products and a sum: 1e-13 relative.
  tab = rk
  tab%cg_from_nose = 12.0_dp; tab%n_strips = 2
  tab%n_c_dn = 2; tab%c_dn_mach(1:2) = [0.0_dp, 2.0_dp]; tab%c_dn_table(1:2) = [1.0_dp, 3.0_dp]
  w = 20.0_dp
  x = [-1.875_dp, 7.375_dp]
  cdn = 1 + abs(w*x)/a
  call check(abs(cdn(2) - cdn(1)) > 0.3_dp, "the two strips' C_dn differ (1.125 and 1.49)")
  fy = -0.5_dp*rho*tab%eta*cdn*tab%diameter*9.25_dp*abs(w*x)*w*x
  call rocket_aero_eval(tab, rho, a, [0.0_dp, 0.0_dp, 0.0_dp], [0.0_dp, 0.0_dp, w], 1.0e9_dp, f, m)
  call check_close(f(2), sum(fy), "F_y = sum of the strips' hand-computed forces", rel=1e-13_dp)
  call check_close(m(3), sum(x*fy), "M_z = sum of x_i F_y,i", rel=1e-13_dp)
  call check(f(1) == 0.0_dp .and. f(3) == 0.0_dp .and. m(1) == 0.0_dp .and. m(2) == 0.0_dp, &
    "no force along x or z, no moment about x or y")
  ! the same body and rate with a sound speed twice as large: the strips'
  ! M_c halve, C_dn = 1 + |w x|/(2a)
  cdn = 1 + abs(w*x)/(2*a)
  fy = -0.5_dp*rho*tab%eta*cdn*tab%diameter*9.25_dp*abs(w*x)*w*x
  call rocket_aero_eval(tab, rho, 2*a, [0.0_dp, 0.0_dp, 0.0_dp], [0.0_dp, 0.0_dp, w], 1.0e9_dp, f, m)
  call check_close(f(2), sum(fy), "the speed of sound passed sets M_c (a doubled: C_dn = 1 + |w x|/2a)", &
    rel=1e-13_dp)

  call section("a NaN Mach number gives NaN, not an end point's value")
  ! A NaN speed of sound or speed (a run gone non-finite) must reach the
  ! force as NaN, so that the run's non-finite check names the quantity; the
  ! search through the points took NaN for "beyond the last point" and held
  ! the last value (2.2 here), a finite coefficient from a NaN input.
  w = ieee_value(1.0_dp, ieee_quiet_nan)
  call check(ieee_is_nan(mach_table_value(3, [0.2_dp, 0.6_dp, 1.0_dp], [1.2_dp, 1.6_dp, 2.2_dp], w)), &
    "table of three points at M = NaN: NaN")
  call check(ieee_is_nan(mach_table_value(1, [0.7_dp], [0.35_dp], w)), "table of one point at M = NaN: NaN")
  call check(mach_table_value(3, [0.2_dp, 0.6_dp, 1.0_dp], [1.2_dp, 1.6_dp, 2.2_dp], huge(1.0_dp)) == 2.2_dp, &
    "a finite Mach number beyond the last point still holds the last value (2.2)")

  call finish()
contains
  !> The broadside force at speed v with the table in `tab` against the
  !> formula with c_dn.
  subroutine broadside(v, c_dn, what)
    real(dp), intent(in) :: v, c_dn
    character(len=*), intent(in) :: what
    real(dp) :: f(3), m(3)
    call rocket_aero_eval(tab, rho, a, [0.0_dp, -v, 0.0_dp], [0.0_dp, 0.0_dp, 0.0_dp], 1.0e9_dp, f, m)
    call check_close(f(2), 0.5_dp*rho*v*v*tab%eta*c_dn*tab%diameter*tab%length, what, rel=1e-12_dp)
  end subroutine broadside
end program test_rocket_mach
