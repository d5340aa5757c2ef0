!> Rotations in the paper's convention, checked against independent facts:
!> the cross product, orthonormality, the kinematic relation (49)-(50) by
!> finite differences of C(e(t)), closed-form quaternion motion, and round trips
!> near pitch +-90 deg (the rocket's firing attitude).
program test_rotation
  use airlaunch_kinds, only: dp, pi, deg2rad
  use airlaunch_rotation
  use testing
  implicit none
  real(dp) :: a(3), b(3), e(3), e2(3), c(3, 3), c2(3, 3), q(4), q2(4), w(3), ed(3), cd(3, 3), h
  real(dp) :: pitches(7), err
  integer :: i, j

  call section("skew matrix is the cross product")
  a = [0.3_dp, -1.2_dp, 2.0_dp]; b = [1.5_dp, 0.7_dp, -0.4_dp]
  call check(maxval(abs(matmul(skew(a), b) - cross_ref(a, b))) < 1e-15_dp, "skew(a) b = a x b")
  call check(maxval(abs(cross(a, b) - cross_ref(a, b))) < 1e-15_dp, "cross(a, b) = a x b")

  call section("sign conventions (x fwd, y up, z right)")
  c = euler_to_dcm([0.0_dp, 30*deg2rad, 0.0_dp])
  call check(maxval(abs(c(:, 1) - [cos(pi/6), sin(pi/6), 0.0_dp])) < 1e-15_dp, "positive pitch raises the nose")
  c = euler_to_dcm([30*deg2rad, 0.0_dp, 0.0_dp])
  call check(c(3, 1) < 0.0_dp, "positive yaw turns the nose to -z (about +y)")
  c = euler_to_dcm([0.0_dp, 0.0_dp, 30*deg2rad])
  call check(c(3, 2) > 0.0_dp, "positive roll tips body y towards +z (about +x)")

  call section("quaternion and matrix agree; orthonormal")
  pitches = [-90.0_dp, -89.9999_dp, -45.0_dp, 0.0_dp, 60.0_dp, 89.9999_dp, 90.0_dp]
  do i = 1, size(pitches)
    e = [0.7_dp, pitches(i)*deg2rad, -1.1_dp]
    c = euler_to_dcm(e)
    q = quat_from_euler(e)
    call check(maxval(abs(quat_to_dcm(q) - c)) < 1e-14_dp, "C(q(e)) = C(e) at pitch " // trim(fmt(pitches(i))))
    call check(maxval(abs(matmul(transpose(c), c) - eye())) < 1e-14_dp, "C^T C = I")
    q2 = dcm_to_quat(c)
    call check(min(norm2(q2 - q), norm2(q2 + q)) < 1e-12_dp, "q(C(q)) = +-q")
    ! round trip through Euler angles: the matrix must come back (angles are
    ! not unique at the gimbal lock, the rotation is)
    e2 = dcm_to_euler(c)
    c2 = euler_to_dcm(e2)
    err = maxval(abs(c2 - c))
    call check(err < 1e-9_dp, "C(e(C)) = C near the lock, err " // trim(fmt(err)))
    if (abs(pitches(i)) < 89.0_dp) call check(maxval(abs(e2 - e)) < 1e-13_dp, "e(C(e)) = e away from the lock")
  end do

  call section("kinematics (49)-(50): skew(w_b) = C^T dC/dt")
  e = [0.4_dp, 1.2_dp, -0.3_dp]; ed = [0.5_dp, -0.8_dp, 1.3_dp]   ! [psi, theta, gamma] rates
  h = 1e-6_dp
  cd = (euler_to_dcm(e + h*ed) - euler_to_dcm(e - h*ed))/(2*h)
  c = matmul(transpose(euler_to_dcm(e)), cd)
  w = [c(3, 2), c(1, 3), c(2, 1)]
  ! W multiplies [gamma_dot, psi_dot, theta_dot] (Eq. 49)
  call check(maxval(abs(matmul(euler_rate_matrix(e), [ed(3), ed(1), ed(2)]) - w)) < 1e-8_dp, &
    "W [gamma', psi', theta'] = body rate (central difference, h = 1e-6)")

  call section("quaternion rate vs closed-form rotation at constant body rate")
  q = quat_from_euler([0.2_dp, 85*deg2rad, 0.1_dp])
  w = [0.3_dp, -0.2_dp, 1.5_dp]
  do j = 1, 3
    h = 0.1_dp*j
    q2 = quat_mul(q, [cos(norm2(w)*h/2), sin(norm2(w)*h/2)*w/norm2(w)])
    ! derivative of the closed form at time h, by central differences
    err = maxval(abs(quat_rate(q2, w) - (quat_mul(q, exp_q(w, h + 1e-6_dp)) - quat_mul(q, exp_q(w, h - 1e-6_dp)))/2e-6_dp))
    call check(err < 1e-8_dp, "qdot = q (x) [0, w]/2 on the exact solution")
  end do
  call check(abs(nose_elevation(quat_from_euler([0.0_dp, 120*deg2rad, 0.0_dp])) - 120*deg2rad) < 1e-13_dp, &
    "nose elevation passes 90 deg continuously")
  ! quat_to_dcm's documented contract: any non-zero multiple of a quaternion is
  ! the same rotation (the integrators' quaternions drift off unit norm between
  ! projections), an orthogonal matrix of determinant 1 (a mutation audit found
  ! no test of it: un-normalised, C(2q) is 4 C(q) off the diagonal)
  block
    real(dp) :: qa(4), ca(3, 3)
    qa = [0.3_dp, -0.5_dp, 0.7_dp, 0.2_dp]
    ca = quat_to_dcm(qa)
    call check(maxval(abs(quat_to_dcm(2.5_dp*qa) - ca)) < 1e-15_dp, "C(k q) = C(q) for k = 2.5")
    call check(maxval(abs(quat_to_dcm(-1.0e-3_dp*qa) - ca)) < 1e-15_dp, "C(k q) = C(q) for k = -1e-3")
    call check(maxval(abs(matmul(transpose(ca), ca) - eye())) < 1e-15_dp, "C(q) orthogonal for a non-unit q")
    call check(abs(ca(1, 1)*(ca(2, 2)*ca(3, 3) - ca(2, 3)*ca(3, 2)) - ca(1, 2)*(ca(2, 1)*ca(3, 3) - &
      ca(2, 3)*ca(3, 1)) + ca(1, 3)*(ca(2, 1)*ca(3, 2) - ca(2, 2)*ca(3, 1)) - 1.0_dp) < 1e-15_dp, "det C(q) = 1")
  end block
  call finish()

contains
  pure function cross_ref(x, y) result(z)
    real(dp), intent(in) :: x(3), y(3)
    real(dp) :: z(3)
    z = [x(2)*y(3) - x(3)*y(2), x(3)*y(1) - x(1)*y(3), x(1)*y(2) - x(2)*y(1)]
  end function cross_ref
  pure function eye() result(m)
    real(dp) :: m(3, 3)
    m = 0; m(1, 1) = 1; m(2, 2) = 1; m(3, 3) = 1
  end function eye
  pure function exp_q(wv, t) result(r)
    real(dp), intent(in) :: wv(3), t
    real(dp) :: r(4)
    r = [cos(norm2(wv)*t/2), sin(norm2(wv)*t/2)*wv/norm2(wv)]
  end function exp_q
  function fmt(x) result(s)
    real(dp), intent(in) :: x
    character(len=24) :: s
    write(s, '(g0.6)') x
  end function fmt
end program test_rotation
