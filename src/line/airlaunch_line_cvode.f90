!> Default line integrator: the lumped-mass line (airlaunch_line_model) as a
!> first-order ODE system integrated by CVODE BDF with the band linear solver.
!>
!> State.  Only the nodes that are not kinematic are states (a fixed,
!> prescribed or body end is given by its motion).  The free nodes
!> first..last are stored node by node, y = [x_first, v_first, x_first+1, ...],
!> six entries per node, so that the Jacobian is banded: the acceleration of
!> node k depends on the positions and velocities of nodes k-1, k, k+1 only.
!> With the entries of node j at 6j+1..6j+6 (x at +1..+3, v at +4..+6):
!>   - row 6j+4..6j+6 (v_k') reaches columns 6(j-1)+1 .. 6(j+1)+6:
!>     lower half-bandwidth (6j+6) - (6j-5) = 11, upper (6j+12) - (6j+4) = 8;
!>   - row 6j+1..6j+3 (x_k' = v_k) reaches columns 6j+4..6j+6 only (upper 3..5).
!> Hence mu = 8, ml = 11: CVODE's difference-quotient band Jacobian costs
!> mu + ml + 1 = 20 force evaluations however long the line, and the band LU
!> costs O(n ml (ml + mu)) for n = 6 (number of free nodes) states.
!> A point-mass end adds its mass to the end node and its weight and drag to
!> the node's load (the end body is lumped with the node: the limit the paper's
!> far-end iteration converges to).
!>
!> Mass matrix.  With the lumped mass v_k' = f_k/m_k; with the mixed one
!> (airlaunch_line_model, "Mass matrix") v' solves M v' = f over the state nodes
!> (airlaunch_line_mass: LAPACK's tridiagonal L D L^T, factored once), the
!> kinematic ends' accelerations moved to the right-hand side.  The Jacobian
!> of v' is then M^-1 df/dy, a full matrix, but the Newton matrix's velocity
!> rows multiplied by M keep the band (airlaunch_lapack_band, setup_from_blocks),
!> so the mixed mass needs the analytic node-block Jacobian: CVODE's difference
!> quotients over the band would be wrong.
!>
!> Jacobian.  The system gives CVODE its analytic Jacobian (x' = v: the identity
!> block; v' = f/m: the blocks of line_model%force_jacobian and of the point
!> masses' drag, divided by the node masses), so a Jacobian costs about one
!> force evaluation instead of mu + ml + 1 = 20; `analytic_jacobian = .false.`
!> in the options falls back to CVODE's difference quotients.  The default
!> scheme hands the blocks straight to the velocity-reduced solver
!> (`node_jacobian`, through CVODE's linear-system hook: no band matrix to zero,
!> save, copy back and scale at every setup) and keeps them while CVODE allows
!> and no segment has switched between slack and taut; a band solver gets them
!> as a band matrix (`jacobian`).
module airlaunch_line_cvode
  use airlaunch_kinds, only: dp, i8
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_ode, only: ode_system, band_view, node_blocks, rhs_ok, rhs_fatal
  use airlaunch_cvode, only: cvode_solver, cvode_options, cvode_stats
  use airlaunch_step_maxima, only: maxima_observer
  use airlaunch_line_model, only: line_model, line_energy, node_state_name, weakest_segment, &
    outside_atmosphere_message
  use airlaunch_line_mass, only: line_mass_matrix
  use airlaunch_line_ends, only: line_end, end_point_mass
  use airlaunch_line_scheme, only: line_scheme, line_scheme_options, line_scheme_stats, scheme_peak_tension, &
    check_fill_target
  implicit none
  private
  public :: line_system, line_cvode, new_line_cvode, line_band_upper, line_band_lower, line_force_jacobian

  !> Upper and lower half-bandwidths of the line Jacobian (see the header).
  integer, parameter :: line_band_upper = 8
  integer, parameter :: line_band_lower = 11

  !> A line's force Jacobian (the blocks of line_model%force_jacobian, plus what
  !> the owner adds for its ends) and the slack/taut pattern it was formed at;
  !> turned into the velocity-reduced solver's node blocks by `to_node_blocks`.
  !> Shared by the default line scheme (line_system) and the rigidized
  !> coupling's line, which differ only in their ends.
  type :: line_force_jacobian
    real(dp), allocatable :: dfdx(:, :, :, :)  !< df_j/dx_(j+d) (3, 3, -1:1, 0:N) [N/m]
    real(dp), allocatable :: dfdv(:, :, :, :)  !< df_j/dv_(j+d) (3, 3, -1:1, 0:N) [N s/m]
    logical, allocatable :: taut(:)            !< which segments were taut (tension > 0) when formed (N)
    logical :: formed = .false.                !< formed at least once since `allocate`
  contains
    procedure :: allocate => force_jacobian_allocate
    procedure :: form => force_jacobian_form
    procedure :: still_valid => force_jacobian_still_valid
    procedure :: to_node_blocks => force_jacobian_to_node_blocks
  end type line_force_jacobian

  !> The discretized line with its two ends as an ODE system y' = f(t, y).
  type, extends(ode_system) :: line_system
    type(line_model) :: model                  !< the line
    type(line_end) :: ends(2)                  !< end at node 0, end at node N
    integer :: first = 0                       !< first state node
    integer :: last = -1                       !< last state node
    real(dp), allocatable :: x(:, :)           !< work: positions (3, 0:N)
    real(dp), allocatable :: v(:, :)           !< work: velocities (3, 0:N)
    real(dp), allocatable :: f(:, :)           !< work: node forces (3, 0:N)
    real(dp), allocatable :: tension(:)        !< work: segment tensions (N)
    real(dp), allocatable :: acc(:, :)         !< work: node accelerations (3, 0:N)
    real(dp) :: end_acc(3, 2) = 0.0_dp         !< work: kinematic ends' accelerations (node 0, node N)
    type(line_mass_matrix) :: mass             !< the mass matrix over the state nodes
    type(line_force_jacobian) :: jac_blocks    !< work: the force Jacobian of the last evaluation
    integer(i8) :: n_forces = 0                !< force evaluations
    !> segment j parts at tension strength(j) [N] (unallocated: the line never
    !> parts); the event function is the smallest margin (weakest_segment)
    real(dp), allocatable :: strength(:)
    real(dp), allocatable :: root_tension(:)   !< work: the event function's tensions (N)
    !> the ground's altitude [m] (-huge: none); its event function is the lowest
    !> state node's altitude above it, after the strength's margin if any
    real(dp) :: ground = -huge(1.0_dp)
  contains
    procedure :: rhs => system_rhs
    procedure :: nroots => system_nroots
    procedure :: roots => system_roots
    procedure :: has_ground => system_has_ground
    procedure :: setup => system_setup
    procedure :: n_state => system_n_state
    procedure :: state_name => system_state_name
    procedure :: pack => system_pack
    procedure :: unpack => system_unpack
    procedure :: energy => system_energy
    procedure :: has_jacobian => system_has_jacobian
    procedure :: jacobian => system_jacobian
    procedure :: has_node_jacobian => system_has_jacobian
    procedure :: node_jacobian => system_node_jacobian
    procedure, private :: force_blocks => system_force_blocks
  end type line_system

  !> The largest segment tension over every internal CVODE step, refined
  !> between steps on the interpolants (airlaunch_step_maxima); its own
  !> tension work array (the system's holds the last right-hand side's, which
  !> the Jacobian reads).
  type, extends(maxima_observer) :: tension_observer
    type(line_system), pointer :: sys => null()
    real(dp), allocatable :: tension(:)
    real(dp) :: seen = -huge(1.0_dp)   !< the largest tension evaluated [N]
    integer :: segment = 0             !< its segment (0: none yet)
  contains
    procedure :: values => tension_values
  end type tension_observer

  !> The default scheme: CVODE BDF + band solver on a `line_system`.
  type, extends(line_scheme) :: line_cvode
    type(line_system), pointer :: sys => null()   !< on the heap: CVODE keeps its address
    type(cvode_solver) :: solver                  !< the integrator
    type(cvode_options) :: opts                   !< its options
    type(tension_observer) :: observer            !< the peak tension over the steps
    !> a line with no state (one segment between kinematic ends) has no
    !> CVODE: advance stops at this time itself (set_stop_time) [s]
    real(dp) :: stateless_stop = -huge(1.0_dp)
  contains
    procedure :: peak_tension => cvode_peak_tension
    procedure :: advance => cvode_advance
    procedure :: get_state => cvode_get_state
    procedure :: stats => cvode_scheme_stats
    procedure :: set_body_motion => cvode_set_body_motion
    procedure :: set_stop_time => cvode_set_stop_time
    procedure :: set_fill_time => cvode_set_fill_time
    procedure :: set_strength => cvode_set_strength
    procedure :: set_ground => cvode_set_ground
    procedure :: part => cvode_part
    procedure :: free => cvode_free
  end type line_cvode

contains

  !> Build the system for `model` with ends `end_a` (node 0) and `end_b` (node N).
  subroutine system_setup(self, model, end_a, end_b, error)
    class(line_system), intent(inout) :: self              !< system (re-initialised)
    type(line_model), intent(in) :: model                  !< the line
    type(line_end), intent(in) :: end_a, end_b             !< ends at node 0 and node N
    type(error_type), allocatable, intent(inout) :: error  !< set if the mass matrix cannot be factored
    integer :: n
    real(dp), allocatable :: node_mass(:)
    self%model = model
    self%ends = [end_a, end_b]
    n = model%n
    self%first = 0
    if (end_a%is_kinematic()) self%first = 1
    self%last = n
    if (end_b%is_kinematic()) self%last = n - 1
    if (allocated(self%x)) deallocate(self%x, self%v, self%f, self%tension, self%acc)
    allocate(self%x(3, 0:n), self%v(3, 0:n), self%f(3, 0:n), self%tension(n), self%acc(3, 0:n))
    call self%jac_blocks%allocate(n)
    self%tension = 0.0_dp
    self%x = 0.0_dp; self%v = 0.0_dp; self%acc = 0.0_dp
    node_mass = model%node_mass
    if (end_a%kind == end_point_mass) node_mass(0) = node_mass(0) + end_a%mass
    if (end_b%kind == end_point_mass) node_mass(n) = node_mass(n) + end_b%mass
    call self%mass%build(node_mass, model%p%mass_per_length*model%l0, model%mass_coupling, self%first, &
      self%last, error)
  end subroutine system_setup

  !> Number of states: 6 per non-kinematic node.
  pure integer function system_n_state(self) result(n)
    class(line_system), intent(in) :: self   !< system
    n = 6*max(0, self%last - self%first + 1)
  end function system_n_state

  !> State vector of node positions x(3,0:N) and velocities v(3,0:N).
  pure subroutine system_pack(self, x, v, y)
    class(line_system), intent(in) :: self   !< system
    real(dp), intent(in) :: x(:, 0:), v(:, 0:)
    real(dp), intent(out) :: y(:)            !< state (n_state)
    integer :: k, j
    do k = self%first, self%last
      j = 6*(k - self%first)
      y(j+1:j+3) = x(:, k)
      y(j+4:j+6) = v(:, k)
    end do
  end subroutine system_pack

  !> State i is node first + (i - 1)/6, component 1 + mod(i - 1, 6) of [x, v].
  function system_state_name(self, i) result(name)
    class(line_system), intent(in) :: self   !< system
    integer, intent(in) :: i                 !< state index
    character(len=:), allocatable :: name
    name = node_state_name(self%first + (i - 1)/6, 1 + modulo(i - 1, 6))
  end function system_state_name

  !> Fill the work arrays x, v from the state y at time t (kinematic ends from
  !> their motion, with their accelerations in end_acc).
  subroutine system_unpack(self, t, y)
    class(line_system), intent(inout) :: self   !< system
    real(dp), intent(in) :: t                   !< time [s]
    real(dp), intent(in) :: y(:)                !< state
    integer :: k, j, n
    n = self%model%n
    if (self%first == 1) call self%ends(1)%motion(t, self%x(:, 0), self%v(:, 0), self%end_acc(:, 1))
    if (self%last == n - 1) call self%ends(2)%motion(t, self%x(:, n), self%v(:, n), self%end_acc(:, 2))
    do k = self%first, self%last
      j = 6*(k - self%first)
      self%x(:, k) = y(j+1:j+3)
      self%v(:, k) = y(j+4:j+6)
    end do
    ! a canopy end's apparent mass, which grows while it fills
    if (self%first == 0 .and. self%ends(1)%canopy_end) call self%mass%set_extra(0, &
      self%ends(1)%apparent_mass(t, self%x(:, 0), self%model%p%air, self%model%p%air_density))
    if (self%last == n .and. self%ends(2)%canopy_end) call self%mass%set_extra(n, &
      self%ends(2)%apparent_mass(t, self%x(:, n), self%model%p%air, self%model%p%air_density))
  end subroutine system_unpack

  !> y' = f(t, y): node velocities and accelerations (Eq. (8); M a = f with
  !> the mixed mass).  No allocation except for the failure message.
  subroutine system_rhs(self, t, y, ydot, status)
    class(line_system), intent(inout) :: self   !< system
    real(dp), intent(in) :: t                   !< time [s]
    real(dp), intent(in) :: y(:)                !< state
    real(dp), intent(out) :: ydot(:)            !< derivative
    integer, intent(out) :: status              !< rhs_ok or rhs_fatal
    integer :: k, j, n, st
    n = self%model%n
    call self%unpack(t, y)
    k = self%model%node_outside_atmosphere(self%x)
    if (k >= 0) then
      self%failure = outside_atmosphere_message(self%x, k)
      status = rhs_fatal
      return
    end if
    call self%model%forces(self%x, self%v, self%f, self%tension, st)
    self%n_forces = self%n_forces + 1
    if (st /= 0) then
      self%failure = "a line tension is not finite (NaN or overflow): the line state diverged"
      status = rhs_fatal
      return
    end if
    if (self%first == 0 .and. self%ends(1)%kind == end_point_mass) self%f(:, 0) = self%f(:, 0) + &
      self%ends(1)%external_load(t, self%x(:, 0), self%v(:, 0), self%model%p%gravity, self%model%p%air, &
      self%model%p%wind, self%model%p%air_density)
    if (self%last == n .and. self%ends(2)%kind == end_point_mass) self%f(:, n) = self%f(:, n) + &
      self%ends(2)%external_load(t, self%x(:, n), self%v(:, n), self%model%p%gravity, self%model%p%air, &
      self%model%p%wind, self%model%p%air_density)
    call self%mass%accelerations(self%f, self%end_acc(:, 1), self%end_acc(:, 2), self%acc)
    do k = self%first, self%last
      j = 6*(k - self%first)
      ydot(j+1:j+3) = self%v(:, k)
      ydot(j+4:j+6) = self%acc(:, k)
    end do
    status = rhs_ok
  end subroutine system_rhs

  !> The line has an analytic Jacobian (system_jacobian).
  logical function system_has_jacobian(self)
    class(line_system), intent(in) :: self   !< system
    system_has_jacobian = allocated(self%jac_blocks%dfdx)
  end function system_has_jacobian

  !> df/dy at (t, y) into CVODE's zeroed band matrix (mu = 8, ml = 11, see the
  !> module header): rows of x_k: dx_k'/dv_k = I; rows of v_k: the force blocks
  !> of node k with respect to the state nodes k-1, k, k+1, divided by the
  !> node's mass.  Kinematic ends are not states: their columns are left out.
  !> No allocation.
  subroutine system_jacobian(self, t, y, jac, status)
    class(line_system), intent(inout) :: self   !< system
    real(dp), intent(in) :: t                   !< time [s]
    real(dp), intent(in) :: y(:)                !< state
    type(band_view), intent(inout) :: jac       !< band matrix, zeroed by CVODE
    integer, intent(out) :: status              !< rhs_ok
    integer :: k, d, j, jj, p
    if (.not. self%mass%is_lumped()) then   ! M^-1 df/dy is full: no band Jacobian
      self%failure = "the line's band Jacobian needs the lumped mass (mass = 'lumped')"
      status = rhs_fatal
      return
    end if
    call self%force_blocks(t, y)
    do k = self%first, self%last
      j = 6*(k - self%first)
      do p = 1, 3
        call jac%set(j + p, j + 3 + p, 1.0_dp)
      end do
      do d = -1, 1
        if (k + d < self%first .or. k + d > self%last) cycle
        jj = 6*(k + d - self%first)
        call jac%set_block(j + 3, jj, self%mass%inv_diagonal(k), self%jac_blocks%dfdx(:, :, d, k))
        call jac%set_block(j + 3, jj + 3, self%mass%inv_diagonal(k), self%jac_blocks%dfdv(:, :, d, k))
      end do
    end do
    status = rhs_ok
  end subroutine system_jacobian

  !> One event function if the line can part (system%strength), one if it has
  !> a ground, in that order.
  integer function system_nroots(self)
    class(line_system), intent(in) :: self   !< system
    system_nroots = merge(1, 0, allocated(self%strength)) + merge(1, 0, self%has_ground())
  end function system_nroots

  !> A ground is watched.
  pure logical function system_has_ground(self)
    class(line_system), intent(in) :: self   !< system
    system_has_ground = self%ground > -huge(1.0_dp)
  end function system_has_ground

  !> The events: the line's smallest margin to breaking (weakest_segment), in
  !> its own tension array (the right-hand side's is the Jacobian's), and the
  !> lowest state node's altitude above the ground.
  subroutine system_roots(self, t, y, g, status)
    class(line_system), intent(inout) :: self   !< system
    real(dp), intent(in) :: t                   !< time [s]
    real(dp), intent(in) :: y(:)                !< state
    real(dp), intent(out) :: g(:)               !< the smallest margin [N]; the lowest node's height [m]
    integer, intent(out) :: status              !< rhs_ok or rhs_fatal
    integer :: k, st
    call self%unpack(t, y)
    status = rhs_ok
    if (self%has_ground()) g(size(g)) = minval(self%x(2, self%first:self%last)) - self%ground
    if (.not. allocated(self%strength)) return
    call self%model%tensions(self%x, self%v, self%root_tension, st)
    if (st /= 0) then
      self%failure = "a line tension is not finite (NaN or overflow): the line state diverged"
      status = rhs_fatal
      return
    end if
    call weakest_segment(self%strength, self%root_tension, g(1), k)
    status = rhs_ok
  end subroutine system_roots

  !> The force Jacobian's blocks (with the point masses' drag) at (t, y), and the
  !> slack/taut pattern they hold for.  CVODE forms a Jacobian right after a
  !> right-hand side at the same state, whose tensions are at hand.
  subroutine system_force_blocks(self, t, y)
    class(line_system), intent(inout) :: self   !< system
    real(dp), intent(in) :: t                   !< time [s]
    real(dp), intent(in) :: y(:)                !< state
    integer :: i, k
    call self%unpack(t, y)
    call self%jac_blocks%form(self%model, self%x, self%v, self%tension)
    do i = 1, 2
      k = merge(0, self%model%n, i == 1)
      if (k < self%first .or. k > self%last .or. self%ends(i)%kind /= end_point_mass) cycle
      self%jac_blocks%dfdv(:, :, 0, k) = self%jac_blocks%dfdv(:, :, 0, k) + self%ends(i)%external_load_dv( &
        t, self%x(:, k), self%v(:, k), self%model%p%air, self%model%p%wind, self%model%p%air_density)
    end do
  end subroutine system_force_blocks

  !> The Jacobian as node blocks for the velocity-reduced solver: d a_k / d x and
  !> d a_k / d v of the state nodes k-1, k, k+1 (the force blocks over the node's
  !> mass; kinematic ends are not states: zero).  Kept when CVODE allows it
  !> (`reuse_ok`) and every segment is still as slack or taut as when they were
  !> formed (the tensions of the right-hand side CVODE has just evaluated at y);
  !> a switch changes the Jacobian discretely and old blocks would make Newton
  !> fail (docs/line.md section 2, "Jacobian refresh").  No allocation.
  subroutine system_node_jacobian(self, t, y, reuse_ok, blk, fresh, status)
    class(line_system), intent(inout) :: self   !< system
    real(dp), intent(in) :: t                   !< time [s]
    real(dp), intent(in) :: y(:)                !< state
    logical, intent(in) :: reuse_ok             !< CVODE allows the last blocks
    type(node_blocks), intent(inout) :: blk     !< the blocks, for nodes first..last (1..last - first + 1)
    logical, intent(out) :: fresh               !< evaluated now
    integer, intent(out) :: status              !< rhs_ok
    status = rhs_ok
    fresh = .not. self%jac_blocks%still_valid(reuse_ok, self%tension)
    if (.not. fresh) return
    call self%force_blocks(t, y)
    call self%jac_blocks%to_node_blocks(self%mass%inv_diagonal, self%first, self%last, blk)
    blk%mass_coupled = .not. self%mass%is_lumped()
    if (blk%mass_coupled) call mass_blocks(self%mass, self%first, self%last, blk)
  end subroutine system_node_jacobian

  !> The node blocks' scaled mass coupling M(k, k + d)/M(k, k) of the state
  !> nodes first..last (the force blocks are already over M(k, k)).
  pure subroutine mass_blocks(mass, first, last, blk)
    type(line_mass_matrix), intent(in) :: mass   !< the mass matrix
    integer, intent(in) :: first, last           !< state nodes
    type(node_blocks), intent(inout) :: blk      !< the blocks
    integer :: k
    do k = first, last
      blk%mass(-1, k - first + 1) = mass%scaled_coupling(k, -1)
      blk%mass(0, k - first + 1) = 1.0_dp
      blk%mass(1, k - first + 1) = mass%scaled_coupling(k, 1)
    end do
  end subroutine mass_blocks

  !> Room for the blocks of a line of n segments; nothing formed yet.
  subroutine force_jacobian_allocate(self, n)
    class(line_force_jacobian), intent(inout) :: self   !< the Jacobian
    integer, intent(in) :: n                            !< segments
    if (allocated(self%dfdx)) deallocate(self%dfdx, self%dfdv, self%taut)
    allocate(self%dfdx(3, 3, -1:1, 0:n), self%dfdv(3, 3, -1:1, 0:n), self%taut(n))
    self%taut = .false.
    self%formed = .false.
  end subroutine force_jacobian_allocate

  !> The line's force blocks at x, v (line_model%force_jacobian) and the pattern
  !> of taut segments they hold for (`tension`: the forces' at the same state).
  !> No allocation.
  subroutine force_jacobian_form(self, model, x, v, tension)
    class(line_force_jacobian), intent(inout) :: self   !< the Jacobian
    type(line_model), intent(in) :: model               !< the line
    real(dp), intent(in) :: x(:, 0:), v(:, 0:)          !< node positions, velocities (3, 0:N)
    real(dp), intent(in) :: tension(:)                  !< segment tensions at x, v (N) [N]
    call model%force_jacobian(x, v, self%dfdx, self%dfdv)
    self%taut = tension > 0.0_dp
    self%formed = .true.
  end subroutine force_jacobian_form

  !> True if the blocks may be kept: the solver allows it (`reuse_ok`), they have
  !> been formed, and every segment is as slack or taut (`tension`, now) as then.
  pure logical function force_jacobian_still_valid(self, reuse_ok, tension) result(ok)
    class(line_force_jacobian), intent(in) :: self   !< the Jacobian
    logical, intent(in) :: reuse_ok                  !< the solver allows the last blocks
    real(dp), intent(in) :: tension(:)               !< segment tensions now (N) [N]
    ok = reuse_ok .and. self%formed
    if (ok) ok = .not. any((tension > 0.0_dp) .neqv. self%taut)
  end function force_jacobian_still_valid

  !> Node blocks of the state nodes first..last (blk's nodes 1..last - first + 1):
  !> d a_k / d x = dfdx / m_k and d a_k / d v = dfdv / m_k, with inv_mass(k) =
  !> 1/m_k the node's whole mass (end bodies lumped); neighbours outside
  !> first..last are not states: zero blocks.  No allocation.
  pure subroutine force_jacobian_to_node_blocks(self, inv_mass, first, last, blk)
    class(line_force_jacobian), intent(in) :: self   !< the Jacobian
    real(dp), intent(in) :: inv_mass(0:)             !< 1/(node mass) (0:N) [1/kg]
    integer, intent(in) :: first, last               !< state nodes
    type(node_blocks), intent(inout) :: blk          !< the blocks
    integer :: k, d, j
    do k = first, last
      j = k - first + 1
      do d = -1, 1
        if (k + d < first .or. k + d > last) then
          blk%ax(:, :, d, j) = 0.0_dp
          blk%av(:, :, d, j) = 0.0_dp
        else
          blk%ax(:, :, d, j) = inv_mass(k)*self%dfdx(:, :, d, k)
          blk%av(:, :, d, j) = inv_mass(k)*self%dfdv(:, :, d, k)
        end if
      end do
    end do
  end subroutine force_jacobian_to_node_blocks

  !> Mechanical energy of line and point-mass ends at time t, state y [J]:
  !> kinetic (a canopy end's apparent mass moving with it) + elastic + gravitational
  !> (the work of kinematic ends is not in it).
  function system_energy(self, t, y) result(e)
    class(line_system), intent(inout) :: self   !< system
    real(dp), intent(in) :: t                   !< time [s]
    real(dp), intent(in) :: y(:)                !< state
    type(line_energy) :: e
    integer :: i, k
    real(dp) :: ek(2)
    call self%unpack(t, y)
    e = self%model%energy(self%x, self%v)
    do i = 1, 2
      k = merge(0, self%model%n, i == 1)
      ek = self%ends(i)%energy(t, self%x(:, k), self%v(:, k), self%model%p%gravity, self%model%p%air, &
        self%model%p%air_density)
      e%kinetic = e%kinetic + ek(1)
      e%potential = e%potential + ek(2)
    end do
  end function system_energy

  !> CVODE's Newton convergence coefficient for a line: 0.1 (CVODE's default) up
  !> to rtol = 1e-4, then 0.1 x 1e-4/rtol, so that the Newton iteration is never
  !> stopped further from the implicit solution than at rtol = 1e-4.  A line's
  !> stiff axial springs turn an unconverged node position into a large force
  !> error: with CVODE's 0.1 at rtol 1e-3 and 1e-2, a slack line (the cable
  !> pendulum, N >= 60) gained energy (up to 81 kJ in a passive system), its
  !> peak tension came out 1.5-15 times too high and the steps multiplied
  !> (162 834 instead of 1 893); at rtol <= 1e-4 the tighter test only costs
  !> time (docs/line.md section 2, "Newton's convergence test").
  pure function line_newton_coefficient(rtol) result(c)
    real(dp), intent(in) :: rtol   !< relative tolerance
    real(dp) :: c
    c = 0.1_dp
    if (rtol > 1.0e-4_dp) c = 0.1_dp*1.0e-4_dp/rtol
  end function line_newton_coefficient

  !> Create the default scheme from the initial node state x0, v0 at time t0.
  subroutine new_line_cvode(scheme, model, end_a, end_b, x0, v0, t0, opts, error)
    type(line_cvode), intent(inout) :: scheme               !< the scheme (re-initialised)
    type(line_model), intent(in) :: model                   !< the line
    type(line_end), intent(in) :: end_a, end_b              !< ends at node 0 and node N
    real(dp), intent(in) :: x0(:, 0:), v0(:, 0:)            !< initial node state
    real(dp), intent(in) :: t0                              !< initial time [s]
    type(line_scheme_options), intent(in) :: opts           !< tolerances
    type(error_type), allocatable, intent(inout) :: error   !< set on failure
    real(dp), allocatable :: y0(:)
    call scheme%free()
    if (model%mass_coupling > 0.0_dp .and. .not. opts%analytic_jacobian) then
      call fatal_error(error, "line (cvode): the mixed mass matrix needs the analytic Jacobian (its Newton " // &
        "matrix is banded only when multiplied by the mass matrix; difference quotients over the band would " // &
        "be wrong): use mass = 'lumped' or analytic_jacobian = .true.")
      return
    end if
    allocate(scheme%sys)
    call scheme%sys%setup(model, end_a, end_b, error)
    if (allocated(error)) return
    scheme%t = t0
    scheme%sys%x = x0
    scheme%sys%v = v0
    scheme%opts = cvode_options(method="bdf", linear_solver="second_order_band", upper_bandwidth=line_band_upper, &
      lower_bandwidth=line_band_lower, rtol=opts%rtol, atol=opts%atol, max_step=opts%max_step, &
      max_order=opts%max_order, max_num_steps=1000000, max_total_steps=opts%max_steps, &
      max_wall_time=opts%max_wall_time, wall_deadline=opts%wall_deadline, &
      analytic_jacobian=opts%analytic_jacobian, t_final=opts%t_final, &
      newton_coefficient=line_newton_coefficient(opts%rtol))
    if (opts%peak_tension) call scheme%start_peak(opts%rtol)
    if (scheme%sys%n_state() == 0) return   ! one segment between two kinematic ends
    if (opts%peak_tension) then
      scheme%observer = tension_observer(trk=scheme%peak, sys=scheme%sys, needs_rate=.false.)
      allocate(scheme%observer%tension(model%n))
    end if
    allocate(y0(scheme%sys%n_state()))
    call scheme%sys%pack(x0, v0, y0)
    call scheme%solver%init(scheme%sys, t0, y0, scheme%opts, error)
  end subroutine new_line_cvode

  !> Integrate to t_out.
  subroutine cvode_advance(self, t_out, error)
    class(line_cvode), intent(inout) :: self               !< scheme
    real(dp), intent(in) :: t_out                          !< output time [s]
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    logical :: event
    integer :: which(2)
    if (self%sys%n_state() == 0) then
      ! (no CVODE to stop: the stop time set last, if it lies ahead, ends the step)
      if (self%stateless_stop > self%t .and. self%stateless_stop < t_out) then
        self%t = self%stateless_stop
      else
        self%t = t_out
      end if
      return
    end if
    if (associated(self%peak)) then
      call self%solver%advance(t_out, error, event, which, observer=self%observer)
    else
      call self%solver%advance(t_out, error, event, which)
    end if
    ! (the strength's event comes first when both are watched: system_nroots;
    ! Fortran does not short-circuit .and.: the indices are guarded apart)
    self%strength_reached = .false.
    self%ground_reached = .false.
    if (event) then
      if (allocated(self%sys%strength)) self%strength_reached = which(1) /= 0
      if (self%sys%has_ground()) self%ground_reached = which(self%sys%nroots()) < 0
    end if
    self%t = self%solver%t
    if (allocated(error)) error%message = "line (cvode): " // error%message
  end subroutine cvode_advance

  !> The peak tension so far (airlaunch_line_scheme), the open sequence of
  !> steps closed first (a maximum at its end refined).
  function cvode_peak_tension(self, t_peak) result(tmax)
    class(line_cvode), intent(inout) :: self   !< scheme
    real(dp), intent(out) :: t_peak            !< its time [s]
    real(dp) :: tmax
    if (associated(self%observer%trk)) call self%observer%finish()
    call self%note_peak_segment(self%observer%seen, self%observer%segment)
    tmax = scheme_peak_tension(self, t_peak)
  end function cvode_peak_tension

  !> The largest segment tension at time t from the interpolated state.
  subroutine tension_values(self, t, q, ok)
    class(tension_observer), intent(inout) :: self
    real(dp), intent(in) :: t
    real(dp), intent(out) :: q(:)
    logical, intent(out) :: ok
    integer :: st, k
    call self%sys%unpack(t, self%y)
    call self%sys%model%tensions(self%sys%x, self%sys%v, self%tension, st)
    ok = st == 0
    if (.not. ok) return
    k = maxloc(self%tension, 1)
    q(1) = self%tension(k)
    if (q(1) > self%seen) then
      self%seen = q(1)
      self%segment = k
    end if
  end subroutine tension_values

  !> Node state at the current time.
  subroutine cvode_get_state(self, x, v)
    class(line_cvode), intent(inout) :: self   !< scheme
    real(dp), intent(out) :: x(:, 0:), v(:, 0:)
    if (self%sys%n_state() > 0) then
      call self%sys%unpack(self%t, self%solver%y)
    else
      call self%sys%unpack(self%t, [real(dp) ::])
    end if
    x = self%sys%x
    v = self%sys%v
  end subroutine cvode_get_state

  !> Work counters.
  function cvode_scheme_stats(self) result(s)
    class(line_cvode), intent(in) :: self   !< scheme
    type(line_scheme_stats) :: s
    type(cvode_stats) :: c
    if (.not. associated(self%sys)) return
    s%rhs_evals = self%sys%n_forces
    if (self%sys%n_state() == 0) return
    c = self%solver%stats()
    s%steps = c%steps
    s%jac_evals = c%jac_evals
    s%failures = c%err_test_fails + c%nonlin_fails
  end function cvode_scheme_stats

  !> Make end `which` a body end with the owner's samples and restart CVODE
  !> there (the end motion may change its derivative at t1).
  subroutine cvode_set_body_motion(self, which, t1, x1, v1, t2, x2, v2, error)
    class(line_cvode), intent(inout) :: self               !< scheme
    integer, intent(in) :: which                           !< 1 = node 0, 2 = node N
    real(dp), intent(in) :: t1, t2, x1(3), v1(3), x2(3), v2(3)
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    real(dp), allocatable :: y(:)
    if (which < 1 .or. which > 2) then
      call fatal_error(error, "line: end index " // str(which) // " is not allowed: 1 (node 0) or 2 (node N)")
      return
    end if
    if (.not. self%sys%ends(which)%is_kinematic()) then
      call fatal_error(error, "line: end " // str(which) // " is not kinematic: a body end must be " // &
        "declared kinematic (body) when the scheme is built")
      return
    end if
    call self%sys%ends(which)%set_body_motion(t1, x1, v1, t2, x2, v2)
    if (self%sys%n_state() == 0) return
    y = self%solver%y
    call self%solver%reinit(self%t, y, error)
  end subroutine cvode_set_body_motion

  !> Do not step past t_stop.
  subroutine cvode_set_stop_time(self, t_stop, error)
    class(line_cvode), intent(inout) :: self               !< scheme
    real(dp), intent(in) :: t_stop                         !< stop time [s]
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    if (self%sys%n_state() == 0) then
      self%stateless_stop = t_stop
      return
    end if
    call self%solver%set_stop_time(t_stop, error)
  end subroutine cvode_set_stop_time

  !> The canopy at end `which` deploys now and fills in `fill_time`: CVODE
  !> restarts here (the drag area's growth starts with a kink for j < 2).
  subroutine cvode_set_fill_time(self, which, fill_time, error)
    class(line_cvode), intent(inout) :: self               !< scheme
    integer, intent(in) :: which                           !< 1 = node 0, 2 = node N
    real(dp), intent(in) :: fill_time                      !< filling time [s]
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    real(dp), allocatable :: y(:)
    call check_fill_target(self%sys%ends, which, fill_time, error)
    if (allocated(error)) return
    self%sys%ends(which)%canopy%fill_time = fill_time
    y = self%solver%y
    call self%solver%reinit(self%t, y, error)
  end subroutine cvode_set_fill_time

  !> Segment j parts at tension strength(j): CVODE watches the smallest
  !> margin as its event (system_roots) and advance stops there
  !> (strength_reached).
  subroutine cvode_set_strength(self, strength, error)
    class(line_cvode), intent(inout) :: self               !< scheme
    real(dp), intent(in) :: strength(:)                    !< per segment [N]
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    if (size(strength) /= self%sys%model%n) then
      call fatal_error(error, "line: " // str(size(strength)) // " segment strengths given for a line of " // &
        str(self%sys%model%n) // " segments")
      return
    end if
    self%sys%strength = strength
    self%sys%root_tension = strength   ! (work: the shape)
    if (self%sys%n_state() == 0) return
    call self%solver%set_roots(self%sys%nroots(), error)
  end subroutine cvode_set_strength

  !> The run ends where the lowest state node reaches the altitude `ground`:
  !> CVODE watches its height above it (system_roots) and advance stops there
  !> (ground_reached).  A line with no state has nothing to watch.
  subroutine cvode_set_ground(self, ground, error)
    class(line_cvode), intent(inout) :: self               !< scheme
    real(dp), intent(in) :: ground                         !< [m]
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    self%sys%ground = ground
    if (self%sys%n_state() == 0) return
    call self%solver%set_roots(self%sys%nroots(), error)
  end subroutine cvode_set_ground

  !> Segment k parts now: CVODE restarts here, the forces having jumped
  !> (nothing if it has parted already).
  subroutine cvode_part(self, k, error)
    class(line_cvode), intent(inout) :: self               !< scheme
    integer, intent(in) :: k                               !< segment 1..N
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    real(dp), allocatable :: y(:)
    if (k < 1 .or. k > self%sys%model%n) then
      call fatal_error(error, "line: segment " // str(k) // " cannot part: the line has segments 1.." // &
        str(self%sys%model%n))
      return
    end if
    self%strength_reached = .false.
    if (self%sys%model%parted(k)) return
    call self%sys%model%part(k)
    if (self%sys%n_state() == 0) return
    y = self%solver%y
    call self%solver%reinit(self%t, y, error)
  end subroutine cvode_part

  !> Release CVODE and the system.
  subroutine cvode_free(self)
    class(line_cvode), intent(inout) :: self   !< scheme
    call self%solver%free()
    if (associated(self%sys)) deallocate(self%sys)
    nullify(self%sys)
    self%observer = tension_observer()
    call self%release_peak()
  end subroutine cvode_free
end module airlaunch_line_cvode
