!> Open chain of 1-3 rigid bodies joined by spherical joints, by Kane's method
!> (Zheng & Zhang 2018, §4.2, Eqs. (51)-(65)): rocket alone; rocket + parachute;
!> rocket + virtual rigid line + parachute.
!>
!> Generalized speeds (53): u = [v, w_1, ..., w_n], v the earth velocity of body 1's
!> CG, w_k the angular velocity of body k in ITS OWN body axes (DESIGN §2: Eq. (57)
!> writes Euler rates; we use body rates and quaternions, Eqs. (49)-(50) are not
!> integrated).  Chain state (size 6 + 7n):
!>   y = [r_1(3), v(3), q_1(4), w_1(3), q_2(4), w_2(3), ...]
!> so that a one-body chain has exactly the 13-state layout of `rigid_body`.
!>
!> Geometry of link k (body axes of k, from its CG): `proximal` = joint with body
!> k-1 (ignored for k = 1), `distal` = joint with body k+1 (for the rocket: the
!> front tie-down point).  Positions of bodies 2..n follow from r_1 and the attitudes:
!>   r_k = r_1 + sum_{j<=k} C_j c_jk,  c_jk = distal_j - proximal_j (j<k), -proximal_k (j=k),
!> with proximal_1 = 0; the velocities (57) follow likewise:
!>   V_k = v + sum_{j<=k} C_j (w_j x c_jk),  so  dV_k/dw_j = -C_j skew(c_jk)   (58)-(59).
!> A (63) = diag(m_k I, J_k) Vhat; B u (63) = [m_k sum_j C_j w_j x (w_j x c_jk); w_k x J_k w_k];
!> R (61) = [F_k (earth, at CG); M_k (body k axes, about CG)];
!> (65): (Vhat^T A) udot = Vhat^T (R - B u), solved by Cholesky (solve_spd, LAPACK).
!>
!> The line as virtual rigid body (§2.4 Steps 1-6): `set_line_link` replaces its
!> mass, inertia and length between steps (m_rigid, J_rigid, d_rigid of Eqs. (20),
!> (31), (32)) in the paper's line frame (z axis towards the front attach point).
module airlaunch_kane_chain
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_linalg, only: solve_spd
  use airlaunch_rotation, only: skew
  use airlaunch_rigid_body, only: rigid_body, check_mass_properties, cross, quaternion_drift_rate
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  implicit none
  private
  public :: kane_chain, chain_link, max_chain_bodies

  !> Longest chain: rocket, line, parachute.
  integer, parameter :: max_chain_bodies = 3

  !> Mass properties and joint points of one body of the chain.
  type :: chain_link
    character(len=:), allocatable :: name   !< for messages
    real(dp) :: mass = 1.0_dp               !< [kg]
    real(dp) :: inertia(3, 3) = 0.0_dp      !< about the CG, body axes [kg m^2]
    real(dp) :: proximal(3) = 0.0_dp        !< joint with the previous body, body axes [m]
    real(dp) :: distal(3) = 0.0_dp          !< joint with the next body, body axes [m]
  end type chain_link

  !> The chain: links and preallocated work arrays of Eqs. (58)-(65).
  type :: kane_chain
    integer :: n = 0                                 !< number of bodies
    type(chain_link), allocatable :: link(:)         !< (n) links, link(1) = rocket
    !> Axial inertia floor of a virtual line body, relative to its transverse inertia.
    real(dp) :: axial_inertia_floor = 1.0e-3_dp
    real(dp), allocatable :: vhat(:, :)              !< (6n, 3+3n) partial velocities (58)-(59)
    real(dp), allocatable :: amat(:, :)              !< (6n, 3+3n) A of (63)
    real(dp), allocatable :: bu(:)                   !< (6n) B u of (63)
    real(dp), allocatable :: mass_matrix(:, :)       !< (3+3n, 3+3n) Vhat^T A
    real(dp), allocatable :: rhs(:, :)               !< (3+3n, ncol) right-hand sides / solutions
    real(dp), allocatable :: load(:)                 !< (6n) R - B u
    real(dp), allocatable :: cvec(:, :, :)           !< (3, n, n) c_jk
  contains
    procedure :: init => chain_init
    procedure :: set_link => chain_set_link
    procedure :: set_line_link => chain_set_line_link
    procedure :: state_size => chain_state_size
    procedure :: speed_size => chain_speed_size
    procedure :: load_bodies => chain_load_bodies
    procedure :: name_bodies => chain_name_bodies
    procedure :: store_bodies => chain_store_bodies
    procedure :: accelerations => chain_accelerations
    procedure :: state_derivative => chain_state_derivative
    procedure :: joint_residual => chain_joint_residual
  end type kane_chain

