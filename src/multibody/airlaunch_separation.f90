!> The rigid separation scene: aircraft B0 (Newton-Euler, Eqs. (47)-(48)) + Kane
!> chain rocket B1 [+ line B2] [+ parachute B3] (Eqs. (51)-(65)) + the cut joint
!> between B0 and B1 solved by the CFA (§3.2-3.3, Eqs. (43), (66)-(68)) + the phase
!> machine of §4.3 (Eqs. (66)-(67)), as one `ode_system` for CVODE.
!>
!> State y = [aircraft r, v, q, w (13) | chain r_1, v_1, (q_k, w_k)_k (6 + 7n)].
!>
!> Phases and events (g-functions for CVODE root finding, inactive ones held at 1):
!>   g1 = t - t0                    Case 0 -> 1 (release) at t0
!>   g2 = CG past the ramp edge     Case 1 -> 2 when it crosses zero upwards (l0 travelled)
!>   g3 = nose tip past the edge    Case 2 -> 3 when it crosses zero upwards (l10 travelled)
!>   g4 = edge normal force N       Case 2 -> 3 early separation when N crosses zero downwards
!>   g5 = lowest point - ground     in every phase, when ground_altitude is set: the
!>                                  aircraft's CG or the rocket's lowest point (its
!>                                  envelope, the cut joint's cylinder) reaching the
!>                                  ground (ground_time, ground_body, ground_point,
!>                                  ground_speed; the phase stays, `landed` tells the
!>                                  caller the scene is over)
!> `advance` integrates to an output time, handles the events (phase change, event
!> time recorded in event_time(1:3), CVODE re-initialised); entering Case 2 with
!> N <= 0 separates at once (early_separation).
!>
!> One evaluation (`evaluate`, used by rhs and roots): sources -> loads on every body;
!> joint basis + bias for the phase; one Kane solve and one aircraft solve with the
!> real loads and the unit constraint wrenches as extra columns (CFA Steps 1-2);
!> alpha, beta from the constraint rows; R_H from cfa_solve (Step 3); accelerations
!> as the affine combination.  After it, the public outputs hold the constraint
!> wrench (lambda, rh_force, rh_moment, normal_force, friction_force, stick), the
!> joint kinematics and residuals (js), the accelerations and l0/l10 (joint).
!>
!> Build a scene: `init` (aircraft and rocket mass properties, chain length, joint
!> geometry and options, t0); `set_link` / `set_line_body` for bodies 2..n;
!> `add_source` for every load model; set the body states in `bodies(0:n)` (e.g. with
!> joint%place_on_rail), `pack_state`, `start` (checks and captures the constraint
!> references), then cvode_solver%init(sys, ...) and `advance` repeatedly.
module airlaunch_separation
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_ode, only: ode_system, rhs_ok, rhs_fatal
  use airlaunch_cvode, only: cvode_solver
  use airlaunch_rigid_body, only: rigid_body, body_state_size, newton_euler, body_state_derivative, &
    check_mass_properties, quaternion_drift_rate
  use airlaunch_force_source, only: force_source, force_source_slot
  use airlaunch_kane_chain, only: kane_chain
  use airlaunch_cut_joint, only: cut_joint, cut_joint_geometry, cut_joint_options, joint_state, &
    joint_components, phase_name, phase_preparation, phase_extraction, phase_rotation, phase_free
  use airlaunch_cfa, only: cfa_workspace, cfa_solve, slide_locked, slide_free, slide_coulomb
  use airlaunch_rotation, only: quat_to_dcm
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  implicit none
  private
  public :: separation_system, separation_nroots
  public :: ground_at_cg, ground_at_nose, ground_at_tail

  !> Number of event functions.
  integer, parameter :: separation_nroots = 5
  !> Largest number of load cases per solve: the real loads + 6 unit wrenches.
  integer, parameter :: ncol_max = 7
  !> Which point reached the ground: the aircraft's CG, the rocket envelope's
  !> nose end or its tail end (the lowest point of that end's rim).
  integer, parameter :: ground_at_cg = 0, ground_at_nose = 1, ground_at_tail = 2

  !> Aircraft + rocket chain + cut joint + phases.
  type, extends(ode_system) :: separation_system
    ! --- configuration
    logical :: aircraft_prescribed = .false.  !< aircraft moves at constant v0, w0 (infinite mass)
    type(kane_chain) :: chain                 !< rocket [+ line] [+ parachute]
    type(cut_joint) :: joint                  !< the B0-B1 cut joint
    real(dp) :: t0 = 0.0_dp                   !< release time (end of Case 0) [s]
    real(dp) :: tie_down(3) = 0.0_dp          !< rocket attach point of chain body 2, rocket axes [m]
    real(dp) :: quat_gain = 1.0_dp            !< quaternion norm drift gain [1/s]
    type(force_source_slot), allocatable :: sources(:)  !< applied-load models
    ! --- phase machine
    integer :: phase = phase_preparation      !< current Case 0..3
    real(dp) :: event_time(3) = -huge(1.0_dp) !< times of 0->1, 1->2, 2->3 (-huge: not yet)
    logical :: early_separation = .false.     !< 2->3 by the normal force reaching zero
    !> Case 2 contact held two-sided (the paper's equality constraint, Eq. (66)):
    !> the edge may pull, Case 2 ends only when the nose passes the edge, and the
    !> first time the normal force turns to pulling is recorded in edge_pull_time.
    logical :: edge_bilateral = .false.
    real(dp) :: edge_pull_time = -huge(1.0_dp) !< first zero crossing of N in Case 2 (bilateral)
    real(dp) :: quat_drift = 0.0_dp           !< largest |1 - |q|| of the state after the last `advance`
    !> Geometric altitude of the ground [m]; -huge: none (no event g5)
    real(dp) :: ground_altitude = -huge(1.0_dp)
    real(dp) :: ground_time = -huge(1.0_dp)   !< when a body reached the ground (-huge: not yet) [s]
    integer :: ground_body = -1               !< which: 0 aircraft, 1 rocket (-1: none)
    integer :: ground_point = -1              !< where: ground_at_cg, _nose or _tail (-1: none)
    real(dp) :: ground_speed = 0.0_dp         !< that point's speed there, earth frame [m/s]
    ! --- bodies (paper numbering 0..n) and their loads, updated by load_state/evaluate
    type(rigid_body), allocatable :: bodies(:)   !< (0:n) 0 aircraft, 1 rocket, 2.. chain
    real(dp), allocatable :: force(:, :)         !< (3, 0:n) applied CG forces, earth [N]
    real(dp), allocatable :: moment(:, :)        !< (3, 0:n) applied moments, body axes [N m]
    ! --- outputs of the last evaluate
    type(joint_state) :: js                   !< joint kinematics, residuals, wrench basis
    real(dp) :: lambda(6) = 0.0_dp            !< R_H amplitudes in the joint basis [N, N m]
    real(dp) :: rh_force(3) = 0.0_dp          !< R_H force on the rocket, earth [N]
    real(dp) :: rh_moment(3) = 0.0_dp         !< R_H moment on the rocket about its CG, rocket axes [N m]
    real(dp) :: normal_force = 0.0_dp         !< contact normal force (> 0 pushing) [N]
    real(dp) :: friction_force = 0.0_dp       !< friction along the exit direction on the rocket [N] (0 in Case 0)
    real(dp) :: lock_force = 0.0_dp           !< Case 0: the lock's force along the exit direction on the rocket [N]
    logical :: stick = .false.                !< the slide sticks
    real(dp) :: a0(3) = 0.0_dp                !< aircraft CG acceleration, earth [m/s^2]
    real(dp) :: wdot0(3) = 0.0_dp             !< aircraft angular acceleration, body [rad/s^2]
    real(dp), allocatable :: udot(:)          !< chain generalized accelerations (3+3n)
    ! --- work arrays
    type(cfa_workspace), private :: ws
    real(dp), private :: alpha(6, 6) = 0.0_dp, beta(6) = 0.0_dp, crow(6, ncol_max) = 0.0_dp
    real(dp), private :: fa(3, ncol_max) = 0.0_dp, ma(3, ncol_max) = 0.0_dp
    real(dp), private :: acc0(3, ncol_max) = 0.0_dp, wd0(3, ncol_max) = 0.0_dp
    real(dp), private :: gyro(ncol_max) = 0.0_dp
  contains
    procedure :: init => sep_init
    procedure :: add_source => sep_add_source
    procedure :: set_link => sep_set_link
    procedure :: set_line_body => sep_set_line_body
    procedure :: state_size => sep_state_size
    procedure :: pack_state => sep_pack_state
    procedure :: load_state => sep_load_state
    procedure :: evaluate_joint => sep_evaluate_joint
    procedure :: start => sep_start
    procedure :: evaluate => sep_evaluate
    procedure :: rhs => sep_rhs
    procedure :: nroots => sep_nroots
    procedure :: roots => sep_roots
    procedure :: handle_event => sep_handle_event
    procedure :: landed => sep_landed
    procedure :: rocket_lowest_point => sep_rocket_lowest_point
    procedure :: normalize_quaternions => sep_normalize_quaternions
    procedure :: has_projection => sep_has_projection
    procedure :: project => sep_project
    procedure :: advance => sep_advance
    procedure :: linear_momentum => sep_linear_momentum
    procedure :: angular_momentum => sep_angular_momentum
    procedure :: kinetic_energy => sep_kinetic_energy
    procedure :: potential_energy => sep_potential_energy
  end type separation_system

contains

  !> Configure the scene.  `aircraft` carries the aircraft's mass properties (and
  !> may carry its state), `rocket` the rocket's; `tie_down` is the rocket point
  !> (rocket axes) where body 2 of the chain is attached (ignored for nchain = 1).
  !> Mass properties are checked here; the geometry and t0 are checked by `start`,
  !> whose errors name the phase and the time.
  subroutine sep_init(self, aircraft, rocket, tie_down, nchain, geometry, options, t0, error, &
      aircraft_prescribed)
    class(separation_system), intent(inout) :: self       !< the scene
    type(rigid_body), intent(in) :: aircraft              !< aircraft B0
    type(rigid_body), intent(in) :: rocket                !< rocket B1 (mass properties)
    real(dp), intent(in) :: tie_down(3)                   !< rocket front tie-down point, rocket axes [m]
    integer, intent(in) :: nchain                         !< bodies in the chain (1..3)
    type(cut_joint_geometry), intent(in) :: geometry      !< joint geometry
    type(cut_joint_options), intent(in) :: options        !< friction and drift control
    real(dp), intent(in) :: t0                            !< release time [s], >= 0 (checked by start)
    type(error_type), allocatable, intent(inout) :: error !< set on invalid input
    logical, intent(in), optional :: aircraft_prescribed  !< aircraft at constant velocity/rate
    self%aircraft_prescribed = .false.
    if (present(aircraft_prescribed)) self%aircraft_prescribed = aircraft_prescribed
    self%t0 = t0
    self%tie_down = tie_down
    call check_mass_properties("aircraft", aircraft%mass, aircraft%inertia, .false., error)
    if (allocated(error)) return
    call self%joint%setup(geometry, options)
    call self%chain%init(nchain, ncol_max, error)
    if (allocated(error)) return
    call self%chain%set_link(1, "rocket", rocket%mass, rocket%inertia, [0.0_dp, 0.0_dp, 0.0_dp], &
      tie_down, error)
    if (allocated(error)) return
    if (allocated(self%bodies)) deallocate(self%bodies, self%force, self%moment, self%udot)
    allocate(self%bodies(0:nchain), self%force(3, 0:nchain), self%moment(3, 0:nchain))
    allocate(self%udot(self%chain%speed_size()))
    self%bodies(0) = aircraft
    self%bodies(0)%name = "aircraft"
    self%bodies(1) = rocket
    call self%chain%name_bodies(self%bodies(1:))
    if (.not. allocated(self%sources)) allocate(self%sources(0))
    call self%ws%init()
    self%phase = phase_preparation
    self%event_time = -huge(1.0_dp)
    self%early_separation = .false.
  end subroutine sep_init

  !> Add an applied-load model (copied into the scene).
  subroutine sep_add_source(self, source)
    class(separation_system), intent(inout) :: self   !< the scene
    class(force_source), intent(in) :: source         !< the model
    type(force_source_slot), allocatable :: tmp(:)
    integer :: n
    if (.not. allocated(self%sources)) allocate(self%sources(0))
    n = size(self%sources)
    allocate(tmp(n + 1))
    tmp(1:n) = self%sources
    allocate(tmp(n + 1)%source, source=source)
    call move_alloc(tmp, self%sources)
  end subroutine sep_add_source

  !> Set the mass properties and joint points of chain body k (see
  !> kane_chain%set_link) and the name of its body: once here, not in every
  !> right-hand side (a deferred-length assignment reallocates).
  subroutine sep_set_link(self, k, name, mass, inertia, proximal, distal, error)
    class(separation_system), intent(inout) :: self       !< the scene
    integer, intent(in) :: k                              !< body number in the chain (1 = rocket)
    character(len=*), intent(in) :: name                  !< name for messages
    real(dp), intent(in) :: mass                          !< [kg]
    real(dp), intent(in) :: inertia(3, 3)                 !< about the CG, body axes [kg m^2]
    real(dp), intent(in) :: proximal(3)                   !< joint with body k-1, body axes [m]
    real(dp), intent(in) :: distal(3)                     !< joint with body k+1, body axes [m]
    type(error_type), allocatable, intent(inout) :: error !< set on invalid input
    call self%chain%set_link(k, name, mass, inertia, proximal, distal, error)
    if (.not. allocated(error)) call self%chain%name_bodies(self%bodies(1:))
  end subroutine sep_set_link

  !> Update the virtual rigid body of the line (chain body k, normally 2) from the
  !> line state between steps (§2.4 Steps 3 and 6): m_rigid, J_rigid, d_rigid.
  subroutine sep_set_line_body(self, k, mass, inertia_xyz, length, error)
    class(separation_system), intent(inout) :: self       !< the scene
    integer, intent(in) :: k                              !< chain body of the line
    real(dp), intent(in) :: mass                          !< m_rigid [kg]
    real(dp), intent(in) :: inertia_xyz(3)                !< J_rigid [kg m^2]
    real(dp), intent(in) :: length                        !< d_rigid [m]
    type(error_type), allocatable, intent(inout) :: error !< set on invalid input
    call self%chain%set_line_link(k, mass, inertia_xyz, length, error)
    if (.not. allocated(error)) call self%chain%name_bodies(self%bodies(1:))
  end subroutine sep_set_line_body

  !> Size of the state vector: 13 + 6 + 7n.
  pure integer function sep_state_size(self) result(m)
    class(separation_system), intent(in) :: self   !< the scene
    m = body_state_size + self%chain%state_size()
  end function sep_state_size

  !> Write y from bodies(0:n) (positions/velocities of bodies 2.. are implied).
  subroutine sep_pack_state(self, y)
    class(separation_system), intent(in) :: self   !< the scene
    real(dp), intent(out) :: y(:)                  !< state (state_size)
    call self%bodies(0)%pack(y(1:body_state_size))
    call self%chain%store_bodies(self%bodies(1:), y(body_state_size+1:))
  end subroutine sep_pack_state

  !> Fill bodies(0:n) from y (kinematics only; mass properties from the configuration).
  subroutine sep_load_state(self, y)
    class(separation_system), intent(inout) :: self   !< the scene
    real(dp), intent(in) :: y(:)                      !< state
    call self%bodies(0)%unpack(y(1:body_state_size))
    call self%chain%load_bodies(y(body_state_size+1:), self%bodies(1:))
  end subroutine sep_load_state

  !> The joint's kinematics and residuals at state y alone (self%js as
  !> `evaluate` leaves them, without the loads and the accelerations).
  subroutine sep_evaluate_joint(self, y)
    class(separation_system), intent(inout) :: self   !< the scene
    real(dp), intent(in) :: y(:)                      !< state
    call self%load_state(y)
    call self%joint%evaluate(self%phase, self%bodies(0), self%bodies(1), self%js)
  end subroutine sep_evaluate_joint

  !> Begin at time t in `phase` from state y: check the state against the joint
  !> geometry, capture the constraint references, evaluate once (so a singular
  !> mass matrix or CFA shows here).  Phase 0 at t >= t0 is released at once;
  !> phase 2 with a normal force <= 0 separates at once (early_separation).
  subroutine sep_start(self, t, y, phase, error)
    class(separation_system), intent(inout) :: self       !< the scene
    real(dp), intent(in) :: t                             !< start time [s]
    real(dp), intent(in) :: y(:)                          !< consistent start state
    integer, intent(in) :: phase                          !< start phase 0..3
    type(error_type), allocatable, intent(inout) :: error !< set with phase and time
    if (phase < phase_preparation .or. phase > phase_free) then
      call fatal_error(error, "separation: start phase " // str(phase) // " is not 0..3")
      return
    end if
    if (size(y) /= self%state_size()) then
      call fatal_error(error, "separation: state has " // str(size(y)) // " entries, the scene needs " // &
        str(self%state_size()))
      return
    end if
    self%phase = phase
    self%event_time = -huge(1.0_dp)
    self%early_separation = .false.
    self%edge_pull_time = -huge(1.0_dp)
    call self%load_state(y)
    if (.not. (self%t0 >= 0.0_dp)) then
      call fatal_error(error, "inconsistent input: release time t0 = " // str(self%t0) // " s must be >= 0")
    else if (self%chain%n > 1 .and. .not. self%joint%inside_rocket(self%tie_down)) then
      call fatal_error(error, "inconsistent geometry: the tie-down point [" // str(self%tie_down(1)) // ", " &
        // str(self%tie_down(2)) // ", " // str(self%tie_down(3)) // "] m lies outside the rocket")
    else
      call self%joint%validate(error)
      if (.not. allocated(error)) call self%joint%capture(phase, self%bodies(0), self%bodies(1), error)
    end if
    if (allocated(error)) then
      error%message = phase_name(phase) // ", t = " // str(t) // " s: " // error%message
      return
    end if
    if (self%phase == phase_preparation .and. t >= self%t0) then
      self%phase = phase_extraction
      self%event_time(1) = t
    end if
    call self%evaluate(t, y, error)
    if (allocated(error)) return
    if (self%phase == phase_rotation .and. self%normal_force <= 0.0_dp .and. .not. self%edge_bilateral) then
      ! the edge cannot pull: the rocket is free from the start
      self%phase = phase_free
      self%event_time(3) = t
      self%early_separation = .true.
      call self%evaluate(t, y, error)
    else if (self%phase == phase_rotation .and. self%normal_force <= 0.0_dp .and. self%edge_pull_time < 0.0_dp) then
      ! a bilateral edge that pulls from the start (as at the Case 1 -> 2 event)
      self%edge_pull_time = t
    end if
  end subroutine sep_start

  !> Evaluate the dynamics at (t, y): loads, Kane + Newton-Euler with the CFA probes,
  !> constraint wrench, accelerations and outputs.  Errors name the phase and time.
  subroutine sep_evaluate(self, t, y, error)
    class(separation_system), intent(inout) :: self       !< the scene
    real(dp), intent(in) :: t                             !< time [s]
    real(dp), intent(in) :: y(:)                          !< state
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    integer :: k, nc, n, mode
    real(dp) :: mu, nrm
    call self%load_state(y)
    n = self%chain%n
    self%force = 0.0_dp
    self%moment = 0.0_dp
    do k = 1, size(self%sources)
      call self%sources(k)%source%add_loads(t, self%bodies, self%force, self%moment, error)
      if (allocated(error)) then
        call fail("force source " // str(k) // ": " // error%message)
        return
      end if
    end do
    if (.not. (all(ieee_is_finite(self%force)) .and. all(ieee_is_finite(self%moment)))) then
      call fail("applied loads are not finite numbers")
      return
    end if
    ! joint basis and bias of the phase
    nc = joint_components(self%phase)
    call self%joint%evaluate(self%phase, self%bodies(0), self%bodies(1), self%js)
    ! Kane (65) with the real loads and the unit wrenches on the rocket (CFA Steps 1-2)
    call self%chain%accelerations(self%bodies(1:n), self%force(:, 1:n), self%moment(:, 1:n), &
      self%js%rocket_force, self%js%rocket_moment, nc, error)
    if (allocated(error)) then
      call fail(error%message)
      return
    end if
    ! aircraft (47)-(48) with the same columns (the reactions)
    if (self%aircraft_prescribed) then
      self%acc0 = 0.0_dp
      self%wd0 = 0.0_dp
    else
      self%fa(:, 1) = self%force(:, 0)
      self%ma(:, 1) = self%moment(:, 0)
      self%fa(:, 2:1+nc) = self%js%aircraft_force(:, 1:nc)
      self%ma(:, 2:1+nc) = self%js%aircraft_moment(:, 1:nc)
      self%gyro = 0.0_dp
      self%gyro(1) = 1.0_dp
      call newton_euler(self%bodies(0), self%fa(:, 1:1+nc), self%ma(:, 1:1+nc), self%gyro(1:1+nc), &
        self%acc0(:, 1:1+nc), self%wd0(:, 1:1+nc), error)
      if (allocated(error)) then
        call fail(error%message)
        return
      end if
    end if
    ! constraint rows of every column: beta (R_H = 0) and alpha (unit components)
    self%lambda = 0.0_dp
    self%stick = .false.
    if (nc > 0) then
      do k = 1, 1 + nc
        call self%joint%rows(self%js, self%acc0(:, k), self%wd0(:, k), self%chain%rhs(1:3, k), &
          self%chain%rhs(4:6, k), self%crow(1:nc, k))
      end do
      self%beta(1:nc) = self%crow(1:nc, 1) + self%js%bias(1:nc)
      self%alpha(1:nc, 1:nc) = self%crow(1:nc, 2:1+nc)
      mu = 0.0_dp
      select case (self%phase)
      case (phase_preparation)
        mode = slide_locked
      case (phase_extraction)
        mu = self%joint%opt%mu_rail
        mode = merge(slide_coulomb, slide_free, mu > 0.0_dp)
      case default
        mu = self%joint%opt%mu_edge
        mode = merge(slide_coulomb, slide_free, mu > 0.0_dp)
        if (self%joint%opt%edge_no_slip) mode = slide_locked
      end select
      call cfa_solve(self%ws, self%alpha, self%beta, nc, mode, mu, self%js%slide_rate, &
        self%joint%opt%stick_velocity, self%lambda, self%stick, error)
      if (allocated(error)) then
        call fail(error%message)
        return
      end if
    end if
    ! CFA Step 3 result: accelerations are affine in R_H
    self%udot = self%chain%rhs(:, 1)
    self%a0 = self%acc0(:, 1)
    self%wdot0 = self%wd0(:, 1)
    self%rh_force = 0.0_dp
    self%rh_moment = 0.0_dp
    do k = 1, nc
      self%udot = self%udot + self%lambda(k)*self%chain%rhs(:, 1+k)
      self%a0 = self%a0 + self%lambda(k)*self%acc0(:, 1+k)
      self%wdot0 = self%wdot0 + self%lambda(k)*self%wd0(:, 1+k)
      self%rh_force = self%rh_force + self%lambda(k)*self%js%rocket_force(:, k)
      self%rh_moment = self%rh_moment + self%lambda(k)*self%js%rocket_moment(:, k)
    end do
    self%normal_force = 0.0_dp
    self%friction_force = 0.0_dp
    self%lock_force = 0.0_dp
    if (nc > 0) then
      self%normal_force = self%lambda(2)
      ! Case 0: the first multiplier is the lock's reaction along the rail (the
      ! rail's static friction is inside it, not separable), not sliding friction
      if (self%phase == phase_preparation) then
        self%lock_force = self%lambda(1)
      else
        self%friction_force = self%lambda(1)
      end if
    end if
    nrm = norm2(self%udot)
    if (.not. ieee_is_finite(nrm)) call fail("accelerations are not finite numbers")
  contains
    !> Raise `msg` prefixed with the phase and time.
    subroutine fail(msg)
      character(len=*), intent(in) :: msg
      character(len=:), allocatable :: text
      text = phase_name(self%phase) // ", t = " // str(t) // " s: " // msg
      call fatal_error(error, text)
    end subroutine fail
  end subroutine sep_evaluate

  !> CVODE right-hand side.
  subroutine sep_rhs(self, t, y, ydot, status)
    class(separation_system), intent(inout) :: self   !< the scene
    real(dp), intent(in) :: t                         !< time [s]
    real(dp), intent(in) :: y(:)                      !< state
    real(dp), intent(out) :: ydot(:)                  !< derivative
    integer, intent(out) :: status                    !< rhs_ok or rhs_fatal
    type(error_type), allocatable :: error
    integer :: m
    call self%evaluate(t, y, error)
    if (allocated(error)) then
      self%failure = error%message
      ydot = 0.0_dp
      status = rhs_fatal
      return
    end if
    m = body_state_size
    if (self%aircraft_prescribed) then
      ydot(1:3) = self%bodies(0)%v
      ydot(4:6) = 0.0_dp
      ydot(7:10) = quaternion_drift_rate(y(7:10), self%bodies(0)%w, self%quat_gain)
      ydot(11:13) = 0.0_dp
    else
      call body_state_derivative(self%bodies(0), y(1:m), self%a0, self%wdot0, self%quat_gain, ydot(1:m))
    end if
    call self%chain%state_derivative(y(m+1:), self%bodies(1:), self%udot, self%quat_gain, ydot(m+1:))
    status = rhs_ok
  end subroutine sep_rhs

  !> Number of event functions (fixed; inactive ones are constant).
  integer function sep_nroots(self)
    class(separation_system), intent(in) :: self   !< the scene
    sep_nroots = separation_nroots
    if (.false.) sep_nroots = self%phase
  end function sep_nroots

  !> Event functions of the phase machine (see the module header).
  subroutine sep_roots(self, t, y, g, status)
    class(separation_system), intent(inout) :: self   !< the scene
    real(dp), intent(in) :: t                         !< time [s]
    real(dp), intent(in) :: y(:)                      !< state
    real(dp), intent(out) :: g(:)                     !< event functions
    integer, intent(out) :: status                    !< rhs_ok or rhs_fatal
    type(error_type), allocatable :: error
    g = 1.0_dp
    status = rhs_ok
    if (self%ground_altitude > -huge(1.0_dp)) g(5) = min(y(2), rocket_lowest(y)) - self%ground_altitude
    select case (self%phase)
    case (phase_preparation)
      g(1) = t - self%t0
    case (phase_extraction)
      call self%load_state(y)
      g(2) = self%joint%cg_past_edge(self%bodies(0), self%bodies(1))
    case (phase_rotation)
      call self%evaluate(t, y, error)
      if (allocated(error)) then
        self%failure = error%message
        status = rhs_fatal
        return
      end if
      g(3) = self%joint%nose_past_edge(self%bodies(0), self%bodies(1))
      g(4) = self%normal_force
    end select
  contains
    !> Height of the rocket's lowest point in y (chain state from
    !> body_state_size + 1: CG position, velocity, quaternion).
    real(dp) function rocket_lowest(y) result(h)
      real(dp), intent(in) :: y(:)
      real(dp) :: c(3, 3)
      integer :: o
      o = body_state_size
      c = quat_to_dcm(y(o + 7:o + 10))
      call self%rocket_lowest_point(y(o + 2), c(2, :), h)
    end function rocket_lowest
  end subroutine sep_roots

  !> Apply the phase transitions of the events in `which` (CVODE root info, +1 a
  !> rising and -1 a falling crossing) at (t, y); `changed` if the phase changed.
  subroutine sep_handle_event(self, t, y, which, changed, error)
    class(separation_system), intent(inout) :: self       !< the scene
    real(dp), intent(in) :: t                             !< event time [s]
    real(dp), intent(in) :: y(:)                          !< state at the event
    integer, intent(in) :: which(:)                       !< root info (separation_nroots)
    logical, intent(out) :: changed                       !< the phase changed
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    changed = .false.
    if (which(5) < 0 .and. self%ground_time < -1.0e300_dp) call land()
    select case (self%phase)
    case (phase_preparation)
      if (which(1) /= 0) then
        self%phase = phase_extraction
        self%event_time(1) = t
        changed = .true.
      end if
    case (phase_extraction)
      if (which(2) > 0) then
        self%phase = phase_rotation
        self%event_time(2) = t
        changed = .true.
        call self%evaluate(t, y, error)
        if (allocated(error)) return
        if (self%normal_force <= 0.0_dp .and. self%edge_bilateral) then
          self%edge_pull_time = t
        else if (self%normal_force <= 0.0_dp) then
          ! the edge cannot push: the rocket leaves the aircraft at once
          self%phase = phase_free
          self%event_time(3) = t
          self%early_separation = .true.
        end if
      end if
    case (phase_rotation)
      if (which(4) < 0 .and. self%edge_bilateral) then
        if (self%edge_pull_time < -1.0e300_dp) self%edge_pull_time = t
        if (which(3) > 0) then
          self%phase = phase_free
          self%event_time(3) = t
          changed = .true.
        end if
      else if (which(4) < 0) then
        self%phase = phase_free
        self%event_time(3) = t
        self%early_separation = .true.
        changed = .true.
      else if (which(3) > 0) then
        self%phase = phase_free
        self%event_time(3) = t
        changed = .true.
      end if
    end select
  contains
    !> The lower of the aircraft's CG and the rocket's lowest point reached the
    !> ground: which body, which point, and that point's speed.
    subroutine land()
      real(dp) :: h, p(3)
      integer :: which_end
      call self%load_state(y)
      call self%rocket_lowest_point(self%bodies(1)%r(2), self%bodies(1)%c(2, :), h, which_end, p)
      self%ground_time = t
      if (h < y(2)) then
        self%ground_body = 1
        self%ground_point = which_end
        self%ground_speed = norm2(self%bodies(1)%point_velocity(p))
      else
        self%ground_body = 0
        self%ground_point = ground_at_cg
        self%ground_speed = norm2(self%bodies(0)%v)
      end if
    end subroutine land
  end subroutine sep_handle_event

  !> The rocket's lowest point: on its envelope, the cut joint's cylinder (radius
  !> rocket_radius, on the rocket's x axis from the tail at nose_x - rocket_length
  !> to the nose at nose_x), the lowest point of the lower end's rim.  From the
  !> CG's height and the earth's vertical in rocket axes (the second row of the
  !> body-to-earth matrix): that point's height, which end (ground_at_nose or
  !> ground_at_tail; the nose when the axis is level) and the point, rocket axes
  !> (those two optional: the event function needs the height alone).
  pure subroutine sep_rocket_lowest_point(self, cg_height, up, height, which_end, point)
    class(separation_system), intent(in) :: self   !< the scene
    real(dp), intent(in) :: cg_height              !< the rocket's CG, earth y [m]
    real(dp), intent(in) :: up(:)                  !< the earth's unit vertical (3), rocket axes (assumed shape: a row of a DCM passes without a copy)
    real(dp), intent(out) :: height                !< the lowest point's earth y [m]
    integer, intent(out), optional :: which_end    !< ground_at_nose or ground_at_tail
    real(dp), intent(out), optional :: point(3)    !< the lowest point, rocket axes [m]
    real(dp) :: x_end(2), s, p(3)
    integer :: e
    associate(geo => self%joint%geo)
      x_end(ground_at_nose) = geo%nose_x
      x_end(ground_at_tail) = geo%nose_x - geo%rocket_length
      e = merge(ground_at_nose, ground_at_tail, up(1)*x_end(ground_at_nose) <= up(1)*x_end(ground_at_tail))
      p = [x_end(e), 0.0_dp, 0.0_dp]
      ! the end face's rim point furthest down: the radius along the face's
      ! steepest downward direction (none when the axis is vertical)
      s = hypot(up(2), up(3))
      if (s > 0.0_dp) p(2:3) = -geo%rocket_radius*up(2:3)/s
    end associate
    height = cg_height + dot_product(up, p)
    if (present(which_end)) which_end = e
    if (present(point)) point = p
  end subroutine sep_rocket_lowest_point

  !> A body has reached the ground (event g5): the scene is over.
  pure logical function sep_landed(self)
    class(separation_system), intent(in) :: self   !< the scene
    sep_landed = self%ground_time > -1.0e300_dp
  end function sep_landed

  !> Integrate to tout, stopping at every event to switch the phase and restart
  !> CVODE.  On return the solver holds the state at tout (quat_drift its largest
  !> quaternion norm error), or at the ground event if a body reached the ground
  !> (`landed`).
  subroutine sep_advance(self, solver, tout, error)
    class(separation_system), intent(inout) :: self       !< the scene (the solver's system)
    type(cvode_solver), intent(inout) :: solver           !< CVODE bound to this scene
    real(dp), intent(in) :: tout                          !< output time [s]
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    logical :: event, changed
    integer :: which(separation_nroots), guard
    do guard = 1, 1000
      call solver%advance(tout, error, event, which)
      if (allocated(error)) then
        error%message = phase_name(self%phase) // ": " // error%message
        return
      end if
      changed = .false.
      if (event) then
        call self%handle_event(solver%t, solver%y, which, changed, error)
        if (allocated(error)) return
      end if
      self%quat_drift = drift(solver%y)
      if (self%landed()) return
      if (changed) then
        call solver%reinit(solver%t, solver%y, error)
        if (allocated(error)) return
      end if
      if (.not. event .or. solver%t >= tout) return
    end do
    call fatal_error(error, phase_name(self%phase) // ", t = " // str(solver%t) // &
      " s: too many events before the output time")
  contains
    !> Largest quaternion norm error of the state.
    real(dp) function drift(y)
      real(dp), intent(in) :: y(:)
      integer :: k, o
      drift = abs(1.0_dp - norm2(y(7:10)))
      do k = 1, self%chain%n
        o = body_state_size + 6 + 7*(k - 1)
        drift = max(drift, abs(1.0_dp - norm2(y(o+1:o+4))))
      end do
    end function drift
  end subroutine sep_advance

  !> Project the quaternions of a state onto unit norm (for a CVODE projection
  !> callback, CVodeSetProjFn, or before a re-initialisation).
  pure subroutine sep_normalize_quaternions(self, y)
    class(separation_system), intent(in) :: self   !< the scene
    real(dp), intent(inout) :: y(:)                !< state
    integer :: k, o
    y(7:10) = y(7:10)/norm2(y(7:10))
    do k = 1, self%chain%n
      o = body_state_size + 6 + 7*(k - 1)
      y(o+1:o+4) = y(o+1:o+4)/norm2(y(o+1:o+4))
    end do
  end subroutine sep_normalize_quaternions

  !> The scene projects its quaternions onto unit norm after every CVODE step
  !> (CVodeSetProjFn), so the norm error stays at round-off whatever the tolerance.
  logical function sep_has_projection(self)
    class(separation_system), intent(in) :: self   !< the scene
    sep_has_projection = .true.
    if (.false.) sep_has_projection = self%phase > 0
  end function sep_has_projection

  !> Projection callback: unit quaternions.
  subroutine sep_project(self, t, y, status)
    class(separation_system), intent(inout) :: self  !< the scene
    real(dp), intent(in) :: t                        !< time [s]
    real(dp), intent(inout) :: y(:)                  !< state, projected in place
    integer, intent(out) :: status                   !< rhs_ok
    call self%normalize_quaternions(y)
    status = rhs_ok
    if (.false.) y(1) = t
  end subroutine sep_project

  !> Total linear momentum of the loaded bodies, earth [kg m/s].
  function sep_linear_momentum(self) result(p)
    class(separation_system), intent(in) :: self   !< the scene (bodies loaded)
    real(dp) :: p(3)
    integer :: k
    p = 0.0_dp
    do k = 0, ubound(self%bodies, 1)
      p = p + self%bodies(k)%linear_momentum()
    end do
  end function sep_linear_momentum

  !> Total angular momentum about the earth origin [kg m^2/s].
  function sep_angular_momentum(self) result(h)
    class(separation_system), intent(in) :: self   !< the scene (bodies loaded)
    real(dp) :: h(3)
    integer :: k
    h = 0.0_dp
    do k = 0, ubound(self%bodies, 1)
      h = h + self%bodies(k)%angular_momentum()
    end do
  end function sep_angular_momentum

  !> Total kinetic energy [J].
  real(dp) function sep_kinetic_energy(self) result(e)
    class(separation_system), intent(in) :: self   !< the scene (bodies loaded)
    integer :: k
    e = 0.0_dp
    do k = 0, ubound(self%bodies, 1)
      e = e + self%bodies(k)%kinetic_energy()
    end do
  end function sep_kinetic_energy

  !> Potential energy in uniform gravity g (earth) [J]: -sum m g.r.
  real(dp) function sep_potential_energy(self, g) result(e)
    class(separation_system), intent(in) :: self   !< the scene (bodies loaded)
    real(dp), intent(in) :: g(3)                   !< gravitational acceleration [m/s^2]
    integer :: k
    e = 0.0_dp
    do k = 0, ubound(self%bodies, 1)
      e = e - self%bodies(k)%mass*dot_product(g, self%bodies(k)%r)
    end do
  end function sep_potential_energy
end module airlaunch_separation
