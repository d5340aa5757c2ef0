!> Pluggable applied loads (the R of Eqs. (60)-(61) and the F0, M0 of (47)-(48)).
!>
!> A force source adds forces and moments to some of the bodies of a scene.  The
!> bodies are numbered as in the paper: 0 aircraft, 1 rocket, 2 line (virtual
!> rigid body), 3 parachute (or whatever the chain holds).  Every source sees the
!> current state of ALL bodies, so one-body loads (gravity, aerodynamics, thrust)
!> and interactions (a line or winch between two bodies) share one interface.
!>
!> Conventions of `add_loads` (accumulate, never overwrite):
!>   force(:, i)   force on body i acting at its CG, EARTH frame [N]
!>   moment(:, i)  moment on body i about its CG, BODY axes of body i [N m]
!> A force acting at a body point p (body axes) adds C^T F x ... via `add_point_force`.
!>
!> To add a source, extend `force_source`, implement `add_loads`, and hand an
!> instance to the scene (`separation_system%add_source`).  A source must not
!> allocate or print; on failure it sets `error` (the scene reports the phase and time).
module airlaunch_force_source
  use airlaunch_kinds, only: dp, g0
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_rigid_body, only: rigid_body, cross
  implicit none
  private
  public :: force_source, force_source_slot, add_point_force
  public :: gravity_source, constant_load_source, pair_force_source

  !> An applied-load model.
  type, abstract :: force_source
  contains
    procedure(add_loads_interface), deferred :: add_loads
  end type force_source

  abstract interface
    !> Add this source's loads on the bodies (see the module header for frames).
    subroutine add_loads_interface(self, t, bodies, force, moment, error)
      import :: force_source, rigid_body, dp, error_type
      implicit none
      class(force_source), intent(inout) :: self            !< the source
      real(dp), intent(in) :: t                             !< time [s]
      type(rigid_body), intent(in) :: bodies(0:)            !< all bodies of the scene, paper numbering
      real(dp), intent(inout) :: force(:, 0:)               !< (3, 0:n) CG forces, earth [N]
      real(dp), intent(inout) :: moment(:, 0:)              !< (3, 0:n) moments about CG, body [N m]
      type(error_type), allocatable, intent(inout) :: error !< set on failure
    end subroutine add_loads_interface
  end interface

  !> Holder so a scene can keep a list of polymorphic sources.
  type :: force_source_slot
    class(force_source), allocatable :: source   !< the source
  end type force_source_slot

  !> Uniform gravity m g on every body (g in the earth frame, default 9.80665 m/s^2 down).
  type, extends(force_source) :: gravity_source
    real(dp) :: g(3) = [0.0_dp, -g0, 0.0_dp]   !< gravitational acceleration, earth [m/s^2]
    integer :: first = 0                      !< first body it acts on
    integer :: last = huge(1)                 !< last body it acts on (clipped to the scene)
  contains
    procedure :: add_loads => gravity_add_loads
  end type gravity_source

  !> A constant load on one body: a force (earth axes, or body axes if
  !> `body_axes_force`) acting at a body point, plus a constant body-axis moment.
  type, extends(force_source) :: constant_load_source
    integer :: body = 1                         !< body index (paper numbering)
    real(dp) :: force(3) = 0.0_dp               !< force [N]
    logical :: body_axes_force = .false.        !< force given in body axes (turns with the body)
    real(dp) :: point(3) = 0.0_dp               !< application point, body axes from the CG [m]
    real(dp) :: moment(3) = 0.0_dp              !< pure moment, body axes [N m]
  contains
    procedure :: add_loads => constant_add_loads
  end type constant_load_source

  !> An internal pull of constant magnitude between two bodies (a winch): the
  !> force `magnitude * C_a direction` acts on body b at point_b and its reaction on
  !> body a at point_a.  With `central`, the direction is instead the line from
  !> point_b to point_a (attraction for magnitude > 0; potential magnitude * distance).
  !> Total momentum is conserved; angular momentum too when the two points lie on
  !> the line of action (always for `central`).
  type, extends(force_source) :: pair_force_source
    integer :: body_a = 0                       !< reacting body (e.g. aircraft)
    integer :: body_b = 1                       !< pulled body (e.g. rocket)
    real(dp) :: magnitude = 0.0_dp              !< pull [N]
    real(dp) :: direction(3) = [-1.0_dp, 0.0_dp, 0.0_dp] !< unit direction in body-a axes
    real(dp) :: point_a(3) = 0.0_dp             !< reaction point, body-a axes [m]
    real(dp) :: point_b(3) = 0.0_dp             !< application point, body-b axes [m]
    logical :: central = .false.                !< act along the line joining the two points
  contains
    procedure :: add_loads => pair_add_loads
  end type pair_force_source

