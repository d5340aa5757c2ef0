!> Validation 6 (issue 3): equivalent rigidization, Eqs. (18)–(32), on line
!> states built by hand with known answers.
!>  1. A straight line in rigid motion: the frame of Eq. (23) with angles
!>     theta, phi rotating at rates theta_dot, phi_dot (body rate
!>     [theta_dot, phi_dot sin(theta), phi_dot cos(theta)], Eq. (6)), the
!>     centre translating at V0.  Expected: d = d_rigid = length (18)–(20), the
!>     angles (24), omega_rigid = the imposed body rate (27), V_rigid = V0 (29),
!>     m_rigid = line mass (31), J_x = J_y = sum m_k r_k^2 about the centre
!>     (32; m L^2/12 plus the lumping correction), J_z = 0.
!>  2. Pure translation: the printed (31) with the |V|^2 fix also gives the
!>     line mass.
!>  3. Uniform stretching (node 0 fixed, v_k = epsdot l0 k e): V_eps = epsdot L e
!>     (25), V_oeps = epsdot L/2 e (30), omega = 0 and J falls back to the
!>     geometric value.
!>  4. A bent line (d > d_rigid) and a line rotating about its centre
!>     (V_rigid = 0: m_rigid falls back to the line mass without dividing by 0).
!>  5. A bent line in rigid motion across its chord, the chord down to 0.001
!>     deg from earth z: m_rigid = line mass (the frame spin of (27) is not a
!>     motion of the mass), J_z = the inertia about the chord.
!>  6. A node next to the centre does not make (32) fall back (J_y continuous
!>     in its distance from the centre).
!> Tolerances: 1e-12 relative (exact arithmetic identities, rounding only).
program test_line_rigidization
  use airlaunch_kinds, only: dp, pi, deg2rad
  use airlaunch_error, only: error_type
  use airlaunch_strings, only: str
  use airlaunch_rotation, only: cross
  use airlaunch_line
  use testing
  implicit none
  integer, parameter :: n = 40
  real(dp), parameter :: length = 12.0_dp, rho = 0.3_dp, tol = 1.0e-12_dp
  type(line_model) :: model
  type(error_type), allocatable :: error
  type(rigid_equivalent) :: q
  real(dp) :: x(3, 0:n), v(3, 0:n), b(3, 3), e(3), centre(3), v0(3), w_body(3), w(3), th, ph, thd, phd
  real(dp) :: jgeo, epsdot, stretch
  integer :: k

  call model%init(line_params(length=length, n_seg=n, mass_per_length=rho), error)
  call check(.not. allocated(error), "model")

  call section("1. straight line in rigid motion")
  th = 50.0_dp*deg2rad; ph = -120.0_dp*deg2rad; thd = 0.3_dp; phd = -0.7_dp
  b = b23(th, ph)
  e = b(3, :)                                  ! body z axis in earth components
  w_body = [thd, phd*sin(th), phd*cos(th)]     ! Eq. (6)
  w = matmul(transpose(b), w_body)
  centre = [3.0_dp, 100.0_dp, -2.0_dp]
  v0 = [12.0_dp, -3.0_dp, 5.0_dp]
  do k = 0, n
    x(:, k) = centre + (k*model%l0 - 0.5_dp*length)*e
    v(:, k) = v0 + cross(w, x(:, k) - centre)
  end do
  q = rigidize(model, x, v)
  call check_close(q%d, length, "d (18) = length [m]", rel=tol)
  call check_close(q%d_rigid, length, "d_rigid (20) = length [m]", rel=tol)
  call check_close(q%theta, th, "theta_rigid (24) [rad]", rel=tol)
  call check_close(q%phi, ph, "phi_rigid (24) [rad]", rel=tol)
  do k = 1, 3
    call check_close(q%omega_body(k), w_body(k), "omega_rigid(" // str(k) // ") (27) = imposed rate [rad/s]", &
      rel=tol, abs=tol)
  end do
  call check(maxval(abs(q%v_rigid - v0)) <= tol*norm2(v0), "V_rigid (29) = centre velocity: " // &
    str(q%v_rigid(1)) // ", " // str(q%v_rigid(2)) // ", " // str(q%v_rigid(3)))
  call check(maxval(abs(q%centre - centre)) <= tol*norm2(centre), "centre x_0 + r_o (21) = midpoint")
  call check_close(q%m_rigid, rho*length, "m_rigid (31) = line mass [kg]", rel=tol)
  jgeo = 0
  do k = 0, n
    jgeo = jgeo + model%node_mass(k)*(k*model%l0 - 0.5_dp*length)**2
  end do
  print '(a, f12.6, a, f12.6, a)', "  sum m_k r_k^2 = ", jgeo, " kg m^2 (continuum m L^2/12 = ", &
    rho*length**3/12, ")"
  call check_close(q%j_rigid(1), jgeo, "J_x (32) = sum m_k r_k^2 [kg m^2]", rel=1.0e-10_dp)
  call check_close(q%j_rigid(2), jgeo, "J_y (32) = sum m_k r_k^2 [kg m^2]", rel=1.0e-10_dp)
  call check_close(q%j_rigid(3), 0.0_dp, "J_z (32) = 0 about the line [kg m^2]", abs=1.0e-12_dp)
  call check(.not. q%m_fallback .and. .not. any(q%j_fallback(1:2)), "no fallback used")

  call section("2. pure translation: (31) as printed, with |V_rigid|^2")
  do k = 0, n
    v(:, k) = v0
  end do
  q = rigidize(model, x, v)
  call check_close(q%m_rigid_eq31, rho*length, "m_rigid_eq31 = line mass [kg]", rel=tol)
  call check_close(q%m_rigid, rho*length, "m_rigid = line mass [kg]", rel=tol)
  call check(all(q%j_fallback), "omega = 0: all J fall back to the geometric values")
  call check_close(q%j_rigid(1), jgeo, "J_x geometric [kg m^2]", rel=1.0e-10_dp)

  call section("3. uniform stretching")
  epsdot = 0.05_dp
  stretch = 1.02_dp
  e = [0.6_dp, 0.0_dp, 0.8_dp]
  do k = 0, n
    x(:, k) = [1.0_dp, 2.0_dp, 3.0_dp] + stretch*k*model%l0*e
    v(:, k) = epsdot*k*model%l0*e
  end do
  q = rigidize(model, x, v)
  call check(maxval(abs(q%v_eps - epsdot*length*e)) <= tol*epsdot*length, "V_eps (25) = epsdot L e: " // &
    str(q%v_eps(1)) // ", " // str(q%v_eps(2)) // ", " // str(q%v_eps(3)) // " (expected " // &
    str(epsdot*length*e(1)) // ", 0, " // str(epsdot*length*e(3)) // ")")
  call check(maxval(abs(q%v_o_eps - 0.5_dp*epsdot*length*e)) <= tol*epsdot*length, "V_oeps (30) = epsdot L/2 e")
  call check(maxval(abs(q%omega_body)) <= tol, "no rotation: omega = 0")
  call check_close(q%d_rigid, stretch*length, "d_rigid = stretched length [m]", rel=tol)
  call check_close(q%theta, acos(0.8_dp), "theta (24) = acos(r_z/|r|) [rad]", rel=tol)

  call section("4. degenerate rates and a bent line")
  do k = 0, n
    x(:, k) = (k*model%l0 - 0.5_dp*length)*[1.0_dp, 0.0_dp, 0.0_dp]
    v(:, k) = cross([0.0_dp, 0.0_dp, 2.0_dp], x(:, k))
  end do
  q = rigidize(model, x, v)
  call check(q%m_fallback, "rotation about the centre: V_rigid = 0 is detected")
  call check_close(q%m_rigid, rho*length, "m_rigid falls back to the line mass [kg]", rel=tol)
  call check_close(q%omega(3), 2.0_dp, "omega_z (earth) = imposed 2 rad/s", rel=tol)
  do k = 0, n
    x(:, k) = length/pi*[sin(pi*k/n), 1.0_dp - cos(pi*k/n), 0.0_dp]   ! a half circle
    v(:, k) = 0
  end do
  q = rigidize(model, x, v)
  call check(q%d > q%d_rigid, "half circle: arc d = " // str(q%d) // " m > chord d_rigid = " // str(q%d_rigid) // " m")
  call check_close(q%d_rigid, 2*length/pi, "chord of the half circle [m]", rel=1.0e-12_dp)
  call check(q%m_fallback .and. all(q%j_fallback), "at rest: geometric fallbacks, no division by zero")
  call check_close(q%m_rigid, rho*length, "at rest: m_rigid = line mass [kg]", rel=tol)

  call section("5. a bent line in rigid motion, rotating across its chord")
  ! A parabola of 1.5 m sag across its chord, the chord tilted theta from
  ! earth z (down to 0.001 deg, where (27)'s frame spin omega_y cot(theta) is
  ! 5.7e4 times omega_y), translating and rotating about an axis across the
  ! chord.  The translational kinetic-energy mass is the line mass whatever
  ! the shape; J_z is the geometric inertia about the chord.
  block
    real(dp) :: thetas(3), s_k, ee(3), en(3), jz
    integer :: it
    thetas = [30.0_dp, 5.0_dp, 1.0e-3_dp]*deg2rad
    do it = 1, size(thetas)
      b = b23(thetas(it), 0.4_dp)
      ee = b(3, :)                                ! chord direction
      en = b(1, :)                                ! across the chord
      w = 0.8_dp*b(1, :) - 0.5_dp*b(2, :)          ! rotation across the chord [rad/s]
      centre = [3.0_dp, 100.0_dp, -2.0_dp]
      do k = 0, n
        s_k = real(k, dp)/n - 0.5_dp
        x(:, k) = centre + s_k*length*ee + 1.5_dp*(1.0_dp - 4.0_dp*s_k**2)*en
        v(:, k) = v0 + cross(w, x(:, k) - centre)
      end do
      q = rigidize(model, x, v)
      call check(q%d > q%d_rigid, "the line is bent")
      call check_close(q%theta, thetas(it), "theta [rad]", rel=1.0e-9_dp)
      call check_close(q%m_rigid, rho*length, "theta = " // str(thetas(it)/deg2rad) // &
        " deg: m_rigid (31) = line mass [kg]", rel=tol)
      jz = 0
      do k = 0, n
        jz = jz + model%node_mass(k)*(sum((x(:, k) - q%centre)**2) - dot_product(x(:, k) - q%centre, ee)**2)
      end do
      call check_close(q%j_rigid(3), jz, "J_z = the inertia about the chord [kg m^2]", rel=1.0e-12_dp)
      call check(.not. q%m_fallback .and. .not. any(q%j_fallback(1:2)) .and. q%j_fallback(3), &
        "no fallback across the chord, the geometric J_z")
    end do
  end block

  call section("6. a node next to the centre does not set the rate scale of (32)")
  ! The straight line of section 1 rotating at 0.3 rad/s about body y, with a
  ! bending velocity 0.2 sin(pi k/N) m/s along body x (so that (32) differs from
  ! the geometric J_y, by 1.8 %); the middle node (at the centre) is moved
  ! 1e-4 m, then 1e-9 m, off the chord along body x and given 0.5 m/s along
  ! body y.  J_y (32) is continuous in that offset: the kink's strain rate moves
  ! it by ~48 delta^2 kg m^2 (5e-7 at 1e-4 m; tolerance 1e-6 relative); it
  ! must not fall back to the geometric value because the node's own rate
  ! |dv|/|r_k| grows without bound.
  block
    real(dp) :: jy(2), offs(2)
    integer :: io
    offs = [1.0e-4_dp, 1.0e-9_dp]
    b = b23(th, ph)
    e = b(3, :)
    w = 0.3_dp*b(2, :)
    do io = 1, 2
      do k = 0, n
        x(:, k) = centre + (k*model%l0 - 0.5_dp*length)*e
        v(:, k) = v0 + cross(w, x(:, k) - centre) + 0.2_dp*sin(pi*k/n)*b(1, :)
      end do
      x(:, n/2) = x(:, n/2) + offs(io)*b(1, :)
      v(:, n/2) = v(:, n/2) + 0.5_dp*b(2, :)
      q = rigidize(model, x, v)
      call check(.not. q%j_fallback(2), "offset " // str(offs(io)) // " m: J_y from (32), no fallback")
      jy(io) = q%j_rigid(2)
    end do
    call check_close(jy(2), jy(1), "J_y at offsets 1e-9 and 1e-4 m [kg m^2]", rel=1.0e-6_dp)
    call check(abs(jy(2) - jgeo) > 0.01_dp*jgeo, "J_y (32) = " // str(jy(2)) // " differs from the geometric " // &
      str(jgeo) // " kg m^2 (the test can tell a fallback)")
  end block
  call finish()

contains

  !> B_rigid of Eq. (23).
  pure function b23(theta, phi) result(bb)
    real(dp), intent(in) :: theta, phi
    real(dp) :: bb(3, 3)
    bb(1, :) = [cos(phi), sin(phi), 0.0_dp]
    bb(2, :) = [-sin(phi)*cos(theta), cos(phi)*cos(theta), sin(theta)]
    bb(3, :) = [sin(phi)*sin(theta), -cos(phi)*sin(theta), cos(theta)]
  end function b23
end program test_line_rigidization
