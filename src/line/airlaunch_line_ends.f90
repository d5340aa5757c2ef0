!> End conditions of a flexible line (issue 3, item 2).
!>
!> Each end of the line (node 0 = end "a", node N = end "b") is one of:
!>  - fixed:       held at `position`;
!>  - prescribed:  moved on a given path (kinematic):
!>                   x(t) = position + velocity*tau + amplitude*(sin(w tau + phi) - sin(phi)),
!>                   tau = t - t_start >= 0, w = 2 pi frequency, phi = phase_deg;
!>                 before t_start the end rests at `position`.  The velocity
!>                 jumps at t_start (a "sudden" start, as in the axial-wave test);
!>  - free:        the end node moves under the line's forces only;
!>  - point_mass:  the end node carries an extra `mass` [kg] with its weight
!>                 (when gravity is on) and a drag `drag_area` = Cd*S [m^2]
!>                 from the air velocity relative to it (a crude parachute);
!>                 or, with `canopy_end`, a parachute canopy (`canopy`,
!>                 airlaunch_parachute: Knacke's inflation law for the drag
!>                 area, the apparent mass of the enclosed air in its inertia
!>                 but not in its weight, and the momentum of the air it
!>                 entrains while it fills); `mass` is then the canopy's;
!>  - body:        kinematic, moved by an outside owner (a rigid body of the
!>                 full simulation) through `set_body_motion`: cubic Hermite
!>                 interpolation between two (t, x, v) samples, linear
!>                 extrapolation outside them.  The line returns the end force
!>                 (see airlaunch_line_model) for the owner to apply to the body.
!> fixed, prescribed and body ends are kinematic: their node is not a state.
module airlaunch_line_ends
  use airlaunch_kinds, only: dp, pi, deg2rad, g0
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_atmosphere, only: isa, air_state
  use airlaunch_parachute, only: parachute, parachute_drag_area, parachute_added_mass, &
    parachute_added_mass_rate, parachute_nominal_diameter
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  implicit none
  private
  public :: line_end, end_kind_code, end_kind_name
  public :: end_fixed, end_prescribed, end_free, end_point_mass, end_body

  integer, parameter :: end_fixed = 1       !< held at `position`
  integer, parameter :: end_prescribed = 2  !< moved on a given path
  integer, parameter :: end_free = 3        !< free end
  integer, parameter :: end_point_mass = 4  !< end carries a point mass
  integer, parameter :: end_body = 5        !< moved by an outside owner

  !> One end of a line.
  type :: line_end
    integer :: kind = end_fixed             !< end_fixed ... end_body
    real(dp) :: position(3) = 0.0_dp        !< fixed / initial position (earth frame) [m]
    real(dp) :: velocity(3) = 0.0_dp        !< prescribed: constant velocity; free, point mass: initial velocity [m/s]
    real(dp) :: amplitude(3) = 0.0_dp       !< prescribed: sinusoid amplitude [m]
    real(dp) :: frequency = 0.0_dp          !< prescribed: sinusoid frequency [Hz]
    real(dp) :: phase_deg = 0.0_dp          !< prescribed: sinusoid phase [deg]
    real(dp) :: t_start = 0.0_dp            !< prescribed: time the motion starts [s]
    real(dp) :: mass = 0.0_dp               !< point mass [kg]
    real(dp) :: drag_area = 0.0_dp          !< point mass drag area Cd*S [m^2] (not with canopy_end)
    logical :: canopy_end = .false.         !< point mass: the canopy below, not drag_area
    type(parachute) :: canopy               !< canopy_end: its drag areas, inflation and apparent
                                            !< mass (its own `mass` is not read: the end's is;
                                            !< its fill_time is the owner's, e.g. from the
                                            !< air speed at the deployment: fill_time)
    ! body ends: the owner's two samples
    real(dp) :: body_t(2) = [0.0_dp, 1.0_dp]  !< sample times [s]
    real(dp) :: body_x(3, 2) = 0.0_dp         !< sample positions [m]
    real(dp) :: body_v(3, 2) = 0.0_dp         !< sample velocities [m/s]
  contains
    procedure :: is_kinematic => end_is_kinematic
    procedure :: motion => end_motion
    procedure :: external_load => end_external_load
    procedure :: external_load_dv => end_external_load_dv
    procedure :: apparent_mass => end_apparent_mass
    procedure :: energy => end_energy
    procedure :: inflating => end_inflating
    procedure :: fill_time => end_fill_time
    procedure :: set_body_motion => end_set_body_motion
    procedure :: check => end_check
  end type line_end

