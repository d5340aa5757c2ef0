!> The flexible line as the sub-stepped subsystem of the rigidized coupling
!> (coupling (a) of DESIGN §4, airlaunch_rigidized_coupling; Zheng & Zhang
!> 2018, §2.4 Step 5): the lumped-mass line of airlaunch_line_model with node 0
!> on the rocket's tie-down path and node N the parachute (the far-end force
!> condition of §2.3, Eq. (16)) or on the chain's B3, as an ODE system for
!> CVODE (`rigidized_line`), and the paper's explicit marching of it
!> (`line_marcher`, §2.3 Steps 1-5) for `&line inner_scheme = 'marching'`.
module airlaunch_rigidized_line
  use airlaunch_kinds, only: dp, i8
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_ode, only: ode_system, node_blocks, rhs_ok, rhs_fatal
  use airlaunch_cvode, only: cvode_stats, step_observer, step_polynomial
  use airlaunch_linalg, only: solve_general
  use airlaunch_line, only: line_model, line_end, line_force_jacobian, node_state_name, marching_diverged, &
    far_end_not_converged
  use airlaunch_parachute, only: parachute, canopy_node_acceleration, canopy_node_jacobian
  use airlaunch_clearance, only: segment_distance
  implicit none
  private
  public :: rigidized_line, line_marcher

  !> The flexible line (sub-stepped subsystem) as an ODE for CVODE: nodes
  !> first..last (6 states each, relative frame), node 0 on the tie-down
  !> point's path, node N the parachute (far_end 'parachute') or on B3's path.
  type, extends(ode_system) :: rigidized_line
    type(line_model) :: model               !< the line
    type(parachute) :: chute                !< canopy at node N
    logical :: far_kinematic = .false.      !< node N follows B3
    real(dp) :: v_ref = 0.0_dp              !< V0 of the reference frame [m/s]
    real(dp) :: h_ref = 0.0_dp              !< h0 of the reference frame [m]
    type(line_end) :: near                  !< node 0: the chain's tie-down samples (relative)
    type(line_end) :: far                   !< node N: B3's samples (relative), far_kinematic only
    !> the aircraft's empennage point (the clearance's): the chain's samples
    !> (relative), so that the line's clearance from it is taken on the sub-steps
    type(line_end) :: tail
    integer :: last = 0                     !< last state node (N or N-1)
    real(dp), allocatable :: x(:, :), v(:, :), f(:, :), tension(:)   !< absolute work arrays (0:N)
    real(dp), allocatable :: inv_mass(:)    !< work: 1/(whole node mass) at the last Jacobian (0:N)
    type(line_force_jacobian) :: jac_blocks !< work: the force Jacobian of the last evaluation
    real(dp) :: chute_drag(3) = 0.0_dp      !< canopy drag of the last evaluation [N]
  contains
    procedure :: rhs => line_rhs
    procedure :: has_node_jacobian => line_has_node_jacobian
    procedure :: node_jacobian => line_node_jacobian
    procedure :: unpack => line_unpack
    procedure :: tail_clearance => line_tail_clearance
    procedure :: pack => line_pack
    procedure :: n_state => line_n_state
    procedure :: setup => line_setup
    procedure :: state_name => line_state_name
  end type rigidized_line

  !> The paper's explicit marching (§2.3, Eqs. (12)-(17), Steps 1-5) as the
  !> rigidized line's sub-stepper, in place of CVODE (`inner_scheme =
  !> 'marching'`).  The state is the rigidized_line's (nodes 1..last, relative
  !> frame).  One sub-step of size h from t to t + h, forces at the old level:
  !>  Step 2, Eq. (15): v_k += h f_k/m_k for the interior nodes;
  !>  Step 3, Eq. (12) with Eq. (10): the segment vectors advanced by their
  !>          nodes' new relative velocity, starting from node 0's displacement
  !>          on its path; the recursion telescopes to x_k += h v_k (the path's
  !>          discrete velocity cancels), which is what is done;
  !>  Steps 4-5, Eq. (16): node N (the parachute, far_end 'parachute') with the
  !>          far-end force condition F_N = canopy drag + weight - (line share
  !>          + canopy + apparent mass) a, a = (v_N' - v_N)/h, solved by Newton
  !>          on v_N' (analytic 3x3 Jacobian, LAPACK) until |e| <= e0; with
  !>          far_end 'chain' node N is on B3's path.
  !> As airlaunch_line_marching (the standalone scheme): semi-implicit
  !> (symplectic) Euler, first order, stable for h <= line_model%stable_step.
  !> Each outer step is cut into equal sub-steps (set_stop_time); a state
  !> inside a sub-step (an output time) is the linear interpolant between its
  !> ends, which is also what a step observer is shown, so the sub-steps do not
  !> depend on the output times.  No allocation after init.
  type :: line_marcher
    real(dp) :: t = 0.0_dp                  !< time of y [s]
    real(dp), allocatable :: y(:)           !< state at t (interpolated inside a sub-step)
    real(dp) :: tn = 0.0_dp, tp = 0.0_dp    !< end of the last sub-step and its start [s]
    real(dp), allocatable :: yn(:), yp(:)   !< the states there
    real(dp), allocatable :: yw(:)          !< the new level while a sub-step is made
    real(dp) :: dt = 0.0_dp                 !< largest sub-step [s]
    real(dp) :: h = 0.0_dp                  !< sub-step of the current outer step [s]
    real(dp) :: t_stop = 0.0_dp             !< end of the current outer step [s]
    real(dp) :: force_tol = 0.0_dp          !< e0 [N]
    integer :: max_iter = 20                !< far-end iterations per sub-step
    integer :: max_steps = 0                !< sub-steps allowed over the run (0: no limit)
    integer(i8) :: steps = 0, forces = 0, iterations = 0
    logical :: restart = .true.             !< the next stretch shown is the first
    type(step_polynomial) :: poly           !< the last sub-step as a degree-1 interpolant
  contains
    procedure :: init => marcher_init
    procedure :: set_stop_time => marcher_set_stop_time
    procedure :: advance => marcher_advance
    procedure :: stats => marcher_stats
    procedure :: free => marcher_free
  end type line_marcher

contains

  !> Build the line subsystem of `model` with the canopy `chute` at node N (or
  !> node N on B3's path: far_kinematic) in the frame translating at v_ref along
  !> x at altitude h_ref; the end motions are set later (set_body_motion).
  subroutine line_setup(self, model, chute, far_kinematic, v_ref, h_ref)
    class(rigidized_line), intent(inout) :: self   !< the line (re-initialised)
    type(line_model), intent(in) :: model          !< the line
    type(parachute), intent(in) :: chute           !< the canopy (fill_time set)
    logical, intent(in) :: far_kinematic           !< node N follows B3
    real(dp), intent(in) :: v_ref, h_ref           !< reference frame [m/s, m]
    integer :: n
    n = model%n
    self%model = model
    self%chute = chute
    self%far_kinematic = far_kinematic
    self%v_ref = v_ref
    self%h_ref = h_ref
    self%last = merge(n - 1, n, far_kinematic)
    if (allocated(self%x)) deallocate(self%x, self%v, self%f, self%tension, self%inv_mass)
    allocate(self%x(3, 0:n), self%v(3, 0:n), self%f(3, 0:n), self%tension(n), self%inv_mass(0:n))
    self%x = 0.0_dp
    self%v = 0.0_dp
    self%tension = 0.0_dp
    self%inv_mass = 1.0_dp/model%node_mass
    call self%jac_blocks%allocate(n)
  end subroutine line_setup

  !> Number of line states.
  pure integer function line_n_state(self) result(m)
    class(rigidized_line), intent(in) :: self
    m = 6*self%last
  end function line_n_state

  !> The smallest distance from the empennage point (its samples, `tail`) at
  !> time t to the line's segments, as last unpacked at t [m] (the direct
  !> coupling's launch_line_clearance: the same segments, the same point).
  real(dp) function line_tail_clearance(self, t) result(d)
    class(rigidized_line), intent(in) :: self
    real(dp), intent(in) :: t
    real(dp) :: p(3), pv(3)
    integer :: j
    call self%tail%motion(t, p, pv)
    p = p + [self%v_ref*t, self%h_ref, 0.0_dp]
    d = huge(1.0_dp)
    do j = 1, self%model%n
      d = min(d, segment_distance(p, self%x(:, j - 1), self%x(:, j)))
    end do
  end function line_tail_clearance

  !> Absolute node positions and velocities at time t from the state y
  !> (node 0 and, for far_kinematic, node N from their samples).
  subroutine line_unpack(self, t, y)
    class(rigidized_line), intent(inout) :: self
    real(dp), intent(in) :: t, y(:)
    real(dp) :: frame_x(3), frame_v(3)
    integer :: k, i, n
    n = self%model%n
    frame_x = [self%v_ref*t, self%h_ref, 0.0_dp]
    frame_v = [self%v_ref, 0.0_dp, 0.0_dp]
    call self%near%motion(t, self%x(:, 0), self%v(:, 0))
    self%x(:, 0) = self%x(:, 0) + frame_x
    self%v(:, 0) = self%v(:, 0) + frame_v
    do k = 1, self%last
      i = 6*(k - 1)
      self%x(:, k) = y(i+1:i+3) + frame_x
      self%v(:, k) = y(i+4:i+6) + frame_v
    end do
    if (self%far_kinematic) then
      call self%far%motion(t, self%x(:, n), self%v(:, n))
      self%x(:, n) = self%x(:, n) + frame_x
      self%v(:, n) = self%v(:, n) + frame_v
    end if
  end subroutine line_unpack

  !> State i of the sub-stepped line: node 1 + (i - 1)/6, [x, v] relative.
  function line_state_name(self, i) result(name)
    class(rigidized_line), intent(in) :: self  !< the line
    integer, intent(in) :: i                   !< state index
    character(len=:), allocatable :: name
    name = node_state_name(1 + (i - 1)/6, 1 + modulo(i - 1, 6))
    if (1 + (i - 1)/6 == self%model%n) name = name // " (parachute)"
  end function line_state_name

  !> State y from absolute node positions and velocities at time t.
  pure subroutine line_pack(self, t, x, v, y)
    class(rigidized_line), intent(in) :: self
    real(dp), intent(in) :: t, x(:, 0:), v(:, 0:)
    real(dp), intent(out) :: y(:)
    integer :: k, i
    do k = 1, self%last
      i = 6*(k - 1)
      y(i+1:i+3) = x(:, k) - [self%v_ref*t, self%h_ref, 0.0_dp]
      y(i+4:i+6) = v(:, k) - [self%v_ref, 0.0_dp, 0.0_dp]
    end do
  end subroutine line_pack

  !> Line right-hand side: Eq. (8) lumped (airlaunch_line_model) for nodes
  !> 1..N-1; node N the parachute, exactly as the direct coupling's node N
  !> (canopy + apparent mass + half a segment, canopy drag and weight).
  subroutine line_rhs(self, t, y, ydot, status)
    class(rigidized_line), intent(inout) :: self
    real(dp), intent(in) :: t
    real(dp), intent(in) :: y(:)
    real(dp), intent(out) :: ydot(:)
    integer, intent(out) :: status
    integer :: k, i, n, st
    logical :: ok
    n = self%model%n
    call self%unpack(t, y)
    call self%model%forces(self%x, self%v, self%f, self%tension, st)
    if (st /= 0) then
      self%failure = "line tension is not finite at t = " // str(t) // " s"
      status = rhs_fatal
      return
    end if
    do k = 1, min(self%last, n - 1)
      i = 6*(k - 1)
      ydot(i+1:i+3) = y(i+4:i+6)
      ydot(i+4:i+6) = self%f(:, k)/self%model%node_mass(k)
    end do
    if (.not. self%far_kinematic) then
      i = 6*(n - 1)
      ydot(i+1:i+3) = y(i+4:i+6)
      call canopy_node_acceleration(self%chute, t, self%x(:, n), self%v(:, n), self%model%node_mass(n), &
        self%f(:, n), self%model%p%air, self%model%p%gravity, ydot(i+4:i+6), self%chute_drag, ok)
      if (.not. ok) then
        self%failure = "parachute altitude " // str(self%x(2, n)) // " m is outside the atmosphere model"
        status = rhs_fatal
        return
      end if
    end if
    status = rhs_ok
  end subroutine line_rhs

  !> The line has its Jacobian as node blocks (line_node_jacobian).
  logical function line_has_node_jacobian(self)
    class(rigidized_line), intent(in) :: self
    line_has_node_jacobian = allocated(self%jac_blocks%dfdx)
  end function line_has_node_jacobian

  !> The Jacobian of line_rhs as node blocks for the velocity-reduced solver
  !> (nodes 1..last): the line's force blocks over the node masses; at the
  !> parachute node (far_end 'parachute') over its whole mass (line share +
  !> canopy + apparent mass), with the canopy drag's velocity derivative
  !> (canopy_node_jacobian).  Kept, as the default line scheme's, while CVODE
  !> allows and no segment switched between slack and taut (the tensions of the
  !> right-hand side CVODE has just evaluated at y).  No allocation.
  subroutine line_node_jacobian(self, t, y, reuse_ok, blk, fresh, status)
    class(rigidized_line), intent(inout) :: self   !< the line
    real(dp), intent(in) :: t                      !< time [s]
    real(dp), intent(in) :: y(:)                   !< state
    logical, intent(in) :: reuse_ok                !< CVODE allows the last blocks
    type(node_blocks), intent(inout) :: blk        !< the blocks (nodes 1..last)
    logical, intent(out) :: fresh                  !< evaluated now
    integer, intent(out) :: status                 !< rhs_ok or rhs_fatal
    real(dp) :: mass, drag_dv(3, 3)
    integer :: n
    logical :: ok
    status = rhs_ok
    fresh = .not. self%jac_blocks%still_valid(reuse_ok, self%tension)
    if (.not. fresh) return
    n = self%model%n
    call self%unpack(t, y)
    call self%jac_blocks%form(self%model, self%x, self%v, self%tension)
    if (.not. self%far_kinematic) then
      call canopy_node_jacobian(self%chute, t, self%x(:, n), self%v(:, n), self%model%node_mass(n), &
        self%model%p%air, mass, drag_dv, ok)
      if (.not. ok) then
        self%failure = "parachute altitude " // str(self%x(2, n)) // " m is outside the atmosphere model"
        status = rhs_fatal
        return
      end if
      self%inv_mass(n) = 1.0_dp/mass
      self%jac_blocks%dfdv(:, :, 0, n) = self%jac_blocks%dfdv(:, :, 0, n) + drag_dv
    end if
    call self%jac_blocks%to_node_blocks(self%inv_mass, 1, self%last, blk)
  end subroutine line_node_jacobian

  ! ------------------------------------------------------------------ marching

  !> Start the marcher on `line` at t0 from the state y0.  A sub-step above the
  !> stability limit is an error naming the limit.
  subroutine marcher_init(self, line, t0, y0, dt, force_tol, max_iterations, max_steps, error)
    class(line_marcher), intent(inout) :: self             !< the marcher (re-initialised)
    type(rigidized_line), intent(in) :: line               !< the line subsystem
    real(dp), intent(in) :: t0                             !< start time [s]
    real(dp), intent(in) :: y0(:)                          !< its state
    real(dp), intent(in) :: dt                             !< largest sub-step [s]; 0: 0.9 of the limit
    real(dp), intent(in) :: force_tol                      !< e0 of the far-end iteration [N]
    integer, intent(in) :: max_iterations                  !< far-end iterations per sub-step
    integer, intent(in) :: max_steps                       !< sub-steps over the run (0: no limit)
    type(error_type), allocatable, intent(inout) :: error  !< set on bad settings
    real(dp) :: limit
    call self%free()
    limit = line%model%stable_step()
    self%dt = dt
    if (self%dt == 0.0_dp) self%dt = 0.9_dp*limit
    if (.not. (self%dt > 0.0_dp .and. self%dt <= limit)) then
      call fatal_error(error, "rigidized coupling: inner_dt = " // str(dt) // " s is not allowed " // &
        "for the marching line: above its stability limit " // str(limit) // " s (2/w (sqrt(1+zeta^2) - " // &
        "zeta), w = 2c/l0, c = " // str(line%model%wave_speed()) // " m/s, l0 = " // str(line%model%l0) // &
        " m); use inner_dt <= that, or 0 for 0.9 of it")
      return
    end if
    if (line%model%mass_coupling > 0.0_dp) then
      call fatal_error(error, "rigidized coupling: the marching line needs the lumped (diagonal) mass")
      return
    end if
    self%force_tol = force_tol
    self%max_iter = max_iterations
    self%max_steps = max_steps
    self%t = t0; self%tn = t0; self%tp = t0; self%t_stop = t0; self%h = 0.0_dp
    allocate(self%y, source=y0)
    allocate(self%yn, source=y0)
    allocate(self%yp, source=y0)
    allocate(self%yw, source=y0)
    allocate(self%poly%c(size(y0), 0:1))
    self%poly%order = 1
    self%restart = .true.
  end subroutine marcher_init

  !> The current outer step ends at t1: equal sub-steps no larger than dt
  !> from the last sub-step's end to t1.
  subroutine marcher_set_stop_time(self, t1)
    class(line_marcher), intent(inout) :: self   !< the marcher
    real(dp), intent(in) :: t1                   !< end of the outer step [s]
    real(dp) :: x, n_sub
    self%t_stop = t1
    ! the count in real arithmetic: a tiny inner_dt must not overflow an integer
    ! (the step budget then stops the march)
    x = (t1 - self%tn)/self%dt - 1.0e-9_dp
    n_sub = aint(x)
    if (n_sub < x) n_sub = n_sub + 1.0_dp
    self%h = (t1 - self%tn)/max(1.0_dp, n_sub)
  end subroutine marcher_set_stop_time

  !> March to t (<= the stop time): sub-steps while their end is before t,
  !> then y = the state at t (the sub-step's linear interpolant inside it).
  !> Each sub-step is shown to `observer`.
  subroutine marcher_advance(self, line, t, error, observer)
    class(line_marcher), intent(inout) :: self             !< the marcher
    type(rigidized_line), intent(inout) :: line            !< the line subsystem (work arrays)
    real(dp), intent(in) :: t                              !< target time [s]
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    class(step_observer), intent(inout), optional :: observer  !< shown the sub-steps
    real(dp) :: eps, s
    logical :: last
    eps = 1.0e-12_dp*max(1.0_dp, abs(t))
    do while (self%tn < t - eps)
      if (.not. (self%h > 0.0_dp) .or. self%tn >= self%t_stop - eps) then
        call fatal_error(error, "line (marching): asked for t = " // str(t) // " s beyond the outer step's end " // &
          str(self%t_stop) // " s")
        return
      end if
      if (self%max_steps > 0 .and. self%steps >= self%max_steps) then
        call fatal_error(error, "line (marching): the step budget of " // str(self%max_steps) // " sub-steps " // &
          "(&run max_steps) is used up at t = " // str(self%tn) // " s")
        return
      end if
      call marcher_step(self, line, error)
      if (allocated(error)) return
      last = abs(self%tn - self%t_stop) <= eps
      if (last) self%tn = self%t_stop
      if (present(observer)) then
        self%poly%tn = self%tn
        self%poly%c(:, 0) = self%yn
        self%poly%c(:, 1) = (self%yn - self%yp)/(self%tn - self%tp)
        call observer%observe(self%poly, self%tp, self%tn, self%restart, last)
        self%restart = .false.
      end if
    end do
    if (abs(t - self%tn) <= eps .or. self%tn == self%tp) then
      self%y = self%yn
      self%t = self%tn
    else
      s = (t - self%tp)/(self%tn - self%tp)
      self%y = self%yp + s*(self%yn - self%yp)
      self%t = t
    end if
  end subroutine marcher_advance

  !> One sub-step of size self%h (Steps 2-5, see line_marcher).
  subroutine marcher_step(self, line, error)
    type(line_marcher), intent(inout) :: self
    type(rigidized_line), intent(inout) :: line
    type(error_type), allocatable, intent(inout) :: error
    integer :: k, i, n, st
    real(dp) :: h
    real(dp), allocatable :: spare(:)
    n = line%model%n
    h = self%h
    call line%unpack(self%tn, self%yn)
    call line%model%forces(line%x, line%v, line%f, line%tension, st)
    self%forces = self%forces + 1
    if (st /= 0) then
      call marching_diverged(self%tn, error)
      return
    end if
    ! Steps 2-3, Eqs. (15), (12): interior velocities, then positions
    do k = 1, min(line%last, n - 1)
      i = 6*(k - 1)
      self%yw(i+4:i+6) = self%yn(i+4:i+6) + h*line%f(:, k)/line%model%node_mass(k)
      self%yw(i+1:i+3) = self%yn(i+1:i+3) + h*self%yw(i+4:i+6)
    end do
    if (.not. line%far_kinematic) call parachute_end_step(self, line, self%tn + h, h, error)
    if (allocated(error)) return
    ! the new level becomes the state, the old one the sub-step's start, and
    ! that storage the next new level (descriptors only: nothing is copied)
    call move_alloc(self%yp, spare)
    call move_alloc(self%yn, self%yp)
    call move_alloc(self%yw, self%yn)
    call move_alloc(spare, self%yw)
    self%tp = self%tn
    self%tn = self%tn + h
    self%steps = self%steps + 1
  end subroutine marcher_step

  !> Steps 4-5, Eq. (16): node N, the parachute, at t1 = t + h from its force
  !> condition with the line's force of the old level (line%f, line%x, line%v
  !> at t), Newton on its new velocity until |e| <= max(e0, round-off).
  subroutine parachute_end_step(self, line, t1, h, error)
    type(line_marcher), intent(inout) :: self
    type(rigidized_line), intent(inout) :: line
    real(dp), intent(in) :: t1, h
    type(error_type), allocatable, intent(inout) :: error
    real(dp) :: x0(3), v0(3), x1(3), v1(3), fl(3), acc(3), drag(3), e(3), jac(3, 3), rhs(3, 1)
    real(dp) :: mass, m_share, floor
    integer :: n, i, it, j
    logical :: ok
    n = line%model%n
    i = 6*(n - 1)
    x0 = line%x(:, n)
    v0 = line%v(:, n)
    fl = line%f(:, n)
    m_share = line%model%node_mass(n)
    v1 = v0
    it = 0
    do
      x1 = x0 + h*v1
      call canopy_node_acceleration(line%chute, t1, x1, v1, m_share, fl, line%model%p%air, &
        line%model%p%gravity, acc, drag, ok)
      if (ok) call canopy_node_jacobian(line%chute, t1, x1, v1, m_share, line%model%p%air, mass, jac, ok)
      if (.not. ok) then
        call fatal_error(error, "line (marching): parachute altitude " // str(x1(2)) // " m is outside the " // &
          "atmosphere model at t = " // str(t1) // " s")
        return
      end if
      e = mass*((v1 - v0)/h - acc)
      floor = 64*epsilon(1.0_dp)*(mass*(norm2(v1) + norm2(v0))/h + norm2(fl) + norm2(drag))
      if (norm2(e) <= max(self%force_tol, floor)) exit
      if (it >= self%max_iter) then
        call far_end_not_converged(t1, norm2(e), self%force_tol, it, error)
        return
      end if
      ! de/dv1 = mass/h I - d drag/d v (the density's change with altitude left out)
      jac = -jac
      do j = 1, 3
        jac(j, j) = jac(j, j) + mass/h
      end do
      rhs(:, 1) = -e
      call solve_general(jac, rhs, error, "line (marching): far-end force Jacobian", estimate_condition=.false.)
      if (allocated(error)) return
      v1 = v1 + rhs(:, 1)
      it = it + 1
    end do
    self%iterations = self%iterations + it
    line%chute_drag = drag
    self%yw(i+4:i+6) = v1 - [line%v_ref, 0.0_dp, 0.0_dp]
    self%yw(i+1:i+3) = self%yn(i+1:i+3) + h*self%yw(i+4:i+6)
  end subroutine parachute_end_step

  !> Counters as CVODE's: sub-steps, force evaluations, far-end iterations.
  function marcher_stats(self) result(s)
    class(line_marcher), intent(in) :: self   !< the marcher
    type(cvode_stats) :: s
    s%steps = int(self%steps, kind(s%steps))
    s%rhs_evals = int(self%forces, kind(s%rhs_evals))
    s%nonlin_iters = int(self%iterations, kind(s%nonlin_iters))
  end function marcher_stats

  !> Release the arrays and reset the counters.
  subroutine marcher_free(self)
    class(line_marcher), intent(inout) :: self   !< the marcher
    if (allocated(self%y)) deallocate(self%y, self%yn, self%yp, self%yw)
    if (allocated(self%poly%c)) deallocate(self%poly%c)
    self%steps = 0; self%forces = 0; self%iterations = 0
  end subroutine marcher_free

end module airlaunch_rigidized_line
