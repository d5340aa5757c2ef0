!> Coupling (a) of DESIGN §4, the paper's way: equivalent rigidization
!> (Zheng & Zhang 2018, §2.4, Eqs. (18)-(32), Steps 1-6) of the flexible line
!> inside the Kane chain of §4.2 (Eqs. (51)-(65)).
!>
!> Two subsystems, each integrated by its own CVODE:
!>  * the CHAIN (rigid subsystem): aircraft B0 (Newton-Euler) + Kane chain
!>    rocket B1 - virtual rigid line B2 - parachute B3 with spherical joints at
!>    the rocket's tie-down point and at the parachute, the cut joint B0-B1 by
!>    the CFA and the four phases (`separation_system` with nchain = 3).  The
!>    line body B2 carries m_rigid (31), J_rigid (32) and d_rigid (20), frozen
!>    over one outer step; B3 is a point mass at the end of B2 (its CG is its
!>    joint) with canopy + apparent mass and a small isotropic inertia;
!>  * the LINE (flexible subsystem, airlaunch_rigidized_line): the lumped-mass line of
!>    airlaunch_line_model, sub-stepped by CVODE (BDF, band) or by the paper's
!>    marching (`inner_scheme = 'marching'`, line_marcher) over the outer
!>    step, node 0 moved kinematically with the rocket's tie-down point taken
!>    from the chain (cubic Hermite through the chain's position and velocity at
!>    both ends of the outer step).
!>
!> Node N, the parachute end of the line.  Taking node N's motion from the
!> chain too makes |x_N - x_0| the chain's own length at every sample, so
!> d_rigid (20) would never change: the line's elasticity could not reach the
!> chain and its tension would stay at the initial stretch (the direct model's
!> falls from 78.8 to 44.5 kN over the paper scenario).  By default
!> (`far_end = 'parachute'`) node N therefore carries the parachute with the
!> far-end force condition of §2.3 (Eq. (16): F_N = canopy drag + weight -
!> (canopy + apparent mass) a), integrated implicitly with the line, which is
!> the limit the paper's far-end iteration (inner iterations, Step 5) converges
!> to.  `far_end = 'chain'` moves node N with B3 (both end motions from the
!> chain), kept for comparison.
!>
!> Outer loop (§2.4 Steps 3-6), one pass per outer step [t, t + H]:
!>  Step 3  refresh B2 (m_rigid, J_rigid, d_rigid) from the line state at t
!>          (`virtual_line_body`) and B3's mass (canopy + apparent mass at its
!>          altitude); B3 moves with the new d_rigid (its position is derived);
!>  Step 4  integrate the chain to t + H (or to its next event): constraint
!>          forces by the CFA and the Kane chain;
!>  Step 5  sub-step the line to the same time with node 0 on the tie-down
!>          point's path over the step (and node N on B3's for 'chain');
!>  Step 6  next step.
!> The line's end forces are NOT applied to the bodies: the chain's B2 carries
!> the line's inertia, weight and drag (its tension is the chain's joint force),
!> applying them again would count the line twice.
!>
!> Loads of B2 and B3 (`rigidized_loads`, a force source): the line's true
!> weight rho L g at B2's CG (not m_rigid g: m_rigid is a kinetic-energy
!> equivalent); the line's aerodynamic drag from the virtual body's own rigid
!> motion, with the line model's law (cross-flow on d*ell, skin friction on
!> pi*d*ell) integrated over `drag_strips` strips of the rod, air density
!> log-linear between the rod's ends (as airlaunch_line_model); the canopy's
!> drag -1/2 rho (Cd S)(t) |v| v and weight at B3 (every velocity relative to the
!> air: the &gust's, airlaunch_gust, at B3 and at each strip's centre is
!> subtracted).  The apparent mass of the
!> canopy is an acceleration-dependent load, which force sources do not
!> support, so it is added to B3's mass (refreshed every outer step).
!>
!> The chain's state is written relative to a frame translating at V0 along x
!> at altitude h0 (as airlaunch_launch_system), so are the line's nodes.
module airlaunch_rigidized_coupling
  use airlaunch_kinds, only: dp, i8, g0, pi
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_atmosphere, only: isa, air_state
  use airlaunch_rotation, only: dcm_to_euler, dcm_to_quat, cross
  use airlaunch_ode, only: ode_system, rhs_ok
  use airlaunch_cvode, only: cvode_solver, cvode_options, cvode_stats, add_stats, step_observer
  use airlaunch_multibody, only: rigid_body, force_source, separation_system, separation_nroots, phase_free, &
    body_state_name
  use airlaunch_line, only: line_model, line_band_upper, line_band_lower, rigid_equivalent, rigidize
  use airlaunch_rigidized_line, only: rigidized_line, line_marcher
  use airlaunch_parachute, only: parachute, parachute_drag_area, parachute_added_mass, parachute_added_mass_rate, &
    parachute_nominal_diameter
  use airlaunch_launch_loads, only: launch_loads
  use airlaunch_gust, only: gust_velocity, air_relative_velocity
  use airlaunch_clearance, only: clearance_geometry, clearance_rate
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  implicit none
  private
  public :: rigidized_settings, virtual_line, virtual_line_body, rigidized_loads, rigidized_chain, line_marcher, &
    rigidized_line, rigidized_coupling, rigidized_nroots, rigidized_pitch_root, rigidized_clearance_root, &
    chain_atol, line_body_attitude, chain_size, &
    continue_phase_machine

  !> Events: the separation scene's and the rocket's Euler-pitch maximum.
  !> the chain's event functions: the separation scene's, the pitch rate's and
  !> the clearance rate's (as the direct system's)
  integer, parameter :: rigidized_pitch_root = separation_nroots + 1, rigidized_clearance_root = separation_nroots + 2
  integer, parameter :: rigidized_nroots = separation_nroots + 2
  !> State size of the chain: aircraft (13) + rocket-line-parachute chain (6 + 7*3).
  integer, parameter :: chain_size = 13 + 6 + 7*3

  !> Settings of the outer loop and the line sub-steps (namelist &line).
  type :: rigidized_settings
    real(dp) :: outer_dt = 0.02_dp          !< outer step H of §2.4 Steps 3-6 [s]
    real(dp) :: chain_rtol = 1.0e-6_dp      !< chain CVODE relative tolerance
    real(dp) :: chain_atol = 1.0e-7_dp      !< chain CVODE absolute tolerance (scaled by chain_atol)
    integer :: chain_max_order = 2          !< chain BDF order
    real(dp) :: inner_rtol = 1.0e-6_dp      !< line sub-steps: CVODE relative tolerance
    real(dp) :: inner_atol = 1.0e-5_dp      !< line sub-steps: absolute tolerance [m, m/s]
    integer :: inner_max_order = 2          !< line BDF order (2: the axial modes, docs/model.md)
    !> line sub-steps: "cvode" (BDF, band; default) or "marching" (the paper's
    !> explicit marching with the far-end force iteration, §2.3 Steps 1-5:
    !> with the rigidization, the paper's method end to end)
    character(len=16) :: inner_scheme = "cvode"
    !> marching: largest sub-step [s]; 0 = 0.9 of its stability limit
    !> (line_model%stable_step: the scheme's cheapest setting)
    real(dp) :: inner_dt = 0.0_dp
    real(dp) :: inner_force_tol = 1.0e-6_dp !< marching: e0 of the far-end force iteration [N]
    integer :: inner_max_iterations = 20    !< marching: far-end iterations per sub-step
    character(len=16) :: far_end = "parachute" !< node N: "parachute" (far-end force) or "chain" (B3's motion)
    !> m_rigid and J_rigid are kept within [1/guard_band, guard_band] times the
    !> line mass and the geometric inertia (see `virtual_line_body`).
    real(dp) :: guard_band = 2.0_dp
    !> Restart the chain's CVODE after every refresh (true) or let its error
    !> control absorb the small jump of the parameters (false).
    logical :: restart_on_refresh = .false.
    !> Steps each of the two integrators (chain, line) may take over the run
    !> (`&run max_steps`); 0 = no limit.
    integer :: max_steps = 0
    !> the run's wall-time budget (`&run max_wall_time`) [s]; 0 = no limit
    real(dp) :: max_wall_time = 0.0_dp
    !> wall_clock() at which it is spent, the run's (cvode_options%wall_deadline)
    real(dp) :: wall_deadline = 0.0_dp
    !> end of the run [s]: the first step after each (re)start of either solver
    !> is sized towards it (cut at the outer step's stop time), not towards the
    !> next output time (cvode_options%t_final)
    real(dp) :: t_end = 0.0_dp
    !> largest step of the chain's and the line's CVODE [s] (0: unlimited; the
    !> scene's &gust sets it, so that no step jumps over the gust)
    real(dp) :: max_step = 0.0_dp
  end type rigidized_settings

  !> The virtual rigid body of the line (§2.4) as the chain uses it.
  type :: virtual_line
    real(dp) :: mass = 0.0_dp            !< m_rigid given to B2 [kg]
    real(dp) :: inertia = 0.0_dp         !< transverse J_rigid given to B2 [kg m^2]
    real(dp) :: length = 0.0_dp          !< d_rigid (20) [m]
    real(dp) :: line_mass = 0.0_dp       !< sum of the node masses [kg]
    real(dp) :: inertia_geometric = 0.0_dp !< transverse inertia of the node masses about the chord midpoint [kg m^2]
    real(dp) :: mass_eq31 = 0.0_dp       !< (31) before the guard [kg]
    real(dp) :: inertia_eq32 = 0.0_dp    !< (32), transverse, before the guard [kg m^2]
    logical :: mass_guarded = .false.    !< (31) was outside the guard band
    logical :: inertia_guarded = .false. !< (32) was outside the guard band
    real(dp) :: omega(3) = 0.0_dp        !< transverse angular velocity of the chord, earth [rad/s]
    type(rigid_equivalent) :: eq         !< the whole rigidization, Eqs. (18)-(32)
  end type virtual_line

  !> Weight and drag of the virtual line B2 and of the parachute B3.
  type, extends(force_source) :: rigidized_loads
    real(dp) :: line_mass = 0.0_dp       !< rho L [kg] (the weight of B2)
    real(dp) :: length = 1.0_dp          !< current d_rigid [m] (set by the refresh)
    real(dp) :: diameter = 0.0_dp        !< line diameter [m]
    real(dp) :: cd_normal = 0.0_dp       !< cross-flow drag coefficient (on d*ell)
    real(dp) :: cd_tangential = 0.0_dp   !< skin-friction coefficient (on pi*d*ell)
    logical :: gravity = .true.          !< weights of B2 and B3
    logical :: air = .true.              !< drag of B2 and B3
    !> Deformation velocity V_eps of the line (Eq. (25)) at the last refresh,
    !> earth [m/s]: the end velocity of Eq. (26), V_2 = V_1 + V_eps + omega x r,
    !> which the rigid chain's kinematics lacks; it enters the air-relative
    !> velocity of B3 (all of it) and of B2's strips (in proportion to their
    !> distance from the rocket end).
    real(dp) :: v_eps(3) = 0.0_dp
    type(parachute) :: chute             !< canopy (B3)
    integer :: drag_strips = 16          !< strips of the rod's drag integral
    ! --- outputs of the last evaluation
    real(dp) :: line_drag(3) = 0.0_dp    !< drag on B2, earth [N]
    real(dp) :: chute_drag(3) = 0.0_dp   !< drag on B3, earth [N]
  contains
    procedure :: add_loads => rigidized_add_loads
  end type rigidized_loads

  !> The chain (rigid subsystem) as an ODE for CVODE.
  !> y = [aircraft r, v, q, w (13) | rocket r, v, q, w, line q, w, parachute q, w (27)],
  !> positions and velocities relative to the translating frame (v_ref, h_ref).
  type, extends(ode_system) :: rigidized_chain
    type(separation_system) :: sep          !< aircraft + chain (nchain = 3) + joint + phases
    integer :: iloads = 0                   !< index of the launch_loads source (0: none)
    integer :: iline = 0                    !< index of the rigidized_loads source (0: none)
    real(dp) :: v_ref = 0.0_dp              !< V0 of the reference frame [m/s]
    real(dp) :: h_ref = 0.0_dp              !< h0 of the reference frame [m]
    logical :: find_pitch_max = .true.      !< event 5 active in Case 3
    type(clearance_geometry) :: clr         !< the clearance milestone's points (event 6)
    real(dp) :: yabs(chain_size) = 0.0_dp   !< absolute state of the last evaluation
  contains
    procedure :: rhs => chain_rhs
    procedure :: nroots => chain_nroots_fn
    procedure :: roots => chain_roots
    procedure :: prepare => chain_prepare
    procedure :: to_absolute => chain_to_absolute
    procedure :: euler_pitch_rate => chain_euler_pitch_rate
    procedure :: line_force => chain_line_force
    procedure :: state_name => chain_state_name
  end type rigidized_chain



  !> Both subsystems, their integrators and the outer loop.
  type :: rigidized_coupling
    type(rigidized_settings) :: opts                !< settings
    type(rigidized_chain), pointer :: chain => null()  !< on the heap: CVODE keeps its address
    type(rigidized_line), pointer :: line => null()    !< on the heap
    type(cvode_solver) :: chain_solver              !< integrates the chain
    type(cvode_solver) :: line_solver               !< sub-steps the line (inner_scheme 'cvode')
    type(line_marcher) :: marcher                   !< sub-steps the line (inner_scheme 'marching')
    logical :: marching = .false.                   !< the marcher sub-steps the line
    real(dp) :: t = 0.0_dp                          !< time both subsystems have reached [s]
    type(virtual_line) :: vl                        !< the virtual body of the last refresh
    real(dp) :: chute_link_mass = 0.0_dp            !< B3's mass of the last refresh [kg]
    real(dp) :: chute_link_inertia = 0.0_dp         !< B3's isotropic inertia [kg m^2]
    integer :: n_refresh = 0                        !< refreshes so far
    integer :: n_guard_mass = 0                     !< refreshes with (31) outside the guard band
    integer :: n_guard_inertia = 0                  !< refreshes with (32) outside the guard band
    !> Changes of the chain's total linear / angular momentum made by the
    !> refreshes (the chain conserves them in between when the loads are internal).
    real(dp) :: momentum_jump(3) = 0.0_dp
    real(dp) :: angular_momentum_jump(3) = 0.0_dp
    real(dp) :: kinetic_energy_jump = 0.0_dp        !< the same for the chain's kinetic energy [J]
    ! samples of the current outer step (relative frame)
    real(dp), private :: tie_x(3) = 0.0_dp, tie_v(3) = 0.0_dp, b3_x(3) = 0.0_dp, b3_v(3) = 0.0_dp
    real(dp), private :: tie0_x(3) = 0.0_dp, tie0_v(3) = 0.0_dp, b30_x(3) = 0.0_dp, b30_v(3) = 0.0_dp
    !> the empennage point (the line's clearance) at the outer step's end and start (relative)
    real(dp), private :: tail_x(3) = 0.0_dp, tail_v(3) = 0.0_dp, tail0_x(3) = 0.0_dp, tail0_v(3) = 0.0_dp
    real(dp), private :: step_t0 = 0.0_dp            !< start of the current outer step [s]
    logical, private :: motion_set = .false.         !< the line's end motions of the step are set
    ! chain states saved at the output times of the current outer step (begin_step)
    integer :: n_saved = 0                           !< number of saved output times
    real(dp), allocatable :: saved_t(:)              !< saved output times [s]
    real(dp), allocatable :: saved_y(:, :)           !< chain states there (relative frame)
  contains
    procedure :: init => coupling_init
    procedure :: refresh => coupling_refresh
    procedure :: begin_step => coupling_begin_step
    procedure :: line_to => coupling_line_to
    procedure :: end_step => coupling_end_step
    procedure :: outer_step => coupling_outer_step
    procedure :: restart_chain => coupling_restart_chain
    procedure :: line_state => coupling_line_state
    procedure :: line_steps => coupling_line_steps
    procedure :: stats => coupling_stats
    procedure :: free => coupling_free
  end type rigidized_coupling

contains

  ! ------------------------------------------------------------------ Step 3

  !> The virtual rigid body of the line state x(3,0:N), v(3,0:N) (earth frame,
  !> absolute velocities), §2.4: d_rigid (20), m_rigid (31) and a transverse
  !> J_rigid (32), with guards.
  !>  * m_rigid: the translational kinetic-energy mass of `rigidize` (Eq. (31)
  !>    with the dimension fix, DESIGN §2), in the earth frame.  It equals the
  !>    line mass for any rigid motion; when |V_rigid| is small against the
  !>    line's internal motion the ratio is meaningless, so it is kept within
  !>    [m/g, g m] of the line mass m (g = guard_band).
  !>  * J_rigid: the chain's line body is transversely isotropic (its axes spin
  !>    with the chain, not with the paper's two-angle frame), so Eq. (32) is
  !>    taken as the energy-equivalent transverse value
  !>    J = (J_x w_x^2 + J_y w_y^2)/(w_x^2 + w_y^2), kept within [J_g/g, g J_g]
  !>    of the geometric transverse inertia J_g of the node masses about the
  !>    chord midpoint (the chain's CG of B2); J_g when the chord does not turn.
  !>    The axial inertia is floored by the chain (kane_chain%set_line_link).
  function virtual_line_body(model, x, v, guard_band) result(vl)
    type(line_model), intent(in) :: model   !< the line
    real(dp), intent(in) :: x(:, 0:)        !< node positions, earth [m]
    real(dp), intent(in) :: v(:, 0:)        !< node velocities, earth [m/s]
    real(dp), intent(in) :: guard_band      !< >= 1
    type(virtual_line) :: vl
    real(dp) :: mid(3), e(3), rk(3), r2, a, wx2, wy2
    integer :: k, n
    n = model%n
    vl%eq = rigidize(model, x, v)
    vl%line_mass = vl%eq%line_mass
    vl%length = vl%eq%d_rigid
    ! (31)
    vl%mass_eq31 = vl%eq%m_rigid
    vl%mass = min(max(vl%eq%m_rigid, vl%line_mass/guard_band), vl%line_mass*guard_band)
    vl%mass_guarded = vl%mass /= vl%eq%m_rigid
    ! geometric transverse inertia about the chord midpoint: mean over two
    ! transverse axes of sum m (|r|^2 - (r.a)^2) = sum m (|r|^2 + (r.e)^2)/2
    mid = 0.5_dp*(x(:, 0) + x(:, n))
    e = 0.0_dp
    if (.not. vl%eq%degenerate) e = vl%eq%r/vl%eq%d_rigid
    vl%inertia_geometric = 0.0_dp
    do k = 0, n
      rk = x(:, k) - mid
      r2 = dot_product(rk, rk)
      a = dot_product(rk, e)
      vl%inertia_geometric = vl%inertia_geometric + 0.5_dp*model%node_mass(k)*(r2 + a*a)
    end do
    ! (32), transverse, energy-weighted
    wx2 = vl%eq%omega_body(1)**2
    wy2 = vl%eq%omega_body(2)**2
    if (wx2 + wy2 > 0.0_dp .and. .not. all(vl%eq%j_fallback(1:2))) then
      vl%inertia_eq32 = (vl%eq%j_rigid(1)*wx2 + vl%eq%j_rigid(2)*wy2)/(wx2 + wy2)
    else
      vl%inertia_eq32 = vl%inertia_geometric
    end if
    vl%inertia = min(max(vl%inertia_eq32, vl%inertia_geometric/guard_band), vl%inertia_geometric*guard_band)
    vl%inertia_guarded = vl%inertia /= vl%inertia_eq32
    ! the chord's transverse angular velocity (the spin of the two-angle frame,
    ! Eq. (27) omega_z, is not a motion of the line)
    vl%omega = vl%eq%omega - dot_product(vl%eq%omega, e)*e
  end function virtual_line_body

  !> Attitude of the chain's line body B2 for the chord r = x_N - x_0: its z
  !> axis points from the parachute to the rocket (kane_chain%set_line_link:
  !> proximal = [0, 0, d/2] is the rocket-side joint), y up in the vertical
  !> plane through the chord (earth x if the chord is vertical), x = y cross z.
  function line_body_attitude(r) result(q)
    real(dp), intent(in) :: r(3)   !< chord, node 0 -> node N [m]
    real(dp) :: q(4)
    real(dp) :: ez(3), ey(3), up(3), c(3, 3)
    ez = -r/norm2(r)
    up = [0.0_dp, 1.0_dp, 0.0_dp]
    if (abs(dot_product(ez, up)) > 1.0_dp - 1.0e-9_dp) up = [1.0_dp, 0.0_dp, 0.0_dp]
    ey = up - dot_product(up, ez)*ez
    ey = ey/norm2(ey)
    c(:, 2) = ey
    c(:, 3) = ez
    c(:, 1) = cross(ey, ez)
    q = dcm_to_quat(c)
  end function line_body_attitude

  ! ------------------------------------------------------------------ loads

  !> Weight and drag of B2 and B3 (see the module header).  No allocation.
  subroutine rigidized_add_loads(self, t, bodies, force, moment, error)
    class(rigidized_loads), intent(inout) :: self
    real(dp), intent(in) :: t
    type(rigid_body), intent(in) :: bodies(0:)
    real(dp), intent(inout) :: force(:, 0:)
    real(dp), intent(inout) :: moment(:, 0:)
    type(error_type), allocatable, intent(inout) :: error
    type(air_state) :: air
    real(dp) :: e(3), ds, s, p(3), vp(3), u(3), ut(3), un(3), drag(3), qn, qt, rho, rho0, slope, y0, y1
    real(dp) :: wp(3), dl(3), mp(3), xs(3)
    integer :: j
    if (ubound(bodies, 1) < 3) then
      call fatal_error(error, "rigidized loads need the chain rocket - line - parachute (bodies 0..3)")
      return
    end if
    associate(b2 => bodies(2), b3 => bodies(3))
      if (self%gravity) then
        force(2, 2) = force(2, 2) - self%line_mass*g0
        force(2, 3) = force(2, 3) - self%chute%mass*g0
      end if
      self%line_drag = 0.0_dp
      self%chute_drag = 0.0_dp
      if (.not. self%air) return
      ! the rod's ends: z = +d/2 (rocket side) and z = -d/2 (parachute side)
      e = b2%c(:, 3)
      y0 = b2%r(2) + 0.5_dp*self%length*e(2)
      y1 = b2%r(2) - 0.5_dp*self%length*e(2)
      air = isa(min(y0, y1))
      if (.not. air%in_range) then
        call fatal_error(error, "line altitude " // str(min(y0, y1)) // " m is outside the atmosphere model")
        return
      end if
      rho0 = air%density
      slope = 0.0_dp
      if (abs(y1 - y0) > 1.0e-3_dp) then
        air = isa(max(y0, y1))
        if (.not. air%in_range) then
          call fatal_error(error, "line altitude " // str(max(y0, y1)) // " m is outside the atmosphere model")
          return
        end if
        slope = log(air%density/rho0)/abs(y1 - y0)
      end if
      qn = 0.5_dp*self%cd_normal*self%diameter
      qt = 0.5_dp*self%cd_tangential*pi*self%diameter
      ds = self%length/self%drag_strips
      do j = 1, self%drag_strips
        s = 0.5_dp*self%length - (j - 0.5_dp)*ds
        p = [0.0_dp, 0.0_dp, s]
        wp = cross(b2%w, p)   ! a function result inside matmul: heap temporary
        vp = b2%v + matmul(b2%c, wp) + (0.5_dp - s/self%length)*self%v_eps
        u = -vp
        if (self%chute%gust%active) then
          xs = b2%r + matmul(b2%c, p)
          u = u + gust_velocity(self%chute%gust, xs)
        end if
        ut = dot_product(u, e)*e
        un = u - ut
        rho = rho0*exp(slope*(b2%r(2) + s*e(2) - min(y0, y1)))
        drag = rho*ds*(qn*norm2(un)*un + qt*norm2(ut)*ut)
        self%line_drag = self%line_drag + drag
        force(:, 2) = force(:, 2) + drag
        dl = matmul(transpose(b2%c), drag)
        mp = cross(p, dl)     ! a function result added to a dummy's section: heap temporary
        moment(:, 2) = moment(:, 2) + mp
      end do
      air = isa(b3%r(2))
      if (.not. air%in_range) then
        call fatal_error(error, "parachute altitude " // str(b3%r(2)) // " m is outside the atmosphere model")
        return
      end if
      vp = air_relative_velocity(self%chute%gust, b3%r, b3%v + self%v_eps)
      ! drag and the filling canopy's apparent-mass momentum (canopy_node_acceleration)
      self%chute_drag = -0.5_dp*air%density*parachute_drag_area(self%chute, t)*norm2(vp)*vp - &
        parachute_added_mass_rate(self%chute, air%density, t)*vp
      force(:, 3) = force(:, 3) + self%chute_drag
    end associate
  end subroutine rigidized_add_loads

  ! ------------------------------------------------------------------ chain

  !> Absolute state from the relative one (aircraft and rocket r, v).
  subroutine chain_to_absolute(self, t, y)
    class(rigidized_chain), intent(inout) :: self
    real(dp), intent(in) :: t, y(:)
    integer :: i
    self%yabs = y
    do i = 0, 1
      self%yabs(13*i+1) = y(13*i+1) + self%v_ref*t
      self%yabs(13*i+2) = y(13*i+2) + self%h_ref
      self%yabs(13*i+4) = y(13*i+4) + self%v_ref
    end do
  end subroutine chain_to_absolute

  !> Bodies from the state, the phase in the launch loads.
  subroutine chain_prepare(self, t, y)
    class(rigidized_chain), intent(inout) :: self
    real(dp), intent(in) :: t, y(:)
    call self%to_absolute(t, y)
    call self%sep%load_state(self%yabs)
    if (self%iloads > 0) then
      select type (s => self%sep%sources(self%iloads)%source)
      type is (launch_loads)
        s%phase = self%sep%phase
      end select
    end if
  end subroutine chain_prepare

  !> Chain right-hand side: the separation system's (Kane + CFA) in the relative frame.
  subroutine chain_rhs(self, t, y, ydot, status)
    class(rigidized_chain), intent(inout) :: self
    real(dp), intent(in) :: t
    real(dp), intent(in) :: y(:)
    real(dp), intent(out) :: ydot(:)
    integer, intent(out) :: status
    call self%prepare(t, y)
    call self%sep%rhs(t, self%yabs, ydot, status)
    if (status /= rhs_ok) then
      if (allocated(self%sep%failure)) self%failure = self%sep%failure
      return
    end if
    ydot(1) = ydot(1) - self%v_ref
    ydot(14) = ydot(14) - self%v_ref
  end subroutine chain_rhs

  !> Number of event functions.
  integer function chain_nroots_fn(self)
    class(rigidized_chain), intent(in) :: self
    chain_nroots_fn = rigidized_nroots
    if (.false.) chain_nroots_fn = self%iloads
  end function chain_nroots_fn

  !> Event functions: the separation scene's and, in Case 3 until found, the
  !> rocket's Euler pitch rate (its first maximum).
  subroutine chain_roots(self, t, y, g, status)
    class(rigidized_chain), intent(inout) :: self
    real(dp), intent(in) :: t
    real(dp), intent(in) :: y(:)
    real(dp), intent(out) :: g(:)
    integer, intent(out) :: status
    g = 1.0_dp
    call self%prepare(t, y)
    call self%sep%roots(t, self%yabs, g(1:separation_nroots), status)
    if (status /= rhs_ok) then
      if (allocated(self%sep%failure)) self%failure = self%sep%failure
      return
    end if
    if (self%sep%phase /= phase_free) return
    if (self%find_pitch_max) g(rigidized_pitch_root) = self%euler_pitch_rate()
    g(rigidized_clearance_root) = clearance_rate(self%clr, self%sep%bodies(0), self%sep%bodies(1))
  end subroutine chain_roots

  !> Euler pitch rate of the rocket [rad/s] (Eqs. (49)-(50), no singularity).
  real(dp) function chain_euler_pitch_rate(self) result(r)
    class(rigidized_chain), intent(in) :: self
    real(dp) :: e(3)
    e = dcm_to_euler(self%sep%bodies(1)%c)
    r = sin(e(3))*self%sep%bodies(1)%w(2) + cos(e(3))*self%sep%bodies(1)%w(3)
  end function chain_euler_pitch_rate

  !> Force of the virtual line B2 on the rocket at the tie-down point, earth
  !> [N]: the chain's joint force, from Newton's law on the rocket,
  !> m1 a1 - F_applied - R_H.  Valid after `sep%evaluate`.
  function chain_line_force(self) result(f)
    class(rigidized_chain), intent(in) :: self
    real(dp) :: f(3)
    f = self%sep%bodies(1)%mass*self%sep%udot(1:3) - self%sep%force(:, 1) - self%sep%rh_force
  end function chain_line_force

  !> Per-component absolute tolerances of the chain state: positions and
  !> velocities (relative frame) 100 atol, quaternions atol, rates 10 atol.
  pure function chain_atol(atol) result(a)
    real(dp), intent(in) :: atol
    real(dp) :: a(chain_size)
    integer :: k, o
    a = 100.0_dp*atol
    a(7:10) = atol
    a(11:13) = 10.0_dp*atol
    do k = 1, 3
      o = 19 + 7*(k - 1)
      a(o+1:o+4) = atol
      a(o+5:o+7) = 10.0_dp*atol
    end do
  end function chain_atol

  !> State i of the chain: the aircraft's 13, the rocket's 13, then attitude
  !> and angular velocity (7 each) of the virtual line body and the parachute link.
  function chain_state_name(self, i) result(name)
    class(rigidized_chain), intent(in) :: self  !< the chain
    integer, intent(in) :: i                    !< state index
    character(len=:), allocatable :: name
    select case (i)
    case (1:13)
      name = "aircraft " // body_state_name(i)
    case (14:26)
      name = "rocket " // body_state_name(i - 13)
    case (27:33)
      name = "virtual line body " // body_state_name(i - 20)
    case default
      name = "parachute link " // body_state_name(i - 27)
    end select
    if (.false.) name = name // str(self%v_ref)
  end function chain_state_name


  ! ------------------------------------------------------------------ coupling

  !> Build both subsystems and their integrators at time t0.
  !> `sep`: the separation system with nchain = 3, its sources (among them a
  !> launch_loads at index iloads and a rigidized_loads at index iline, 0 if
  !> absent) and the states of bodies 0 (aircraft) and 1 (rocket), absolute.
  !> x0, v0: the line's nodes (absolute, node 0 at the tie-down point), which
  !> also place B2 along the chord and B3 at node N.  `phase`: start phase.
  !> `machine`: a separation system whose phase machine the chain continues
  !> (a switch from the direct coupling during a run: its phase, event times
  !> and the cut joint's references captured at the run's start) instead of
  !> starting a new one in `phase`.
  subroutine coupling_init(self, sep, iloads, iline, model, chute, x0, v0, v_ref, h_ref, t0, phase, opts, error, &
      machine)
    class(rigidized_coupling), intent(inout) :: self       !< the coupling (re-initialised)
    type(separation_system), intent(in) :: sep             !< configured chain scene
    integer, intent(in) :: iloads                          !< launch_loads source index (0: none)
    integer, intent(in) :: iline                           !< rigidized_loads source index (0: none)
    type(line_model), intent(in) :: model                  !< the line
    type(parachute), intent(in) :: chute                   !< the canopy (fill_time set)
    real(dp), intent(in) :: x0(:, 0:), v0(:, 0:)           !< line nodes at t0, earth [m, m/s]
    real(dp), intent(in) :: v_ref, h_ref                   !< reference frame [m/s, m]
    real(dp), intent(in) :: t0                             !< start time [s]
    integer, intent(in) :: phase                           !< start phase
    type(rigidized_settings), intent(in) :: opts           !< settings
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    type(separation_system), intent(in), optional :: machine !< phase machine to continue
    type(cvode_options) :: copt, lopt
    real(dp) :: y(chain_size), e(3)
    real(dp), allocatable :: yl(:), atol_l(:)
    integer :: n

    call self%free()
    self%opts = opts
    ! a fresh start: counters and books of a previous run of this coupling go
    self%n_refresh = 0
    self%n_guard_mass = 0
    self%n_guard_inertia = 0
    self%momentum_jump = 0.0_dp
    self%angular_momentum_jump = 0.0_dp
    self%kinetic_energy_jump = 0.0_dp
    self%n_saved = 0
    self%motion_set = .false.
    if (.not. (opts%outer_dt > 0.0_dp)) then
      call fatal_error(error, "rigidized coupling: outer_dt = " // str(opts%outer_dt) // " s must be > 0")
      return
    end if
    if (.not. (opts%guard_band >= 1.0_dp)) then
      call fatal_error(error, "rigidized coupling: guard_band = " // str(opts%guard_band) // " must be >= 1")
      return
    end if
    if (sep%chain%n /= 3) then
      call fatal_error(error, "rigidized coupling: the chain must hold rocket, line and parachute (3 bodies)")
      return
    end if
    n = model%n
    if (opts%far_end == "chain" .and. n < 2) then
      call fatal_error(error, "rigidized coupling: far_end = 'chain' needs n_seg >= 2 (both end nodes are " // &
        "kinematic)")
      return
    end if
    allocate(self%chain, self%line)
    self%chain%sep = sep
    if (present(machine)) call continue_phase_machine(self%chain%sep, machine)
    self%chain%iloads = iloads
    self%chain%iline = iline
    self%chain%v_ref = v_ref
    self%chain%h_ref = h_ref
    ! --- the line subsystem
    call self%line%setup(model, chute, opts%far_end == "chain", v_ref, h_ref)
    self%line%x = x0
    self%line%v = v0
    ! --- Step 1: the virtual body from the line; B2 along the chord, B3 at node N
    self%vl = virtual_line_body(model, x0, v0, opts%guard_band)
    if (self%vl%eq%degenerate) then
      call fatal_error(error, "rigidized coupling: the line's ends coincide at t = " // str(t0) // &
        " s (no virtual body axis)")
      return
    end if
    associate(s => self%chain%sep)
      call s%bodies(2)%set_attitude(line_body_attitude(self%vl%eq%r))
      s%bodies(2)%w = matmul(transpose(s%bodies(2)%c), self%vl%omega)
      call s%bodies(3)%set_attitude([1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp])
      s%bodies(3)%w = 0.0_dp
      call s%pack_state(y)
    end associate
    ! relative chain state
    y(1:2) = y(1:2) - [v_ref*t0, h_ref]
    y(4) = y(4) - v_ref
    y(14:15) = y(14:15) - [v_ref*t0, h_ref]
    y(17) = y(17) - v_ref
    call set_links(self, t0, y, error)
    if (allocated(error)) return
    ! the rocket's tie-down must coincide with node 0
    e = self%chain%sep%bodies(2)%point_position(self%chain%sep%chain%link(2)%proximal) - x0(:, 0)
    if (norm2(e) > 1.0e-6_dp*(1.0_dp + self%vl%length)) then
      call fatal_error(error, "rigidized coupling: line node 0 is " // str(norm2(e)) // " m away from the " // &
        "rocket's tie-down point at t = " // str(t0) // " s")
      return
    end if
    if (present(machine)) then
      call self%chain%sep%evaluate(t0, self%chain%yabs, error)
    else
      call self%chain%sep%start(t0, self%chain%yabs, phase, error)
    end if
    if (allocated(error)) return
    copt = cvode_options(method="bdf", linear_solver="dense", rtol=opts%chain_rtol, &
      atol_vector=chain_atol(opts%chain_atol), max_order=opts%chain_max_order, max_num_steps=1000000, &
      max_total_steps=opts%max_steps, max_wall_time=opts%max_wall_time, wall_deadline=opts%wall_deadline, &
      t_final=opts%t_end, max_step=opts%max_step)
    call self%chain_solver%init(self%chain, t0, y, copt, error)
    if (allocated(error)) return
    ! --- the line's integrator
    allocate(yl(self%line%n_state()), atol_l(self%line%n_state()))
    call self%line%pack(t0, x0, v0, yl)
    atol_l = opts%inner_atol
    lopt = cvode_options(method="bdf", linear_solver="second_order_band", upper_bandwidth=line_band_upper, &
      lower_bandwidth=line_band_lower, rtol=opts%inner_rtol, atol_vector=atol_l, &
      max_order=opts%inner_max_order, max_num_steps=1000000, max_total_steps=opts%max_steps, t_final=opts%t_end, &
      max_step=opts%max_step, max_wall_time=opts%max_wall_time, wall_deadline=opts%wall_deadline)
    self%t = t0
    call sample_ends(self, t0, self%chain_solver%y)
    call self%line%near%set_body_motion(t0, self%tie_x, self%tie_v, t0 + opts%outer_dt, &
      self%tie_x + opts%outer_dt*self%tie_v, self%tie_v)
    call self%line%far%set_body_motion(t0, self%b3_x, self%b3_v, t0 + opts%outer_dt, &
      self%b3_x + opts%outer_dt*self%b3_v, self%b3_v)
    self%marching = opts%inner_scheme == "marching"
    if (self%marching) then
      call self%marcher%init(self%line, t0, yl, opts%inner_dt, opts%inner_force_tol, opts%inner_max_iterations, &
        opts%max_steps, error)
    else
      call self%line_solver%init(self%line, t0, yl, lopt, error)
    end if
  end subroutine coupling_init

  !> Continue the phase machine of `from` in `to` (separation systems of the
  !> same aircraft, rocket and cut joint, possibly with different chains):
  !> the phase, the event times, the edge flags and the joint's constraint
  !> references (captured once, at the run's start: a new capture would take
  !> the present constraint drift for exact).  The caller then loads the state
  !> and evaluates, as `start` would.
  pure subroutine continue_phase_machine(to, from)
    type(separation_system), intent(inout) :: to
    type(separation_system), intent(in) :: from
    to%phase = from%phase
    to%event_time = from%event_time
    to%early_separation = from%early_separation
    to%edge_pull_time = from%edge_pull_time
    to%joint = from%joint
  end subroutine continue_phase_machine

  !> Give B2 the virtual body self%vl and B3 its mass at time t (chain state y,
  !> relative); updates the rod length in the loads.
  subroutine set_links(self, t, y, error)
    type(rigidized_coupling), intent(inout) :: self
    real(dp), intent(in) :: t, y(:)
    type(error_type), allocatable, intent(inout) :: error
    type(air_state) :: air
    real(dp) :: j3, r3
    associate(s => self%chain%sep)
      call s%set_line_body(2, self%vl%mass, [self%vl%inertia, self%vl%inertia, 0.0_dp], self%vl%length, error)
      if (allocated(error)) return
      call self%chain%prepare(t, y)   ! B3 now at the end of the new rod
      air = isa(s%bodies(3)%r(2))
      if (.not. air%in_range) then
        call fatal_error(error, "parachute altitude " // str(s%bodies(3)%r(2)) // " m is outside the " // &
          "atmosphere model at t = " // str(t) // " s")
        return
      end if
      self%chute_link_mass = self%line%chute%mass + parachute_added_mass(self%line%chute, air%density, t)
      ! small isotropic inertia of a solid sphere of the inflated diameter: it
      ! does not enter the motion (B3's CG is its joint: its rotation is decoupled)
      r3 = 0.35_dp*parachute_nominal_diameter(self%line%chute)
      j3 = 0.4_dp*self%chute_link_mass*r3**2
      self%chute_link_inertia = j3
      call s%set_link(3, "parachute", self%chute_link_mass, reshape([j3, 0.0_dp, 0.0_dp, 0.0_dp, j3, &
        0.0_dp, 0.0_dp, 0.0_dp, j3], [3, 3]), [0.0_dp, 0.0_dp, 0.0_dp], [0.0_dp, 0.0_dp, 0.0_dp], error)
      if (allocated(error)) return
      if (self%chain%iline > 0) then
        select type (src => s%sources(self%chain%iline)%source)
        type is (rigidized_loads)
          src%length = self%vl%length
          src%v_eps = self%vl%eq%v_eps
        end select
      end if
      call self%chain%prepare(t, y)
    end associate
  end subroutine set_links

  !> Samples of the line's end motions from the chain state y (relative) at t:
  !> the rocket's tie-down point and B3 (relative frame).
  subroutine sample_ends(self, t, y)
    type(rigidized_coupling), intent(inout) :: self
    real(dp), intent(in) :: t, y(:)
    real(dp) :: frame_x(3), frame_v(3)
    call self%chain%prepare(t, y)
    frame_x = [self%chain%v_ref*t, self%chain%h_ref, 0.0_dp]
    frame_v = [self%chain%v_ref, 0.0_dp, 0.0_dp]
    associate(s => self%chain%sep)
      self%tie_x = s%bodies(1)%point_position(s%tie_down) - frame_x
      self%tie_v = s%bodies(1)%point_velocity(s%tie_down) - frame_v
      self%b3_x = s%bodies(3)%r - frame_x
      self%b3_v = s%bodies(3)%v - frame_v
      self%tail_x = s%bodies(0)%point_position(self%chain%clr%point) - frame_x
      self%tail_v = s%bodies(0)%point_velocity(self%chain%clr%point) - frame_v
    end associate
  end subroutine sample_ends

  !> §2.4 Step 3: the virtual body from the line state at self%t.  Records the
  !> change of the chain's momentum this makes.
  subroutine coupling_refresh(self, error)
    class(rigidized_coupling), intent(inout) :: self       !< the coupling
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    real(dp) :: p0(3), h0(3), e0
    call unpack_line(self)
    self%vl = virtual_line_body(self%line%model, self%line%x, self%line%v, self%opts%guard_band)
    if (self%vl%eq%degenerate) then
      call fatal_error(error, "the line's ends coincide at t = " // str(self%t) // " s (no virtual body axis)")
      return
    end if
    self%n_refresh = self%n_refresh + 1
    if (self%vl%mass_guarded) self%n_guard_mass = self%n_guard_mass + 1
    if (self%vl%inertia_guarded) self%n_guard_inertia = self%n_guard_inertia + 1
    call self%chain%prepare(self%t, self%chain_solver%y)
    p0 = self%chain%sep%linear_momentum()
    h0 = self%chain%sep%angular_momentum()
    e0 = self%chain%sep%kinetic_energy()
    call set_links(self, self%t, self%chain_solver%y, error)
    if (allocated(error)) return
    self%kinetic_energy_jump = self%kinetic_energy_jump + self%chain%sep%kinetic_energy() - e0
    self%momentum_jump = self%momentum_jump + self%chain%sep%linear_momentum() - p0
    self%angular_momentum_jump = self%angular_momentum_jump + self%chain%sep%angular_momentum() - h0
    if (self%opts%restart_on_refresh) call self%restart_chain(error)
  end subroutine coupling_refresh

  !> Restart the chain's CVODE at self%t (after an event or a refresh); the
  !> solver keeps its counters' totals over the restart.
  subroutine coupling_restart_chain(self, error)
    class(rigidized_coupling), intent(inout) :: self       !< the coupling
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    real(dp), allocatable :: y(:)
    allocate(y, source=self%chain_solver%y)
    call self%chain_solver%reinit(self%t, y, error)
  end subroutine coupling_restart_chain

  !> §2.4 Steps 3-4 of one outer step from self%t towards t_target: refresh
  !> the virtual body from the line (Step 3) and integrate the chain to
  !> t_target or its first event (Step 4).  The chain's states at the output
  !> times t_out inside (self%t, t_target] are saved from CVODE's interpolant
  !> while it passes them (n_saved, saved_t, saved_y), so that the outer step
  !> does not depend on the output cadence.  On an event `event` is true,
  !> `which` holds CVODE's root info and the step ends at the event.  Then
  !> `line_to` each saved time (to record both subsystems there) and
  !> `end_step` (Step 5).
  subroutine coupling_begin_step(self, t_target, event, which, error, t_out, observer)
    class(rigidized_coupling), intent(inout) :: self       !< the coupling
    real(dp), intent(in) :: t_target                       !< end of the step [s]
    logical, intent(out) :: event                          !< the chain stopped at an event
    integer, intent(out) :: which(:)                       !< root info (rigidized_nroots)
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    real(dp), intent(in), optional :: t_out(:)             !< output times, ascending
    class(step_observer), intent(inout), optional :: observer  !< shown the chain's steps
    real(dp) :: eps
    integer :: j, nt
    event = .false.
    which = 0
    self%n_saved = 0
    call self%refresh(error)
    if (allocated(error)) return
    self%step_t0 = self%t
    eps = 1.0e-12_dp*max(1.0_dp, abs(t_target))
    call sample_ends(self, self%t, self%chain_solver%y)
    self%tie0_x = self%tie_x; self%tie0_v = self%tie_v; self%b30_x = self%b3_x; self%b30_v = self%b3_v
    self%tail0_x = self%tail_x; self%tail0_v = self%tail_v
    nt = 0
    if (present(t_out)) nt = size(t_out)
    if (.not. allocated(self%saved_t)) allocate(self%saved_y(chain_size, 0), self%saved_t(0))
    if (size(self%saved_t) < nt) then
      deallocate(self%saved_y, self%saved_t)
      allocate(self%saved_y(chain_size, nt), self%saved_t(nt))
    end if
    call self%chain_solver%set_stop_time(t_target, error)
    if (allocated(error)) return
    do j = 1, nt
      if (t_out(j) <= self%t + eps) cycle
      if (t_out(j) >= t_target - eps) exit
      call self%chain_solver%advance(t_out(j), error, event, which, observer)
      if (allocated(error) .or. event) return
      self%n_saved = self%n_saved + 1
      self%saved_t(self%n_saved) = t_out(j)
      self%saved_y(:, self%n_saved) = self%chain_solver%y
    end do
    call self%chain_solver%advance(t_target, error, event, which, observer)
    if (allocated(error) .or. event) return
    ! an output time at the step's end, to rounding (the grid's k h and the
    ! outputs' m output_dt): recorded there, under its own time
    do j = 1, nt
      if (abs(t_out(j) - t_target) <= eps) then
        self%n_saved = self%n_saved + 1
        self%saved_t(self%n_saved) = t_out(j)
        self%saved_y(:, self%n_saved) = self%chain_solver%y
        exit
      end if
    end do
  end subroutine coupling_begin_step

  !> Step 5 up to time t inside the current outer step (a saved output time):
  !> the line sub-stepped along the chain's end motions; its state at t is then
  !> in the line solver (`line_state`).
  subroutine coupling_line_to(self, t, error, observer)
    class(rigidized_coupling), intent(inout) :: self       !< the coupling
    real(dp), intent(in) :: t                              !< target time, <= the chain's [s]
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    class(step_observer), intent(inout), optional :: observer  !< shown the line's sub-steps
    real(dp) :: t1
    t1 = self%chain_solver%t
    if (.not. self%motion_set) then
      ! the end motions over [t0, t1] (the chain has reached t1)
      call sample_ends(self, t1, self%chain_solver%y)
      call self%line%near%set_body_motion(self%step_t0, self%tie0_x, self%tie0_v, t1, self%tie_x, self%tie_v)
      if (self%line%far_kinematic) call self%line%far%set_body_motion(self%step_t0, self%b30_x, self%b30_v, t1, &
        self%b3_x, self%b3_v)
      call self%line%tail%set_body_motion(self%step_t0, self%tail0_x, self%tail0_v, t1, self%tail_x, self%tail_v)
      if (self%marching) then
        call self%marcher%set_stop_time(t1)
      else
        call self%line_solver%set_stop_time(t1, error)
      end if
      if (allocated(error)) then
        error%message = "line sub-steps: " // error%message
        return
      end if
      self%motion_set = .true.
    end if
    if (self%marching) then
      if (self%marcher%t >= t) return
      call self%marcher%advance(self%line, min(t, t1), error, observer)
    else
      if (self%line_solver%t >= t) return
      call self%line_solver%advance(min(t, t1), error, observer=observer)
    end if
    if (allocated(error)) error%message = "line sub-steps: " // error%message
  end subroutine coupling_line_to

  !> Step 5 to the end of the outer step (the chain's time): both subsystems
  !> are then at self%t.
  subroutine coupling_end_step(self, error, observer)
    class(rigidized_coupling), intent(inout) :: self       !< the coupling
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    class(step_observer), intent(inout), optional :: observer  !< shown the line's sub-steps
    real(dp) :: t1
    t1 = self%chain_solver%t
    if (t1 > self%step_t0) then
      call self%line_to(t1, error, observer)
      if (allocated(error)) return
    end if
    self%motion_set = .false.
    self%t = t1
  end subroutine coupling_end_step

  !> One whole outer step (begin_step, end_step) without outputs.
  subroutine coupling_outer_step(self, t_target, event, which, error)
    class(rigidized_coupling), intent(inout) :: self       !< the coupling
    real(dp), intent(in) :: t_target                       !< end of the step [s]
    logical, intent(out) :: event                          !< the chain stopped at an event
    integer, intent(out) :: which(:)                       !< root info (rigidized_nroots)
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    call self%begin_step(t_target, event, which, error)
    if (allocated(error)) return
    call self%end_step(error)
  end subroutine coupling_outer_step

  !> The line's nodes (earth, absolute) and segment tensions at the line
  !> solver's time (self%t, or an output time inside an outer step).
  subroutine coupling_line_state(self, x, v, tension)
    class(rigidized_coupling), intent(inout) :: self   !< the coupling
    real(dp), intent(out) :: x(:, 0:), v(:, 0:)        !< nodes (3, 0:N) [m, m/s]
    real(dp), intent(out) :: tension(:)                !< (N) [N]
    integer :: st
    call unpack_line(self)
    call self%line%model%forces(self%line%x, self%line%v, self%line%f, self%line%tension, st)
    x = self%line%x
    v = self%line%v
    tension = self%line%tension
  end subroutine coupling_line_state

  !> Counters: chain (all restarts: the solver keeps the totals) and line summed.
  function coupling_stats(self) result(s)
    class(rigidized_coupling), intent(in) :: self   !< the coupling
    type(cvode_stats) :: s
    s = self%chain_solver%stats()
    if (self%marching) then
      call add_stats(s, self%marcher%stats())
    else
      call add_stats(s, self%line_solver%stats())
    end if
  end function coupling_stats

  !> Steps the line's sub-stepper has taken so far.
  integer(i8) function coupling_line_steps(self) result(n)
    class(rigidized_coupling), intent(in) :: self   !< the coupling
    if (self%marching) then
      n = self%marcher%steps
    else
      n = int(self%line_solver%steps_taken(), i8)
    end if
  end function coupling_line_steps

  !> The line's nodes (self%line%x, %v) from its sub-stepper's state.
  subroutine unpack_line(self)
    type(rigidized_coupling), intent(inout) :: self
    if (self%marching) then
      call self%line%unpack(self%marcher%t, self%marcher%y)
    else
      call self%line%unpack(self%line_solver%t, self%line_solver%y)
    end if
  end subroutine unpack_line

  !> Release both integrators and subsystems.
  subroutine coupling_free(self)
    class(rigidized_coupling), intent(inout) :: self   !< the coupling
    call self%chain_solver%free()
    call self%line_solver%free()
    call self%marcher%free()
    self%marching = .false.
    if (associated(self%chain)) deallocate(self%chain)
    if (associated(self%line)) deallocate(self%line)
    nullify(self%chain, self%line)
  end subroutine coupling_free


end module airlaunch_rigidized_coupling
