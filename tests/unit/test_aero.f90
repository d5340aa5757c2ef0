!> Aerodynamic models against independent references: wind-axis projections
!> of the aircraft force, stability-derivative signs, the cross-flow integral
!> of the rocket in closed form, the inflation law, and a trim consistency check
!> (calibrate at the paper's angle of attack, then fly: same angle, zero elevator).
program test_aero
  use airlaunch_kinds, only: dp, pi, deg2rad, g0
  use airlaunch_error, only: error_type
  use airlaunch_strings, only: str
  use airlaunch_aircraft_aero
  use airlaunch_rocket_aero
  use airlaunch_parachute
  use airlaunch_trim
  use airlaunch_atmosphere
  use testing
  use, intrinsic :: ieee_exceptions, only: ieee_overflow, ieee_get_flag, ieee_set_flag
  implicit none
  type(aircraft_aero) :: ac
  type(aircraft_aero_out) :: o
  type(rocket_aero) :: rk
  type(parachute) :: pc
  type(trim_problem) :: tp
  type(trim_result) :: tr, tr2
  type(error_type), allocatable :: error
  type(air_state) :: air
  real(dp) :: v, alpha, vb(3), qs, f(3), m(3), expected, rho, w, l, beta, vhat(3), fperp(3), x, f0(3), m0(3), &
    cn, tol
  real(dp), parameter :: small_alphas(3) = [1.0e-8_dp, 1.0e-6_dp, 1.0e-3_dp]
  integer :: k, sgn

  call section("aircraft: lift normal to and drag along the relative wind")
  ac%cl0 = 0.3_dp
  v = 200.0_dp; alpha = 4*deg2rad; rho = 0.4
  vb = v*[cos(alpha), -sin(alpha), 0.0_dp]
  o = aircraft_aero_eval(ac, rho, vb, [0.0_dp, 0.0_dp, 0.0_dp], 0.0_dp)
  qs = 0.5_dp*rho*v*v*ac%wing_area
  call check_close(o%alpha, alpha, "alpha from the body velocity", abs=1e-14_dp)
  call check_close(-dot_product(o%force, vb/v), qs*(ac%cd0 + ac%k_induced*o%cl**2), "force along -V = qS CD", rel=1e-12_dp)
  call check_close(o%cl, ac%cl0 + ac%cl_alpha*alpha, "CL = CL0 + CLa alpha", rel=1e-14_dp)
  call check_close(norm2(o%force - dot_product(o%force, vb/v)*vb/v), qs*o%cl, "|force normal to V| = qS CL", rel=1e-12_dp)
  call check(abs(o%force(3)) + abs(o%moment(1)) + abs(o%moment(2)) == 0.0_dp, "symmetric flight: no lateral force or moment")

  call section("aircraft: drag along -V in sideslip (wind axes)")
  ! beta = 10 deg, no side-force derivative: the aerodynamic force is
  ! qS (CL l - CD V/|V|) with l normal to V in the plane of symmetry, so its
  ! component along V is -qS CD and the rest has magnitude qS CL and no body-z
  ! part.  One evaluation: round-off, 1e-12 relative.  (A drag kept in the
  ! body x-y plane gives -qS CD cos(beta): 1.5e-2 off.)
  block
    type(aircraft_aero) :: acb
    acb = ac
    acb%cy_beta = 0.0_dp
    beta = 10*deg2rad
    vb = v*[cos(beta)*cos(alpha), -cos(beta)*sin(alpha), sin(beta)]
    vhat = vb/v
    o = aircraft_aero_eval(acb, rho, vb, [0.0_dp, 0.0_dp, 0.0_dp], 0.0_dp)
    call check_close(o%beta, beta, "beta from the body velocity", abs=1e-14_dp)
    call check_close(-dot_product(o%force, vhat), qs*(acb%cd0 + acb%k_induced*o%cl**2), &
      "force along -V = qS CD at beta = 10 deg", rel=1e-12_dp)
    fperp = o%force - dot_product(o%force, vhat)*vhat
    call check_close(norm2(fperp), qs*o%cl, "|force normal to V| = qS CL at beta = 10 deg", rel=1e-12_dp)
    call check_close(fperp(3), 0.0_dp, "the lift has no body-z part (plane of symmetry)", abs=1e-12_dp*qs*o%cl)
  end block

  call section("aircraft: signs of the stability derivatives")
  o = aircraft_aero_eval(ac, rho, [v, 0.0_dp, 10.0_dp], [0.0_dp, 0.0_dp, 0.0_dp], 0.0_dp)
  call check(o%moment(2) < 0.0_dp, "weathercock: wind from the right turns the nose right (-y moment)")
  call check(o%force(3) < 0.0_dp, "side force opposes sideslip")
  o = aircraft_aero_eval(ac, rho, [v, 0.0_dp, 0.0_dp], [0.0_dp, 0.0_dp, 0.1_dp], 0.0_dp)
  call check(o%moment(3) < ac%cm0*qs*ac%chord, "pitch damping opposes a nose-up rate")
  ac%attitude_hold = .true.; ac%theta_ref = 0.0_dp
  o = aircraft_aero_eval(ac, rho, [v, 0.0_dp, 0.0_dp], [0.0_dp, 0.0_dp, 0.0_dp], 2*deg2rad)
  call check(o%delta_e > 0.0_dp .and. o%moment(3) < qs*ac%chord*ac%cm0, "attitude hold: nose above reference -> nose-down elevator")
  ac%attitude_hold = .false.

  call section("rocket: cross-flow force at 90 deg in closed form")
  rho = 0.41351_dp; v = 50.0_dp
  call rocket_aero_eval(rk, rho, 300.0_dp, [0.0_dp, -v, 0.0_dp], [0.0_dp, 0.0_dp, 0.0_dp], 1.0e9_dp, f, m)
  expected = 0.5_dp*rho*v*v*rk%eta*rk%c_dn*rk%diameter*rk%length
  ! at alpha = 90 deg the potential term sin(2 alpha) vanishes; the strip sum of a uniform load is exact
  call check_close(f(2), expected, "F_y = 1/2 rho V^2 eta Cdn d L", rel=1e-12_dp)
  call check_close(m(3), expected*(rk%length/2 - rk%cg_from_nose), "moment of a uniform load about the CG", abs=1e-6_dp*expected)

  call section("rocket: pitch damping of a pure rotation")
  rk%n_strips = 400
  w = 0.8_dp
  call rocket_aero_eval(rk, rho, 300.0_dp, [0.0_dp, 0.0_dp, 0.0_dp], [0.0_dp, 0.0_dp, w], 1.0e9_dp, f, m)
  ! M = -1/2 rho eta Cdn d w|w| int |x| x^2 dx over [-L/2, L/2] (CG at mid-length);
  ! midpoint rule with 400 strips: relative error ~ (dx/L)^2 ~ 1e-5
  l = rk%length/2
  expected = -0.5_dp*rho*rk%eta*rk%c_dn*rk%diameter*w*abs(w)*2*l**4/4
  call check_close(m(3), expected, "damping moment", rel=1e-4_dp)
  call check(abs(f(2)) < 1e-9_dp*abs(expected), "no net force for a rotation about the mid-point")
  rk%n_strips = 16

  call section("rocket: static stability")
  alpha = 2*deg2rad; v = 194.7_dp
  vb = v*[cos(alpha), -sin(alpha), 0.0_dp]
  call rocket_aero_eval(rk, rho, 300.0_dp, vb, [0.0_dp, 0.0_dp, 0.0_dp], 1.0e9_dp, f, m)
  call check(m(3) > 0.0_dp .and. f(2) > 0.0_dp, "without fins the centre of pressure is ahead of the CG (unstable)")
  rk%cn_alpha_fin = 20.0_dp
  call rocket_aero_eval(rk, rho, 300.0_dp, vb, [0.0_dp, 0.0_dp, 0.0_dp], 1.0e9_dp, f, m)
  call check(m(3) < 0.0_dp, "large fins move it aft of the CG (stable)")
  rk%cn_alpha_fin = 0.0_dp
  call rocket_aero_eval(rk, rho, 300.0_dp, vb, [0.0_dp, 0.0_dp, 0.0_dp], rk%cg_from_nose - rk%length - 0.1_dp, f, m)
  call check(all(f == 0.0_dp) .and. all(m == 0.0_dp), "fully shielded inside the bay: no load")

  call section("rocket: slender-body slope C_N -> 2 alpha at small angles")
  ! body alone (no cross-flow drag, no fins): C_N = sin(2a) cos(a/2) =
  ! 2a (1 - (2/3 + 1/8) a^2 + ...), so C_N/(2a) - 1 is below a^2 in magnitude,
  ! plus round-off (1e-12).  acos(v_x/v) lost it: -1.0 at 1e-8, 1.6e-4 at 1e-6.
  rk = rocket_aero()
  rk%c_dn = 0.0_dp
  v = 194.7_dp
  do k = 1, size(small_alphas)
    alpha = small_alphas(k)
    vb = v*[cos(alpha), -sin(alpha), 0.0_dp]
    call rocket_aero_eval(rk, rho, 300.0_dp, vb, [0.0_dp, 0.0_dp, 0.0_dp], 1.0e9_dp, f, m)
    cn = f(2)/(0.5_dp*rho*v*v*pi*rk%diameter**2/4)
    tol = 1.0e-12_dp + alpha**2
    call check_close(cn/(2*alpha), 1.0_dp, "C_N/(2 alpha) at alpha = " // str(alpha) // " rad", abs=tol)
  end do

  call section("rocket: fins of a pitching rocket with no cross-flow at the CG")
  ! the paper's X fins (Barrowman: CN_alpha = 6.4734 on S_ref, centre of
  ! pressure 17.333 m from the nose, flat-plate 3.6193 at 90 deg); V along the
  ! body axis, pitch rate q: the fins see v_y = q x_f (x_f = CG - fin < 0), so
  !   F_y = -1/2 rho S_ref (CN_alpha V + CN_90 |q x_f|) q x_f,  M_z = x_f F_y.
  ! Cross-flow drag off to isolate the fins; one evaluation: 1e-12 relative.
  rk = rocket_aero()
  rk%cn_alpha_fin = 6.4734_dp; rk%x_fin_from_nose = 17.3333_dp; rk%cn_fin_90 = 3.6193_dp
  rk%c_dn = 0.0_dp
  v = 194.7_dp; w = 0.5_dp
  x = rk%cg_from_nose - rk%x_fin_from_nose
  expected = -0.5_dp*rho*pi*rk%diameter**2/4*(rk%cn_alpha_fin*v + rk%cn_fin_90*abs(w*x))*w*x
  call rocket_aero_eval(rk, rho, 300.0_dp, [v, 0.0_dp, 0.0_dp], [0.0_dp, 0.0_dp, w], 1.0e9_dp, f, m)
  call check_close(f(2), expected, "fin normal force of a pure pitch rate", rel=1e-12_dp)
  call check_close(m(3), x*expected, "fin damping moment of a pure pitch rate", rel=1e-12_dp)
  call check(m(3) < 0.0_dp, "the fins damp a nose-up rate")
  ! continuity in v_y at 0 (with the cross-flow drag): the loads' slope in v_y
  ! is ~ rho V S_ref (1 + CN_alpha/2) ~ 7e2 N per m/s, so a step of 1e-9 m/s
  ! changes them by < 1e-6 N, ~ 5e-10 of |F_y|; allowed: 1e-8 relative.
  rk%c_dn = 1.2_dp
  call rocket_aero_eval(rk, rho, 300.0_dp, [v, 0.0_dp, 0.0_dp], [0.0_dp, 0.0_dp, w], 1.0e9_dp, f0, m0)
  do sgn = -1, 1, 2
    call rocket_aero_eval(rk, rho, 300.0_dp, [v, sgn*1.0e-9_dp, 0.0_dp], [0.0_dp, 0.0_dp, w], 1.0e9_dp, f, m)
    call check_close(f(2), f0(2), "F_y continuous at v_y = 0 (" // str(sgn*1.0e-9_dp) // ")", &
      abs=1e-8_dp*abs(f0(2)))
    call check_close(m(3), m0(3), "M_z continuous at v_y = 0 (" // str(sgn*1.0e-9_dp) // ")", &
      abs=1e-8_dp*abs(m0(3)))
  end do
  rk = rocket_aero()

  call section("rocket: fins passing the ramp edge, against a clipped polygon")
  ! The share of the fin planform outside the bay (aft of the edge) against an
  ! independent computation: the trapezoid clipped by the edge's line
  ! (Sutherland-Hodgman) and its area by the shoelace formula, over 201 edge
  ! positions from before the trailing edge to past the leading edge, for the
  ! paper's fins (trailing edge swept back), a trailing edge swept forward, and
  ! a sweep longer than the root chord.  Both are exact: 1e-12 allowed.  Then
  ! the fin force of a pitching rocket at half exposure is half the force in
  ! the open of the same fins at the exposed part's centre (cross-flow drag
  ! off; the potential term has no cross-flow).
  block
    real(dp), parameter :: geo(3, 3) = reshape([2.0_dp, 1.0_dp, 1.0_dp, 2.0_dp, 0.5_dp, 0.3_dp, &
      1.0_dp, 1.0_dp, 1.5_dp], [3, 3])   ! (root chord, tip chord, sweep) per case
    real(dp) :: s_e, share, worst, x_shield, lo, hi, fopen(3), mopen(3)
    integer :: c, i
    do c = 1, 3
      rk = rocket_aero()
      rk%fin_root_le_from_nose = 16.0_dp
      rk%fin_root_chord = geo(1, c); rk%fin_tip_chord = geo(2, c); rk%fin_sweep = geo(3, c)
      lo = -0.5_dp; hi = max(geo(1, c), geo(3, c) + geo(2, c)) + 0.5_dp
      worst = 0.0_dp
      do i = 0, 200
        s_e = lo + (hi - lo)*i/200.0_dp      ! the edge, aft of the root's leading edge
        x_shield = rk%cg_from_nose - rk%fin_root_le_from_nose - s_e
        share = fin_exposed_fraction(rk, x_shield)
        worst = max(worst, abs(share - clipped_share(geo(:, c), 1.34_dp, s_e)))
      end do
      call check(worst <= 1.0e-12_dp, "exposed share of fin " // str(c) // " against the clipped polygon: worst " // &
        str(worst))
    end do
    rk = rocket_aero()
    rk%cn_alpha_fin = 6.4734_dp; rk%x_fin_from_nose = 17.3333_dp; rk%cn_fin_90 = 3.6193_dp
    rk%fin_root_le_from_nose = 16.5_dp; rk%fin_root_chord = 2.0_dp; rk%fin_tip_chord = 1.0_dp; rk%fin_sweep = 1.0_dp
    rk%c_dn = 0.0_dp
    ! the edge where half the planform is out: bisection on the share
    lo = rk%cg_from_nose - rk%length; hi = rk%cg_from_nose - rk%fin_root_le_from_nose
    do i = 1, 200
      x_shield = 0.5_dp*(lo + hi)
      if (fin_exposed_fraction(rk, x_shield) < 0.5_dp) then
        lo = x_shield
      else
        hi = x_shield
      end if
    end do
    call rocket_aero_eval(rk, rho, 300.0_dp, [v, 0.0_dp, 0.0_dp], [0.0_dp, 0.0_dp, w], x_shield, f, m)
    ! in the open: the same fins as a point at the exposed part's centre (it
    ! sets the local velocity of the pitching rocket and the moment's arm)
    block
      type(rocket_aero) :: point_fin
      real(dp) :: share, x_cp
      call fin_exposure(rk, x_shield, share, x_cp)
      point_fin = rk
      point_fin%fin_root_chord = 0.0_dp
      point_fin%x_fin_from_nose = rk%cg_from_nose - x_cp
      call rocket_aero_eval(point_fin, rho, 300.0_dp, [v, 0.0_dp, 0.0_dp], [0.0_dp, 0.0_dp, w], 1.0e9_dp, fopen, mopen)
    end block
    call check_close(f(2), 0.5_dp*fopen(2), "half the planform out: half the fin force", rel=1e-12_dp)
    call check_close(m(3), 0.5_dp*mopen(3), "half the planform out: half the fin moment", rel=1e-12_dp)
    call rocket_aero_eval(rk, rho, 300.0_dp, [v, 0.0_dp, 0.0_dp], [0.0_dp, 0.0_dp, w], &
      rk%cg_from_nose - rk%length, f, m)
    call check(f(2) == 0.0_dp .and. m(3) == 0.0_dp, "fins with their trailing edge at the edge: no fin force")
  end block
  rk = rocket_aero()

  call section("rocket: the exposed fins' centre of pressure, in closed form")
  ! The paper's fins (root chord 2, tip chord 1, sweep 1: the trailing edge
  ! square to the axis at 2 m aft of the root's leading edge) with the edge
  ! s aft of that leading edge.  Strip theory, each strip's force at its
  ! quarter chord, worked by hand: for s >= 1 the exposed part is the
  ! rectangle [s, 2] over the whole span, centre s + (2 - s)/4; for s < 1 the
  ! strips e < s (span fraction) run from s to 2 and the strips e > s from e
  ! to 2, so with c = 2 - s
  !   A = s c + int_s^1 (2 - e) de,   M = s c (s + c/4) + int_s^1 (2 - e)(e + (2 - e)/4) de,
  ! the integrals by their primitives (prim_area, prim_mom), centre M/A.  All out, the centre is Barrowman's
  ! (17.3333 m from the nose, the configuration's formula).  The centre is
  ! where the fin force acts: its moment over its force.  1e-12 allowed
  ! (round-off of the two sums).
  block
    real(dp) :: s_e, share, x_cp, area, mom, worst, x_shield, expected_cp
    integer :: i
    rk = rocket_aero()
    rk%cn_alpha_fin = 6.4734_dp; rk%cn_fin_90 = 3.6193_dp
    rk%fin_root_le_from_nose = 16.5_dp; rk%fin_root_chord = 2.0_dp; rk%fin_tip_chord = 1.0_dp; rk%fin_sweep = 1.0_dp
    ! Barrowman's centre of pressure of the whole fin (airlaunch_scenario_config's formula)
    rk%x_fin_from_nose = 16.5_dp + 1.0_dp*(2.0_dp + 2*1.0_dp)/(3*3.0_dp) + (3.0_dp - 2.0_dp/3.0_dp)/6
    worst = 0.0_dp
    do i = 1, 199
      s_e = 2.0_dp*i/200.0_dp
      x_shield = rk%cg_from_nose - rk%fin_root_le_from_nose - s_e
      call fin_exposure(rk, x_shield, share, x_cp)
      if (s_e >= 1.0_dp) then
        expected_cp = s_e + (2.0_dp - s_e)/4
        area = 2.0_dp - s_e
      else
        ! strips e in [0, s]: chord 2 - s from s; e in [s, 1]: chord 2 - e from e,
        ! their moment (2 - e)(e + (2 - e)/4) = (2 - e)(3e + 2)/4 = (4 + 4e - 3e^2)/4
        area = s_e*(2.0_dp - s_e) + (prim_area(1.0_dp) - prim_area(s_e))
        mom = s_e*(2.0_dp - s_e)*(s_e + (2.0_dp - s_e)/4) + (prim_mom(1.0_dp) - prim_mom(s_e))
        expected_cp = mom/area
      end if
      worst = max(worst, abs(share - area/1.5_dp))
      worst = max(worst, abs((rk%cg_from_nose - x_cp) - (16.5_dp + expected_cp)))
    end do
    call check(worst <= 1.0e-12_dp, "exposed share and centre of the paper's fins against the closed form: worst " // &
      str(worst))
    ! the other planforms of the share test (a trailing edge swept forward: the
    ! edge meets it inside the span; a sweep longer than the root chord):
    ! their centre against the strip integral by the midpoint rule over
    ! 20 000 strips, blind to where the kinks lie (its error is of order h^2,
    ! h = 1/20000, from the kinks' strips: ~ 2.5e-9 m; 1e-7 m allowed)
    block
      real(dp), parameter :: geo2(3, 2) = reshape([2.0_dp, 0.5_dp, 0.3_dp, 1.0_dp, 1.0_dp, 1.5_dp], [3, 2])
      real(dp) :: cr, ct, xr, e, le, te, front, a_sum, m_sum, worst_cp, lo, hi
      integer :: c, k
      integer, parameter :: n_strips = 20000
      worst_cp = 0.0_dp
      do c = 1, 2
        rk%fin_root_chord = geo2(1, c); rk%fin_tip_chord = geo2(2, c); rk%fin_sweep = geo2(3, c)
        cr = geo2(1, c); ct = geo2(2, c); xr = geo2(3, c)
        rk%x_fin_from_nose = 16.5_dp + xr*(cr + 2*ct)/(3*(cr + ct)) + (cr + ct - cr*ct/(cr + ct))/6
        lo = 0.0_dp; hi = max(cr, xr + ct)
        do i = 1, 39
          s_e = lo + (hi - lo)*i/40.0_dp
          call fin_exposure(rk, rk%cg_from_nose - rk%fin_root_le_from_nose - s_e, share, x_cp)
          if (share <= 0.0_dp) cycle
          a_sum = 0.0_dp; m_sum = 0.0_dp
          do k = 1, n_strips
            e = (k - 0.5_dp)/n_strips
            le = xr*e
            te = le + cr + (ct - cr)*e
            front = min(te, max(le, s_e))
            a_sum = a_sum + (te - front)
            m_sum = m_sum + (te - front)*(front + (te - front)/4)
          end do
          if (a_sum > 0.0_dp) worst_cp = max(worst_cp, abs((rk%cg_from_nose - x_cp) - (16.5_dp + m_sum/a_sum)))
        end do
      end do
      call check(worst_cp <= 1.0e-7_dp, "exposed centre of two other planforms against the strip sum: worst " // &
        str(worst_cp) // " m")
    end block
    rk%fin_root_chord = 2.0_dp; rk%fin_tip_chord = 1.0_dp; rk%fin_sweep = 1.0_dp
    rk%x_fin_from_nose = 16.5_dp + 1.0_dp*(2.0_dp + 2*1.0_dp)/(3*3.0_dp) + (3.0_dp - 2.0_dp/3.0_dp)/6
    call fin_exposure(rk, 0.0_dp, share, x_cp)   ! the edge at the CG: all out
    call check_close(rk%cg_from_nose - x_cp, rk%x_fin_from_nose, "all out: Barrowman's centre of pressure", &
      rel=1e-14_dp)
    ! the force acts there: moment over force, a quarter of the root chord out
    x_shield = rk%cg_from_nose - rk%fin_root_le_from_nose - 1.5_dp
    call fin_exposure(rk, x_shield, share, x_cp)
    rk%c_dn = 0.0_dp
    call rocket_aero_eval(rk, rho, 300.0_dp, [v, 0.0_dp, 0.0_dp], [0.0_dp, 0.0_dp, w], x_shield, f, m)
    call check_close(m(3)/f(2), x_cp, "the fin force acts at the exposed part's centre", rel=1e-12_dp)
    call check_close(rk%cg_from_nose - x_cp, 16.5_dp + 1.5_dp + 0.5_dp/4, &
      "a quarter of the root chord out: its centre at the strip's quarter chord", rel=1e-14_dp)
  end block
  call section("fins of a smaller rocket far from the ramp edge: no overflow")
  ! In free flight the scene passes x_shield = huge (nothing shields) and the
  ! edge's distance in span fractions, s_e / x_r, overflowed for a sweep under
  ! 1 m (and (s_e - c_r)/(x_r + c_t - c_r) for a chord difference under 1 m):
  ! harmless in the release build (-inf, clipped to 0), fatal in the checked
  ! build, which traps overflows - the paper's fins (x_r = 1 m, x_r + c_t - c_r
  ! = 0) never reached it, their quarter-scale copy did.  Reference: all out,
  ! the share 1 and Barrowman's centre of pressure; all in, the share 0; and
  ! no overflow raised.
  block
    real(dp) :: share, x_cp, cr, ct, xr, barrowman
    logical :: overflow
    integer :: j
    real(dp), parameter :: planforms(3, 2) = reshape([0.5_dp, 0.25_dp, 0.25_dp, 0.5_dp, 0.3_dp, 0.1_dp], [3, 2])
    do j = 1, 2
      rk = rocket_aero(length=4.625_dp, diameter=0.4_dp, cg_from_nose=2.3125_dp)
      cr = planforms(1, j); ct = planforms(2, j); xr = planforms(3, j)
      rk%fin_root_chord = cr; rk%fin_tip_chord = ct; rk%fin_sweep = xr
      rk%fin_root_le_from_nose = rk%length - cr
      barrowman = rk%fin_root_le_from_nose + xr*(cr + 2*ct)/(3*(cr + ct)) + (cr + ct - cr*ct/(cr + ct))/6
      rk%x_fin_from_nose = barrowman
      call ieee_set_flag(ieee_overflow, .false.)
      call fin_exposure(rk, huge(1.0_dp), share, x_cp)
      call ieee_get_flag(ieee_overflow, overflow)
      call check(.not. overflow, "planform " // str(j) // ", all out (x_shield = huge): no overflow")
      call check_close(share, 1.0_dp, "planform " // str(j) // ", all out: share 1", rel=1e-15_dp)
      call check_close(rk%cg_from_nose - x_cp, barrowman, "planform " // str(j) // ", all out: Barrowman's centre", &
        rel=1e-14_dp)
      call ieee_set_flag(ieee_overflow, .false.)
      call fin_exposure(rk, -huge(1.0_dp), share, x_cp)
      call ieee_get_flag(ieee_overflow, overflow)
      call check(.not. overflow, "planform " // str(j) // ", all in (x_shield = -huge): no overflow")
      call check_close(share, 0.0_dp, "planform " // str(j) // ", all in: share 0", abs=0.0_dp)
    end do
    ! the whole rocket's loads likewise: the exposed length's share,
    ! (x_shield - x_tail)/length, overflowed for a rocket under 1 m long (a
    ! 1:20 model of the paper's, 0.925 m).  Reference: the loads with the edge
    ! one length ahead of the nose, all out as well, bit for bit.
    block
      real(dp) :: f_far(3), m_far(3)
      rk = rocket_aero(length=0.925_dp, diameter=0.08_dp, cg_from_nose=0.4625_dp, cp_pot_from_nose=0.1_dp)
      call ieee_set_flag(ieee_overflow, .false.)
      call rocket_aero_eval(rk, 1.0_dp, 300.0_dp, [40.0_dp, -3.0_dp, 1.0_dp], [0.0_dp, 0.2_dp, 0.5_dp], &
        huge(1.0_dp), f, m)
      call ieee_get_flag(ieee_overflow, overflow)
      call check(.not. overflow, "a 0.925 m rocket, all out (x_shield = huge): no overflow")
      call rocket_aero_eval(rk, 1.0_dp, 300.0_dp, [40.0_dp, -3.0_dp, 1.0_dp], [0.0_dp, 0.2_dp, 0.5_dp], &
        rk%cg_from_nose + rk%length, f_far, m_far)
      call check(all(f == f_far) .and. all(m == m_far), "a 0.925 m rocket, all out: the loads of an edge " // &
        "one length ahead of the nose, bit for bit")
    end block
  end block
  rk = rocket_aero()

  call section("parachute: inflation law and apparent mass")
  pc%deploy_time = 1.0_dp; pc%fill_time = 0.4_dp
  call check_close(parachute_drag_area(pc, 0.5_dp), pc%packed_drag_area, "packed before deployment", rel=1e-15_dp)
  call check_close(parachute_drag_area(pc, 1.2_dp), pc%packed_drag_area + (pc%drag_area - pc%packed_drag_area)*0.25_dp, &
    "quadratic growth: half the fill time gives a quarter", rel=1e-14_dp)
  call check_close(parachute_drag_area(pc, 2.0_dp), pc%drag_area, "fully open after the fill time", rel=1e-15_dp)
  call check_close(parachute_added_mass(pc, 0.41351_dp, 2.0_dp), &
    0.41351_dp*pi/6*(0.7_dp*sqrt(4*10.0_dp/(pi*0.75_dp)))**3, "m_a = rho pi/6 (0.7 D0)^3", rel=1e-14_dp)
  call check(parachute_added_mass(pc, 0.41351_dp, 2.0_dp) > 2*pc%mass, "apparent mass at 10 km exceeds the canopy mass")

  call section("parachute: momentum of canopy and entrained air while it fills")
  ! A free canopy (no line force, no weight) decelerating through its filling at
  ! 10 km, its acceleration integrated by RK4: the momentum theorem for canopy +
  ! apparent mass, (m + m_a(T)) v(T) - (m + m_a(0)) v(0) = integral of the drag
  ! alone (-1/2 rho CdS |v| v, computed here from the drag area), holds to the
  ! integration error (1e-11 relative with 48 000 steps over 0.6 s; tolerance 1e-8).  Without the
  ! (dm_a/dt) v term the canopy kept the entrained air's momentum: off by m_a v,
  ! ~80 % of the momentum.
  block
    real(dp) :: vel(3), xk(3), t, dt, impulse(3), p0(3), p1(3), acc(3), drag(3), kv(3, 4), kd(3, 4), rho10
    logical :: ok
    integer :: step, stage
    real(dp), parameter :: cstage(4) = [0.0_dp, 0.5_dp, 0.5_dp, 1.0_dp], wstage(4) = [1.0_dp, 2.0_dp, 2.0_dp, 1.0_dp]
    pc%deploy_time = 0.1_dp; pc%fill_time = 0.4_dp
    xk = [0.0_dp, 10000.0_dp, 0.0_dp]
    air = isa(xk(2))
    rho10 = air%density
    vel = [-150.0_dp, -20.0_dp, 5.0_dp]
    t = 0.0_dp
    dt = 0.6_dp/48000   ! the filling's start and end (0.1, 0.5 s) on step boundaries
    impulse = 0.0_dp
    p0 = (pc%mass + parachute_added_mass(pc, rho10, t))*vel
    do step = 1, 48000
      do stage = 1, 4   ! classical RK4 on v, the drag integrated alongside
        if (stage == 1) then
          call canopy_node_acceleration(pc, t, xk, vel, 0.0_dp, [0.0_dp, 0.0_dp, 0.0_dp], .true., .false., acc, &
            drag, ok)
        else
          call canopy_node_acceleration(pc, t + cstage(stage)*dt, xk, vel + cstage(stage)*dt*kv(:, stage - 1), &
            0.0_dp, [0.0_dp, 0.0_dp, 0.0_dp], .true., .false., acc, drag, ok)
        end if
        kv(:, stage) = acc
        associate(u => vel + cstage(stage)*dt*merge(kv(:, max(stage - 1, 1)), [0.0_dp, 0.0_dp, 0.0_dp], stage > 1))
          kd(:, stage) = -0.5_dp*rho10*parachute_drag_area(pc, t + cstage(stage)*dt)*norm2(u)*u
        end associate
      end do
      vel = vel + dt/6*matmul(kv, wstage)
      impulse = impulse + dt/6*matmul(kd, wstage)
      t = step*dt
    end do
    p1 = (pc%mass + parachute_added_mass(pc, rho10, t))*vel
    call check(ok, "inside the atmosphere")
    call check_close(norm2(p1 - p0 - impulse)/norm2(p0), 0.0_dp, "momentum change = the drag's impulse", abs=1e-8_dp)
    call check(abs(p1(1)) < 0.9_dp*abs(p0(1)), "the canopy lost momentum")
    ! the Jacobian's velocity block: d(drag + momentum term)/dv against central
    ! differences of the force canopy_node_acceleration reports (the momentum
    ! term's -(dm_a/dt) I was overwritten by the drag's block, helper-36)
    block
      real(dp) :: jac(3, 3), fd(3, 3), dplus(3), dminus(3), mass, hv
      integer :: jv
      call canopy_node_jacobian(pc, 0.3_dp, xk, vel, 0.0_dp, .true., mass, jac, ok)
      hv = 1e-4_dp
      do jv = 1, 3
        call canopy_node_acceleration(pc, 0.3_dp, xk, vel + hv*unit(jv), 0.0_dp, [0.0_dp, 0.0_dp, 0.0_dp], &
          .true., .false., acc, dplus, ok)
        call canopy_node_acceleration(pc, 0.3_dp, xk, vel - hv*unit(jv), 0.0_dp, [0.0_dp, 0.0_dp, 0.0_dp], &
          .true., .false., acc, dminus, ok)
        fd(:, jv) = (dplus - dminus)/(2*hv)
      end do
      ! central differences of a smooth quadratic force: exact to rounding (1e-8 relative)
      call check_close(maxval(abs(jac - fd))/maxval(abs(fd)), 0.0_dp, "d(drag)/dv at mid-filling", abs=1e-7_dp)
    end block
    pc%deploy_time = -1.0_dp
  end block

  call section("trim: calibrate at the paper's alpha, then fly")
  air = isa(10000.0_dp)
  ac = aircraft_aero()
  tp = trim_problem(aircraft_mass=89000.0_dp, rocket_mass=28000.0_dp, r_rocket=[0.0_dp, -1.5_dp, 0.0_dp], &
    r_tie=[9.25_dp, -1.5_dp, 0.0_dp], pull=0.5_dp*air%density*(0.65_dp*air%sound_speed)**2*10.0_dp, &
    density=air%density, speed=0.65_dp*air%sound_speed, mode="calibrate", alpha_target=1.2174_dp*deg2rad)
  call trim_case0(tp, ac, tr, error)
  call check(.not. allocated(error), "calibration converges")
  tp%mode = "fly"
  call trim_case0(tp, ac, tr2, error)
  call check(.not. allocated(error), "trim converges")
  call check_close(tr2%alpha/deg2rad, 1.2174_dp, "trimmed alpha [deg]", abs=1e-6_dp)
  call check_close(tr2%delta_e, 0.0_dp, "trimmed elevator [rad]", abs=1e-8_dp)
  call check_close(tr2%thrust, tr%thrust, "thrust agrees", rel=1e-8_dp)
  ! lift carries the weight to within the thrust and drag components (sin alpha ~ 2 %)
  call check_close((tr%cl0 + ac%cl_alpha*1.2174_dp*deg2rad)*tp%density*tp%speed**2/2*ac%wing_area, &
    117000.0_dp*g0, "lift ~ weight", rel=2e-2_dp)
  ! thrust balances aircraft drag + parachute pull (cos alpha ~ 1)
  call check_close(tr%thrust, tp%pull + (ac%cd0 + ac%k_induced*(117000*g0/(tp%density*tp%speed**2/2*ac%wing_area))**2) &
    *tp%density*tp%speed**2/2*ac%wing_area, "thrust ~ drag + pull", rel=2e-2_dp)

  call section("trim: an equilibrium beyond the elevator limit is refused")
  ! the calibrated aircraft at Mach 0.35: first with an unlimited elevator
  ! (the reference: its equilibrium), then with a limit of half that elevator:
  ! the same equilibrium is found (1e-9 rad: Newton converged to 1e-10 of the
  ! weight) and refused as infeasible; `ac` is left as it was
  block
    type(aircraft_aero) :: ac_free, ac_lim
    type(trim_result) :: tr_free, tr_lim
    tp%speed = 0.35_dp*air%sound_speed
    ac_free = ac
    ac_free%delta_e_max = huge(1.0_dp)
    call trim_case0(tp, ac_free, tr_free, error)
    call check(.not. allocated(error) .and. .not. tr_free%infeasible, "unlimited elevator: the trim converges")
    call check(tr_free%alpha > 0.0_dp .and. tr_free%alpha < 15*deg2rad .and. tr_free%delta_e < 0.0_dp, &
      "slow flight: alpha within its range, nose-up (negative) elevator")
    if (allocated(error)) deallocate(error)
    ac_lim = ac
    ac_lim%delta_e_max = 0.5_dp*abs(tr_free%delta_e)
    call trim_case0(tp, ac_lim, tr_lim, error)
    call check(allocated(error) .and. tr_lim%infeasible, "elevator beyond its limit: error, infeasible")
    if (allocated(error)) then
      call check(index(error%message, "beyond the elevator limit (allowed") > 0 .and. &
        index(error%message, new_line("a")) == 0, "one line naming the elevator limit: " // error%message)
      deallocate(error)
    end if
    call check_close(tr_lim%delta_e, tr_free%delta_e, "the refused elevator is the equilibrium's", abs=1e-9_dp)
    call check(ac_lim%delta_e_trim == ac%delta_e_trim .and. ac_lim%thrust == ac%thrust, "aircraft left unchanged")
  end block
  call finish()
contains

  !> int (2 - e) de: the exposed chord of the paper's fins aft of their leading edge.
  pure real(dp) function prim_area(e)
    real(dp), intent(in) :: e
    prim_area = 2*e - e**2/2
  end function prim_area

  !> int (4 + 4 e - 3 e^2)/4 de: those strips' chord times their quarter-chord point.
  pure real(dp) function prim_mom(e)
    real(dp), intent(in) :: e
    prim_mom = e + e**2/2 - e**3/4
  end function prim_mom
  !> The share of a trapezoidal fin (root chord, tip chord, sweep; semi-span b)
  !> aft of s_e (measured aft from the root's leading edge): the planform
  !> clipped by the half-plane s >= s_e (Sutherland-Hodgman), areas by the
  !> shoelace formula.
  function clipped_share(geo, b, s_e) result(share)
    real(dp), intent(in) :: geo(3), b, s_e
    real(dp) :: share, p(2, 4), q(2, 8), a, d
    integer :: i, j, nq
    p(:, 1) = [0.0_dp, 0.0_dp]; p(:, 2) = [geo(1), 0.0_dp]
    p(:, 3) = [geo(3) + geo(2), b]; p(:, 4) = [geo(3), b]
    nq = 0
    do i = 1, 4
      j = modulo(i, 4) + 1                   ! the edge p_i -> p_j
      if (p(1, i) >= s_e) then
        nq = nq + 1; q(:, nq) = p(:, i)
      end if
      if ((p(1, i) >= s_e) .neqv. (p(1, j) >= s_e)) then
        d = (s_e - p(1, i))/(p(1, j) - p(1, i))
        nq = nq + 1; q(:, nq) = p(:, i) + d*(p(:, j) - p(:, i))
      end if
    end do
    a = 0.0_dp
    do i = 1, nq
      j = modulo(i, nq) + 1
      a = a + q(1, i)*q(2, j) - q(1, j)*q(2, i)
    end do
    share = abs(0.5_dp*a)/(0.5_dp*b*(geo(1) + geo(2)))
  end function clipped_share

  !> The unit vector along axis k.
  pure function unit(k) result(e)
    integer, intent(in) :: k
    real(dp) :: e(3)
    e = 0.0_dp
    e(k) = 1.0_dp
  end function unit
end program test_aero
