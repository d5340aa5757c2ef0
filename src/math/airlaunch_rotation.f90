!> Rotations in the paper's convention (Zheng & Zhang 2018, Eqs. (49)-(50)).
!>
!> Earth frame: x forward, y up, z right.  Body frame: x along the body axis
!> (nose), y up, z right.  Euler angles: yaw psi about y, then pitch theta about
!> z', then roll gamma about x''.  The direction-cosine matrix C maps body
!> components to earth components: v_e = C v_b, C = Ry(psi) Rz(theta) Rx(gamma).
!> Attitude is integrated as a unit quaternion q = [w, x, y, z] representing C;
!> Euler angles are output only (the kinematics (50) is singular at pitch +-90 deg,
!> the rocket's firing attitude).
module airlaunch_rotation
  use airlaunch_kinds, only: dp, pi
  implicit none
  private
  public :: skew, quat_mul, quat_conj, quat_normalize, quat_to_dcm, dcm_to_quat
  public :: quat_from_euler, quat_to_euler, euler_to_dcm, dcm_to_euler
  public :: quat_rate, quat_rotate, quat_rotate_inv, euler_rate_matrix
  public :: rot_x, rot_y, rot_z, nose_elevation, cross

contains

  !> Skew-symmetric (cross-product) matrix: skew(a) b = a x b.
  pure function skew(a) result(s)
    real(dp), intent(in) :: a(3)   !< vector
    real(dp) :: s(3, 3)
    s(:, 1) = [0.0_dp, a(3), -a(2)]
    s(:, 2) = [-a(3), 0.0_dp, a(1)]
    s(:, 3) = [a(2), -a(1), 0.0_dp]
  end function skew

  !> Cross product a x b.
  pure function cross(a, b) result(c)
    real(dp), intent(in) :: a(3), b(3)   !< vectors
    real(dp) :: c(3)
    c = [a(2)*b(3) - a(3)*b(2), a(3)*b(1) - a(1)*b(3), a(1)*b(2) - a(2)*b(1)]
  end function cross

  !> Active rotation about x by angle a [rad].
  pure function rot_x(a) result(r)
    real(dp), intent(in) :: a   !< angle [rad]
    real(dp) :: r(3, 3)
    r = reshape([1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, cos(a), sin(a), 0.0_dp, -sin(a), cos(a)], [3, 3])
  end function rot_x

  !> Active rotation about y by angle a [rad].
  pure function rot_y(a) result(r)
    real(dp), intent(in) :: a   !< angle [rad]
    real(dp) :: r(3, 3)
    r = reshape([cos(a), 0.0_dp, -sin(a), 0.0_dp, 1.0_dp, 0.0_dp, sin(a), 0.0_dp, cos(a)], [3, 3])
  end function rot_y

  !> Active rotation about z by angle a [rad].
  pure function rot_z(a) result(r)
    real(dp), intent(in) :: a   !< angle [rad]
    real(dp) :: r(3, 3)
    r = reshape([cos(a), sin(a), 0.0_dp, -sin(a), cos(a), 0.0_dp, 0.0_dp, 0.0_dp, 1.0_dp], [3, 3])
  end function rot_z

  !> Body-to-earth matrix from Euler angles [yaw, pitch, roll] (rad).
  pure function euler_to_dcm(e) result(c)
    real(dp), intent(in) :: e(3)   !< [psi, theta, gamma] [rad]
    real(dp) :: c(3, 3), ry(3, 3), rz(3, 3), rx(3, 3)
    ! named factors: gfortran 12 mis-warns on matmul of function results
    ry = rot_y(e(1)); rz = rot_z(e(2)); rx = rot_x(e(3))
    c = matmul(ry, matmul(rz, rx))
  end function euler_to_dcm

  !> Euler angles [yaw, pitch, roll] (rad) from a body-to-earth matrix.
  !> Pitch in [-pi/2, pi/2]; at the gimbal lock (|pitch| = 90 deg) roll is set
  !> to zero and the whole heading goes to yaw, so the round trip C -> e -> C holds.
  pure function dcm_to_euler(c) result(e)
    real(dp), intent(in) :: c(3, 3)   !< body-to-earth matrix
    real(dp) :: e(3)
    real(dp) :: cth
    cth = sqrt(c(2, 2)**2 + c(2, 3)**2)
    e(2) = atan2(c(2, 1), cth)
    if (cth > 1.0e-12_dp) then
      e(1) = atan2(-c(3, 1), c(1, 1))
      e(3) = atan2(-c(2, 3), c(2, 2))
    else
      e(3) = 0.0_dp
      e(1) = atan2(c(1, 3), c(3, 3))
    end if
  end function dcm_to_euler

  !> Hamilton product p q (quaternions as [w, x, y, z]).
  pure function quat_mul(p, q) result(r)
    real(dp), intent(in) :: p(4), q(4)   !< factors
    real(dp) :: r(4)
    r(1) = p(1)*q(1) - p(2)*q(2) - p(3)*q(3) - p(4)*q(4)
    r(2) = p(1)*q(2) + p(2)*q(1) + p(3)*q(4) - p(4)*q(3)
    r(3) = p(1)*q(3) - p(2)*q(4) + p(3)*q(1) + p(4)*q(2)
    r(4) = p(1)*q(4) + p(2)*q(3) - p(3)*q(2) + p(4)*q(1)
  end function quat_mul

  !> Conjugate quaternion.
  pure function quat_conj(q) result(r)
    real(dp), intent(in) :: q(4)   !< quaternion
    real(dp) :: r(4)
    r = [q(1), -q(2), -q(3), -q(4)]
  end function quat_conj

  !> Unit quaternion with non-negative scalar part.
  pure function quat_normalize(q) result(r)
    real(dp), intent(in) :: q(4)   !< quaternion
    real(dp) :: r(4)
    r = q/norm2(q)
  end function quat_normalize

  !> Body-to-earth matrix of a (not necessarily unit) quaternion.
  pure function quat_to_dcm(qin) result(c)
    real(dp), intent(in) :: qin(4)   !< quaternion [w, x, y, z]
    real(dp) :: c(3, 3), q(4), w, x, y, z
    q = qin/norm2(qin)
    w = q(1); x = q(2); y = q(3); z = q(4)
    c(1, :) = [1.0_dp - 2*(y*y + z*z), 2*(x*y - w*z), 2*(x*z + w*y)]
    c(2, :) = [2*(x*y + w*z), 1.0_dp - 2*(x*x + z*z), 2*(y*z - w*x)]
    c(3, :) = [2*(x*z - w*y), 2*(y*z + w*x), 1.0_dp - 2*(x*x + y*y)]
  end function quat_to_dcm

  !> Unit quaternion of a rotation matrix (Shepperd's method: robust at any angle).
  pure function dcm_to_quat(c) result(q)
    real(dp), intent(in) :: c(3, 3)   !< body-to-earth matrix
    real(dp) :: q(4), tr, s
    tr = c(1, 1) + c(2, 2) + c(3, 3)
    if (tr > max(c(1, 1), c(2, 2), c(3, 3))) then
      s = 2*sqrt(1 + tr)
      q = [0.25_dp*s, (c(3, 2) - c(2, 3))/s, (c(1, 3) - c(3, 1))/s, (c(2, 1) - c(1, 2))/s]
    else if (c(1, 1) >= c(2, 2) .and. c(1, 1) >= c(3, 3)) then
      s = 2*sqrt(1 + c(1, 1) - c(2, 2) - c(3, 3))
      q = [(c(3, 2) - c(2, 3))/s, 0.25_dp*s, (c(1, 2) + c(2, 1))/s, (c(1, 3) + c(3, 1))/s]
    else if (c(2, 2) >= c(3, 3)) then
      s = 2*sqrt(1 + c(2, 2) - c(1, 1) - c(3, 3))
      q = [(c(1, 3) - c(3, 1))/s, (c(1, 2) + c(2, 1))/s, 0.25_dp*s, (c(2, 3) + c(3, 2))/s]
    else
      s = 2*sqrt(1 + c(3, 3) - c(1, 1) - c(2, 2))
      q = [(c(2, 1) - c(1, 2))/s, (c(1, 3) + c(3, 1))/s, (c(2, 3) + c(3, 2))/s, 0.25_dp*s]
    end if
    if (q(1) < 0.0_dp) q = -q
    q = q/norm2(q)
  end function dcm_to_quat

  !> Quaternion of Euler angles [yaw, pitch, roll] (rad): q = qy(psi) qz(theta) qx(gamma).
  pure function quat_from_euler(e) result(q)
    real(dp), intent(in) :: e(3)   !< [psi, theta, gamma] [rad]
    real(dp) :: q(4)
    q = quat_mul(quat_mul([cos(e(1)/2), 0.0_dp, sin(e(1)/2), 0.0_dp], &
                          [cos(e(2)/2), 0.0_dp, 0.0_dp, sin(e(2)/2)]), &
                 [cos(e(3)/2), sin(e(3)/2), 0.0_dp, 0.0_dp])
  end function quat_from_euler

  !> Euler angles [yaw, pitch, roll] (rad) of a quaternion.
  pure function quat_to_euler(q) result(e)
    real(dp), intent(in) :: q(4)   !< quaternion [w, x, y, z]
    real(dp) :: e(3)
    e = dcm_to_euler(quat_to_dcm(q))
  end function quat_to_euler

  !> Time derivative of the attitude quaternion for body angular velocity w_b:
  !> qdot = 1/2 q (x) [0, w_b].  Callers normalise q where they read it.
  pure function quat_rate(q, w_b) result(qd)
    real(dp), intent(in) :: q(4)     !< attitude quaternion
    real(dp), intent(in) :: w_b(3)   !< body angular velocity [rad/s]
    real(dp) :: qd(4)
    qd = 0.5_dp*quat_mul(q, [0.0_dp, w_b])
  end function quat_rate

  !> Rotate a body vector into the earth frame: C v.
  pure function quat_rotate(q, v) result(r)
    real(dp), intent(in) :: q(4), v(3)   !< quaternion, body vector
    real(dp) :: r(3), c(3, 3)
    c = quat_to_dcm(q)
    r = matmul(c, v)
  end function quat_rotate

  !> Rotate an earth vector into the body frame: C^T v.
  pure function quat_rotate_inv(q, v) result(r)
    real(dp), intent(in) :: q(4), v(3)   !< quaternion, earth vector
    real(dp) :: r(3), c(3, 3)
    c = quat_to_dcm(q)
    r = matmul(v, c)
  end function quat_rotate_inv

  !> Matrix W of Eqs. (49)-(50): w_body = W [gamma_dot, psi_dot, theta_dot].
  !> Used for output and tests only (singular at pitch +-90 deg).
  pure function euler_rate_matrix(e) result(w)
    real(dp), intent(in) :: e(3)   !< [psi, theta, gamma] [rad]
    real(dp) :: w(3, 3), th, ga
    th = e(2); ga = e(3)
    w(1, :) = [1.0_dp, sin(th), 0.0_dp]
    w(2, :) = [0.0_dp, cos(th)*cos(ga), sin(ga)]
    w(3, :) = [0.0_dp, -cos(th)*sin(ga), cos(ga)]
  end function euler_rate_matrix

  !> Continuous nose-elevation angle [rad] of the body x axis in the vertical
  !> plane of the earth x-y axes: 0 level forward, pi/2 straight up, pi level aft.
  !> Unlike the Euler pitch it does not fold back at 90 deg.
  pure function nose_elevation(q) result(a)
    real(dp), intent(in) :: q(4)   !< attitude quaternion
    real(dp) :: a, c(3, 3)
    c = quat_to_dcm(q)
    a = atan2(c(2, 1), c(1, 1))
    if (a < -pi/2) a = a + 2*pi
  end function nose_elevation
end module airlaunch_rotation
