!> The abstract ODE system every integrated scene implements (Neko-style
!> deferred bindings).  The solver (airlaunch_cvode) only sees this interface.
module airlaunch_ode
  use airlaunch_kinds, only: dp
  implicit none
  private
  public :: ode_system, band_view, node_blocks, rhs_ok, rhs_recoverable, rhs_fatal

  !> Status codes of a right-hand side, as SUNDIALS reads them.
  integer, parameter :: rhs_ok = 0           !< derivative computed
  integer, parameter :: rhs_recoverable = 1  !< retry with a smaller step
  integer, parameter :: rhs_fatal = -1       !< stop: `failure` says why

  !> Write access to a band matrix in SUNDIALS' (= LAPACK's) column storage:
  !> A(i, j) at ab((j - 1) ldim + smu + i - j + 1), smu rows above the diagonal.
  !> Filled by a system's analytic Jacobian (the solver zeroes it first).
  type :: band_view
    real(dp), pointer :: ab(:) => null()   !< the storage, column by column
    integer :: ldim = 0                    !< leading dimension (rows stored per column)
    integer :: smu = 0                     !< stored upper bandwidth
    integer :: mu = 0                      !< upper bandwidth of the structure
    integer :: ml = 0                      !< lower bandwidth of the structure
  contains
    procedure :: set => band_view_set
    procedure :: set_block => band_view_set_block
  end type band_view

  !> The Jacobian of a second-order system stored node by node (three positions,
  !> then three velocities per node, x' = v): for node j and neighbour d = -1, 0, 1
  !> the 3x3 blocks d a_j / d x_(j+d) and d a_j / d v_(j+d) of the accelerations,
  !> and CVODE's gamma of the Newton matrix I - gamma J they stand for.  Filled by
  !> the system (`node_jacobian`), read by the velocity-reduced band solver
  !> (airlaunch_lapack_band) without a band matrix in between.
  type :: node_blocks
    real(dp), allocatable :: ax(:, :, :, :)   !< (3, 3, -1:1, nodes) d a_j / d x_(j+d) [1/s^2]
    real(dp), allocatable :: av(:, :, :, :)   !< (3, 3, -1:1, nodes) d a_j / d v_(j+d) [1/s]
    real(dp) :: gamma = 0.0_dp                !< of the Newton matrix I - gamma J [s]
    !> A non-diagonal mass matrix M (the accelerations solve M a = f, f the
    !> forces): then ax, av are the force blocks over M's diagonal, D^-1 df/dx
    !> and D^-1 df/dv, and mass(d, j) = M(j, j + d)/M(j, j) (times I3, d = -1, 1;
    !> 0 where j + d is not a state node) - the Newton matrix's velocity rows
    !> scaled by D^-1 M (docs/line.md section 2).  Not coupled: M diagonal, and
    !> ax, av are the accelerations' derivatives.
    logical :: mass_coupled = .false.
    real(dp), allocatable :: mass(:, :)       !< (-1:1, nodes) M(j, j + d)/M(j, j)
  end type node_blocks

  !> A first-order system y' = f(t, y) with optional event functions g(t, y).
  type, abstract :: ode_system
    !> Set by rhs/roots before returning rhs_fatal: the quantity that failed.
    character(len=:), allocatable :: failure
  contains
    procedure(rhs_interface), deferred :: rhs
    procedure :: nroots => ode_nroots
    procedure :: roots => ode_roots
    procedure :: has_projection => ode_has_projection
    procedure :: project => ode_project
    procedure :: has_jacobian => ode_has_jacobian
    procedure :: jacobian => ode_jacobian
    procedure :: has_node_jacobian => ode_has_node_jacobian
    procedure :: node_jacobian => ode_node_jacobian
    procedure :: velocity_partners => ode_velocity_partners
    procedure :: state_name => ode_state_name
  end type ode_system

  abstract interface
    !> Derivative ydot = f(t, y); status one of rhs_ok, rhs_recoverable, rhs_fatal.
    subroutine rhs_interface(self, t, y, ydot, status)
      import :: ode_system, dp
      implicit none
      class(ode_system), intent(inout) :: self
      real(dp), intent(in) :: t
      real(dp), intent(in) :: y(:)
      real(dp), intent(out) :: ydot(:)
      integer, intent(out) :: status
    end subroutine rhs_interface
  end interface

contains

  !> Number of event functions (default: none).
  integer function ode_nroots(self)
    class(ode_system), intent(in) :: self   !< the system
    ode_nroots = 0
    if (.false.) ode_nroots = len(self%failure)
  end function ode_nroots

  !> Event functions g(t, y); an event is a sign change of a component.
  subroutine ode_roots(self, t, y, g, status)
    class(ode_system), intent(inout) :: self  !< the system
    real(dp), intent(in) :: t                 !< time [s]
    real(dp), intent(in) :: y(:)              !< state
    real(dp), intent(out) :: g(:)             !< event functions
    integer, intent(out) :: status            !< rhs_ok or rhs_fatal
    g = 0.0_dp
    status = rhs_ok
    if (.false.) g = t + y(1) + len(self%failure)
  end subroutine ode_roots

  !> True if the system projects its state onto an invariant manifold after
  !> each step (e.g. unit quaternions); the solver then installs `project`.
  logical function ode_has_projection(self)
    class(ode_system), intent(in) :: self   !< the system
    ode_has_projection = .false.
    if (.false.) ode_has_projection = allocated(self%failure)
  end function ode_has_projection

  !> Projection: y is replaced by the nearest state on the manifold (default:
  !> unchanged).  Called by CVODE after each step when has_projection is true.
  subroutine ode_project(self, t, y, status)
    class(ode_system), intent(inout) :: self  !< the system
    real(dp), intent(in) :: t                 !< time [s]
    real(dp), intent(inout) :: y(:)           !< state, projected in place
    integer, intent(out) :: status            !< rhs_ok or rhs_fatal
    status = rhs_ok
    if (.false.) y(1) = t + len(self%failure)
  end subroutine ode_project

  !> A(i, j) = value (i - j within the stored band: the caller's structure).
  pure subroutine band_view_set(self, i, j, value)
    class(band_view), intent(inout) :: self   !< the matrix
    integer, intent(in) :: i, j               !< row, column (1-based)
    real(dp), intent(in) :: value             !< entry
    self%ab((j - 1)*self%ldim + self%smu + i - j + 1) = value
  end subroutine band_view_set

  !> A(i0+1:i0+m, j0+1:j0+n) = scale * a, a column slice of the storage per
  !> column (every entry within the stored band: the caller's structure).
  pure subroutine band_view_set_block(self, i0, j0, scale, a)
    class(band_view), intent(inout) :: self   !< the matrix
    integer, intent(in) :: i0, j0             !< row and column before the block
    real(dp), intent(in) :: scale             !< factor
    real(dp), intent(in) :: a(:, :)           !< the block
    integer :: q, base
    do q = 1, size(a, 2)
      base = (j0 + q - 1)*self%ldim + self%smu + i0 - (j0 + q) + 1
      self%ab(base + 1:base + size(a, 1)) = scale*a(:, q)
    end do
  end subroutine band_view_set_block

  !> True if the system provides an analytic band Jacobian (`jacobian`); the
  !> solver then uses it instead of difference quotients.
  logical function ode_has_jacobian(self)
    class(ode_system), intent(in) :: self   !< the system
    ode_has_jacobian = .false.
    if (.false.) ode_has_jacobian = allocated(self%failure)
  end function ode_has_jacobian

  !> The Jacobian df/dy at (t, y) into the zeroed band matrix `jac` (default: none).
  subroutine ode_jacobian(self, t, y, jac, status)
    class(ode_system), intent(inout) :: self  !< the system
    real(dp), intent(in) :: t                 !< time [s]
    real(dp), intent(in) :: y(:)              !< state
    type(band_view), intent(inout) :: jac     !< the matrix, zeroed by the solver
    integer, intent(out) :: status            !< rhs_ok, rhs_recoverable or rhs_fatal
    status = rhs_fatal
    self%failure = "the system has no analytic Jacobian"
    if (.false.) jac%ldim = int(t + y(1))
  end subroutine ode_jacobian

  !> True if the system is second order, stored node by node, and provides its
  !> Jacobian as node blocks (`node_jacobian`); the velocity-reduced band solver
  !> then reads them directly.
  logical function ode_has_node_jacobian(self)
    class(ode_system), intent(in) :: self   !< the system
    ode_has_node_jacobian = .false.
    if (.false.) ode_has_node_jacobian = allocated(self%failure)
  end function ode_has_node_jacobian

  !> The Jacobian's node blocks at (t, y) into `blk` (its ax and av; the solver
  !> sets gamma).  With `reuse_ok` (CVODE judges the last Jacobian young enough)
  !> the system may keep the blocks of its last evaluation if it knows them to be
  !> still valid; `fresh` says whether it evaluated them.  Default: none.
  subroutine ode_node_jacobian(self, t, y, reuse_ok, blk, fresh, status)
    class(ode_system), intent(inout) :: self  !< the system
    real(dp), intent(in) :: t                 !< time [s]
    real(dp), intent(in) :: y(:)              !< state
    logical, intent(in) :: reuse_ok           !< the last blocks may be kept
    type(node_blocks), intent(inout) :: blk   !< the blocks
    logical, intent(out) :: fresh             !< evaluated now
    integer, intent(out) :: status            !< rhs_ok, rhs_recoverable or rhs_fatal
    fresh = .false.
    status = rhs_fatal
    self%failure = "the system has no node-block Jacobian"
    if (.false.) blk%gamma = t + y(1) + merge(1, 0, reuse_ok)
  end subroutine ode_node_jacobian

  !> The states that are positions with x' = v exactly (v another state, not a
  !> position itself): partner(i) = the index of v for such a state i, 0 for
  !> every other state.  Read once by the position-reduced band solver, which
  !> eliminates them from Newton's system.  Default: none.
  subroutine ode_velocity_partners(self, partner)
    class(ode_system), intent(in) :: self     !< the system
    integer, intent(out) :: partner(:)        !< (number of states)
    partner = 0
    if (.false.) partner(1) = len(self%failure)
  end subroutine ode_velocity_partners

  !> What state i is, for messages (e.g. "rocket velocity y"); default "state i".
  function ode_state_name(self, i) result(name)
    class(ode_system), intent(in) :: self     !< the system
    integer, intent(in) :: i                  !< state index
    character(len=:), allocatable :: name
    character(len=16) :: buf
    write(buf, '(i0)') i
    name = "state " // trim(buf)
    if (.false.) name = name // self%failure
  end function ode_state_name
end module airlaunch_ode
