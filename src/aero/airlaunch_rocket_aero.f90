!> Aerodynamics of a slender rocket (no fins by default) up to and beyond
!> 90 deg angle of attack, by the Allen-Perkins / Jorgensen model:
!>
!>   C_N = sin(2 a) cos(a/2)            (potential, slender-body theory; acts
!>                                        near the nose: unstable)
!>       + eta C_dn (S_p/S_ref) sin^2 a (viscous cross-flow; acts along the body)
!>
!> (L. H. Jorgensen, "Prediction of static aerodynamic characteristics for
!> slender bodies alone and with lifting surfaces to very high angles of
!> attack", NASA TR R-474, 1977; H. J. Allen & E. W. Perkins, NACA TR 1048,
!> 1951).  The cross-flow part is integrated over `n_strips` strips with the
!> local velocity v + w x r, so the same term gives the static force at any
!> angle and the pitch/yaw damping of a rotating body.  Strips ahead of
!> `x_shield` (body x) are shielded (inside the cargo bay) and feel no air; the
!> potential and axial terms are scaled by the exposed fraction of the length
!> (a simple shielding model for a rocket that leaves the bay tail first),
!> the potential term acting at the exposed part's front (the ramp edge)
!> while its own centre is still in the bay.
!> Axial force: -1/2 rho |u| u S_ref C_A.  Optional fins (a documented
!> configuration choice) add, at their centre of pressure x_fin and with the
!> local velocity there (so they damp rotation too),
!>   C_N,fin = cn_alpha_fin sin(a) |cos(a)| + cn_fin_90 sin^2(a)
!> (the linear Barrowman slope at small angles and the flat-plate cross-flow
!> normal force at 90 deg, Hoerner, Fluid-Dynamic Drag, 1965: C_N = 1.28 on the
!> projected fin area), opposite to the local cross-flow velocity.  While the
!> fins pass the ramp edge (tail first) their force is scaled by the share of
!> their planform outside the bay, acting at the exposed part's centre of
!> pressure (fin_exposure, thirty-first session: before, at the whole fins'):
!> it grows continuously from 0 to 1 over the root chord, as the hull's and
!> the nose's shares do over the length.
!>
!> In a gust the caller may pass the gust field with the body's pose: each
!> station then reads the gust at its own place (gust penetration), as a
!> frozen gust meets a moving body.  v_b stays the CG's air-relative velocity;
!> a station at body x adds the change of the gust between the CG and itself,
!> -(C^T)(w(r + x c_1) - w(r)).  The cross-flow strips read it at their
!> centres, the fins at their centre of pressure, the potential term at its
!> centre (or, while that is still in the bay, at the front of the exposed
!> part), the axial force at the CG.  Without the gust every station reads the
!> CG's.  A gust whose velocity changes linearly along the body gives the
!> strips and the fins the local air of a pitch or yaw rate of the body in
!> uniform air (Etkin's equivalence; tests/unit/test_gust.f90 checks it).
!>
!> Optional Mach dependence (default off: the paper's constant coefficients,
!> bit for bit).  With a table of n_c_dn points the cross-flow drag
!> coefficient of each strip is C_dn(M_c), M_c = |v_c|/a, piecewise linear in
!> the strip's own cross-flow Mach number (|v_c| its local cross-flow speed,
!> rotation and gust included; a the local speed of sound the caller passes
!> with rho) and held constant beyond the table's ends; the scalar c_dn is then
!> not used.  Likewise C_A(M), M = |v_b|/a the CG's free-stream Mach number,
!> from a table of n_c_axial points.  Jorgensen (NASA TR R-474, 1977) shows
!> C_dn of a circular cylinder rising above its subcritical 1.2 as M_c nears
!> 1: the tables let a user give such a curve (docs/model.md).
!>
!> Body frame: x along the axis towards the nose, origin at the CG.
module airlaunch_rocket_aero
  use, intrinsic :: ieee_arithmetic, only: ieee_is_nan
  use airlaunch_kinds, only: dp, pi
  use airlaunch_gust, only: gust_field, gust_velocity
  implicit none
  private
  public :: rocket_aero, rocket_aero_eval, fin_exposed_fraction, fin_exposure, mach_table_value

  !> Most points of a Mach table (c_dn_mach/c_dn_table, c_axial_mach/c_axial_table).
  integer, parameter, public :: max_mach_points = 16

  !> Geometry and coefficients of the rocket.
  type :: rocket_aero
    real(dp) :: length = 18.5_dp          !< [m]
    real(dp) :: diameter = 1.6_dp         !< [m]
    real(dp) :: cg_from_nose = 9.25_dp    !< [m]
    real(dp) :: cp_pot_from_nose = 2.0_dp !< centre of the potential normal force [m] (~ half the nose length)
    real(dp) :: c_axial = 0.35_dp         !< axial force coefficient (subsonic, blunt base)
    real(dp) :: c_dn = 1.2_dp             !< cross-flow drag coefficient of a circular cylinder (subcritical)
    real(dp) :: eta = 0.7_dp              !< finite-length factor of the cross-flow drag (L/d ~ 11)
    real(dp) :: cn_alpha_fin = 0.0_dp     !< fin normal-force slope on S_ref [1/rad]; 0 = no fins
    real(dp) :: x_fin_from_nose = 17.5_dp !< fin centre of pressure [m]
    real(dp) :: cn_fin_90 = 0.0_dp        !< fin normal-force coefficient at 90 deg on S_ref
    ! the fins' trapezoidal planform (for their exposure at the ramp edge); a
    ! root chord of 0 makes the fins a point at x_fin_from_nose, in the air
    ! once that point is out of the bay
    real(dp) :: fin_root_le_from_nose = 0.0_dp !< root leading edge aft of the nose [m]
    real(dp) :: fin_root_chord = 0.0_dp   !< [m]
    real(dp) :: fin_tip_chord = 0.0_dp    !< [m]
    real(dp) :: fin_sweep = 0.0_dp        !< leading-edge offset root to tip [m]
    integer :: n_strips = 16              !< strips of the cross-flow integral
    ! optional Mach tables (0 points: the constant c_dn, c_axial above);
    ! piecewise linear, constant beyond the ends, Mach points strictly increasing
    integer :: n_c_dn = 0                 !< points of the C_dn(M_c) table
    real(dp) :: c_dn_mach(max_mach_points) = 0.0_dp   !< cross-flow Mach numbers M_c
    real(dp) :: c_dn_table(max_mach_points) = 0.0_dp  !< C_dn at them
    integer :: n_c_axial = 0              !< points of the C_A(M) table
    real(dp) :: c_axial_mach(max_mach_points) = 0.0_dp   !< free-stream Mach numbers M
    real(dp) :: c_axial_table(max_mach_points) = 0.0_dp  !< C_A at them
  end type rocket_aero

contains

  !> Force (body frame) and moment about the CG (body frame) for air-relative
  !> CG velocity v_b and body rates w_b.  Strips with body x > x_shield are
  !> shielded (x measured from the CG, towards the nose); pass a large value
  !> for a fully exposed rocket.  `sound_speed` (the local speed of sound, from
  !> the atmosphere model with rho) sets the Mach numbers of the optional
  !> tables; it is not used without them.
  !> With `gust`, `r_cg` and `c` present the stations read the gust where they
  !> are (module header); v_b is the CG's air-relative velocity either way.
  pure subroutine rocket_aero_eval(p, rho, sound_speed, v_b, w_b, x_shield, force, moment, gust, r_cg, c)
    type(rocket_aero), intent(in) :: p
    real(dp), intent(in) :: rho, sound_speed, v_b(3), w_b(3), x_shield
    real(dp), intent(out) :: force(3), moment(3)
    type(gust_field), intent(in), optional :: gust   !< the gust, read at each station
    real(dp), intent(in), optional :: r_cg(3)        !< the CG, earth frame [m] (with gust)
    real(dp), intent(in), optional :: c(3, 3)        !< body-to-earth rotation (with gust)
    real(dp) :: s_ref, dx, x, v_loc(3), vp(3), vpn, f(3), v, alpha, exposed, x_nose, x_tail
    real(dp) :: x_lo, x_hi, w_cg(3), fin_share, c_a, c_dn
    logical :: penetrating
    integer :: i
    force = 0; moment = 0
    s_ref = pi*p%diameter**2/4
    x_nose = p%cg_from_nose
    x_tail = p%cg_from_nose - p%length
    ! an edge a length or more ahead of the nose leaves all of it out (the
    ! quotient below >= 2): taken so, x_shield = huge (free flight) cannot
    ! overflow it for a rocket under 1 m long
    if (x_shield >= x_nose + p%length) then
      exposed = 1.0_dp
    else
      exposed = max(0.0_dp, min(1.0_dp, (x_shield - x_tail)/p%length))
    end if
    if (exposed <= 0.0_dp) return
    penetrating = present(gust) .and. present(r_cg) .and. present(c)
    if (penetrating) penetrating = gust%active
    if (penetrating) w_cg = gust_velocity(gust, r_cg)
    v = norm2(v_b)
    ! axial force, scaled by the exposed fraction
    c_a = p%c_axial
    if (p%n_c_axial > 0) c_a = mach_table_value(p%n_c_axial, p%c_axial_mach, p%c_axial_table, v/sound_speed)
    force(1) = -0.5_dp*rho*abs(v_b(1))*v_b(1)*s_ref*c_a*exposed
    ! viscous cross-flow, strip by strip with the local velocity
    dx = p%length/p%n_strips
    do i = 1, p%n_strips
      x_lo = x_tail + (i - 1)*dx
      x_hi = min(x_lo + dx, x_shield)
      if (x_hi <= x_lo) cycle
      x = 0.5_dp*(x_lo + x_hi)
      v_loc = v_b + [0.0_dp, w_b(3)*x, -w_b(2)*x]   ! v + w x (x, 0, 0)
      if (penetrating) v_loc = v_loc - gust_change(x)
      vp = [0.0_dp, v_loc(2), v_loc(3)]
      vpn = norm2(vp)
      c_dn = p%c_dn
      if (p%n_c_dn > 0) c_dn = mach_table_value(p%n_c_dn, p%c_dn_mach, p%c_dn_table, vpn/sound_speed)
      f = -0.5_dp*rho*p%eta*c_dn*p%diameter*(x_hi - x_lo)*vpn*vp
      force = force + f
      moment = moment + [0.0_dp, -x*f(3), x*f(2)]    ! (x,0,0) x f
    end do
    ! potential (slender-body) normal force near the nose, opposite to the
    ! cross-flow velocity of the body; scaled by the exposed fraction.  While
    ! its centre cp_pot is still in the bay it acts at the exposed part's
    ! front, the ramp edge: slender-body theory puts the force where the
    ! cross-section enters the stream (dS/dx), which for the hull emerging
    ! tail first is the edge, not a nose still shielded in the bay (before the
    ! thirty-fourth session it acted at cp_pot inside the bay).  It takes no
    ! part of the rotation (vpn > 0 implies v > 0); the fins below use their
    ! local velocity and act on a pitching body too.  Penetrating a gust, it
    ! reads the air where it acts.
    x = min(x_nose - p%cp_pot_from_nose, x_shield)
    v_loc = v_b
    if (penetrating) then
      v_loc = v_loc - gust_change(x)
      v = norm2(v_loc)
    end if
    vp = [0.0_dp, v_loc(2), v_loc(3)]
    vpn = norm2(vp)
    if (vpn > 0.0_dp) then
      ! atan2 keeps full relative precision at small angles (acos(v_x/v) does not)
      alpha = atan2(vpn, v_loc(1))
      f = -0.5_dp*rho*v*v*s_ref*sin(2*alpha)*cos(alpha/2)*exposed*vp/vpn
      force = force + f
      moment = moment + [0.0_dp, -x*f(3), x*f(2)]
    end if
    if (p%cn_alpha_fin > 0.0_dp) then
      call fin_exposure(p, x_shield, fin_share, x)
      if (fin_share > 0.0_dp) then
        v_loc = v_b + [0.0_dp, w_b(3)*x, -w_b(2)*x]
        if (penetrating) v_loc = v_loc - gust_change(x)
        vp = [0.0_dp, v_loc(2), v_loc(3)]
        vpn = norm2(vp)
        if (vpn > 0.0_dp) then
          ! C_N,fin q S_ref along -vp/|vp|, with sin(a) = |vp|/|v|, |cos(a)| = |v_x|/|v|
          f = -0.5_dp*rho*s_ref*(p%cn_alpha_fin*abs(v_loc(1)) + p%cn_fin_90*vpn)*fin_share*vp
          force = force + f
          moment = moment + [0.0_dp, -x*f(3), x*f(2)]
        end if
      end if
    end if
  contains
    !> The change of the gust between the CG and body x, body frame (only
    !> when penetrating: gust, r_cg and c present).
    pure function gust_change(xs) result(u)
      real(dp), intent(in) :: xs
      real(dp) :: u(3), dw(3)
      integer :: j
      ! C^T dw by its columns (matmul of the optional c allocates a temporary)
      dw = gust_velocity(gust, r_cg + xs*c(:, 1)) - w_cg
      do j = 1, 3
        u(j) = dot_product(c(:, j), dw)
      end do
    end function gust_change
  end subroutine rocket_aero_eval

  !> The value of a Mach table of n points (xs strictly increasing) at
  !> Mach number x: piecewise linear between the points, the end value beyond
  !> either end (a table of one point is a constant).  At a point it returns
  !> that point's value exactly.  A NaN Mach number gives NaN (a run gone
  !> non-finite is named by its non-finite check, not carried on by an end
  !> point's value; and the ordered comparisons below would raise the invalid
  !> flag, a trap in the checked build).
  pure real(dp) function mach_table_value(n, xs, ys, x) result(y)
    integer, intent(in) :: n             !< points (1 to size(xs))
    real(dp), intent(in) :: xs(:), ys(:) !< Mach numbers and values
    real(dp), intent(in) :: x            !< Mach number
    integer :: i
    if (ieee_is_nan(x)) then
      y = x
      return
    end if
    if (x <= xs(1)) then
      y = ys(1)
      return
    end if
    do i = 2, n
      if (x < xs(i)) then
        y = ys(i-1) + (ys(i) - ys(i-1))*((x - xs(i-1))/(xs(i) - xs(i-1)))
        return
      end if
    end do
    y = ys(n)
  end function mach_table_value

  !> Share of the fins' planform outside the bay, body x <= x_shield (the
  !> rocket leaves tail first): fin_exposure's share.
  pure real(dp) function fin_exposed_fraction(p, x_shield) result(share)
    type(rocket_aero), intent(in) :: p
    real(dp), intent(in) :: x_shield     !< the ramp edge, body x from the CG [m]
    real(dp) :: x_cp
    call fin_exposure(p, x_shield, share, x_cp)
  end function fin_exposed_fraction

  !> The fins' planform outside the bay, body x <= x_shield (the rocket leaves
  !> tail first): its share of the whole planform and its centre of pressure.
  !> The trapezoid (root chord c_r from its leading edge, tip chord c_t offset
  !> aft by the sweep x_r at the semi-span) is cut by the edge's line across
  !> the span.  At span fraction e the chord runs from x_r e to
  !> x_r e + c_r + (c_t - c_r) e aft of the root's leading edge; the exposed
  !> chord c(e), the part aft of the edge, and its front a(e) are linear in e
  !> between the points where the edge meets the leading or the trailing edge,
  !> so the trapezoidal rule integrates the area, and Simpson's rule the
  !> strips' quarter-chord moment c (a + c/4) (quadratic), exactly on those
  !> pieces.  The centre of pressure is that moment over the area: strip
  !> theory, whose value for the whole trapezoid,
  !>   x_r (c_r + 2 c_t)/(3 (c_r + c_t)) + (c_r^2 + c_r c_t + c_t^2)/(6 (c_r + c_t)),
  !> is Barrowman's (the same two terms), so the exposed part's centre is
  !> x_fin_from_nose shifted by the difference: the fins' centre of pressure
  !> once all of them are out.  Share and centre are continuous and the share
  !> non-decreasing in x_shield: 0 with the trailing edge in the bay, 1 with
  !> the root's leading edge out.  Without a root chord, 1 or 0 as the centre
  !> of pressure (x_fin_from_nose) is out or in.
  pure subroutine fin_exposure(p, x_shield, share, x_cp)
    type(rocket_aero), intent(in) :: p
    real(dp), intent(in) :: x_shield     !< the ramp edge, body x from the CG [m]
    real(dp), intent(out) :: share       !< the share of the planform outside the bay
    real(dp), intent(out) :: x_cp        !< its centre of pressure, body x from the CG [m]
    real(dp) :: s_e, e(4), cr, ct, xr, area, moment, whole
    integer :: i
    x_cp = p%cg_from_nose - p%x_fin_from_nose
    if (p%fin_root_chord <= 0.0_dp) then
      share = merge(1.0_dp, 0.0_dp, x_cp <= x_shield)
      return
    end if
    cr = p%fin_root_chord; ct = p%fin_tip_chord; xr = p%fin_sweep
    s_e = (p%cg_from_nose - p%fin_root_le_from_nose) - x_shield   ! the edge, aft of the root's leading edge
    ! an edge ahead of the fins (s_e <= 0: all out) or aft of them (s_e >=
    ! their extent max(c_r, x_r + c_t): all in) gives the same e, front and
    ! chords wherever it is; held within +-extent, free flight's x_shield =
    ! huge cannot overflow s_e / x_r below (a sweep under 1 m did)
    s_e = min(max(cr, xr + ct), max(-max(cr, xr + ct), s_e))
    ! the kinks of the exposed chord: where the edge meets the leading edge
    ! (x_r e = s_e) and the trailing edge (c_r + (x_r + c_t - c_r) e = s_e)
    e = [0.0_dp, 1.0_dp, 1.0_dp, 1.0_dp]
    if (xr > 0.0_dp) e(2) = min(1.0_dp, max(0.0_dp, s_e/xr))
    if (abs(xr + ct - cr) > 0.0_dp) e(3) = min(1.0_dp, max(0.0_dp, (s_e - cr)/(xr + ct - cr)))
    e(2:3) = [minval(e(2:3)), maxval(e(2:3))]
    area = 0.0_dp; moment = 0.0_dp
    do i = 1, 3
      area = area + 0.5_dp*(e(i+1) - e(i))*(chord_aft(e(i)) + chord_aft(e(i+1)))
      moment = moment + (e(i+1) - e(i))/6*(strip_moment(e(i)) + 4*strip_moment(0.5_dp*(e(i) + e(i+1))) + &
        strip_moment(e(i+1)))
    end do
    share = min(1.0_dp, max(0.0_dp, area/(0.5_dp*(cr + ct))))
    if (area > 0.0_dp) then
      ! the whole trapezoid's strip-theory centre, aft of the root's leading edge
      whole = xr*(cr + 2*ct)/(3*(cr + ct)) + (cr**2 + cr*ct + ct**2)/(6*(cr + ct))
      x_cp = x_cp - (moment/area - whole)
    end if
  contains
    !> The front of the strip at span fraction e aft of the edge, from the
    !> root's leading edge: the edge, or the fin's leading or trailing edge.
    pure real(dp) function front_aft(e) result(a)
      real(dp), intent(in) :: e
      a = min(trailing(e), max(xr*e, s_e))
    end function front_aft
    !> The fin's trailing edge at span fraction e, from the root's leading edge.
    pure real(dp) function trailing(e)
      real(dp), intent(in) :: e
      trailing = xr*e + cr + (ct - cr)*e
    end function trailing
    !> The chord aft of the edge at span fraction e.
    pure real(dp) function chord_aft(e) result(c)
      real(dp), intent(in) :: e
      c = trailing(e) - front_aft(e)
    end function chord_aft
    !> The exposed strip's chord times its quarter-chord point, aft of the
    !> root's leading edge, at span fraction e.
    pure real(dp) function strip_moment(e) result(g)
      real(dp), intent(in) :: e
      g = chord_aft(e)*(front_aft(e) + chord_aft(e)/4)
    end function strip_moment
  end subroutine fin_exposure
end module airlaunch_rocket_aero
