!> The discrete 1 - cosine gust (airlaunch_gust) against its definition, and
!> its use by the line's drag and the canopy's drag against the same loads
!> computed with the gust's velocity as a uniform wind (line_params%wind, the
!> canopy velocity minus the air's): the two paths are independent code.
!> Gust penetration: the rocket's stations in a gust that changes linearly
!> along it against the same rocket rotating in uniform air (Etkin's
!> equivalence of a gust gradient and a body rate), and the aircraft's
!> empennage terms against the published damping derivatives they stand for.
program test_gust
  use airlaunch_kinds, only: dp, pi
  use airlaunch_error, only: error_type
  use airlaunch_gust
  use airlaunch_line_model, only: line_model, line_params
  use airlaunch_parachute, only: parachute, canopy_node_acceleration, canopy_node_jacobian
  use airlaunch_rocket_aero, only: rocket_aero, rocket_aero_eval
  use airlaunch_aircraft_aero, only: aircraft_aero, aircraft_aero_eval, aircraft_aero_out
  use airlaunch_rotation, only: rot_x, cross
  use testing
  implicit none
  type(gust_field) :: g
  real(dp), parameter :: u(3) = [0.0_dp, 12.0_dp, -5.0_dp], h = 30.0_dp, x0 = 100.0_dp
  real(dp) :: s, w(3), wm(3), wp(3), slope, d
  integer :: k

  call section("shape: zero outside [x_front, x_front + 2H], U at x_front + H")
  g = make_gust(u, h, x0)
  call check(g%active, "a gust with a nonzero peak is active")
  call check(all(gust_velocity(g, [x0 - 1.0e-9_dp, 0.0_dp, 0.0_dp]) == 0.0_dp), "zero before the front")
  call check(all(gust_velocity(g, [x0 + 2*h + 1.0e-9_dp, 0.0_dp, 0.0_dp]) == 0.0_dp), "zero behind the gust")
  w = gust_velocity(g, [x0 + h, -7.0_dp, 3.0_dp])
  call check_close(norm2(w - u), 0.0_dp, "the peak U at x_front + H (any y, z)", abs=1.0e-14_dp*norm2(u))
  ! (U/2)(1 - cos(pi s/H)) at s = H/3: (U/2)(1 - 1/2) = U/4
  w = gust_velocity(g, [x0 + h/3, 0.0_dp, 0.0_dp])
  call check_close(norm2(w - u/4), 0.0_dp, "U/4 at s = H/3", abs=1.0e-14_dp*norm2(u))
  block
    type(gust_field) :: calm
    calm = make_gust([0.0_dp, 0.0_dp, 0.0_dp], h, x0)
    call check(all(gust_velocity(calm, [x0 + h, 0.0_dp, 0.0_dp]) == 0.0_dp) .and. .not. calm%active, &
      "zero peak: inactive, zero everywhere")
  end block

  call section("smoothness: w and dw/dx continuous at both edges (C^1)")
  ! just inside an edge w = U (pi s/H)^2/4 + O(s^4): the value at s = 1e-3 H
  ! is 2.5e-6 |U|, and the one-sided slope w(s)/s is pi^2 s/(4 H^2) |U| -> 0
  do k = 0, 1
    d = 1.0e-3_dp*h
    s = merge(d, 2*h - d, k == 0)
    w = gust_velocity(g, [x0 + s, 0.0_dp, 0.0_dp])
    call check_close(norm2(w), norm2(u)*pi**2*1.0e-6_dp/4, "w at 1e-3 H inside edge " // merge("front", "back ", k == 0), &
      rel=1.0e-5_dp)
  end do
  ! the largest slope pi |U| / (2H) at s = H/2, by a central difference (h^2 error ~ 1e-10)
  wm = gust_velocity(g, [x0 + h/2 - 1.0e-3_dp, 0.0_dp, 0.0_dp])
  wp = gust_velocity(g, [x0 + h/2 + 1.0e-3_dp, 0.0_dp, 0.0_dp])
  slope = norm2(wp - wm)/2.0e-3_dp
  call check_close(slope, pi*norm2(u)/(2*h), "largest slope pi |U| / (2H) at s = H/2", rel=1.0e-8_dp)

  call section("Küssner's lift build-up: the closed form against Duhamel's integral by quadrature")
  ! w_K(s) = integral_0^min(s, 2H) w'(s') psi(2 (s - s')/c) ds', psi Jones'
  ! approximation 1 - exp(-0.13 sigma)/2 - exp(-sigma)/2, written here from its
  ! definition; composite Simpson over 20 000 intervals (error ~1e-15 |U|);
  ! tolerance 1e-11 |U|, the closed form's rounding
  block
    real(dp), parameter :: chord = 6.0_dp
    real(dp) :: stations(6), wk(3), ref(3), top, ds, sp, f
    integer :: j, i
    integer, parameter :: n = 20000
    stations = [h/3, h, 1.7_dp*h, 2*h, 2*h + 3*chord, 2*h + 40*chord]
    do j = 1, size(stations)
      s = stations(j)
      top = min(s, 2*h)
      ds = top/n
      ref = 0.0_dp
      do i = 0, n
        sp = i*ds
        f = merge(1.0_dp, merge(4.0_dp, 2.0_dp, mod(i, 2) == 1), i == 0 .or. i == n)
        ref = ref + f*(0.5_dp*pi/h*sin(pi*sp/h))*psi(2*(s - sp)/chord)*u
      end do
      ref = ref*ds/3
      wk = lagged_gust_velocity(g, [x0 + s, 4.0_dp, -2.0_dp], chord)
      call check_close(norm2(wk - ref), 0.0_dp, "w_K at s = " // trim(ftoa(s/h)) // " H", abs=1.0e-11_dp*norm2(u))
    end do
    ! it lags: below the gust on its way up, above it after its peak, and still
    ! there (decaying) behind the gust
    call check(norm2(lagged_gust_velocity(g, [x0 + h/3, 0.0_dp, 0.0_dp], chord)) < &
      norm2(gust_velocity(g, [x0 + h/3, 0.0_dp, 0.0_dp])), "below the gust on its way up")
    wk = lagged_gust_velocity(g, [x0 + 2*h + chord, 0.0_dp, 0.0_dp], chord)
    call check(dot_product(wk, u) > 0.0_dp .and. all(gust_velocity(g, [x0 + 2*h + chord, 0.0_dp, 0.0_dp]) == 0.0_dp), &
      "behind the gust: still the gust's sign, where the gust is 0")
    call check(all(lagged_gust_velocity(g, [x0 - 1.0e-9_dp, 0.0_dp, 0.0_dp], chord) == 0.0_dp), "zero before the front")
    ! a chord 1e-6 of the gust's: the quasi-steady gust, to O(c/H)
    wk = lagged_gust_velocity(g, [x0 + h/3, 0.0_dp, 0.0_dp], 1.0e-6_dp*h)
    call check_close(norm2(wk - u/4), 0.0_dp, "a vanishing chord: the gust itself", abs=1.0e-5_dp*norm2(u))
  end block

  call section("the line's drag in the gust = with the gust's velocity as its wind")
  block
    type(line_model) :: a, b
    type(error_type), allocatable :: error
    real(dp) :: x(3, 0:4), v(3, 0:4), fa(3, 0:4), fb(3, 0:4), ta(4), tb(4)
    integer :: sa, sb
    ! a line across the flight path at x = x_front + H (every segment midpoint
    ! at the gust's peak), stretched, moving, in the ISA air at 3 km
    do k = 0, 4
      x(:, k) = [x0 + h, 3000.0_dp - 2.5_dp*k, 0.3_dp*k]
      v(:, k) = [150.0_dp + k, -2.0_dp*k, 1.0_dp]
    end do
    call a%init(line_params(length=9.0_dp, n_seg=4, ea=1.0e5_dp, mass_per_length=0.3_dp, air=.true.), error)
    call b%init(line_params(length=9.0_dp, n_seg=4, ea=1.0e5_dp, mass_per_length=0.3_dp, air=.true., wind=u), error)
    call check(.not. allocated(error), "the lines initialise")
    a%gust = g
    call a%forces(x, v, fa, ta, sa)
    call b%forces(x, v, fb, tb, sb)
    ! the same operations on the same numbers: the wind of one is the other's
    ! gust (to its last bit, U - (U/2)(1 - cos pi) = 0)
    call check_close(maxval(abs(fa - fb)), 0.0_dp, "node forces (gust vs uniform wind U)", &
      abs=1.0e-12_dp*maxval(abs(fb)))
    block
      real(dp) :: jxa(3, 3, -1:1, 0:4), jva(3, 3, -1:1, 0:4), jxb(3, 3, -1:1, 0:4), jvb(3, 3, -1:1, 0:4)
      call a%force_jacobian(x, v, jxa, jva)
      call b%force_jacobian(x, v, jxb, jvb)
      call check_close(maxval(abs(jva - jvb)), 0.0_dp, "velocity Jacobian (gust vs uniform wind U)", &
        abs=1.0e-12_dp*maxval(abs(jvb)))
      call check_close(maxval(abs(jxa - jxb)), 0.0_dp, "position Jacobian (the gust's gradient left out at its peak)", &
        abs=1.0e-12_dp*maxval(abs(jxb)))
    end block
    ! and the gust made a difference: without it the drag is another
    a%gust = gust_field()
    call a%forces(x, v, fa, ta, sa)
    call check(maxval(abs(fa - fb)) > 1.0e-3_dp*maxval(abs(fb)), "without the gust the forces differ")
  end block

  call section("the canopy's drag in the gust = its velocity relative to the air")
  block
    type(parachute) :: p, q
    real(dp) :: xc(3), vc(3), fl(3), acc_a(3), acc_b(3), drag_a(3), drag_b(3), ma, mb, ja(3, 3), jb(3, 3)
    logical :: ok_a, ok_b
    p%deploy_time = 0.5_dp; p%fill_time = 1.0_dp   ! mid-filling: the apparent mass's momentum term on
    q = p
    p%gust = g
    xc = [x0 + h, 3000.0_dp, 0.0_dp]
    vc = [140.0_dp, 3.0_dp, -2.0_dp]
    fl = [-5000.0_dp, 200.0_dp, 10.0_dp]
    call canopy_node_acceleration(p, 1.0_dp, xc, vc, 0.2_dp, fl, .true., .true., acc_a, drag_a, ok_a)
    call canopy_node_acceleration(q, 1.0_dp, xc, vc - u, 0.2_dp, fl, .true., .true., acc_b, drag_b, ok_b)
    call check(ok_a .and. ok_b, "the canopy is inside the atmosphere model")
    call check_close(norm2(drag_a - drag_b), 0.0_dp, "drag and momentum force from v - U", abs=1.0e-14_dp*norm2(drag_b))
    call check_close(norm2(acc_a - acc_b), 0.0_dp, "acceleration", abs=1.0e-14_dp*norm2(acc_b))
    call canopy_node_jacobian(p, 1.0_dp, xc, vc, 0.2_dp, .true., ma, ja, ok_a)
    call canopy_node_jacobian(q, 1.0_dp, xc, vc - u, 0.2_dp, .true., mb, jb, ok_b)
    call check_close(maxval(abs(ja - jb)), 0.0_dp, "velocity Jacobian of the drag at v - U", abs=1.0e-14_dp*maxval(abs(jb)))
  end block

  call section("the rocket in a gust that changes linearly along it = the rocket rotating in uniform air")
  ! A frozen gust whose velocity changes by k per metre of flight path meets a
  ! station at body x (body x along the flight path) with k x more than the CG:
  ! relative to its air the station moves at v - k x, as on a body rotating at w2 = k_z,
  ! w3 = -k_y (body frame) in uniform air, whose station moves at
  ! v + (0, w3 x, -w2 x).  The 1 - cos gust is linear about s = H/2 (its
  ! inflection) up to the cubic term, (pi x/H)^2/6 = 1.4e-8 of the change at
  ! the rocket's ends for H = 1e5 m, hence the bound 1e-5 of the part the
  ! gust's change (or the rotation) makes: measured 1.1e-8 and 9e-9, the cubic
  ! term itself.  The fins are on, and the potential term's centre
  ! is the CG, where both read the same air; the body rolled by 30 deg, so the
  ! gust's vertical and lateral parts mix in the body frame.
  block
    type(rocket_aero) :: rk
    type(gust_field) :: gl
    real(dp), parameter :: hl = 1.0e5_dp, ul(3) = [0.0_dp, 2000.0_dp, -900.0_dp]
    real(dp) :: c(3, 3), r_cg(3), v_air(3), w0(3), k_b(3), w_eq(3), vb(3)
    real(dp) :: f_g(3), m_g(3), f_r(3), m_r(3), f_0(3), m_0(3)
    rk%cn_alpha_fin = 8.0_dp; rk%cn_fin_90 = 1.28_dp
    rk%cp_pot_from_nose = rk%cg_from_nose
    gl = make_gust(ul, hl, 0.0_dp)
    c = rot_x(30.0_dp*pi/180)
    r_cg = [hl/2, 3000.0_dp, 0.0_dp]
    w0 = [0.01_dp, -0.02_dp, 0.05_dp]                     ! a body rate of its own
    v_air = [190.0_dp, -6.0_dp, 2.5_dp] - gust_velocity(gl, r_cg)
    vb = matmul(transpose(c), v_air)
    ! the gust's change per metre of body x (body x = earth x here), body frame
    k_b = matmul(transpose(c), ul)*pi/(2*hl)
    ! a station at x reads v - k_b x; the rotation w x (x, 0, 0) = (0, w3 x, -w2 x)
    w_eq = w0 + [0.0_dp, k_b(3), -k_b(2)]
    call rocket_aero_eval(rk, 0.9_dp, 300.0_dp, vb, w0, huge(1.0_dp), f_g, m_g, gust=gl, r_cg=r_cg, c=c)
    call rocket_aero_eval(rk, 0.9_dp, 300.0_dp, vb, w_eq, huge(1.0_dp), f_r, m_r)
    call rocket_aero_eval(rk, 0.9_dp, 300.0_dp, vb, w0, huge(1.0_dp), f_0, m_0)
    call check(norm2(m_r - m_0) > 1.0e-3_dp*norm2(m_0), "the gust's change along the rocket matters (moment)")
    call check_close(norm2(f_g - f_r), 0.0_dp, "force: gust gradient = body rate", abs=1.0e-5_dp*norm2(f_r - f_0))
    call check_close(norm2(m_g - m_r), 0.0_dp, "moment: gust gradient = body rate", abs=1.0e-5_dp*norm2(m_r - m_0))
    ! inside the bay nothing reads the gust (the shielded strips, the potential
    ! and axial terms scaled by the exposed part): half out, the same identity
    call rocket_aero_eval(rk, 0.9_dp, 300.0_dp, vb, w0, 0.0_dp, f_g, m_g, gust=gl, r_cg=r_cg, c=c)
    call rocket_aero_eval(rk, 0.9_dp, 300.0_dp, vb, w_eq, 0.0_dp, f_r, m_r)
    call rocket_aero_eval(rk, 0.9_dp, 300.0_dp, vb, w0, 0.0_dp, f_0, m_0)
    call check_close(norm2(m_g - m_r), 0.0_dp, "half in the bay: gust gradient = body rate", &
      abs=1.0e-5_dp*norm2(m_r - m_0))
  end block

  call section("the aircraft's empennage in a gust: the damping derivatives it stands for")
  ! The empennage terms with the air a rotation gives the empennage point
  ! (w x r_t) must reproduce the damping that tail supplies: Cm_q = -21 and
  ! Cn_r = -0.30 of the 747 class (Heffley & Jewell, NASA CR-2144, 1972) from
  ! the defaults CL_alpha_tail = 0.656, CY_beta_fin = -0.677 at the default
  ! empennage point (-24, 6, 0) m.  Tiny rates (the terms are linear to
  ! (r_t w/V)^2 ~ 1e-10); bound 0.1 %: the defaults carry three digits.
  block
    type(aircraft_aero) :: ac
    type(aircraft_aero_out) :: o0, o1
    real(dp), parameter :: rho = 0.41351_dp, vv = 195.0_dp, rate = 1.0e-4_dp
    real(dp) :: vb(3), qs, w(3)
    vb = [vv, 0.0_dp, 0.0_dp]
    qs = 0.5_dp*rho*vv**2*ac%wing_area
    o0 = aircraft_aero_eval(ac, rho, vb, [0.0_dp, 0.0_dp, 0.0_dp], 0.0_dp)
    o1 = aircraft_aero_eval(ac, rho, vb, [0.0_dp, 0.0_dp, 0.0_dp], 0.0_dp, v_tail=vb)
    call check(all(o1%force == o0%force) .and. all(o1%moment == o0%moment), "the same air at the empennage adds nothing")
    w = [0.0_dp, 0.0_dp, rate]                  ! pitch rate q
    o1 = aircraft_aero_eval(ac, rho, vb, [0.0_dp, 0.0_dp, 0.0_dp], 0.0_dp, v_tail=vb + cross(w, ac%tail_point))
    call check_close((o1%moment(3) - o0%moment(3))/(qs*ac%chord)/(rate*ac%chord/(2*vv)), -21.0_dp, &
      "tail's Cm_q", rel=1.0e-3_dp)
    w = [0.0_dp, -rate, 0.0_dp]                 ! yaw rate r = -w_y (nose right)
    o1 = aircraft_aero_eval(ac, rho, vb, [0.0_dp, 0.0_dp, 0.0_dp], 0.0_dp, v_tail=vb + cross(w, ac%tail_point))
    ! yawing moment about +y is -qSb Cn
    call check_close(-(o1%moment(2) - o0%moment(2))/(qs*ac%span)/(rate*ac%span/(2*vv)), -0.30_dp, &
      "fin's Cn_r", rel=1.0e-3_dp)
  end block

  call finish()
contains

  !> Jones' approximation of Küssner's function at sigma half-chords travelled.
  pure real(dp) function psi(sigma)
    real(dp), intent(in) :: sigma
    psi = 1.0_dp - 0.5_dp*exp(-0.13_dp*sigma) - 0.5_dp*exp(-sigma)
  end function psi

  !> A short decimal text of x.
  function ftoa(x) result(t)
    real(dp), intent(in) :: x
    character(len=16) :: t
    write (t, "(f8.3)") x
    t = adjustl(t)
  end function ftoa
end program test_gust
