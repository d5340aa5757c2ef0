!> The CVODE wrapper on problems with closed-form solutions: a harmonic
!> oscillator (dense, band and fixed-point solvers), an event located at the
!> analytic crossing, and a failing right-hand side reported with its time.
module oscillator_system
  use airlaunch_kinds, only: dp
  use airlaunch_ode, only: ode_system, rhs_ok, rhs_fatal
  implicit none
  private
  public :: oscillator

  !> x'' = -w^2 x as [x, v]; event at x = 0; fails after t_fail if set.
  type, extends(ode_system) :: oscillator
    real(dp) :: omega = 2.0_dp
    real(dp) :: t_fail = huge(1.0_dp)
  contains
    procedure :: rhs
    procedure :: nroots
    procedure :: roots
  end type oscillator
contains
  subroutine rhs(self, t, y, ydot, status)
    class(oscillator), intent(inout) :: self
    real(dp), intent(in) :: t, y(:)
    real(dp), intent(out) :: ydot(:)
    integer, intent(out) :: status
    ydot = [y(2), -self%omega**2*y(1)]
    status = rhs_ok
    if (t > self%t_fail) then
      self%failure = "test quantity became invalid"
      status = rhs_fatal
    end if
  end subroutine rhs
  integer function nroots(self)
    class(oscillator), intent(in) :: self
    nroots = 1
    if (self%omega < 0) nroots = 1
  end function nroots
  subroutine roots(self, t, y, g, status)
    class(oscillator), intent(inout) :: self
    real(dp), intent(in) :: t, y(:)
    real(dp), intent(out) :: g(:)
    integer, intent(out) :: status
    g(1) = y(1)
    status = rhs_ok
    if (t < 0 .and. self%omega < 0) status = rhs_ok
  end subroutine roots
end module oscillator_system

program test_cvode
  use airlaunch_kinds, only: dp, pi
  use airlaunch_error, only: error_type
  use airlaunch_cvode
  use oscillator_system
  use testing
  implicit none
  type(oscillator), target :: osc
  type(cvode_solver) :: solver
  type(cvode_options) :: opts
  type(error_type), allocatable :: error
  character(len=16), parameter :: solvers(4) = [character(len=16) :: "dense", "band", "sundials_band", "none"]
  character(len=8), parameter :: methods(4) = [character(len=8) :: "bdf", "bdf", "bdf", "adams"]
  logical :: event
  integer :: which(1), k

  do k = 1, 4
    call section("oscillator, " // trim(methods(k)) // " + " // trim(solvers(k)))
    opts = cvode_options(method=methods(k), linear_solver=solvers(k), upper_bandwidth=1, &
      lower_bandwidth=1, rtol=1e-10_dp, atol=1e-12_dp)
    call solver%init(osc, 0.0_dp, [1.0_dp, 0.0_dp], opts, error)
    call check(.not. allocated(error), "init")
    call solver%set_roots(0, error)
    call solver%advance(3.0_dp, error)
    call check(.not. allocated(error), "advance")
    ! tolerance 1e-10 relative per step, ~ a few hundred steps: 1e-7 bounds the global error
    call check_close(solver%y(1), cos(2*3.0_dp), "x(3) = cos(6)", abs=1e-7_dp)
    call check_close(solver%y(2), -2*sin(2*3.0_dp), "v(3) = -2 sin(6)", abs=2e-7_dp)
    call solver%free()
  end do

  call section("event location")
  opts = cvode_options(rtol=1e-10_dp, atol=1e-12_dp)
  call solver%init(osc, 0.0_dp, [1.0_dp, 0.0_dp], opts, error)
  call solver%advance(2.0_dp, error, event, which)
  call check(event .and. which(1) == -1, "x crosses zero downwards")
  call check_close(solver%t, pi/4, "first zero of cos(2t) at pi/4", abs=1e-8_dp)
  call solver%reinit(solver%t, solver%y, error)
  call solver%advance(3.0_dp, error, event, which)
  call check(event .and. which(1) == 1, "then upwards")
  call check_close(solver%t, 3*pi/4, "second zero at 3 pi/4", abs=1e-8_dp)
  call solver%free()

  call section("failure is reported with time and quantity")
  osc%t_fail = 0.5_dp
  call solver%init(osc, 0.0_dp, [1.0_dp, 0.0_dp], opts, error)
  call solver%set_roots(0, error)
  call solver%advance(2.0_dp, error)
  call check(allocated(error), "a fatal right-hand side stops the integration")
  if (allocated(error)) then
    call check(index(error%message, "test quantity became invalid") > 0 .and. &
      index(error%message, "t = ") > 0, "message: " // error%message)
    deallocate(error)
  end if
  ! a second failure of the same solver replaces the kept SUNDIALS message
  call solver%advance(2.0_dp, error)
  call check(allocated(error), "a second failure is reported too")
  call solver%free()
  call finish()
end program test_cvode
