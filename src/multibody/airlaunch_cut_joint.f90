!> The cut joint H between aircraft B0 and rocket B1 (Zheng & Zhang 2018, §3.1, §4.3,
!> Eq. (66)), one constraint set per phase, written for the constraint force
!> algorithm (CFA, §3.3): for each phase the joint gives
!>   * a basis of constraint wrenches R_H (component i: a force or moment on the rocket
!>     and its reaction on the aircraft at the SAME spatial point), which is the
!>     transpose of the constraint Jacobian, so the joint does no work on allowed motion;
!>   * the constraint rows at acceleration level, c = Jac * accelerations + bias, where
!>     bias holds the velocity-product terms and the Baumgarte drift control
!>     c = phi'' + 2 zeta w_n phi' + w_n^2 phi (gains `baumgarte_omega`, `baumgarte_zeta`);
!>     the slide row (used while the friction sticks, or always with `edge_no_slip`)
!>     is s'' + stick_rate s' = 0 instead: the slide rate decays in 1/stick_rate;
!>   * the constraint residual (position, angle, velocity, angular velocity).
!>
!> Geometry (input): joint frame E = [e1, e2, e3] in aircraft axes: e1 = rail direction
!> (the way the rocket slides out, aft), e2 = deck normal (aircraft y made normal to e1),
!> e3 = e1 x e2 (lateral; the ramp-edge line).  The rail line passes through
!> `floor_point`; the ramp edge `edge_point` lies on it.  Rocket axes: `contact_point`
!> is a point of the rocket's underside contact line (parallel to the rocket x axis),
!> `nose_x` the x of the nose tip (front end of that line).  The rocket envelope
!> (length, radius) serves the consistency checks.
!>
!> Components and rows (component 1 is always the slide along the exit direction,
!> 2 the contact normal, 3 the lateral direction):
!>   Case 0 locked (6): forces along e1, e2, e3 at the contact point, moments about e1..e3;
!>       rows: contact-point position fixed in the aircraft frame, relative attitude fixed.
!>   Case 1 rail (6): as Case 0, but row 1 (slide) is free: Coulomb friction mu_rail.
!>   Case 2 ramp edge (5): forces along -x_r (slide), y_r (normal), z_r (lateral) of the
!>       rocket at the edge point, moments about R h1 x e1 and R h1 x e2 (relative roll
!>       and yaw), h1 = edge axis e3 in rocket axes: pitch about the edge and slide free,
!>       Coulomb friction mu_edge on the slide (or no slip at all, `edge_no_slip`).
!>       The contact is one-sided: component 2 (the normal force, > 0 pushing) is reported
!>       so that an event can detect its zero crossing.
!>   Case 3 free (0).
module airlaunch_cut_joint
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_rigid_body, only: rigid_body, cross
  use airlaunch_rotation, only: rot_z
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  implicit none
  private
  public :: cut_joint, cut_joint_geometry, cut_joint_options, joint_state
  public :: phase_preparation, phase_extraction, phase_rotation, phase_free, phase_name
  public :: joint_components

  integer, parameter :: phase_preparation = 0  !< Case 0: rocket locked to the aircraft
  integer, parameter :: phase_extraction = 1   !< Case 1: sliding on the rail
  integer, parameter :: phase_rotation = 2     !< Case 2: tipping over the ramp edge
  integer, parameter :: phase_free = 3         !< Case 3: free flight

  !> Geometry of the cut joint (see the module header).
  type :: cut_joint_geometry
    real(dp) :: rail_direction(3) = [-1.0_dp, 0.0_dp, 0.0_dp] !< aircraft axes, exit direction
    real(dp) :: floor_point(3) = [0.0_dp, -1.0_dp, 0.0_dp]    !< aircraft axes, a point of the rail line [m]
    real(dp) :: edge_point(3) = [-10.0_dp, -1.0_dp, 0.0_dp]   !< aircraft axes, the ramp edge [m]
    real(dp) :: contact_point(3) = [0.0_dp, -1.0_dp, 0.0_dp]  !< rocket axes, underside below the CG [m]
    real(dp) :: nose_x = 9.25_dp          !< rocket axes: x of the nose tip [m]
    real(dp) :: rocket_length = 18.5_dp   !< envelope length [m]
    real(dp) :: rocket_radius = 1.0_dp    !< envelope radius [m]
  end type cut_joint_geometry

  !> Friction and drift-control settings.
  type :: cut_joint_options
    real(dp) :: mu_rail = 0.0_dp           !< Coulomb friction coefficient on the rail (Case 1)
    real(dp) :: mu_edge = 0.0_dp           !< Coulomb friction coefficient at the ramp edge (Case 2)
    logical :: edge_no_slip = .false.      !< Case 2 without sliding (pure pivot about the edge)
    real(dp) :: stick_velocity = 1.0e-4_dp !< Karnopp stick band half-width [m/s]
    real(dp) :: stick_rate = 1.0e3_dp      !< decay rate of the slide rate while sticking [1/s]
    real(dp) :: baumgarte_omega = 10.0_dp  !< drift control natural frequency w_n [rad/s]
    real(dp) :: baumgarte_zeta = 1.0_dp    !< drift control damping ratio
  end type cut_joint_options

  !> Joint quantities of the current state (filled by `cut_joint%evaluate`).
  type :: joint_state
    integer :: phase = phase_preparation
    integer :: ncomp = 0                     !< number of wrench components / rows
    real(dp) :: rocket_force(3, 6) = 0.0_dp  !< per component: force on the rocket, earth
    real(dp) :: rocket_moment(3, 6) = 0.0_dp !< moment on the rocket about its CG, rocket axes
    real(dp) :: aircraft_force(3, 6) = 0.0_dp   !< reaction force on the aircraft, earth
    real(dp) :: aircraft_moment(3, 6) = 0.0_dp  !< reaction moment about its CG, aircraft axes
    real(dp) :: bias(6) = 0.0_dp             !< velocity terms + Baumgarte of each row
    real(dp) :: slide = 0.0_dp               !< slide coordinate [m] (Case 1: along the rail
                                             !< from floor_point; Case 2: edge ahead of contact_point)
    real(dp) :: slide_rate = 0.0_dp          !< rocket contact velocity relative to the aircraft
                                             !< along the exit direction [m/s]
    real(dp) :: res_position = 0.0_dp        !< constraint residual, position [m]
    real(dp) :: res_angle = 0.0_dp           !< constraint residual, angle [rad]
    real(dp) :: res_velocity = 0.0_dp        !< constraint residual, velocity [m/s]
    real(dp) :: res_rate = 0.0_dp            !< constraint residual, angular velocity [rad/s]
    ! cached kinematics used by `rows`
    real(dp) :: c0(3, 3) = 0.0_dp, c1(3, 3) = 0.0_dp, rel(3, 3) = 0.0_dp
    real(dp) :: w(3) = 0.0_dp                !< Cases 0-1: contact point in aircraft axes
    real(dp) :: eps(3) = 0.0_dp              !< Case 2: edge point in rocket axes
    real(dp) :: mdir(3, 2) = 0.0_dp          !< Case 2: moment directions, aircraft axes
  end type joint_state

  !> The cut joint: geometry, options and the references captured at the start.
  type :: cut_joint
    type(cut_joint_geometry) :: geo
    type(cut_joint_options) :: opt
    real(dp) :: e(3, 3) = 0.0_dp        !< joint frame [e1 e2 e3] in aircraft axes
    real(dp) :: w_ref(3) = 0.0_dp       !< Case 0: contact point in aircraft axes
    real(dp) :: rel_ref(3, 3) = 0.0_dp  !< Cases 0-1: relative attitude C0^T C1
    real(dp) :: h1(3) = [0.0_dp, 0.0_dp, 1.0_dp] !< Case 2: edge axis e3 in rocket axes
    real(dp) :: l0 = 0.0_dp             !< CG-to-edge distance along the rail at the start [m]
    real(dp) :: l10 = 0.0_dp            !< nose-to-edge distance along the rail at the start [m]
  contains
    procedure :: setup => joint_setup
    procedure :: validate => joint_validate
    procedure :: capture => joint_capture
    procedure :: inside_rocket => joint_inside_rocket
    procedure :: evaluate => joint_evaluate
    procedure :: rows => joint_rows
    procedure :: cg_past_edge => joint_cg_past_edge
    procedure :: nose_past_edge => joint_nose_past_edge
    procedure :: place_on_rail => joint_place_on_rail
    procedure :: place_on_edge => joint_place_on_edge
  end type cut_joint