contains

  !> Create a chain of n bodies (1 to 3) able to solve ncol load cases at once
  !> (the CFA probes, §3.3).  Links default to unit spheres; set them with set_link.
  subroutine chain_init(self, n, ncol, error)
    class(kane_chain), intent(inout) :: self              !< chain
    integer, intent(in) :: n                              !< number of bodies
    integer, intent(in) :: ncol                           !< load cases per solve (>= 1)
    type(error_type), allocatable, intent(inout) :: error !< set on a bad n
    integer :: nu, k
    if (n < 1 .or. n > max_chain_bodies) then
      call fatal_error(error, "Kane chain: " // str(n) // " bodies requested (1 to " // &
        str(max_chain_bodies) // " supported)")
      return
    end if
    self%n = n
    nu = 3 + 3*n
    if (allocated(self%link)) deallocate(self%link)
    allocate(self%link(n))
    do k = 1, n
      self%link(k)%name = "chain body " // str(k)
      self%link(k)%inertia = reshape([1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, 1.0_dp, 0.0_dp, &
                                      0.0_dp, 0.0_dp, 1.0_dp], [3, 3])
    end do
    self%link(1)%name = "rocket"
    if (allocated(self%vhat)) deallocate(self%vhat, self%amat, self%bu, self%mass_matrix, &
      self%rhs, self%load, self%cvec)
    allocate(self%vhat(6*n, nu), self%amat(6*n, nu), self%bu(6*n), self%mass_matrix(nu, nu), &
      self%rhs(nu, max(1, ncol)), self%load(6*n), self%cvec(3, n, n))
  end subroutine chain_init

  !> Set the mass properties and joint points of body k.  Zero mass or inertia is
  !> accepted here (a virtual body may vanish); a singular mass matrix is then
  !> reported by the solve, with the phase and time.
  subroutine chain_set_link(self, k, name, mass, inertia, proximal, distal, error)
    class(kane_chain), intent(inout) :: self              !< chain
    integer, intent(in) :: k                              !< body number in the chain (1 = rocket)
    character(len=*), intent(in) :: name                  !< name for messages
    real(dp), intent(in) :: mass                          !< [kg]
    real(dp), intent(in) :: inertia(3, 3)                 !< about the CG, body axes [kg m^2]
    real(dp), intent(in) :: proximal(3)                   !< joint with body k-1, body axes [m]
    real(dp), intent(in) :: distal(3)                     !< joint with body k+1, body axes [m]
    type(error_type), allocatable, intent(inout) :: error !< set on invalid input
    if (k < 1 .or. k > self%n) then
      call fatal_error(error, "Kane chain: no body " // str(k) // " in a chain of " // str(self%n))
      return
    end if
    call check_mass_properties(name, mass, inertia, k > 1, error)
    if (allocated(error)) return
    if (.not. (all(ieee_is_finite(proximal)) .and. all(ieee_is_finite(distal)))) then
      call fatal_error(error, trim(name) // ": joint points are not finite numbers")
      return
    end if
    self%link(k)%name = name
    self%link(k)%mass = mass
    self%link(k)%inertia = inertia
    self%link(k)%proximal = proximal
    self%link(k)%distal = distal
  end subroutine chain_set_link

  !> The flexible line as the virtual rigid body of equivalent rigidization
  !> (§2.4): mass m_rigid (31), principal inertia J_rigid (32) and length d_rigid
  !> (20), in the paper's line frame: z towards the front (rocket-side) attach point,
  !> so proximal = [0, 0, d/2], distal = [0, 0, -d/2].  A line has (almost) no axial
  !> inertia; its spin about its own axis between two spherical joints is
  !> undetermined, so J_z is floored at `axial_inertia_floor * max(J_x, J_y)` to keep
  !> the mass matrix regular (that spin is decoupled and carries no load).
  subroutine chain_set_line_link(self, k, mass, inertia_xyz, length, error)
    class(kane_chain), intent(inout) :: self              !< chain
    integer, intent(in) :: k                              !< body number of the line (2 normally)
    real(dp), intent(in) :: mass                          !< m_rigid [kg]
    real(dp), intent(in) :: inertia_xyz(3)                !< J_rigid about x, y, z (line frame) [kg m^2]
    real(dp), intent(in) :: length                        !< d_rigid [m]
    type(error_type), allocatable, intent(inout) :: error !< set on invalid input
    real(dp) :: jm(3, 3)
    if (.not. (length > 0.0_dp)) then
      call fatal_error(error, "line body: length d_rigid must be positive (got " // str(length) // " m)")
      return
    end if
    jm = 0.0_dp
    jm(1, 1) = inertia_xyz(1)
    jm(2, 2) = inertia_xyz(2)
    jm(3, 3) = max(inertia_xyz(3), self%axial_inertia_floor*max(inertia_xyz(1), inertia_xyz(2)))
    call self%set_link(k, "line (virtual rigid body)", mass, jm, [0.0_dp, 0.0_dp, 0.5_dp*length], &
      [0.0_dp, 0.0_dp, -0.5_dp*length], error)
  end subroutine chain_set_line_link

  !> Number of state variables, 6 + 7n.
  pure integer function chain_state_size(self) result(m)
    class(kane_chain), intent(in) :: self  !< chain
    m = 6 + 7*self%n
  end function chain_state_size

  !> Number of generalized speeds, 3 + 3n.
  pure integer function chain_speed_size(self) result(m)
    class(kane_chain), intent(in) :: self  !< chain
    m = 3 + 3*self%n
  end function chain_speed_size

  !> Fill bodies(1:n) (mass properties, positions, velocities, attitudes, rates)
  !> from the chain state y; bodies 2..n are placed by the joint kinematics (57).
  !> Runs in every right-hand side: no allocation (the bodies' names are set where
  !> the links are set, by the owner of the bodies).
  subroutine chain_load_bodies(self, y, bodies)
    class(kane_chain), intent(inout) :: self    !< chain (c_jk cached)
    real(dp), intent(in) :: y(:)                !< chain state (6 + 7n)
    type(rigid_body), intent(inout) :: bodies(:) !< (n) bodies of the chain, bodies(1) = rocket
    integer :: j, k, o
    real(dp) :: wc(3)
    do k = 1, self%n
      o = 6 + 7*(k - 1)
      call bodies(k)%set_attitude(y(o+1:o+4))
      bodies(k)%w = y(o+5:o+7)
      bodies(k)%mass = self%link(k)%mass
      bodies(k)%inertia = self%link(k)%inertia
    end do
    do k = 1, self%n
      do j = 1, self%n
        if (j < k) then
          ! body 1 has no previous body: its proximal point is ignored (r_1 is its CG)
          self%cvec(:, j, k) = self%link(j)%distal
          if (j > 1) self%cvec(:, j, k) = self%cvec(:, j, k) - self%link(j)%proximal
        else if (j == k .and. k > 1) then
          self%cvec(:, j, k) = -self%link(k)%proximal
        else
          self%cvec(:, j, k) = 0.0_dp
        end if
      end do
      bodies(k)%r = y(1:3)
      bodies(k)%v = y(4:6)
      do j = 1, k
        ! w_j x c_jk in a local first: a function result as a matmul argument
        ! becomes a heap temporary in gfortran
        wc = cross(bodies(j)%w, self%cvec(:, j, k))
        bodies(k)%r = bodies(k)%r + matmul(bodies(j)%c, self%cvec(:, j, k))
        bodies(k)%v = bodies(k)%v + matmul(bodies(j)%c, wc)
      end do
    end do
  end subroutine chain_load_bodies

  !> Give bodies(1:n) the names of the links (for messages).  Call it once
  !> after the links are set, not per right-hand side (a deferred-length
  !> assignment reallocates).
  subroutine chain_name_bodies(self, bodies)
    class(kane_chain), intent(in) :: self         !< chain
    type(rigid_body), intent(inout) :: bodies(:)  !< (n) bodies of the chain
    integer :: k
    do k = 1, min(self%n, size(bodies))
      bodies(k)%name = self%link(k)%name
    end do
  end subroutine chain_name_bodies

  !> Write the chain state y from bodies(1:n): r_1, v_1 and every attitude and rate
  !> (positions and velocities of bodies 2..n are implied by the joints).
  subroutine chain_store_bodies(self, bodies, y)
    class(kane_chain), intent(in) :: self        !< chain
    type(rigid_body), intent(in) :: bodies(:)    !< (n) bodies
    real(dp), intent(out) :: y(:)                !< chain state (6 + 7n)
    integer :: k, o
    y(1:3) = bodies(1)%r
    y(4:6) = bodies(1)%v
    do k = 1, self%n
      o = 6 + 7*(k - 1)
      y(o+1:o+4) = bodies(k)%q
      y(o+5:o+7) = bodies(k)%w
    end do
  end subroutine chain_store_bodies

  !> Kane's equations (65) for several load cases sharing one factorization.
  !> Column 1 is the real case: applied loads `force`, `moment` (frames as in
  !> force_source) with the velocity terms B u.  Columns 2..ncol are probe wrenches
  !> acting on body 1 only (probe_force earth at its CG, probe_moment body axes),
  !> without B u, so that udot is affine in the probe amplitudes (CFA, §3.3).
  !> On return self%rhs(:, c) holds udot of case c.  Bodies must be loaded.
  subroutine chain_accelerations(self, bodies, force, moment, probe_force, probe_moment, nprobe, error)
    class(kane_chain), intent(inout) :: self              !< chain
    type(rigid_body), intent(in) :: bodies(:)             !< (n) loaded bodies
    real(dp), intent(in) :: force(:, :)                   !< (3, n) CG forces, earth [N]
    real(dp), intent(in) :: moment(:, :)                  !< (3, n) moments, body axes [N m]
    real(dp), intent(in) :: probe_force(:, :)             !< (3, >= nprobe) body-1 probe forces, earth
    real(dp), intent(in) :: probe_moment(:, :)            !< (3, >= nprobe) body-1 probe moments, body
    integer, intent(in) :: nprobe                         !< number of probes (<= ncol - 1)
    type(error_type), allocatable, intent(inout) :: error !< set if Vhat^T A is singular
    integer :: j, k, r0, c0, nu
    real(dp) :: acc(3), sc(3, 3), wwc(3), jw(3), gyro(3), vtr(3 + 3*max_chain_bodies)
    ! No allocation here (every right-hand side): function results go to locals
    ! first; gfortran copies a function result to a heap temporary when it is a
    ! matmul argument or is assigned to a section of an allocatable component.
    ! Partial velocities (58)-(59) and the velocity terms B u of (63)
    self%vhat = 0.0_dp
    do k = 1, self%n
      r0 = 6*(k - 1)
      self%vhat(r0+1, 1) = 1.0_dp
      self%vhat(r0+2, 2) = 1.0_dp
      self%vhat(r0+3, 3) = 1.0_dp
      acc = 0.0_dp
      do j = 1, k
        c0 = 3 + 3*(j - 1)
        sc = skew(self%cvec(:, j, k))
        wwc = cross(bodies(j)%w, cross(bodies(j)%w, self%cvec(:, j, k)))
        self%vhat(r0+1:r0+3, c0+1:c0+3) = -matmul(bodies(j)%c, sc)
        acc = acc + matmul(bodies(j)%c, wwc)
      end do
      c0 = 3 + 3*(k - 1)
      self%vhat(r0+4, c0+1) = 1.0_dp
      self%vhat(r0+5, c0+2) = 1.0_dp
      self%vhat(r0+6, c0+3) = 1.0_dp
      ! A = [m_k Vhat_k; J_k what_k]
      self%amat(r0+1:r0+3, :) = self%link(k)%mass*self%vhat(r0+1:r0+3, :)
      self%amat(r0+4:r0+6, :) = matmul(self%link(k)%inertia, self%vhat(r0+4:r0+6, :))
      jw = matmul(self%link(k)%inertia, bodies(k)%w)
      gyro = cross(bodies(k)%w, jw)
      self%bu(r0+1:r0+3) = self%link(k)%mass*acc
      self%bu(r0+4:r0+6) = gyro
      self%load(r0+1:r0+3) = force(:, k) - self%bu(r0+1:r0+3)
      self%load(r0+4:r0+6) = moment(:, k) - self%bu(r0+4:r0+6)
    end do
    self%mass_matrix = matmul(transpose(self%vhat), self%amat)
    self%rhs = 0.0_dp
    ! Vhat^T (R - B u) through a local buffer: straight into self%rhs(:, 1),
    ! libgfortran's matmul would allocate its result (self may alias).  Still
    ! libgfortran's matmul, not a loop of dot_product: its FMA kernel rounds
    ! differently, and the rigidized coupling's results stay bit-identical.
    nu = size(self%rhs, 1)
    vtr(1:nu) = matmul(transpose(self%vhat), self%load)
    self%rhs(:, 1) = vtr(1:nu)
    ! A wrench on body 1 enters through Vhat_1 = [E 0], what_1 = [0 E 0]: rows 1:6
    do k = 1, min(nprobe, size(self%rhs, 2) - 1)
      self%rhs(1:3, k+1) = probe_force(:, k)
      self%rhs(4:6, k+1) = probe_moment(:, k)
    end do
    ! every right-hand side: the cheap conditioning check (the message is built on failure only)
    call solve_spd(self%mass_matrix, self%rhs, error, "Kane mass matrix Vhat^T A (Eq. (65))", &
      estimate_condition=.false.)
    if (allocated(error)) error%message = error%message // " of a " // str(self%n) // "-body chain"
  end subroutine chain_accelerations

  !> Chain state derivative from udot: rdot_1 = v, vdot = udot(1:3), quaternion
  !> kinematics of every body (with norm drift gain), wdot_k = udot.
  subroutine chain_state_derivative(self, y, bodies, udot, quat_gain, ydot)
    class(kane_chain), intent(in) :: self        !< chain
    real(dp), intent(in) :: y(:)                 !< chain state
    type(rigid_body), intent(in) :: bodies(:)    !< (n) loaded bodies
    real(dp), intent(in) :: udot(:)              !< (3+3n) generalized accelerations
    real(dp), intent(in) :: quat_gain            !< quaternion drift gain [1/s]
    real(dp), intent(out) :: ydot(:)             !< chain state derivative
    integer :: k, o
    ydot(1:3) = y(4:6)
    ydot(4:6) = udot(1:3)
    do k = 1, self%n
      o = 6 + 7*(k - 1)
      ydot(o+1:o+4) = quaternion_drift_rate(y(o+1:o+4), bodies(k)%w, quat_gain)
      ydot(o+5:o+7) = udot(3+3*(k-1)+1:3+3*k)
    end do
  end subroutine chain_state_derivative

  !> Largest position mismatch of the spherical joints recomputed from the
  !> loaded bodies (zero by construction: a check of the kinematics) [m].
  real(dp) function chain_joint_residual(self, bodies) result(res)
    class(kane_chain), intent(in) :: self        !< chain
    type(rigid_body), intent(in) :: bodies(:)    !< (n) loaded bodies
    integer :: k
    res = 0.0_dp
    do k = 2, self%n
      res = max(res, norm2(bodies(k-1)%point_position(self%link(k-1)%distal) - &
        bodies(k)%point_position(self%link(k)%proximal)))
    end do
  end function chain_joint_residual
end module airlaunch_kane_chain
