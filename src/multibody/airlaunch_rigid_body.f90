!> Rigid bodies with quaternion attitude (Zheng & Zhang 2018, §4.1, Eqs. (47)-(48)).
!>
!> State of one body, in this order (13 numbers, `pack`/`unpack`):
!>   r(3)  position of the centre of gravity, earth frame [m] (x forward, y up, z right)
!>   v(3)  velocity of the centre of gravity, earth frame [m/s]
!>   q(4)  unit quaternion [w, x, y, z] of the body-to-earth rotation C (v_e = C v_b)
!>   w(3)  angular velocity in body axes [rad/s]
!> Mass properties: mass [kg] and the inertia tensor about the CG in body axes [kg m^2].
!>
!> Newton-Euler (47)-(48) with v in the EARTH frame: m dv/dt = F (earth) -- the paper's
!> omega~ V term of (47) belongs to a body-axis velocity and vanishes here -- and
!> J dw/dt + w x J w = M (body axes, about the CG), solved with LAPACK (solve_spd).
!> Attitude is integrated as a quaternion, qdot = 1/2 q (x) [0, w] (no Euler angles,
!> DESIGN §2: the kinematics (49)-(50) is singular at pitch +-90 deg); an optional
!> drift term k (1 - |q|^2) q pulls |q| back to one (zero on the unit sphere, so
!> it does not change the motion).  Consumers always read q/|q|.
module airlaunch_rigid_body
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_linalg, only: solve_spd
  use airlaunch_rotation, only: quat_to_dcm, quat_rate
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  implicit none
  private
  public :: rigid_body, body_state_size, new_rigid_body, check_mass_properties
  public :: newton_euler, body_state_derivative, quaternion_drift_rate, cross, body_state_name

  !> Number of state variables of one free rigid body.
  integer, parameter :: body_state_size = 13

  !> A rigid body: mass properties and its current kinematic state.
  type :: rigid_body
    character(len=:), allocatable :: name   !< for messages ("aircraft", "rocket", ...)
    real(dp) :: mass = 1.0_dp               !< mass [kg]
    real(dp) :: inertia(3, 3) = reshape([1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, 1.0_dp, 0.0_dp, &
                                         0.0_dp, 0.0_dp, 1.0_dp], [3, 3]) !< about CG, body axes [kg m^2]
    real(dp) :: r(3) = 0.0_dp               !< CG position, earth [m]
    real(dp) :: v(3) = 0.0_dp               !< CG velocity, earth [m/s]
    real(dp) :: q(4) = [1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp] !< body-to-earth unit quaternion
    real(dp) :: w(3) = 0.0_dp               !< angular velocity, body axes [rad/s]
    real(dp) :: c(3, 3) = reshape([1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, 1.0_dp, 0.0_dp, &
                                   0.0_dp, 0.0_dp, 1.0_dp], [3, 3]) !< C(q): body -> earth (kept in step with q)
  contains
    procedure :: pack => body_pack
    procedure :: unpack => body_unpack
    procedure :: set_attitude => body_set_attitude
    procedure :: point_position => body_point_position
    procedure :: point_velocity => body_point_velocity
    procedure :: kinetic_energy => body_kinetic_energy
    procedure :: linear_momentum => body_linear_momentum
    procedure :: angular_momentum => body_angular_momentum
  end type rigid_body