contains

  !> Code of an end kind name ("fixed", "prescribed", "free", "point_mass",
  !> "body"); 0 if unknown.
  pure integer function end_kind_code(name) result(code)
    character(len=*), intent(in) :: name   !< kind name
    select case (trim(adjustl(name)))
    case ("fixed")
      code = end_fixed
    case ("prescribed")
      code = end_prescribed
    case ("free")
      code = end_free
    case ("point_mass")
      code = end_point_mass
    case ("body")
      code = end_body
    case default
      code = 0
    end select
  end function end_kind_code

  !> Name of an end kind code.
  pure function end_kind_name(code) result(name)
    integer, intent(in) :: code   !< kind code
    character(len=:), allocatable :: name
    select case (code)
    case (end_fixed)
      name = "fixed"
    case (end_prescribed)
      name = "prescribed"
    case (end_free)
      name = "free"
    case (end_point_mass)
      name = "point_mass"
    case (end_body)
      name = "body"
    case default
      name = "unknown"
    end select
  end function end_kind_name

  !> True if the end's motion is given (fixed, prescribed, body).
  elemental logical function end_is_kinematic(self)
    class(line_end), intent(in) :: self   !< end
    end_is_kinematic = self%kind == end_fixed .or. self%kind == end_prescribed .or. self%kind == end_body
  end function end_is_kinematic

  !> Position, velocity and acceleration of a kinematic end at time t.
  !> For free and point-mass ends it returns the initial position and velocity.
  pure subroutine end_motion(self, t, x, v, a)
    class(line_end), intent(in) :: self      !< end
    real(dp), intent(in) :: t                !< time [s]
    real(dp), intent(out) :: x(3)            !< position [m]
    real(dp), intent(out) :: v(3)            !< velocity [m/s]
    real(dp), intent(out), optional :: a(3)  !< acceleration [m/s^2]
    real(dp) :: tau, w, phi, acc(3)
    acc = 0.0_dp
    select case (self%kind)
    case (end_prescribed)
      tau = t - self%t_start
      if (tau < 0.0_dp) then
        x = self%position
        v = 0.0_dp
      else
        w = 2.0_dp*pi*self%frequency
        phi = self%phase_deg*deg2rad
        x = self%position + self%velocity*tau + self%amplitude*(sin(w*tau + phi) - sin(phi))
        v = self%velocity + self%amplitude*w*cos(w*tau + phi)
        acc = -self%amplitude*w**2*sin(w*tau + phi)
      end if
    case (end_body)
      call hermite(self, t, x, v, acc)
    case (end_fixed)
      x = self%position
      v = 0.0_dp
    case default
      x = self%position
      v = self%velocity
    end select
    if (present(a)) a = acc
  end subroutine end_motion

  !> Cubic Hermite interpolation of the owner's two samples (linear
  !> extrapolation with the end velocity outside them).
  pure subroutine hermite(self, t, x, v, a)
    type(line_end), intent(in) :: self   !< body end
    real(dp), intent(in) :: t            !< time [s]
    real(dp), intent(out) :: x(3), v(3), a(3)
    real(dp) :: h, s, h00, h10, h01, h11, d00, d10, d01, d11, e00, e10, e01, e11
    h = self%body_t(2) - self%body_t(1)
    a = 0.0_dp
    ! the samples' own times interpolate (s = 0, 1: x, v exact, a one-sided)
    if (h <= 0.0_dp .or. t < self%body_t(1)) then
      x = self%body_x(:, 1) + self%body_v(:, 1)*(t - self%body_t(1))
      v = self%body_v(:, 1)
      return
    else if (t > self%body_t(2)) then
      x = self%body_x(:, 2) + self%body_v(:, 2)*(t - self%body_t(2))
      v = self%body_v(:, 2)
      return
    end if
    s = (t - self%body_t(1))/h
    h00 = 2*s**3 - 3*s**2 + 1;  h10 = s**3 - 2*s**2 + s
    h01 = -2*s**3 + 3*s**2;     h11 = s**3 - s**2
    d00 = 6*s**2 - 6*s;         d10 = 3*s**2 - 4*s + 1
    d01 = -6*s**2 + 6*s;        d11 = 3*s**2 - 2*s
    e00 = 12*s - 6;             e10 = 6*s - 4
    e01 = -12*s + 6;            e11 = 6*s - 2
    x = h00*self%body_x(:, 1) + h10*h*self%body_v(:, 1) + h01*self%body_x(:, 2) + h11*h*self%body_v(:, 2)
    v = (d00*self%body_x(:, 1) + d01*self%body_x(:, 2))/h + d10*self%body_v(:, 1) + d11*self%body_v(:, 2)
    a = (e00*self%body_x(:, 1) + e01*self%body_x(:, 2))/h**2 + (e10*self%body_v(:, 1) + e11*self%body_v(:, 2))/h
  end subroutine hermite

  !> Set the motion of a body end from two samples (t1, x1, v1), (t2, x2, v2)
  !> of the owner's body (e.g. the start and end of an outer step).
  pure subroutine end_set_body_motion(self, t1, x1, v1, t2, x2, v2)
    class(line_end), intent(inout) :: self   !< end (becomes a body end)
    real(dp), intent(in) :: t1, t2           !< sample times [s]
    real(dp), intent(in) :: x1(3), v1(3)     !< position, velocity at t1
    real(dp), intent(in) :: x2(3), v2(3)     !< position, velocity at t2
    self%kind = end_body
    self%body_t = [t1, t2]
    self%body_x(:, 1) = x1; self%body_x(:, 2) = x2
    self%body_v(:, 1) = v1; self%body_v(:, 2) = v2
  end subroutine end_set_body_motion

  !> External load on a point-mass end at time t, position x, velocity v [N]:
  !> its weight (if gravity) and its drag 1/2 rho CdS |u| u, u = wind - v (if
  !> air); a canopy's drag area is its inflation law's at t, and while it fills
  !> the air it entrains is brought to its velocity: + (dm_a/dt) u
  !> (airlaunch_parachute, canopy_node_acceleration, with the wind).  Zero for
  !> the other kinds.
  function end_external_load(self, t, x, v, gravity, air, wind, air_density) result(f)
    class(line_end), intent(in) :: self    !< end
    real(dp), intent(in) :: t              !< time [s]
    real(dp), intent(in) :: x(3), v(3)     !< end position [m], velocity [m/s]
    logical, intent(in) :: gravity, air    !< loads switched on
    real(dp), intent(in) :: wind(3)        !< air velocity [m/s]
    real(dp), intent(in) :: air_density    !< fixed density [kg/m^3]; 0 = ISA at x(2)
    real(dp) :: f(3), u(3), rho, cds
    f = 0.0_dp
    if (self%kind /= end_point_mass) return
    if (gravity) f(2) = -self%mass*g0
    if (.not. air) return
    cds = end_drag_area(self, t)
    if (.not. (cds > 0.0_dp)) return
    rho = density(x, air_density)
    u = wind - v
    f = f + 0.5_dp*rho*cds*norm2(u)*u
    if (self%canopy_end) f = f + parachute_added_mass_rate(self%canopy, rho, t)*u
  end function end_external_load

  !> Derivative of end_external_load with respect to the end velocity [N s/m]:
  !> the point mass's drag F = rho CdS |u| u / 2, u = wind - v, gives
  !> dF/dv = -rho CdS (|u| I + u u^T/|u|)/2, and a filling canopy's entrained
  !> air - (dm_a/dt) I (the ISA density's dependence on the altitude is left
  !> out).  Zero for other kinds or with the air off.
  pure function end_external_load_dv(self, t, x, v, air, wind, air_density) result(d)
    class(line_end), intent(in) :: self    !< end
    real(dp), intent(in) :: t              !< time [s]
    real(dp), intent(in) :: x(3), v(3)     !< end position [m], velocity [m/s]
    logical, intent(in) :: air             !< drag switched on
    real(dp), intent(in) :: wind(3)        !< air velocity [m/s]
    real(dp), intent(in) :: air_density    !< fixed density [kg/m^3]; 0 = ISA at x(2)
    real(dp) :: d(3, 3), u(3), un, rho, cds, rate
    integer :: i, j
    d = 0.0_dp
    if (self%kind /= end_point_mass .or. .not. air) return
    cds = end_drag_area(self, t)
    if (.not. (cds > 0.0_dp)) return
    rho = density(x, air_density)
    u = wind - v
    un = sqrt(dot_product(u, u))
    do j = 1, 3
      do i = 1, 3
        if (un > 0.0_dp) d(i, j) = u(i)*u(j)/un
      end do
      d(j, j) = d(j, j) + un
    end do
    d = -0.5_dp*rho*cds*d
    if (.not. self%canopy_end) return
    rate = parachute_added_mass_rate(self%canopy, rho, t)
    do j = 1, 3
      d(j, j) = d(j, j) - rate
    end do
  end function end_external_load_dv

  !> Apparent mass of a canopy end at time t and position x [kg]: in its
  !> inertia, not in its weight (Knacke ch. 6; airlaunch_parachute).  Zero for
  !> every other end and with the air off.
  pure real(dp) function end_apparent_mass(self, t, x, air, air_density) result(ma)
    class(line_end), intent(in) :: self    !< end
    real(dp), intent(in) :: t              !< time [s]
    real(dp), intent(in) :: x(3)           !< end position [m]
    logical, intent(in) :: air             !< air switched on
    real(dp), intent(in) :: air_density    !< fixed density [kg/m^3]; 0 = ISA at x(2)
    ma = 0.0_dp
    if (self%kind /= end_point_mass .or. .not. self%canopy_end .or. .not. air) return
    ma = parachute_added_mass(self%canopy, density(x, air_density), t)
  end function end_apparent_mass

  !> Kinetic and gravitational energy of a point-mass end at time t [J]: the
  !> apparent mass of a canopy moves with it, its weight is the canopy's only.
  !> Zero for the other kinds.
  pure function end_energy(self, t, x, v, gravity, air, air_density) result(e)
    class(line_end), intent(in) :: self    !< end
    real(dp), intent(in) :: t              !< time [s]
    real(dp), intent(in) :: x(3), v(3)     !< end position [m], velocity [m/s]
    logical, intent(in) :: gravity, air    !< loads switched on
    real(dp), intent(in) :: air_density    !< fixed density [kg/m^3]; 0 = ISA at x(2)
    real(dp) :: e(2)                       !< kinetic, potential
    e = 0.0_dp
    if (self%kind /= end_point_mass) return
    e(1) = 0.5_dp*(self%mass + self%apparent_mass(t, x, air, air_density))*dot_product(v, v)
    if (gravity) e(2) = self%mass*g0*x(2)
  end function end_energy

  !> True for a canopy end whose mass and drag change with time (it deploys).
  elemental logical function end_inflating(self)
    class(line_end), intent(in) :: self   !< end
    end_inflating = self%kind == end_point_mass .and. self%canopy_end .and. self%canopy%deploy_time >= 0.0_dp
  end function end_inflating

  !> A canopy's filling time t_f = n D0 / V [s] (Knacke, NWC TP 6575, ch. 5)
  !> when it deploys into the air speed V = `speed` (> 0) relative to it.
  pure real(dp) function end_fill_time(self, speed) result(t_f)
    class(line_end), intent(in) :: self   !< canopy end
    real(dp), intent(in) :: speed         !< air speed relative to the end at its deployment [m/s]
    t_f = self%canopy%fill_constant*parachute_nominal_diameter(self%canopy)/speed
  end function end_fill_time

  !> Drag area of a point-mass end at time t [m^2]: a canopy's inflation law,
  !> otherwise the fixed drag_area.
  pure real(dp) function end_drag_area(self, t) result(cds)
    type(line_end), intent(in) :: self   !< end
    real(dp), intent(in) :: t            !< time [s]
    if (self%canopy_end) then
      cds = parachute_drag_area(self%canopy, t)
    else
      cds = self%drag_area
    end if
  end function end_drag_area

  !> The air density at x: the fixed one, or ISA at x(2) when it is 0.
  pure real(dp) function density(x, air_density) result(rho)
    real(dp), intent(in) :: x(3)          !< position [m]
    real(dp), intent(in) :: air_density   !< fixed density [kg/m^3]; 0 = ISA
    rho = air_density
    if (rho <= 0.0_dp) rho = isa_density(x(2))
  end function density

  !> ISA density at altitude y [kg/m^3].
  pure real(dp) function isa_density(y) result(rho)
    real(dp), intent(in) :: y   !< altitude [m]
    type(air_state) :: a
    a = isa(y)
    rho = a%density
  end function isa_density

  !> Validate an end; `name` ("end_a", "end_b") prefixes the message.
  subroutine end_check(self, name, error)
    class(line_end), intent(in) :: self                    !< end
    character(len=*), intent(in) :: name                   !< which end, for the message
    type(error_type), allocatable, intent(inout) :: error  !< set on bad input
    if (self%kind < end_fixed .or. self%kind > end_body) then
      call fatal_error(error, name // ": kind code " // str(self%kind) // " is not allowed: use fixed, " // &
        "prescribed, free, point_mass or body")
    else if (.not. all(ieee_is_finite([self%position, self%velocity, self%amplitude, self%phase_deg, &
        self%t_start]))) then
      call fatal_error(error, name // ": position, velocity, amplitude, phase_deg and t_start must be finite")
    else if (self%kind == end_point_mass .and. .not. (self%mass > 0.0_dp .and. ieee_is_finite(self%mass))) then
      call fatal_error(error, name // ": mass = " // str(self%mass) // " kg is not allowed for a " // &
        "point_mass end: must be > 0 and finite")
    else if (.not. (self%drag_area >= 0.0_dp .and. ieee_is_finite(self%drag_area))) then
      call fatal_error(error, name // ": drag_area = " // str(self%drag_area) // " m^2 is not allowed: " // &
        "must be >= 0 and finite")
    else if (.not. (self%frequency >= 0.0_dp .and. ieee_is_finite(self%frequency))) then
      call fatal_error(error, name // ": frequency = " // str(self%frequency) // " Hz is not allowed: " // &
        "must be >= 0 and finite")
    else if (self%canopy_end) then
      call check_canopy(self, name, error)
    end if
  end subroutine end_check

  !> Validate a canopy end: a point mass, drag areas 0 <= packed < open (the
  !> packed one only where the canopy deploys during the run: open from the
  !> start it never uses it), a filling time set when it deploys.
  subroutine check_canopy(self, name, error)
    type(line_end), intent(in) :: self                     !< end with canopy_end
    character(len=*), intent(in) :: name                   !< which end, for the message
    type(error_type), allocatable, intent(inout) :: error  !< set on bad input
    associate (c => self%canopy)
      if (self%kind /= end_point_mass) then
        call fatal_error(error, name // ": a canopy needs a point_mass end, not " // end_kind_name(self%kind))
      else if (.not. (c%packed_drag_area >= 0.0_dp .and. ieee_is_finite(c%drag_area) .and. &
          (c%packed_drag_area < c%drag_area .or. .not. self%inflating()))) then
        call fatal_error(error, name // ": the canopy's drag areas (packed " // str(c%packed_drag_area) // &
          ", open " // str(c%drag_area) // " m^2) are not allowed: need 0 <= packed < open (a canopy that deploys), finite")
      else if (.not. (c%added_mass_factor >= 0.0_dp .and. ieee_is_finite(c%added_mass_factor) .and. &
          c%cd0 > 0.0_dp .and. c%inflation_exponent >= 1.0_dp)) then
        call fatal_error(error, name // ": the canopy's added_mass_factor must be >= 0, cd0 > 0 and " // &
          "inflation_exponent >= 1")
      else if (self%inflating() .and. .not. (c%fill_time > 0.0_dp .and. ieee_is_finite(c%fill_time))) then
        call fatal_error(error, name // ": the canopy deploys at " // str(c%deploy_time) // " s but its " // &
          "filling time " // str(c%fill_time) // " s is not > 0 and finite")
      end if
    end associate
  end subroutine check_canopy
end module airlaunch_line_ends