contains

  !> Add a force F (earth) acting at body point p (body axes) to body i's loads.
  pure subroutine add_point_force(body, p, f, force, moment)
    type(rigid_body), intent(in) :: body   !< the body
    real(dp), intent(in) :: p(3)           !< application point, body axes from the CG [m]
    real(dp), intent(in) :: f(3)           !< force, earth [N]
    real(dp), intent(inout) :: force(3)    !< the body's CG force, earth [N]
    real(dp), intent(inout) :: moment(3)   !< the body's moment about the CG, body [N m]
    force = force + f
    moment = moment + cross(p, matmul(transpose(body%c), f))
  end subroutine add_point_force

  subroutine gravity_add_loads(self, t, bodies, force, moment, error)
    class(gravity_source), intent(inout) :: self
    real(dp), intent(in) :: t
    type(rigid_body), intent(in) :: bodies(0:)
    real(dp), intent(inout) :: force(:, 0:)
    real(dp), intent(inout) :: moment(:, 0:)
    type(error_type), allocatable, intent(inout) :: error
    integer :: i
    do i = max(self%first, 0), min(self%last, ubound(bodies, 1))
      force(:, i) = force(:, i) + bodies(i)%mass*self%g
    end do
    if (.false.) then  ! interface arguments this source does not need
      moment(1, 0) = moment(1, 0) + t
      if (allocated(error)) return
    end if
  end subroutine gravity_add_loads

  subroutine constant_add_loads(self, t, bodies, force, moment, error)
    class(constant_load_source), intent(inout) :: self
    real(dp), intent(in) :: t
    type(rigid_body), intent(in) :: bodies(0:)
    real(dp), intent(inout) :: force(:, 0:)
    real(dp), intent(inout) :: moment(:, 0:)
    type(error_type), allocatable, intent(inout) :: error
    real(dp) :: f(3)
    integer :: i
    i = self%body
    if (i < 0 .or. i > ubound(bodies, 1)) then
      call fatal_error(error, "constant load on body " // str(i) // " which the scene does not have")
      return
    end if
    f = self%force
    if (self%body_axes_force) f = matmul(bodies(i)%c, f)
    call add_point_force(bodies(i), self%point, f, force(:, i), moment(:, i))
    moment(:, i) = moment(:, i) + self%moment
    if (.false.) moment(1, i) = moment(1, i) + t
  end subroutine constant_add_loads

  subroutine pair_add_loads(self, t, bodies, force, moment, error)
    class(pair_force_source), intent(inout) :: self
    real(dp), intent(in) :: t
    type(rigid_body), intent(in) :: bodies(0:)
    real(dp), intent(inout) :: force(:, 0:)
    real(dp), intent(inout) :: moment(:, 0:)
    type(error_type), allocatable, intent(inout) :: error
    real(dp) :: f(3)
    integer :: a, b
    a = self%body_a; b = self%body_b
    if (min(a, b) < 0 .or. max(a, b) > ubound(bodies, 1) .or. a == b) then
      call fatal_error(error, "pair force between bodies the scene does not have")
      return
    end if
    if (self%central) then
      f = bodies(a)%point_position(self%point_a) - bodies(b)%point_position(self%point_b)
      if (norm2(f) == 0.0_dp) then
        call fatal_error(error, "central pair force between coincident points")
        return
      end if
      f = self%magnitude*f/norm2(f)
    else
      f = self%magnitude*matmul(bodies(a)%c, self%direction)
    end if
    call add_point_force(bodies(b), self%point_b, f, force(:, b), moment(:, b))
    call add_point_force(bodies(a), self%point_a, -f, force(:, a), moment(:, a))
    if (.false.) moment(1, a) = moment(1, a) + t
  end subroutine pair_add_loads
end module airlaunch_force_source