contains

  !> A rigid body with validated mass properties (state at rest at the origin).
  function new_rigid_body(name, mass, inertia, error) result(body)
    character(len=*), intent(in) :: name                  !< name for messages
    real(dp), intent(in) :: mass                          !< mass [kg], > 0
    real(dp), intent(in) :: inertia(3, 3)                 !< inertia about the CG, body axes [kg m^2]
    type(error_type), allocatable, intent(inout) :: error !< set if the mass properties are invalid
    type(rigid_body) :: body
    body%name = name
    body%mass = mass
    body%inertia = inertia
    call check_mass_properties(name, mass, inertia, .false., error)
  end function new_rigid_body

  !> Validate mass properties: positive (or, if allow_zero, non-negative) mass and a
  !> symmetric inertia tensor with positive (non-negative) diagonal; positive
  !> definiteness is checked by the solves.  The triangle inequality J1 + J2 >= J3
  !> of a real mass distribution is NOT enforced: the paper's aircraft (Ix, Iy, Iz =
  !> 540 740, 737 480, 117 030 kg m^2) violates it (Ix + Iz < Iy) and must be accepted.
  subroutine check_mass_properties(name, mass, inertia, allow_zero, error)
    character(len=*), intent(in) :: name                  !< body name for the message
    real(dp), intent(in) :: mass                          !< mass [kg]
    real(dp), intent(in) :: inertia(3, 3)                 !< inertia tensor [kg m^2]
    logical, intent(in) :: allow_zero                     !< accept zero mass/inertia (virtual bodies)
    type(error_type), allocatable, intent(inout) :: error !< set on invalid input
    real(dp) :: scale, j1, j2, j3
    if (.not. (ieee_is_finite(mass) .and. all(ieee_is_finite(inertia)))) then
      call fatal_error(error, trim(name) // ": mass properties are not finite numbers")
      return
    end if
    if (mass < 0.0_dp .or. (mass == 0.0_dp .and. .not. allow_zero)) then
      call fatal_error(error, trim(name) // ": mass must be positive (got " // str(mass) // " kg)")
      return
    end if
    scale = max(maxval(abs(inertia)), tiny(1.0_dp))
    if (maxval(abs(inertia - transpose(inertia))) > 1.0e-12_dp*scale) then
      call fatal_error(error, trim(name) // ": inertia tensor is not symmetric")
      return
    end if
    j1 = inertia(1, 1); j2 = inertia(2, 2); j3 = inertia(3, 3)
    if (min(j1, j2, j3) < 0.0_dp .or. (.not. allow_zero .and. min(j1, j2, j3) <= 0.0_dp)) then
      call fatal_error(error, trim(name) // ": principal moments of inertia must be positive (got " &
        // str(j1) // ", " // str(j2) // ", " // str(j3) // " kg m^2)")
      return
    end if
  end subroutine check_mass_properties

  !> Write the 13 state numbers [r, v, q, w] into y(1:13).
  pure subroutine body_pack(self, y)
    class(rigid_body), intent(in) :: self  !< body
    real(dp), intent(out) :: y(:)          !< destination, size >= 13
    y(1:3) = self%r
    y(4:6) = self%v
    y(7:10) = self%q
    y(11:13) = self%w
  end subroutine body_pack

  !> Read the 13 state numbers [r, v, q, w] from y(1:13); q is normalised and C updated.
  pure subroutine body_unpack(self, y)
    class(rigid_body), intent(inout) :: self  !< body
    real(dp), intent(in) :: y(:)              !< source, size >= 13
    self%r = y(1:3)
    self%v = y(4:6)
    call self%set_attitude(y(7:10))
    self%w = y(11:13)
  end subroutine body_unpack

  !> Set the attitude from a (not necessarily unit) quaternion; C follows.
  pure subroutine body_set_attitude(self, q)
    class(rigid_body), intent(inout) :: self  !< body
    real(dp), intent(in) :: q(4)              !< quaternion [w, x, y, z]
    self%q = q/norm2(q)
    self%c = quat_to_dcm(self%q)
  end subroutine body_set_attitude

  !> Earth position of a body-fixed point p (body axes, from the CG).
  pure function body_point_position(self, p) result(x)
    class(rigid_body), intent(in) :: self  !< body
    real(dp), intent(in) :: p(3)           !< point, body axes [m]
    real(dp) :: x(3)
    x = self%r + matmul(self%c, p)
  end function body_point_position

  !> Earth velocity of a body-fixed point p (body axes, from the CG).
  pure function body_point_velocity(self, p) result(u)
    class(rigid_body), intent(in) :: self  !< body
    real(dp), intent(in) :: p(3)           !< point, body axes [m]
    real(dp) :: u(3), wp(3)
    wp = cross(self%w, p)
    u = self%v + matmul(self%c, wp)
  end function body_point_velocity

  !> Kinetic energy 1/2 m v.v + 1/2 w.J w [J].
  pure real(dp) function body_kinetic_energy(self) result(e)
    class(rigid_body), intent(in) :: self  !< body
    e = 0.5_dp*self%mass*dot_product(self%v, self%v) + 0.5_dp*dot_product(self%w, matmul(self%inertia, self%w))
  end function body_kinetic_energy

  !> Linear momentum m v, earth frame [kg m/s].
  pure function body_linear_momentum(self) result(p)
    class(rigid_body), intent(in) :: self  !< body
    real(dp) :: p(3)
    p = self%mass*self%v
  end function body_linear_momentum

  !> Angular momentum about the earth origin, earth frame: r x m v + C J w [kg m^2/s].
  pure function body_angular_momentum(self) result(h)
    class(rigid_body), intent(in) :: self  !< body
    real(dp) :: h(3)
    h = cross(self%r, self%mass*self%v) + matmul(self%c, matmul(self%inertia, self%w))
  end function body_angular_momentum

  !> Newton-Euler accelerations, Eqs. (47)-(48), for ncol load cases at once:
  !> a(:,k) = F(:,k)/m (earth), J wdot(:,k) = M(:,k) - gyro * (w x J w) (body axes).
  !> The gyroscopic term is added to every column with weight gyro(k) (1 for a real
  !> load case, 0 for a unit probe of the CFA, which must be linear in the load).
  subroutine newton_euler(body, force, moment, gyro, a, wdot, error)
    type(rigid_body), intent(in) :: body                  !< body (mass properties and w)
    real(dp), intent(in) :: force(:, :)                   !< (3, ncol) forces at the CG, earth [N]
    real(dp), intent(in) :: moment(:, :)                  !< (3, ncol) moments about the CG, body [N m]
    real(dp), intent(in) :: gyro(:)                       !< (ncol) weight of the gyroscopic term
    real(dp), intent(out) :: a(:, :)                      !< (3, ncol) CG accelerations, earth [m/s^2]
    real(dp), intent(out), contiguous :: wdot(:, :)       !< (3, ncol) angular accelerations, body [rad/s^2]
    type(error_type), allocatable, intent(inout) :: error !< set if J is singular
    real(dp) :: jmat(3, 3), h(3)
    integer :: k
    a = force/body%mass
    h = cross(body%w, matmul(body%inertia, body%w))
    do k = 1, size(moment, 2)
      wdot(:, k) = moment(:, k) - gyro(k)*h
    end do
    jmat = body%inertia
    ! the inertia was validated when the body was made: the cheap check suffices here
    call solve_spd(jmat, wdot, error, "inertia tensor (Eq. (48))", estimate_condition=.false.)
    if (allocated(error)) error%message = body%name // " " // error%message
  end subroutine newton_euler

  !> Derivative of the 13-state of one body from its accelerations.
  pure subroutine body_state_derivative(body, y, a, wdot, quat_gain, ydot)
    type(rigid_body), intent(in) :: body   !< body (v, w)
    real(dp), intent(in) :: y(:)           !< its 13 raw state numbers (q as integrated)
    real(dp), intent(in) :: a(3)           !< CG acceleration, earth [m/s^2]
    real(dp), intent(in) :: wdot(3)        !< angular acceleration, body [rad/s^2]
    real(dp), intent(in) :: quat_gain      !< quaternion norm drift gain k [1/s]
    real(dp), intent(out) :: ydot(:)       !< 13 derivatives
    ydot(1:3) = body%v
    ydot(4:6) = a
    ydot(7:10) = quaternion_drift_rate(y(7:10), body%w, quat_gain)
    ydot(11:13) = wdot
  end subroutine body_state_derivative

  !> qdot = 1/2 q (x) [0, w] + k (1 - |q|^2) q: the kinematics of the raw integrated
  !> quaternion plus a norm-restoring term that vanishes on |q| = 1.
  pure function quaternion_drift_rate(q, w, gain) result(qd)
    real(dp), intent(in) :: q(4)     !< raw quaternion
    real(dp), intent(in) :: w(3)     !< body angular velocity [rad/s]
    real(dp), intent(in) :: gain     !< k [1/s]
    real(dp) :: qd(4)
    qd = quat_rate(q, w) + gain*(1.0_dp - dot_product(q, q))*q
  end function quaternion_drift_rate

  !> Cross product.
  pure function cross(a, b) result(c)
    real(dp), intent(in) :: a(3), b(3)   !< factors
    real(dp) :: c(3)
    c = [a(2)*b(3) - a(3)*b(2), a(3)*b(1) - a(1)*b(3), a(1)*b(2) - a(2)*b(1)]
  end function cross

  !> What component j (1..13) of a body's state is, e.g. "angular velocity z (body axes)".
  pure function body_state_name(j) result(name)
    integer, intent(in) :: j  !< component of [r, v, q, w]
    character(len=:), allocatable :: name
    character(len=1), parameter :: xyz(3) = ["x", "y", "z"], wxyz(4) = ["w", "x", "y", "z"]
    select case (j)
    case (1:3)
      name = "position " // xyz(j)
    case (4:6)
      name = "velocity " // xyz(j - 3)
    case (7:10)
      name = "attitude quaternion " // wxyz(j - 6)
    case (11:13)
      name = "angular velocity " // xyz(j - 10) // " (body axes)"
    case default
      name = "?"
    end select
  end function body_state_name
end module airlaunch_rigid_body
