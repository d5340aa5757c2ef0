!> Carrier-aircraft aerodynamics: linear stability derivatives about the
!> clean aircraft's centre of gravity, with an elevator, constant thrust and
!> an optional pitch-attitude hold.
!>
!> The paper gives the wing (S = 300 m^2, b = 51 m, c = 6 m) and the trim angle
!> of attack (1.2174 deg at 10 km, Mach 0.65) but no coefficients.  Defaults are
!> the longitudinal derivatives of a large transport (Boeing 747 class, per rad,
!> Heffley & Jewell, NASA CR-2144, 1972): CL_alpha = 5.7, Cm_alpha = -1.45,
!> Cm_q = -21, Cm_alphadot = -3.3, Cm_de = -1.4, CL_de = 0.36.  The lateral-
!> directional derivatives are order-of-magnitude values of the same class
!> (they only damp asymmetric disturbances; the paper's scenario is symmetric).  CL0 and Cm0 are not free: the trim solver
!> (airlaunch_trim) sets them so that the Case 0 system trims at the paper's
!> angle of attack with zero elevator.
!>
!> Axes: body x forward, y up, z right.  alpha = atan2(-v_y, v_x) of the
!> body-frame air-relative velocity, beta = asin(v_z/V).  Lift is normal to the
!> velocity in the body x-y plane (the plane of symmetry), drag along -V (the
!> wind axis, also in sideslip), the side force C_Y along body z.  Pitch rate is w_z
!> (nose up positive); the standard yaw rate (nose right) is r = -w_y, so the
!> yawing moment about +y is -qSb Cn.  Cm_alphadot is folded into Cm_q
!> (quasi-steady: alpha_dot ~ q in the short-period motion), since alpha_dot
!> is not a state.
!>
!> Gust penetration: the derivatives hold for air that is the same over the
!> whole aircraft (the wing's and the CG's).  When a gust's air velocity at the
!> empennage differs, the caller passes the body-frame air-relative velocity
!> there, v_tail (without the rotation's part, which Cm_q and Cn_r already
!> hold).  The horizontal tail then adds the lift
!>   dL = qbar S CL_alpha_tail (alpha_tail - alpha)
!> normal to the velocity in the plane of symmetry, and the fin the side force
!>   dY = qbar S CY_beta_fin (beta_tail - beta)
!> along body z, both at the empennage point `tail_point` (their moments
!> r_tail x dF).  CL_alpha_tail and CY_beta_fin are the tail's and the fin's
!> slopes on the wing area (without downwash); their defaults are the ones
!> that give the 747-class Cm_q = -21 and Cn_r = -0.30 as the tail's damping,
!> Cm_q = -2 CL_alpha_tail (l_t/c)^2 and Cn_r = 2 CY_beta_fin (l_t/b)^2 with
!> the arm l_t = 24 m of the default empennage point (docs/model.md "Gusts").
module airlaunch_aircraft_aero
  use airlaunch_kinds, only: dp, deg2rad
  use airlaunch_rotation, only: cross
  implicit none
  private
  public :: aircraft_aero, aircraft_aero_eval, aircraft_aero_out

  !> Aerodynamic and propulsive data of the carrier.
  type :: aircraft_aero
    real(dp) :: wing_area = 300.0_dp      !< S [m^2]
    real(dp) :: span = 51.0_dp            !< b [m]
    real(dp) :: chord = 6.0_dp            !< mean aerodynamic chord c [m]
    real(dp) :: cl0 = 0.0_dp              !< lift at alpha = 0, delta_e = 0 (set by trim)
    real(dp) :: cl_alpha = 5.7_dp         !< [1/rad]
    real(dp) :: cl_q = 0.0_dp             !< [1/rad] (per q c/(2V)); neglected by default
    real(dp) :: cl_de = 0.36_dp           !< [1/rad]
    real(dp) :: cd0 = 0.018_dp            !< zero-lift drag
    real(dp) :: k_induced = 0.0459_dp     !< CD = cd0 + k CL^2; 1/(pi e AR), AR = 8.67, e = 0.8
    real(dp) :: cm0 = 0.0_dp              !< pitching moment at alpha = 0 (set by trim)
    real(dp) :: cm_alpha = -1.45_dp       !< [1/rad]
    real(dp) :: cm_q = -24.3_dp           !< [1/rad] Cm_q + Cm_alphadot (-21 - 3.3)
    real(dp) :: cm_de = -1.4_dp           !< [1/rad]
    real(dp) :: cy_beta = -0.96_dp        !< side force [1/rad]
    real(dp) :: croll_beta = -0.221_dp    !< rolling moment Cl_beta [1/rad]
    real(dp) :: croll_p = -0.45_dp        !< Cl_p
    real(dp) :: croll_r = 0.101_dp        !< Cl_r
    real(dp) :: cn_beta = 0.150_dp        !< yawing moment Cn_beta [1/rad]
    real(dp) :: cn_p = -0.121_dp          !< Cn_p
    real(dp) :: cn_r = -0.30_dp           !< Cn_r
    real(dp) :: thrust = 0.0_dp           !< along body x through the CG [N] (set by trim)
    real(dp) :: delta_e_trim = 0.0_dp     !< elevator at trim [rad]
    real(dp) :: delta_e_max = 25.0_dp*deg2rad   !< elevator limit [rad] (25 deg)
    logical :: attitude_hold = .false.    !< elevator pitch-attitude hold
    real(dp) :: k_theta = 2.0_dp          !< hold gain [rad elevator / rad pitch error]
    real(dp) :: k_q = 0.5_dp              !< hold gain [rad elevator / (rad/s) pitch rate]
    real(dp) :: theta_ref = 0.0_dp        !< held pitch attitude [rad] (set by trim)
    real(dp) :: cl_alpha_tail = 0.656_dp  !< horizontal tail's lift slope on S [1/rad] (gust penetration)
    real(dp) :: cy_beta_fin = -0.677_dp   !< fin's side-force slope on S [1/rad] (gust penetration)
    real(dp) :: tail_point(3) = [-24.0_dp, 6.0_dp, 0.0_dp]   !< empennage, body frame [m] (set by the scene)
  end type aircraft_aero

  !> What the model computed (for output and tests).
  type :: aircraft_aero_out
    real(dp) :: force(3) = 0.0_dp   !< body frame [N], aerodynamic + thrust
    real(dp) :: moment(3) = 0.0_dp  !< body frame about the CG [N m]
    real(dp) :: alpha = 0.0_dp      !< [rad]
    real(dp) :: beta = 0.0_dp       !< [rad]
    real(dp) :: cl = 0.0_dp, cd = 0.0_dp, cm = 0.0_dp
    real(dp) :: delta_e = 0.0_dp    !< elevator used [rad]
  end type aircraft_aero_out

contains

  !> Forces and moments for body-frame air-relative velocity v_b, body rates
  !> w_b, air density rho and pitch attitude theta (used by the hold only).
  !> With v_tail, the empennage's own air (gust penetration, module header).
  pure function aircraft_aero_eval(p, rho, v_b, w_b, theta, v_tail) result(o)
    type(aircraft_aero), intent(in) :: p
    real(dp), intent(in) :: rho, v_b(3), w_b(3), theta
    real(dp), intent(in), optional :: v_tail(3)   !< air-relative velocity at the empennage, body [m/s]
    type(aircraft_aero_out) :: o
    real(dp) :: v, qbar, qhat, phat, rhat, ca, sa, cy, croll, cn, vt, d_alpha, d_beta, df(3)
    v = norm2(v_b)
    if (v <= 0.0_dp) then
      o%force = [p%thrust, 0.0_dp, 0.0_dp]
      return
    end if
    o%alpha = atan2(-v_b(2), v_b(1))
    o%beta = asin(max(-1.0_dp, min(1.0_dp, v_b(3)/v)))
    qbar = 0.5_dp*rho*v*v
    qhat = w_b(3)*p%chord/(2*v)
    phat = w_b(1)*p%span/(2*v)
    rhat = -w_b(2)*p%span/(2*v)
    o%delta_e = p%delta_e_trim
    if (p%attitude_hold) then
      o%delta_e = p%delta_e_trim + p%k_theta*(theta - p%theta_ref) + p%k_q*w_b(3)
      o%delta_e = max(-p%delta_e_max, min(p%delta_e_max, o%delta_e))
    end if
    o%cl = p%cl0 + p%cl_alpha*o%alpha + p%cl_q*qhat + p%cl_de*o%delta_e
    o%cd = p%cd0 + p%k_induced*o%cl**2
    o%cm = p%cm0 + p%cm_alpha*o%alpha + p%cm_q*qhat + p%cm_de*o%delta_e
    cy = p%cy_beta*o%beta
    croll = p%croll_beta*o%beta + p%croll_p*phat + p%croll_r*rhat
    cn = p%cn_beta*o%beta + p%cn_p*phat + p%cn_r*rhat
    ca = cos(o%alpha); sa = sin(o%alpha)
    ! lift normal to V in the plane of symmetry, drag along -V (wind axes, also
    ! in sideslip), side force along body z (C_Y is a body-axis derivative)
    o%force = qbar*p%wing_area*(o%cl*[sa, ca, 0.0_dp] - o%cd*v_b/v + [0.0_dp, 0.0_dp, cy])
    o%force(1) = o%force(1) + p%thrust
    o%moment = qbar*p%wing_area*[p%span*croll, -p%span*cn, p%chord*o%cm]
    if (present(v_tail)) then
      vt = norm2(v_tail)
      if (vt > 0.0_dp) then
        d_alpha = atan2(-v_tail(2), v_tail(1)) - o%alpha
        d_beta = asin(max(-1.0_dp, min(1.0_dp, v_tail(3)/vt))) - o%beta
        df = qbar*p%wing_area*(p%cl_alpha_tail*d_alpha*[sa, ca, 0.0_dp] + [0.0_dp, 0.0_dp, p%cy_beta_fin*d_beta])
        o%force = o%force + df
        o%moment = o%moment + cross(p%tail_point, df)
      end if
    end if
  end function aircraft_aero_eval
end module airlaunch_aircraft_aero