contains

  !> Human name of a phase, for messages.
  pure function phase_name(phase) result(s)
    integer, intent(in) :: phase   !< 0..3
    character(len=:), allocatable :: s
    select case (phase)
    case (phase_preparation)
      s = "phase 0 (preparation, locked)"
    case (phase_extraction)
      s = "phase 1 (extraction on the rail)"
    case (phase_rotation)
      s = "phase 2 (rotation over the ramp edge)"
    case (phase_free)
      s = "phase 3 (free flight)"
    case default
      s = "unknown phase " // str(phase)
    end select
  end function phase_name

  !> Number of constraint-wrench components of a phase.
  pure integer function joint_components(phase) result(n)
    integer, intent(in) :: phase   !< 0..3
    select case (phase)
    case (phase_preparation, phase_extraction)
      n = 6
    case (phase_rotation)
      n = 5
    case default
      n = 0
    end select
  end function joint_components

  !> Store the geometry and options and build the joint frame (no checks: call
  !> `validate` before running; the placement helpers only need the frame).
  subroutine joint_setup(self, geo, opt)
    class(cut_joint), intent(inout) :: self               !< joint
    type(cut_joint_geometry), intent(in) :: geo           !< geometry
    type(cut_joint_options), intent(in) :: opt            !< options
    real(dp) :: e1(3), e2(3)
    self%geo = geo
    self%opt = opt
    e1 = [-1.0_dp, 0.0_dp, 0.0_dp]
    if (norm2(geo%rail_direction) > 0.0_dp) e1 = geo%rail_direction/norm2(geo%rail_direction)
    e2 = [0.0_dp, 1.0_dp, 0.0_dp] - e1(2)*e1
    if (norm2(e2) < 1.0e-6_dp) e2 = [1.0_dp, 0.0_dp, 0.0_dp] - e1(1)*e1
    e2 = e2/norm2(e2)
    self%e(:, 1) = e1
    self%e(:, 2) = e2
    self%e(:, 3) = cross(e1, e2)
  end subroutine joint_setup

  !> Check the state-independent geometry and options.
  subroutine joint_validate(self, error)
    class(cut_joint), intent(in) :: self                  !< joint (set up)
    type(error_type), allocatable, intent(inout) :: error !< set on inconsistent input
    real(dp) :: e1(3), e2(3), d(3)
    associate(geo => self%geo, opt => self%opt)
    if (.not. (all(ieee_is_finite(geo%rail_direction)) .and. all(ieee_is_finite(geo%floor_point)) &
        .and. all(ieee_is_finite(geo%edge_point)) .and. all(ieee_is_finite(geo%contact_point)))) then
      call fatal_error(error, "inconsistent geometry: joint points are not finite numbers")
      return
    end if
    if (norm2(geo%rail_direction) <= 0.0_dp) then
      call fatal_error(error, "inconsistent geometry: rail direction is the zero vector")
      return
    end if
    e1 = geo%rail_direction/norm2(geo%rail_direction)
    e2 = [0.0_dp, 1.0_dp, 0.0_dp] - e1(2)*e1
    if (norm2(e2) < 1.0e-6_dp) then
      call fatal_error(error, "inconsistent geometry: rail direction is vertical in aircraft axes")
      return
    end if
    if (.not. (geo%rocket_length > 0.0_dp .and. geo%rocket_radius > 0.0_dp)) then
      call fatal_error(error, "inconsistent geometry: rocket length and radius must be positive (got " &
        // str(geo%rocket_length) // " m, " // str(geo%rocket_radius) // " m)")
      return
    end if
    if (.not. (geo%nose_x > 0.0_dp .and. geo%nose_x <= geo%rocket_length)) then
      call fatal_error(error, "inconsistent geometry: the nose tip x = " // str(geo%nose_x) // &
        " m must lie ahead of the CG and within the rocket length " // str(geo%rocket_length) // " m")
      return
    end if
    if (.not. self%inside_rocket(geo%contact_point)) then
      call fatal_error(error, "inconsistent geometry: the contact point [" // str(geo%contact_point(1)) &
        // ", " // str(geo%contact_point(2)) // ", " // str(geo%contact_point(3)) // &
        "] m lies outside the rocket (length " // str(geo%rocket_length) // " m, radius " // &
        str(geo%rocket_radius) // " m, nose at x = " // str(geo%nose_x) // " m)")
      return
    end if
    d = geo%edge_point - geo%floor_point
    d = d - dot_product(d, e1)*e1
    if (norm2(d) > 1.0e-6_dp) then
      call fatal_error(error, "inconsistent geometry: the ramp edge lies " // str(norm2(d)) // &
        " m off the rail line")
      return
    end if
    if (opt%mu_rail < 0.0_dp .or. opt%mu_edge < 0.0_dp .or. .not. (opt%stick_velocity > 0.0_dp) &
        .or. .not. (opt%baumgarte_omega >= 0.0_dp) .or. .not. (opt%baumgarte_zeta >= 0.0_dp) &
        .or. .not. (opt%stick_rate > 0.0_dp)) then
      call fatal_error(error, "cut joint: friction coefficients and Baumgarte gains must be >= 0 " // &
        "and the stick band > 0")
      return
    end if
    end associate
  end subroutine joint_validate

  !> True if the rocket-axis point p lies inside the rocket envelope (cylinder of
  !> the given radius from the tail at nose_x - length to the nose at nose_x).
  pure logical function joint_inside_rocket(self, p) result(inside)
    class(cut_joint), intent(in) :: self   !< joint
    real(dp), intent(in) :: p(3)           !< point, rocket axes [m]
    real(dp) :: tol
    tol = 1.0e-9_dp*self%geo%rocket_length
    inside = p(1) <= self%geo%nose_x + tol .and. p(1) >= self%geo%nose_x - self%geo%rocket_length - tol &
      .and. hypot(p(2), p(3)) <= self%geo%rocket_radius*(1.0_dp + 1.0e-9_dp)
  end function joint_inside_rocket

  !> Capture the references of the constraints from a consistent start state in
  !> `phase` and check it: Cases 0-1 need the contact point on the rail line, the
  !> rocket axis along the rail, nose first (l10 > l0) and the CG ahead of the ramp
  !> edge (l0 > 0); Case 2 needs the edge on the contact line.
  subroutine joint_capture(self, phase, b0, b1, error)
    class(cut_joint), intent(inout) :: self               !< joint
    integer, intent(in) :: phase                          !< starting phase
    type(rigid_body), intent(in) :: b0, b1                !< aircraft and rocket
    type(error_type), allocatable, intent(inout) :: error !< set on an inconsistent state
    real(dp) :: rel(3, 3), w(3), rho_cg(3), rho_nose(3), eps(3), tol, ax(3)
    tol = 1.0e-6_dp*max(1.0_dp, self%geo%rocket_length)
    rel = matmul(transpose(b0%c), b1%c)
    self%rel_ref = rel
    rho_cg = matmul(transpose(b0%c), b1%r - b0%r)
    w = rho_cg + matmul(rel, self%geo%contact_point)
    self%w_ref = w
    self%h1 = matmul(transpose(rel), self%e(:, 3))
    rho_nose = rho_cg + matmul(rel, [self%geo%nose_x, 0.0_dp, 0.0_dp])
    self%l0 = dot_product(self%e(:, 1), self%geo%edge_point - rho_cg)
    self%l10 = dot_product(self%e(:, 1), self%geo%edge_point - rho_nose)
    select case (phase)
    case (phase_preparation, phase_extraction)
      ax = matmul(rel, [1.0_dp, 0.0_dp, 0.0_dp])
      if (norm2(cross(ax, self%e(:, 1))) > 1.0e-6_dp) then
        call fatal_error(error, "inconsistent geometry: the rocket axis is not parallel to the rail (" &
          // str(norm2(cross(ax, self%e(:, 1)))) // " rad off)")
        return
      end if
      if (self%l10 <= self%l0) then
        call fatal_error(error, "inconsistent geometry: l10 = " // str(self%l10) // " m <= l0 = " // &
          str(self%l0) // " m (the nose must be farther from the ramp edge than the CG)")
        return
      end if
      if (self%l0 <= 0.0_dp) then
        call fatal_error(error, "inconsistent geometry: l0 = " // str(self%l0) // &
          " m (the rocket CG must start ahead of the ramp edge)")
        return
      end if
      w = w - self%geo%floor_point
      if (hypot(dot_product(w, self%e(:, 2)), dot_product(w, self%e(:, 3))) > tol) then
        call fatal_error(error, "inconsistent geometry: the rocket contact point is " // &
          str(hypot(dot_product(w, self%e(:, 2)), dot_product(w, self%e(:, 3)))) // " m off the rail line")
        return
      end if
    case (phase_rotation)
      eps = matmul(transpose(b1%c), b0%r + matmul(b0%c, self%geo%edge_point) - b1%r)
      if (hypot(eps(2) - self%geo%contact_point(2), eps(3) - self%geo%contact_point(3)) > tol) then
        call fatal_error(error, "inconsistent geometry: the ramp edge is " // &
          str(hypot(eps(2) - self%geo%contact_point(2), eps(3) - self%geo%contact_point(3))) // &
          " m off the rocket's contact line")
        return
      end if
    end select
  end subroutine joint_capture

  !> Constraint wrench basis, velocity terms with drift control and residuals of
  !> `phase` for the current bodies (§3.2, Eqs. (34)-(41): the rows are the second
  !> time derivatives of the constraints (66), written in the joint frame).
  subroutine joint_evaluate(self, phase, b0, b1, js)
    class(cut_joint), intent(in) :: self   !< joint
    integer, intent(in) :: phase           !< 0..3
    type(rigid_body), intent(in) :: b0, b1 !< aircraft and rocket (loaded)
    type(joint_state), intent(inout) :: js !< result
    real(dp) :: p(3), wd(3), bw(3), om(3), bom(3), phi(3), rerr(3, 3), kp, kd
    real(dp) :: epsd(3), beps(3), rh1(3), g(3), m(3), pos(3)
    integer :: i, k
    js%phase = phase
    js%ncomp = joint_components(phase)
    js%rocket_force = 0.0_dp; js%rocket_moment = 0.0_dp
    js%aircraft_force = 0.0_dp; js%aircraft_moment = 0.0_dp
    js%bias = 0.0_dp
    js%res_position = 0.0_dp; js%res_angle = 0.0_dp; js%res_velocity = 0.0_dp; js%res_rate = 0.0_dp
    js%slide = 0.0_dp; js%slide_rate = 0.0_dp
    js%c0 = b0%c
    js%c1 = b1%c
    js%rel = matmul(transpose(b0%c), b1%c)
    kd = 2.0_dp*self%opt%baumgarte_zeta*self%opt%baumgarte_omega
    kp = self%opt%baumgarte_omega**2
    ! relative angular velocity in aircraft axes and its velocity-product term
    om = matmul(js%rel, b1%w) - b0%w
    bom = -cross(b0%w, matmul(js%rel, b1%w))
    select case (phase)
    case (phase_preparation, phase_extraction)
      p = self%geo%contact_point
      call point_seen_from(b0, b1, p, js%w, wd, bw)
      ! small-angle attitude error vee(Rerr - Rerr^T)/2 of Rerr = R R_ref^T
      rerr = matmul(js%rel, transpose(self%rel_ref))
      phi = 0.5_dp*[rerr(3, 2) - rerr(2, 3), rerr(1, 3) - rerr(3, 1), rerr(2, 1) - rerr(1, 2)]
      if (phase == phase_preparation) then
        pos = js%w - self%w_ref
      else
        pos = js%w - self%geo%floor_point
      end if
      do i = 1, 3
        js%bias(i) = dot_product(self%e(:, i), bw + kd*wd)
        if (i > 1 .or. phase == phase_preparation) js%bias(i) = js%bias(i) + kp*dot_product(self%e(:, i), pos)
        js%bias(3+i) = dot_product(self%e(:, i), bom + kd*om + kp*phi)
      end do
      ! rail slide row, used only while sticking: drive the slide rate to zero
      if (phase == phase_extraction) js%bias(1) = dot_product(self%e(:, 1), bw) + &
        self%opt%stick_rate*dot_product(self%e(:, 1), wd)
      ! wrench basis: forces along e_i at the contact point, moments about e_i
      do i = 1, 3
        g = matmul(b0%c, self%e(:, i))
        js%rocket_force(:, i) = g
        js%rocket_moment(:, i) = cross(p, matmul(transpose(b1%c), g))
        js%aircraft_force(:, i) = -g
        js%aircraft_moment(:, i) = -cross(js%w, self%e(:, i))
        js%rocket_moment(:, 3+i) = matmul(transpose(js%rel), self%e(:, i))
        js%aircraft_moment(:, 3+i) = -self%e(:, i)
      end do
      js%slide = dot_product(self%e(:, 1), js%w - self%geo%floor_point)
      js%slide_rate = dot_product(self%e(:, 1), wd)
      js%res_angle = norm2(phi)
      js%res_rate = norm2(om)
      if (phase == phase_preparation) then
        js%res_position = norm2(pos)
        js%res_velocity = norm2(wd)
      else
        js%res_position = hypot(dot_product(self%e(:, 2), pos), dot_product(self%e(:, 3), pos))
        js%res_velocity = hypot(dot_product(self%e(:, 2), wd), dot_product(self%e(:, 3), wd))
      end if
    case (phase_rotation)
      p = self%geo%edge_point
      call point_seen_from(b1, b0, p, js%eps, epsd, beps)
      ! row 1: slide along the exit direction -x_r; rows 2-3: contact and lateral
      js%bias(1) = beps(1) + self%opt%stick_rate*epsd(1)
      js%bias(2) = beps(2) + kd*epsd(2) + kp*(js%eps(2) - self%geo%contact_point(2))
      js%bias(3) = beps(3) + kd*epsd(3) + kp*(js%eps(3) - self%geo%contact_point(3))
      rh1 = matmul(js%rel, self%h1)
      do k = 1, 2
        g = self%e(:, k)
        m = cross(rh1, g)
        js%mdir(:, k) = m
        js%bias(3+k) = dot_product(bom, m) + dot_product(om, cross(cross(om, rh1), g)) &
          + kd*dot_product(om, m) + kp*dot_product(rh1, g)
        js%rocket_moment(:, 3+k) = matmul(transpose(js%rel), m)
        js%aircraft_moment(:, 3+k) = -m
      end do
      do i = 1, 3
        g = 0.0_dp
        g(i) = 1.0_dp
        if (i == 1) g(1) = -1.0_dp
        js%rocket_force(:, i) = matmul(b1%c, g)
        js%rocket_moment(:, i) = cross(js%eps, g)
        js%aircraft_force(:, i) = -js%rocket_force(:, i)
        js%aircraft_moment(:, i) = -cross(p, matmul(js%rel, g))
      end do
      js%slide = js%eps(1) - self%geo%contact_point(1)
      js%slide_rate = epsd(1)
      js%res_position = hypot(js%eps(2) - self%geo%contact_point(2), js%eps(3) - self%geo%contact_point(3))
      js%res_velocity = hypot(epsd(2), epsd(3))
      js%res_angle = hypot(dot_product(rh1, self%e(:, 1)), dot_product(rh1, self%e(:, 2)))
      js%res_rate = hypot(dot_product(om, js%mdir(:, 1)), dot_product(om, js%mdir(:, 2)))
    end select
  end subroutine joint_evaluate

  !> The point p fixed in body b seen from body a, in a's axes (the constraint
  !> vector of Eq. (66) and its derivatives): position pos = Ca^T (r_b + Cb p - r_a),
  !> its rate vel, and the velocity-product part `bias` of its second derivative
  !> (the part free of the accelerations).  Cross products are kept out of
  !> matmul (a function result there is a heap temporary).
  pure subroutine point_seen_from(a, b, p, pos, vel, bias)
    type(rigid_body), intent(in) :: a, b   !< observing body, carrying body
    real(dp), intent(in) :: p(3)           !< the point in b's axes [m]
    real(dp), intent(out) :: pos(3)        !< [m]
    real(dp), intent(out) :: vel(3)        !< [m/s]
    real(dp), intent(out) :: bias(3)       !< [m/s^2]
    real(dp) :: wp(3), wwp(3), dv(3), u(3)
    pos = matmul(transpose(a%c), b%r + matmul(b%c, p) - a%r)
    wp = cross(b%w, p)
    wwp = cross(b%w, wp)
    dv = b%v + matmul(b%c, wp) - a%v
    u = matmul(transpose(a%c), dv)
    vel = u - cross(a%w, pos)
    bias = matmul(transpose(a%c), matmul(b%c, wwp)) - cross(a%w, u) - cross(a%w, vel)
  end subroutine point_seen_from

  !> Linear part of the constraint rows for given body accelerations (one CFA
  !> column): c = Jac [a0, wdot0, a1, wdot1] (bias excluded).
  pure subroutine joint_rows(self, js, a0, wd0, a1, wd1, c)
    class(cut_joint), intent(in) :: self   !< joint
    type(joint_state), intent(in) :: js    !< kinematics of the current state
    real(dp), intent(in) :: a0(3), wd0(3)  !< aircraft CG acceleration (earth), angular acc. (body)
    real(dp), intent(in) :: a1(3), wd1(3)  !< rocket CG acceleration (earth), angular acc. (body)
    real(dp), intent(out) :: c(:)          !< (ncomp) row accelerations
    real(dp) :: lw(3), lom(3), p(3), wp(3)   ! wp: a cross product kept out of matmul (no heap temporary)
    integer :: i
    c = 0.0_dp
    lom = matmul(js%rel, wd1) - wd0
    select case (js%phase)
    case (phase_preparation, phase_extraction)
      p = self%geo%contact_point
      wp = cross(wd1, p)
      lw = matmul(transpose(js%c0), a1 + matmul(js%c1, wp) - a0) - cross(wd0, js%w)
      do i = 1, 3
        c(i) = dot_product(self%e(:, i), lw)
        c(3+i) = dot_product(self%e(:, i), lom)
      end do
    case (phase_rotation)
      p = self%geo%edge_point
      wp = cross(wd0, p)
      lw = matmul(transpose(js%c1), a0 + matmul(js%c0, wp) - a1) - cross(wd1, js%eps)
      c(1:3) = lw
      c(4) = dot_product(lom, js%mdir(:, 1))
      c(5) = dot_product(lom, js%mdir(:, 2))
    end select
  end subroutine joint_rows

  !> Event function of Case 1 -> 2 (Eq. (67)): distance [m] of the rocket CG past
  !> the ramp edge along the rail (negative before, crosses zero upwards).
  pure real(dp) function joint_cg_past_edge(self, b0, b1) result(g)
    class(cut_joint), intent(in) :: self    !< joint
    type(rigid_body), intent(in) :: b0, b1  !< aircraft and rocket
    g = dot_product(self%e(:, 1), matmul(transpose(b0%c), b1%r - b0%r) - self%geo%edge_point)
  end function joint_cg_past_edge

  !> Event function of Case 2 -> 3 (Eq. (67)): distance [m] of the ramp edge ahead
  !> of the nose tip along the rocket axis (negative before, crosses zero upwards).
  pure real(dp) function joint_nose_past_edge(self, b0, b1) result(g)
    class(cut_joint), intent(in) :: self    !< joint
    type(rigid_body), intent(in) :: b0, b1  !< aircraft and rocket
    real(dp) :: eps(3)
    eps = matmul(transpose(b1%c), b0%r + matmul(b0%c, self%geo%edge_point) - b1%r)
    g = eps(1) - self%geo%nose_x
  end function joint_nose_past_edge

  !> Put the rocket on the rail, nose first (rocket x = -e1, y = e2), its CG at
  !> distance l0 ahead of the ramp edge along the rail, moving with the aircraft
  !> plus `slide_rate` along the exit direction.  Mass properties are untouched.
  subroutine joint_place_on_rail(self, b0, l0, slide_rate, b1)
    class(cut_joint), intent(in) :: self      !< joint (set up)
    type(rigid_body), intent(in) :: b0        !< aircraft
    real(dp), intent(in) :: l0                !< CG distance ahead of the edge [m]
    real(dp), intent(in) :: slide_rate        !< sliding speed along e1 [m/s]
    type(rigid_body), intent(inout) :: b1     !< rocket: state set
    real(dp) :: rel(3, 3), w(3), rho(3)
    rel(:, 1) = -self%e(:, 1)
    rel(:, 2) = self%e(:, 2)
    rel(:, 3) = -self%e(:, 3)
    call b1%set_attitude(rot_to_quat(matmul(b0%c, rel)))
    rel = matmul(transpose(b0%c), b1%c)
    w = self%geo%edge_point + (dot_product(self%e(:, 1), matmul(rel, self%geo%contact_point)) - l0)*self%e(:, 1)
    rho = w - matmul(rel, self%geo%contact_point)
    b1%r = b0%r + matmul(b0%c, rho)
    b1%w = matmul(transpose(rel), b0%w)
    b1%v = b0%v + matmul(b0%c, cross(b0%w, rho)) + slide_rate*matmul(b0%c, self%e(:, 1))
  end subroutine joint_place_on_rail

  !> Put the rocket on the ramp edge (Case 2): nose-first mounting turned nose-up
  !> by `pitch` about the edge axis, the edge `slide` ahead of the contact point
  !> along the contact line, with relative pitch rate and slide rate (exit direction).
  subroutine joint_place_on_edge(self, b0, slide, pitch, slide_rate, pitch_rate, b1)
    class(cut_joint), intent(in) :: self      !< joint (set up)
    type(rigid_body), intent(in) :: b0        !< aircraft
    real(dp), intent(in) :: slide             !< edge position ahead of the contact point [m]
    real(dp), intent(in) :: pitch             !< relative nose-up pitch [rad]
    real(dp), intent(in) :: slide_rate        !< rocket sliding speed along -x_r [m/s]
    real(dp), intent(in) :: pitch_rate        !< relative pitch rate [rad/s]
    type(rigid_body), intent(inout) :: b1     !< rocket: state set
    real(dp) :: rel(3, 3), eps(3), rz(3, 3)
    rel(:, 1) = -self%e(:, 1)
    rel(:, 2) = self%e(:, 2)
    rel(:, 3) = -self%e(:, 3)
    rz = rot_z(pitch)
    rel = matmul(rel, rz)
    call b1%set_attitude(rot_to_quat(matmul(b0%c, rel)))
    eps = self%geo%contact_point + [slide, 0.0_dp, 0.0_dp]
    b1%r = b0%r + matmul(b0%c, self%geo%edge_point) - matmul(b1%c, eps)
    b1%w = matmul(transpose(matmul(transpose(b0%c), b1%c)), b0%w) + [0.0_dp, 0.0_dp, pitch_rate]
    b1%v = b0%v + matmul(b0%c, cross(b0%w, self%geo%edge_point)) &
      - slide_rate*matmul(b1%c, [1.0_dp, 0.0_dp, 0.0_dp]) - matmul(b1%c, cross(b1%w, eps))
  end subroutine joint_place_on_edge

  !> Quaternion of a rotation matrix (wrapper kept local to avoid a name clash).
  pure function rot_to_quat(c) result(q)
    use airlaunch_rotation, only: dcm_to_quat
    real(dp), intent(in) :: c(3, 3)   !< body-to-earth matrix
    real(dp) :: q(4)
    q = dcm_to_quat(c)
  end function rot_to_quat
end module airlaunch_cut_joint
