!> The air-launch system as one ODE for CVODE: the rigid separation scene of
!> src/multibody (aircraft B0 + rocket B1 + cut joint by the CFA + phases) and
!> the flexible line B2 whose last node carries the parachute B3 (direct
!> coupling, DESIGN §4 (b)): the line's interior nodes and the parachute are
!> integrated together with the bodies, and the line's end force acts on the
!> rocket at its tie-down point.
!>
!> State (relative to a reference frame translating at the initial speed V0
!> along x at the initial altitude h0, so that positions and velocities stay
!> small numbers and CVODE's relative tolerance resolves the line's stretch):
!>   y = [aircraft r, v, q, w (13) | rocket r, v, q, w (13) | nodes 1..N: x, v (6 each)]
!> with r_abs = r + (V0 t, h0, 0) and v_abs = v + (V0, 0, 0) for every point
!> quantity.  Node N is the parachute: mass m_N + m_canopy + m_apparent, drag of
!> its inflating canopy.  The half-segment mass at node 0 (rho l0/2) is
!> neglected against the rocket's (its weight and drag are in the end force).
!>
!> Without a line (`&line enabled = .false.`, has_line false) the state is the
!> 26 rigid components alone: no line arrays are allocated, no line force is
!> computed and the rocket's tie-down carries no force.
!>
!> Events: the four of the separation scene (release, CG past the edge, nose
!> past the edge, edge normal force zero) and, in Case 3 until it is found, the
!> first maximum of the rocket's Euler pitch (Euler pitch rate
!> theta' = sin(gamma) w_y + cos(gamma) w_z crossing zero downwards); the
!> clearance's minima, the gust's passing, and the line reaching its breaking
!> strength (the smallest margin of a segment's tension to its strength - the
!> line's, or the weak link's at its segment - a continuous function of the
!> state, crossing zero: the segment that has it parts, line_model%part).
module airlaunch_launch_system
  use airlaunch_kinds, only: dp, g0
  use airlaunch_error, only: error_type
  use airlaunch_strings, only: str
  use airlaunch_atmosphere, only: isa, air_state
  use airlaunch_rotation, only: dcm_to_euler
  use airlaunch_ode, only: ode_system, rhs_ok, rhs_fatal, band_view
  use airlaunch_separation, only: separation_system, separation_nroots
  use airlaunch_cut_joint, only: phase_free, phase_rotation
  use airlaunch_line_model, only: line_model, node_state_name, weakest_segment
  use airlaunch_rigid_body, only: body_state_name
  use airlaunch_parachute, only: parachute, canopy_node_acceleration
  use airlaunch_launch_loads, only: launch_loads
  use airlaunch_clearance, only: clearance_geometry, clearance_rate, segment_distance
  implicit none
  private
  public :: launch_system, launch_nroots, rigid_size, launch_pitch_root, launch_clearance_root, launch_gust_root
  public :: launch_break_root

  !> Events: the separation scene's and the pitch maximum.
  !> event functions: the separation scene's, then the rocket's Euler pitch
  !> rate (its first maximum) and the clearance's rate (its minima), in Case 3
  !> and, while a &gust is watched, the last point of the scene passing its back
  !> edge (after which the step cap the gust needs is lifted), and, when the
  !> line has a breaking strength, its segments' margin to it
  integer, parameter :: launch_pitch_root = separation_nroots + 1, launch_clearance_root = separation_nroots + 2
  integer, parameter :: launch_gust_root = separation_nroots + 3, launch_break_root = separation_nroots + 4
  integer, parameter :: launch_nroots = separation_nroots + 4
  !> Rigid part of the state (aircraft + rocket).
  integer, parameter :: rigid_size = 26
  !> Largest distance in the state vector between a state and one its rate
  !> depends on: the aircraft (1-13), the rocket (14-26) and node 1 (27-32)
  !> are coupled through the rail constraint and the line's pull (28 at most),
  !> a node with its neighbours (within 11).  One weak exception: the line's
  !> air density is fitted between its lowest and highest node (line_model's
  !> air_density_fit), so every node's drag depends, by ~1e-8 of the entries,
  !> on those two nodes' altitudes - left out, like the band's far couplings
  integer, parameter :: coupling_reach = rigid_size + 6 - 1

  !> The whole system.
  type, extends(ode_system) :: launch_system
    type(separation_system) :: sep          !< aircraft + rocket + joint + phases
    type(line_model) :: line                !< the line, node N = parachute
    type(parachute) :: chute                !< the canopy
    integer :: iloads = 0                   !< index of the launch_loads source in sep%sources
    real(dp) :: v_ref = 0.0_dp              !< V0 of the reference frame [m/s]
    real(dp) :: h_ref = 0.0_dp              !< h0 of the reference frame [m]
    real(dp) :: tie_down(3) = 0.0_dp        !< rocket axes [m]
    logical :: find_pitch_max = .true.      !< event 5 active in Case 3
    type(clearance_geometry) :: clr         !< the clearance milestone's points (event 6)
    logical :: has_line = .true.            !< false: no line, no parachute (state = rigid part)
    !> a &gust ahead of a point of the scene: event 7 watches for the last point
    !> to pass the gust's back edge at x = gust_back
    logical :: gust_watch = .false.
    real(dp) :: gust_back = 0.0_dp          !< x_front + 2H [m]
    !> largest step of the scene's integrators while a gust is ahead [s] (0:
    !> no gust, unlimited): a quarter of its passage 2H/V0 (launch_coupled)
    real(dp) :: gust_max_step = 0.0_dp
    !> segment j of the line parts when its tension reaches strength(j) [N]
    !> (event launch_break_root: the smallest margin, weakest_segment); set by
    !> the scene from &line breaking_strength and the weak link only when the
    !> line can break, huge(1.0_dp) for a segment that never does
    real(dp), allocatable :: strength(:)
    !> the line is cut at segment break_segment at this time [s] (a scheduled
    !> stop of the direct solver, launch_coupled); < 0: never, or done
    real(dp) :: break_time = -1.0_dp
    integer :: break_segment = 1
    ! --- work arrays and outputs of the last evaluation (no allocation in rhs)
    real(dp), allocatable :: yabs(:), ydabs(:)
    real(dp), allocatable :: x(:, :), v(:, :), f(:, :), tension(:)
    !> work of the difference-quotient Jacobian (state, its right-hand side,
    !> the perturbed ones, the increments); allocated by the scene with yabs
    real(dp), allocatable :: jac_y(:), jac_f0(:), jac_f1(:), jac_inc(:)
    real(dp) :: chute_drag(3) = 0.0_dp
  contains
    procedure :: rhs => launch_rhs
    procedure :: nroots => launch_nroots_fn
    procedure :: roots => launch_roots
    procedure :: prepare => launch_prepare
    procedure :: load_bodies => launch_load_bodies
    procedure :: to_absolute => launch_to_absolute
    procedure :: euler_pitch_rate => launch_euler_pitch_rate
    procedure :: gust_clearance => launch_gust_clearance
    procedure :: line_tensions => launch_line_tensions
    procedure :: weakest_segment => launch_weakest_segment
    procedure :: may_still_part => launch_may_still_part
    procedure :: line_clearance => launch_line_clearance
    procedure :: velocity_partners => launch_velocity_partners
    procedure :: has_projection => launch_has_projection
    procedure :: has_jacobian => launch_has_jacobian
    procedure :: jacobian => launch_jacobian
    procedure :: project => launch_project
    procedure :: state_name => launch_state_name
  end type launch_system

