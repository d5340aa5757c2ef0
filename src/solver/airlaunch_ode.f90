!> The abstract ODE system every integrated scene implements (Neko-style
!> deferred bindings).  The solver (airlaunch_cvode) only sees this interface.
module airlaunch_ode
  use airlaunch_kinds, only: dp
  implicit none
  private
  public :: ode_system, rhs_ok, rhs_recoverable, rhs_fatal

  !> Status codes of a right-hand side, as SUNDIALS reads them.
  integer, parameter :: rhs_ok = 0           !< derivative computed
  integer, parameter :: rhs_recoverable = 1  !< retry with a smaller step
  integer, parameter :: rhs_fatal = -1       !< stop: `failure` says why

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
  end type ode_system

  abstract interface
    !> Derivative ydot = f(t, y); status one of rhs_ok, rhs_recoverable, rhs_fatal.
    subroutine rhs_interface(self, t, y, ydot, status)
      import :: ode_system, dp
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
end module airlaunch_ode