contains

  !> State i: the aircraft's 13, the rocket's 13, then the line's nodes 1..N
  !> (node N carries the parachute); positions and velocities relative to the
  !> reference frame (see the module's header).
  function launch_state_name(self, i) result(name)
    class(launch_system), intent(in) :: self  !< the system
    integer, intent(in) :: i                  !< state index
    character(len=:), allocatable :: name
    integer :: k
    if (i <= 13) then
      name = "aircraft " // body_state_name(i)
    else if (i <= rigid_size) then
      name = "rocket " // body_state_name(i - 13)
    else
      k = 1 + (i - rigid_size - 1)/6
      name = node_state_name(k, 1 + modulo(i - rigid_size - 1, 6))
      if (k == self%line%n) name = name // " (parachute)"
    end if
  end function launch_state_name

  !> Absolute state (earth frame) of the rigid part and the nodes from y.
  subroutine launch_to_absolute(self, t, y)
    class(launch_system), intent(inout) :: self
    real(dp), intent(in) :: t, y(:)
    integer :: k, n, i
    self%yabs = y
    do i = 0, 1   ! aircraft, rocket
      self%yabs(13*i+1) = y(13*i+1) + self%v_ref*t
      self%yabs(13*i+2) = y(13*i+2) + self%h_ref
      self%yabs(13*i+4) = y(13*i+4) + self%v_ref
    end do
    if (.not. self%has_line) return
    n = self%line%n
    do k = 1, n
      i = rigid_size + 6*(k - 1)
      self%x(:, k) = y(i+1:i+3) + [self%v_ref*t, self%h_ref, 0.0_dp]
      self%v(:, k) = y(i+4:i+6) + [self%v_ref, 0.0_dp, 0.0_dp]
    end do
  end subroutine launch_to_absolute

  !> Everything the rigid scene needs before it evaluates: bodies from the
  !> state, the line's node forces, the end force and phase in the loads.
  !> The absolute state from y and the bodies loaded from it (no forces).
  subroutine launch_load_bodies(self, t, y)
    class(launch_system), intent(inout) :: self
    real(dp), intent(in) :: t, y(:)
    call self%to_absolute(t, y)
    call self%sep%load_state(self%yabs(1:rigid_size))
  end subroutine launch_load_bodies

  subroutine launch_prepare(self, t, y, status)
    class(launch_system), intent(inout) :: self
    real(dp), intent(in) :: t, y(:)
    integer, intent(out) :: status
    call self%load_bodies(t, y)
    if (self%has_line) then
      call place_tie_down(self)
      call self%line%forces(self%x, self%v, self%f, self%tension, status)
      if (status /= 0) then
        self%failure = "line tension is not finite at t = " // str(t) // " s"
        status = rhs_fatal
        return
      end if
    end if
    select type (s => self%sep%sources(self%iloads)%source)
    type is (launch_loads)
      if (self%has_line) s%line_force = self%f(:, 0)   ! else it keeps its zero
      s%phase = self%sep%phase
    end select
    status = rhs_ok
  end subroutine launch_prepare

  subroutine launch_rhs(self, t, y, ydot, status)
    class(launch_system), intent(inout) :: self
    real(dp), intent(in) :: t
    real(dp), intent(in) :: y(:)
    real(dp), intent(out) :: ydot(:)
    integer, intent(out) :: status
    integer :: k, n, i
    logical :: ok
    call self%prepare(t, y, status)
    if (status /= rhs_ok) return
    call self%sep%rhs(t, self%yabs(1:rigid_size), ydot(1:rigid_size), status)
    if (status /= rhs_ok) then
      if (allocated(self%sep%failure)) self%failure = self%sep%failure
      return
    end if
    ydot(1:3) = ydot(1:3) - [self%v_ref, 0.0_dp, 0.0_dp]
    ydot(14:16) = ydot(14:16) - [self%v_ref, 0.0_dp, 0.0_dp]
    if (.not. self%has_line) return
    n = self%line%n
    do k = 1, n - 1
      i = rigid_size + 6*(k - 1)
      ydot(i+1:i+3) = y(i+4:i+6)
      ydot(i+4:i+6) = self%f(:, k)/self%line%node_mass(k)
    end do
    ! node N: the parachute
    i = rigid_size + 6*(n - 1)
    ydot(i+1:i+3) = y(i+4:i+6)
    call canopy_node_acceleration(self%chute, t, self%x(:, n), self%v(:, n), self%line%node_mass(n), &
      self%f(:, n), .true., .true., ydot(i+4:i+6), self%chute_drag, ok)
    if (.not. ok) then
      self%failure = "parachute altitude " // str(self%x(2, n)) // " m is outside the atmosphere model"
      status = rhs_fatal
      return
    end if
    status = rhs_ok
  end subroutine launch_rhs

  integer function launch_nroots_fn(self)
    class(launch_system), intent(in) :: self
    launch_nroots_fn = launch_nroots
    if (.false.) launch_nroots_fn = self%iloads
  end function launch_nroots_fn

  subroutine launch_roots(self, t, y, g, status)
    class(launch_system), intent(inout) :: self
    real(dp), intent(in) :: t
    real(dp), intent(in) :: y(:)
    real(dp), intent(out) :: g(:)
    integer, intent(out) :: status
    integer :: k
    g = 1.0_dp
    if (self%sep%phase == phase_rotation) then
      ! the edge's normal force (event 4) needs the whole evaluation, with the
      ! line's pull on the rocket
      call self%prepare(t, y, status)
      if (status /= rhs_ok) return
    else
      ! the other events read the bodies' states only: no line forces (they were
      ! a third of the event functions' cost, ~5 % of a sweep case)
      call self%load_bodies(t, y)
    end if
    call self%sep%roots(t, self%yabs(1:rigid_size), g(1:separation_nroots), status)
    if (status /= rhs_ok) then
      if (allocated(self%sep%failure)) self%failure = self%sep%failure
      return
    end if
    if (self%gust_watch) g(launch_gust_root) = self%gust_clearance()
    if (allocated(self%strength)) then   ! a line that can break
      ! the tensions: prepare's in Case 2, else of the state just loaded
      if (self%sep%phase /= phase_rotation) then
        call self%line_tensions(t, status)
        if (status /= rhs_ok) return
      end if
      call self%weakest_segment(g(launch_break_root), k)
    end if
    if (self%sep%phase /= phase_free) return
    if (self%find_pitch_max) g(launch_pitch_root) = self%euler_pitch_rate()
    g(launch_clearance_root) = clearance_rate(self%clr, self%sep%bodies(0), self%sep%bodies(1))
  end subroutine launch_roots

  !> The line's smallest margin to breaking and its segment k
  !> (airlaunch_line_model's weakest_segment) for the tensions last computed.
  pure subroutine launch_weakest_segment(self, margin, k)
    class(launch_system), intent(in) :: self
    real(dp), intent(out) :: margin
    integer, intent(out) :: k
    call weakest_segment(self%strength, self%tension, margin, k)
  end subroutine launch_weakest_segment

  !> The line's clearance from the aircraft's empennage point (the rocket
  !> clearance's point, clr%point): the smallest distance of the point from the
  !> line's segments that have not parted [m], from the bodies and nodes as
  !> prepare left them (node 0 at the tie-down); huge without a line.
  pure real(dp) function launch_line_clearance(self) result(d)
    class(launch_system), intent(in) :: self
    real(dp) :: p(3)
    integer :: j
    d = huge(1.0_dp)
    if (.not. self%has_line) return
    p = self%sep%bodies(0)%point_position(self%clr%point)
    do j = 1, self%line%n
      if (self%line%n_parted > 0) then
        if (self%line%parted(j)) cycle
      end if
      d = min(d, segment_distance(p, self%x(:, j - 1), self%x(:, j)))
    end do
  end function launch_line_clearance

  !> The line can still part later in the run: its scheduled cut (&line
  !> break_time) is still to come, or a segment that has not parted has a
  !> strength (&line breaking_strength, the weak link's).  A run that stops
  !> once its milestones are final (&run stop_when_final) must not stop then.
  pure logical function launch_may_still_part(self) result(may)
    class(launch_system), intent(in) :: self
    integer :: j
    may = .false.
    if (.not. self%has_line) return
    if (self%break_time > 0.0_dp) then
      may = .true.
      return
    end if
    if (.not. allocated(self%strength)) return
    do j = 1, size(self%strength)
      if (self%line%parted(j)) cycle
      if (self%strength(j) < huge(1.0_dp)) then
        may = .true.
        return
      end if
    end do
  end function launch_may_still_part

  !> The line's segment tensions into self%tension, for the bodies and nodes
  !> loaded (load_bodies): what prepare's line forces give, without the loads.
  subroutine launch_line_tensions(self, t, status)
    class(launch_system), intent(inout) :: self
    real(dp), intent(in) :: t
    integer, intent(out) :: status
    call place_tie_down(self)
    call self%line%tensions(self%x, self%v, self%tension, status)
    if (status /= 0) then
      self%failure = "line tension is not finite at t = " // str(t) // " s"
      status = rhs_fatal
    else
      status = rhs_ok
    end if
  end subroutine launch_line_tensions

  !> The line's node 0 at the rocket's tie-down point (rocket loaded).
  subroutine place_tie_down(self)
    class(launch_system), intent(inout) :: self
    self%x(:, 0) = self%sep%bodies(1)%point_position(self%tie_down)
    self%v(:, 0) = self%sep%bodies(1)%point_velocity(self%tie_down)
  end subroutine place_tie_down


  !> How far the scene's last point (the points at which the bodies read the
  !> gust, launch_loads%rearmost_gust_point, and the line's nodes) is past the
  !> gust's back edge [m]: negative while any of them may still read the gust
  !> (bodies and nodes loaded: load_bodies).
  real(dp) function launch_gust_clearance(self) result(d)
    class(launch_system), intent(in) :: self
    integer :: k
    d = huge(1.0_dp)
    select type (s => self%sep%sources(self%iloads)%source)
    type is (launch_loads)
      d = s%rearmost_gust_point(self%sep%bodies)
    end select
    if (self%has_line) then
      do k = 1, self%line%n
        d = min(d, self%x(1, k))
      end do
    end if
    d = d - self%gust_back
  end function launch_gust_clearance

  !> The positions with x' = v: both bodies' (relative) positions and every
  !> node's, for the position-reduced Newton solver.
  subroutine launch_velocity_partners(self, partner)
    class(launch_system), intent(in) :: self
    integer, intent(out) :: partner(:)
    integer :: k, i, p
    partner = 0
    do p = 1, 3
      partner(p) = 3 + p
      partner(13 + p) = 16 + p
    end do
    if (.not. self%has_line) return
    do k = 1, self%line%n
      i = rigid_size + 6*(k - 1)
      do p = 1, 3
        partner(i + p) = i + 3 + p
      end do
    end do
  end subroutine launch_velocity_partners

  !> The Newton matrix is the system's own difference quotients (launch_jacobian),
  !> with the line (its band) and without it (26 rigid states, a full band:
  !> rigid_only_options).  CVODE's own dense quotients perturb a state near 0 by
  !> 1000 h u N |f| / ewt_j, which at a tight atol falls below the rounding of
  !> V0 + v: a rocket stuck on the rail (Karnopp, s'' + stick_rate s' = 0) lost
  !> its stick row from the Newton matrix and the run crawled at h ~ 1/stick_rate
  !> (3 s stuck at atol 1e-12: 2 849 steps, 2 064 convergence failures).
  logical function launch_has_jacobian(self)
    class(launch_system), intent(in) :: self
    launch_has_jacobian = allocated(self%jac_y)
  end function launch_has_jacobian

  !> Band Jacobian by difference quotients, columns perturbed together when no
  !> state depends on two of them (but for the density fit, coupling_reach;
  !> every state depends on those at most
  !> `coupling_reach` away: the aircraft's first on node 1's last, through the
  !> rocket's constraint and the line's pull; CVODE grouped by the stored band,
  !> 18, and the couplings beyond it were read into other columns' entries: the
  !> planar paper scenario drifted 4 mm out of its plane), each state's increment sqrt(eps) times the number the
  !> right-hand side works with: max(|y_j|, |y_j + offset_j|, 1), the offset
  !> being V0 t, h0 or V0 for the x, y positions and the x velocity of the
  !> frame moving with the carrier (prepare adds it back).  CVODE's own
  !> increment for a state near 0 is 1000 h u N |f| / ewt_j: with the system at
  !> rest (the trimmed Case 0) it fell below the rounding of V0 + v, and the
  !> line's dashpot (its stiffest term) vanished from the Newton matrix - at
  !> N = 240, rtol 1e-9 the run took 293 893 steps with 107 183 Newton failures
  !> in Case 0 (helper-33's diagnosis; docs/performance.md).
  subroutine launch_jacobian(self, t, y, jac, status)
    class(launch_system), intent(inout) :: self
    real(dp), intent(in) :: t
    real(dp), intent(in) :: y(:)
    type(band_view), intent(inout) :: jac
    integer, intent(out) :: status
    real(dp), parameter :: srur = sqrt(epsilon(1.0_dp))
    real(dp) :: offset
    integer :: n, width, g, i, j, c
    n = size(y)
    width = 2*coupling_reach + 1
    do j = 1, n
      ! component within its body (13 states) or node (6 states)
      if (j <= rigid_size) then
        c = 1 + modulo(j - 1, 13)
      else
        c = 1 + modulo(j - rigid_size - 1, 6)
      end if
      select case (c)
      case (1)
        offset = self%v_ref*t
      case (2)
        offset = self%h_ref
      case (4)
        offset = self%v_ref
      case default
        offset = 0.0_dp
      end select
      self%jac_y(j) = y(j) + srur*max(abs(y(j)), abs(y(j) + offset), 1.0_dp)
      self%jac_inc(j) = self%jac_y(j) - y(j)   ! the increment as represented
    end do
    call self%rhs(t, y, self%jac_f0, status)
    if (status /= rhs_ok) return
    self%jac_y(1:n) = y
    do g = 1, min(width, n)
      do j = g, n, width
        self%jac_y(j) = y(j) + self%jac_inc(j)
      end do
      call self%rhs(t, self%jac_y(1:n), self%jac_f1, status)
      if (status /= rhs_ok) return
      do j = g, n, width
        self%jac_y(j) = y(j)
        do i = max(1, j - jac%mu), min(n, j + jac%ml)
          call jac%set(i, j, (self%jac_f1(i) - self%jac_f0(i))/self%jac_inc(j))
        end do
      end do
    end do
  end subroutine launch_jacobian

  !> Unit quaternions after every step (the rigid part's projection).
  logical function launch_has_projection(self)
    class(launch_system), intent(in) :: self
    launch_has_projection = .true.
    if (.false.) launch_has_projection = self%iloads > 0
  end function launch_has_projection

  subroutine launch_project(self, t, y, status)
    class(launch_system), intent(inout) :: self
    real(dp), intent(in) :: t
    real(dp), intent(inout) :: y(:)
    integer, intent(out) :: status
    call self%sep%project(t, y(1:rigid_size), status)
  end subroutine launch_project

  !> Euler pitch rate of the rocket [rad/s] from its body rates (no
  !> singularity): theta' = sin(gamma) w_y + cos(gamma) w_z (Eqs. (49)-(50)).
  real(dp) function launch_euler_pitch_rate(self) result(r)
    class(launch_system), intent(in) :: self
    real(dp) :: e(3)
    e = dcm_to_euler(self%sep%bodies(1)%c)
    r = sin(e(3))*self%sep%bodies(1)%w(2) + cos(e(3))*self%sep%bodies(1)%w(3)
  end function launch_euler_pitch_rate
end module airlaunch_launch_system
