!> The flexible line (suspension line, body B2) of Zheng & Zhang (2018) §2.1–2.2
!> as a lumped-mass semi-discretization of the continuum Eqs. (3), (5), (8), (10).
!>
!> Discretization.  The unstretched line (length L, material coordinate s) is cut
!> into N equal segments of unstretched length l0 = L/N between nodes 0..N.
!> Mass is conserved per material element (Eq. (5): rho* ds1 = rho ds), so each
!> segment carries rho*l0 whatever its stretch; half of it is lumped at each end
!> node (node masses rho*l0/2 at nodes 0 and N, rho*l0 inside).  Segment k joins
!> nodes k-1 and k; its stretched vector is dx_k = x_k - x_{k-1}, length
!> ell_k = |dx_k|, tangent t_k = dx_k/ell_k (Eq. (2)), strain eps_k = ell_k/l0 - 1
!> and strain rate epsdot_k = t_k . (v_k - v_{k-1}) / l0.
!>
!> Constitutive law (Eq. (3) with internal damping, tension only):
!>     T_k = max(0, EA eps_k + c_d epsdot_k)   if eps_k > 0,
!>     T_k = 0                                 if eps_k <= 0 (slack),
!> so the line never carries compression.  c_d [N s] is an axial (Kelvin–Voigt)
!> damping coefficient: a segment dashpot of c_d/l0 [N s/m].  It damps the axial
!> mode of circular frequency w with damping ratio zeta = w c_d / (2 EA).  When
!> c_d > 0 the tension jumps by c_d*epsdot at the instant a segment goes taut
!> (a slack line cannot carry the dashpot force); with c_d = 0 the tension is a
!> continuous function of the state and the elastic energy 1/2 EA l0 eps^2 is C^1.
!>
!> Momentum (Eq. (8)) at node k:  m_k a_k = T_{k+1} t_{k+1} - T_k t_k + f_k,
!> where f_k lumps half of the distributed load f of each adjacent segment:
!>  - weight rho l0 g (earth frame: y up, so g = (0, -g0, 0)),
!>  - aerodynamic drag from the air velocity relative to the segment midpoint,
!>    u = wind + w_gust(midpoint) - (v_{k-1}+v_k)/2 (w_gust: the air-launch
!>    scene's discrete gust, airlaunch_gust; zero elsewhere), split into its
!>    tangential part u_t = (u.t)t and
!>    cross-flow part u_n = u - u_t (the independence principle):
!>        D = 1/2 rho_air ell_d [ Cd_n d |u_n| u_n + Cd_t pi d |u_t| u_t ],
!>    i.e. cross-flow drag on the projected area d*ell_d and skin friction on the
!>    wetted area pi*d*ell_d (MoorDyn's convention), ell_d = max(ell, l0): the
!>    stretched length of a taut segment, the material length l0 of a slack one
!>    (its crumpled material is all in the air; with the chord ell a slack line
!>    lost area and fell faster the finer it was cut).  The direction split
!>    still uses the chord's t (a slack segment's true shape is unknown: a
!>    model choice, docs/line.md section 1).  rho_air is the ISA density
!>    at the segment midpoint altitude y (see `air_density_fit`), or a fixed value.
!>  - optionally a settling aid: a linear damper to the earth frame,
!>    -alpha m_k v_k (mass-proportional "Rayleigh" damping, alpha [1/s]; m_k the
!>    line's own node mass, not a point-mass or canopy end's), used
!>    only to let static problems (catenary) settle; zero by default.
!> A parted segment (`parted`, set by the air-launch scene where the line breaks:
!> &line breaking_strength or break_time) carries no tension and no drag from
!> then on: its two halves stay with their nodes as mass (the lumped node
!> masses are unchanged) but their drag - half a segment each, at most 1/N of
!> the line's - is left out (the chord between the parted nodes no longer says
!> where the halves trail).
!> The compatibility Eq. (10) d/dt((1+eps) t) = dV/ds is satisfied identically by
!> the node kinematics: d/dt dx_k = v_k - v_{k-1}.
!>
!> The spatial discretization is second-order accurate in l0 (central differences
!> of the wave operator with lumped mass); the convergence test shows it.
!>
!> Mass matrix (`mass`).  "lumped" (the paper's, and the only one its explicit
!> marching scheme can use): the diagonal node masses above.  "mixed": each
!> segment's mass rho*l0 is distributed by the average of the lumped and the
!> consistent (linear-element) mass matrices,
!>     M_seg = rho l0 [[1/2 - beta, beta], [beta, 1/2 - beta]] (x) I3,  beta = 1/12,
!> which keeps the node loads (weight, drag) and the total momentum of the lumped
!> line (M's column sums are the lumped masses) but makes the dispersion of the
!> chain's waves fourth-order: for a mode of wavenumber k,
!>     (w l0/c)^2 = 2 (1 - cos k l0) / (1 - 2 beta (1 - cos k l0))
!>              = (k l0)^2 + (beta - 1/12) (k l0)^4 + O((k l0)^6),
!> so the (k l0)^4 term vanishes at beta = 1/12 (lumped: beta = 0, consistent:
!> 1/6, both second-order).  The accelerations then solve the tridiagonal
!> system M a = f (airlaunch_line_mass); the kinetic energy is 1/2 v^T M v.
!>
!> Use by an outside owner (the full simulation): the end nodes 0 and N are then
!> kinematic, tied to bodies (node 0: rocket nose, node N: parachute).  The owner
!> integrates nodes 1..N-1 with a_k = f_k/m_k and applies f(:,0) to the body at
!> node 0 and f(:,N) to the body at node N.  The end force contains
!>     f(:,0) = T_1 t_1 + m_0 g + D_1/2 (- alpha m_0 v_0),
!>     f(:,N) = -T_N t_N + m_N g + D_N/2 (- alpha m_N v_N),
!> i.e. the end segment's tension plus the loads of the end half-segment (its
!> weight and half its drag).  The half-segment mass m_0 = node_mass(0) =
!> rho*l0/2 is NOT accelerated by the line: the owner adds it to the body's mass
!> (its weight is already in f, so no gravity is applied to it again), or
!> neglects it (error of order m_0/m_body).  The tension alone is `tension(1)`,
!> `tension(N)` with `end_tangent`.  With the mixed mass the support of a
!> kinematic node 0 feels f(:,0) - m_0 a_0 - beta rho l0 (a_1 - a_0) (node 0's
!> row of M a); f(:,0) is the lumped-mass end force with either matrix (the line
!> scene records it as line_end_force; docs/line.md section 4).
module airlaunch_line_model
  use airlaunch_kinds, only: dp, g0, pi
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_atmosphere, only: isa, air_state, isa_min_altitude, isa_max_altitude
  use airlaunch_gust, only: gust_field, gust_velocity
  implicit none
  private
  public :: weakest_segment, segment_strengths, outside_atmosphere_message, cascade_note
  public :: line_params, line_model, line_energy, node_state_name, marching_stable_step, marching_diverged, &
    far_end_not_converged

  !> Physical parameters of one line (all SI; namelist group `&line`).
  type :: line_params
    real(dp) :: length = 60.0_dp           !< unstretched length L [m]
    integer :: n_seg = 60                  !< number of segments N (>= 1)
    real(dp) :: ea = 1.0e6_dp              !< axial stiffness EA [N]
    real(dp) :: mass_per_length = 0.2_dp   !< mass per unstretched length rho [kg/m]
    real(dp) :: damping = 0.0_dp           !< axial damping c_d [N s]: T = EA eps + c_d epsdot
    real(dp) :: settling_damping = 0.0_dp  !< settling aid alpha [1/s]: f = -alpha m v (0 = off)
    real(dp) :: diameter = 0.02_dp         !< aerodynamic diameter d [m]
    real(dp) :: cd_normal = 1.2_dp         !< cross-flow drag coefficient (on d*ell)
    real(dp) :: cd_tangential = 0.01_dp    !< tangential (skin-friction) coefficient (on pi*d*ell)
    logical :: gravity = .true.            !< weight of the line on
    logical :: air = .false.               !< aerodynamic drag of the line on
    real(dp) :: wind(3) = 0.0_dp           !< uniform air velocity, earth frame [m/s]
    real(dp) :: air_density = 0.0_dp       !< fixed air density [kg/m^3]; 0 = ISA at the altitude y
    character(len=8) :: mass = "lumped"    !< mass matrix: "lumped" (diagonal) or "mixed" (see the header)
  end type line_params

  !> One discretized line (no module state: one object per line).
  type :: line_model
    type(line_params) :: p                   !< parameters
    integer :: n = 0                         !< number of segments N
    real(dp) :: l0 = 0.0_dp                  !< unstretched segment length L/N [m]
    real(dp), allocatable :: node_mass(:)    !< lumped node masses m_k, k = 0..N [kg]
    !> beta of the segment mass matrix (0: lumped, 1/12: mixed; see the header)
    real(dp) :: mass_coupling = 0.0_dp
    !> a discrete gust in the air, read at each segment's midpoint (the
    !> air-launch scene's &gust; inactive by default)
    type(gust_field) :: gust
    !> the segments the line has broken at (their tension and drag are zero
    !> from then on; the air-launch scene's break, see the header), and how
    !> many there are (0: the line is whole)
    logical, allocatable :: parted(:)
    integer :: n_parted = 0
  contains
    procedure :: init => model_init
    procedure :: forces => model_forces
    procedure :: tensions => model_tensions
    procedure :: force_jacobian => model_force_jacobian
    procedure :: energy => model_energy
    procedure :: wave_speed => model_wave_speed
    procedure :: stable_step => model_stable_step
    procedure :: total_mass => model_total_mass
    procedure :: end_tangent => model_end_tangent
    procedure :: node_outside_atmosphere => model_node_outside_atmosphere
    procedure :: part => model_part
    procedure :: part_reached => model_part_reached
  end type line_model

  !> Mechanical energy of the line [J] (end bodies not included).
  type :: line_energy
    real(dp) :: kinetic = 0.0_dp     !< sum 1/2 m_k |v_k|^2
    real(dp) :: elastic = 0.0_dp     !< sum 1/2 EA l0 eps_k^2 over taut segments
    real(dp) :: potential = 0.0_dp   !< sum m_k g0 y_k (zero when gravity is off)
  end type line_energy

  !> Segments shorter than this fraction of l0 have no defined tangent.
  real(dp), parameter :: tiny_fraction = 1.0e-12_dp
  !> beta of the mixed mass matrix: fourth-order wave dispersion (see the header).
  real(dp), parameter :: mixed_mass_coupling = 1.0_dp/12.0_dp

contains

  !> Check the parameters and build the discretization.  Every rejected value
  !> gives one line naming the variable, its value and what is allowed.
  subroutine model_init(self, params, error)
    class(line_model), intent(inout) :: self               !< line (re-initialised)
    type(line_params), intent(in) :: params                !< physical parameters
    type(error_type), allocatable, intent(inout) :: error  !< set on bad input
    integer :: k

    call check_params(params, error)
    if (allocated(error)) return
    self%p = params
    self%n = params%n_seg
    self%l0 = params%length/params%n_seg
    if (allocated(self%node_mass)) deallocate(self%node_mass)
    allocate(self%node_mass(0:self%n))
    do k = 0, self%n
      self%node_mass(k) = params%mass_per_length*self%l0
    end do
    self%node_mass(0) = 0.5_dp*self%node_mass(0)
    self%node_mass(self%n) = 0.5_dp*self%node_mass(self%n)
    if (allocated(self%parted)) deallocate(self%parted)
    allocate(self%parted(self%n), source=.false.)
    self%n_parted = 0
    self%mass_coupling = 0.0_dp
    if (params%mass == "mixed") self%mass_coupling = mixed_mass_coupling
  end subroutine model_init

  !> Validate the line parameters.
  subroutine check_params(p, error)
    type(line_params), intent(in) :: p                     !< parameters
    type(error_type), allocatable, intent(inout) :: error  !< set on bad input
    if (p%n_seg < 1) then
      call fatal_error(error, "line: n_seg = " // str(p%n_seg) // " is not allowed: the number of " // &
        "segments must be >= 1")
    else if (.not. (p%length > 0.0_dp)) then
      call fatal_error(error, "line: length = " // str(p%length) // " m is not allowed: the unstretched " // &
        "length must be > 0")
    else if (.not. (p%ea > 0.0_dp)) then
      call fatal_error(error, "line: ea = " // str(p%ea) // " N is not allowed: the axial stiffness " // &
        "EA must be > 0")
    else if (.not. (p%mass_per_length > 0.0_dp)) then
      call fatal_error(error, "line: mass_per_length = " // str(p%mass_per_length) // " kg/m is not " // &
        "allowed: the mass per length must be > 0 (the node masses divide the nodal forces)")
    else if (.not. (p%damping >= 0.0_dp)) then
      call fatal_error(error, "line: damping = " // str(p%damping) // " N s is not allowed: the axial " // &
        "damping coefficient must be >= 0")
    else if (.not. (p%settling_damping >= 0.0_dp)) then
      call fatal_error(error, "line: settling_damping = " // str(p%settling_damping) // " 1/s is not " // &
        "allowed: must be >= 0")
    else if (.not. (p%diameter >= 0.0_dp)) then
      call fatal_error(error, "line: diameter = " // str(p%diameter) // " m is not allowed: must be >= 0")
    else if (.not. (p%cd_normal >= 0.0_dp)) then
      call fatal_error(error, "line: cd_normal = " // str(p%cd_normal) // " is not allowed: must be >= 0")
    else if (.not. (p%cd_tangential >= 0.0_dp)) then
      call fatal_error(error, "line: cd_tangential = " // str(p%cd_tangential) // " is not allowed: " // &
        "must be >= 0")
    else if (.not. (p%air_density >= 0.0_dp)) then
      call fatal_error(error, "line: air_density = " // str(p%air_density) // " kg/m^3 is not allowed: " // &
        "must be > 0, or 0 for the ISA density at the line's altitude")
    else if (any(p%wind /= p%wind)) then
      call fatal_error(error, "line: wind has a NaN component: must be finite [m/s]")
    else if (p%mass /= "lumped" .and. p%mass /= "mixed") then
      call fatal_error(error, "line: mass = '" // trim(p%mass) // "' is not allowed: use 'lumped' or 'mixed'")
    end if
  end subroutine check_params

  !> Nodal forces and segment tensions for node positions x(3,0:N) and
  !> velocities v(3,0:N) (earth frame, y up).  f(:,k) is the total force on node
  !> k from the tensions of its segments and its lumped distributed loads (see
  !> the module header for what the end forces contain).  Hot path: no
  !> allocation, no I/O.  status = 0, or 1 if a tension is not finite.
  subroutine model_forces(self, x, v, f, tension, status)
    class(line_model), intent(in) :: self      !< line
    real(dp), intent(in) :: x(:, 0:)           !< node positions (3, 0:N) [m]
    real(dp), intent(in) :: v(:, 0:)           !< node velocities (3, 0:N) [m/s]
    real(dp), intent(out) :: f(:, 0:)          !< node forces (3, 0:N) [N]
    real(dp), intent(out) :: tension(:)        !< segment tensions T_k, k = 1..N [N]
    integer, intent(out) :: status             !< 0 ok, 1 non-finite tension
    integer :: k, n
    real(dp) :: dx(3), t(3), u(3), ut(3), un(3), drag(3), mid(3)
    real(dp) :: ell, tk, ea, cd, tiny_len, rho_a, y_lo, rho_lo, log_slope
    real(dp) :: qn, qt

    n = self%n
    ea = self%p%ea
    cd = self%p%damping
    tiny_len = tiny_fraction*self%l0
    f(:, 0:n) = 0.0_dp
    if (self%p%gravity) f(2, 0:n) = -g0*self%node_mass(0:n)
    if (self%p%settling_damping > 0.0_dp) then
      do k = 0, n
        f(:, k) = f(:, k) - self%p%settling_damping*self%node_mass(k)*v(:, k)
      end do
    end if
    if (self%p%air) call air_density_fit(self, x, y_lo, rho_lo, log_slope)
    qn = 0.5_dp*self%p%cd_normal*self%p%diameter
    qt = 0.5_dp*self%p%cd_tangential*pi*self%p%diameter

    do k = 1, n
      if (self%n_parted > 0) then
        if (self%parted(k)) then
          tension(k) = 0.0_dp
          cycle
        end if
      end if
      dx = x(:, k) - x(:, k-1)
      ell = length3(dx)
      if (ell > tiny_len) then
        t = dx/ell
      else
        t = 0.0_dp
      end if
      tk = axial_tension(ea, cd, self%l0, ell, t, v(:, k-1), v(:, k))
      tension(k) = tk
      f(:, k-1) = f(:, k-1) + tk*t
      f(:, k) = f(:, k) - tk*t
      if (self%p%air .and. ell > tiny_len) then
        ! distributed drag f of Eq. (8), half to each node
        u = self%p%wind - 0.5_dp*(v(:, k-1) + v(:, k))
        if (self%gust%active) then
          mid = 0.5_dp*(x(:, k-1) + x(:, k))
          u = u + gust_velocity(self%gust, mid)
        end if
        ut = dot_product(u, t)*t
        un = u - ut
        rho_a = rho_lo
        if (log_slope /= 0.0_dp) rho_a = rho_lo*exp(log_slope*(0.5_dp*(x(2, k-1) + x(2, k)) - y_lo))
        ! area from the material length max(ell, l0): a slack segment keeps its drag
        drag = rho_a*max(ell, self%l0)*(qn*length3(un)*un + qt*length3(ut)*ut)
        f(:, k-1) = f(:, k-1) + 0.5_dp*drag
        f(:, k) = f(:, k) + 0.5_dp*drag
      end if
    end do
    status = 0
    if (.not. (abs(sum(tension(1:n))) <= huge(1.0_dp))) status = 1
  end subroutine model_forces

  !> The error of an explicit (marching) step whose force evaluation at time t
  !> found a tension that is not finite (the state diverged).
  subroutine marching_diverged(t, error)
    real(dp), intent(in) :: t                              !< time of the state [s]
    type(error_type), allocatable, intent(inout) :: error  !< set
    call fatal_error(error, "line (marching): a line tension is not finite at t = " // str(t) // &
      " s: the state diverged")
  end subroutine marching_diverged

  !> The error of a marching step whose far-end force iteration (Eq. (16))
  !> stopped at t with residual |e| above e0 after `iterations`.
  subroutine far_end_not_converged(t, residual, e0, iterations, error)
    real(dp), intent(in) :: t, residual, e0                !< time [s], |e| and e0 [N]
    integer, intent(in) :: iterations                      !< iterations made
    type(error_type), allocatable, intent(inout) :: error  !< set
    call fatal_error(error, "line (marching): the far-end force iteration did not converge at t = " // &
      str(t) // " s: |e| = " // str(residual) // " N > e0 = " // str(e0) // " N after " // &
      str(iterations) // " iterations")
  end subroutine far_end_not_converged

  !> The segment tensions alone (those of model_forces, without its loads).
  !> status = 0, or 1 if a tension is not finite.
  subroutine model_tensions(self, x, v, tension, status)
    class(line_model), intent(in) :: self      !< line
    real(dp), intent(in) :: x(:, 0:)           !< node positions (3, 0:N) [m]
    real(dp), intent(in) :: v(:, 0:)           !< node velocities (3, 0:N) [m/s]
    real(dp), intent(out) :: tension(:)        !< segment tensions T_k, k = 1..N [N]
    integer, intent(out) :: status             !< 0 ok, 1 non-finite tension
    integer :: k
    real(dp) :: ell, t(3), dx(3)
    do k = 1, self%n
      tension(k) = 0.0_dp
      if (self%n_parted > 0) then
        if (self%parted(k)) cycle
      end if
      dx = x(:, k) - x(:, k-1)
      ell = length3(dx)
      t = 0.0_dp
      if (ell > tiny_fraction*self%l0) t = dx/ell
      tension(k) = axial_tension(self%p%ea, self%p%damping, self%l0, ell, t, v(:, k-1), v(:, k))
    end do
    status = 0
    if (.not. (abs(sum(tension(1:self%n))) <= huge(1.0_dp))) status = 1
  end subroutine model_tensions

  !> Tension of a segment of length ell and unit tangent t whose end nodes move
  !> at va and vb, Eq. (3) with the dashpot: EA eps + c_d epsdot while
  !> stretched, never compression.
  pure real(dp) function axial_tension(ea, cd, l0, ell, t, va, vb) result(tk)
    real(dp), intent(in) :: ea, cd, l0      !< EA [N], c_d [N s], rest length [m]
    real(dp), intent(in) :: ell, t(3)       !< length [m], unit tangent
    real(dp), intent(in) :: va(3), vb(3)    !< node velocities [m/s]
    real(dp) :: eps
    eps = ell/l0 - 1.0_dp
    tk = 0.0_dp
    if (eps > 0.0_dp) tk = max(0.0_dp, ea*eps + cd*(dot_product(t, vb - va)/l0))
  end function axial_tension

  !> Derivatives of model_forces' nodal forces with respect to the node
  !> positions and velocities, block tridiagonal: dfdx(:, :, d, j) = df_j/dx_(j+d)
  !> and dfdv(:, :, d, j) = df_j/dv_(j+d), d = -1, 0, 1 (zero where j + d is
  !> outside 0..N).  Per taut segment (T = EA eps + c_d epsdot > 0, Eq. (3)) with
  !> dx = x_k - x_(k-1), t = dx/ell, P = I - t t^T:
  !>   d(T t)/d(dx) = (EA/l0) t t^T + c_d/(l0 ell) t (P dv)^T + (T/ell) P,
  !>   d(T t)/d(dv) = (c_d/l0) t t^T;
  !> slack segments (eps <= 0) contribute nothing.  A stretched segment whose
  !> tension the dashpot clips to zero (fast shortening, EA eps + c_d epsdot < 0)
  !> has zero force and zero derivative, but it gets the blocks above with T = 0:
  !> the taut side of the kink.  This is a deliberate approximation of the
  !> Newton matrix (the force itself is unchanged): with the exact zero blocks,
  !> Newton's iterates failed to cross back to taut and CVODE took 10 % more
  !> steps and 45 % more Jacobians on the heavily damped pendulum (material
  !> damping, N = 60, rtol 1e-3: 2.21 G instructions against 1.56 G; difference
  !> quotients 2.10 G; docs/line.md section 2).
  !> Drag of a segment, D = rho ell_d (qn |un| un + qt |ut| ut) with
  !> ell_d = max(ell, l0), u = wind - (v_(k-1) + v_k)/2, ut = (u.t) t,
  !> un = u - ut, half to each node:
  !>   dD/du = rho ell_d (qn A_n P + qt A_t t t^T),  A = |w| I + w w^T/|w|,
  !>   dD/d(dx) = [D t^T/ell] + rho (ell_d/ell) (qt A_t - qn A_n) (t u^T + (u.t) I) P,
  !> the bracketed area term only for a taut segment (ell > l0; a slack one's
  !> area does not move with dx),
  !> and, with the ISA density, its local gradient along y (the density fit's
  !> dependence on the lowest and highest node is left out: an approximate
  !> Jacobian there, exact with a fixed `air_density`; likewise the gust's
  !> change along x, w_gust' <= pi |U|/(2H), is left out of dD/dx: u holds the
  !> gust's value).  Settling damping:
  !> -alpha m_k I on the diagonal.  Hot path: no allocation.
  subroutine model_force_jacobian(self, x, v, dfdx, dfdv)
    class(line_model), intent(in) :: self        !< line
    real(dp), intent(in) :: x(:, 0:)             !< node positions (3, 0:N) [m]
    real(dp), intent(in) :: v(:, 0:)             !< node velocities (3, 0:N) [m/s]
    real(dp), intent(out) :: dfdx(:, :, -1:, 0:) !< df_j/dx_(j+d) (3, 3, -1:1, 0:N) [N/m]
    real(dp), intent(out) :: dfdv(:, :, -1:, 0:) !< df_j/dv_(j+d) (3, 3, -1:1, 0:N) [N s/m]
    integer :: k, i
    real(dp) :: dx(3), dv(3), t(3), pdv(3), u(3), ut(3), un(3), drag(3), mid(3)
    real(dp) :: p(3, 3), tt(3, 3), kb(3, 3), cb(3, 3), an(3, 3), at(3, 3), gu(3, 3), ddx(3, 3), dut(3, 3)
    real(dp) :: ell, ell_d, eps, tk, ea, cd, tiny_len, rho_a, y_lo, rho_lo, log_slope, qn, qt, un_n, ut_n, ud

    ea = self%p%ea
    cd = self%p%damping
    tiny_len = tiny_fraction*self%l0
    dfdx = 0.0_dp
    dfdv = 0.0_dp
    if (self%p%settling_damping > 0.0_dp) then
      do k = 0, self%n
        do i = 1, 3
          dfdv(i, i, 0, k) = -self%p%settling_damping*self%node_mass(k)
        end do
      end do
    end if
    if (self%p%air) call air_density_fit(self, x, y_lo, rho_lo, log_slope)
    qn = 0.5_dp*self%p%cd_normal*self%p%diameter
    qt = 0.5_dp*self%p%cd_tangential*pi*self%p%diameter

    do k = 1, self%n
      if (self%n_parted > 0) then
        if (self%parted(k)) cycle
      end if
      dx = x(:, k) - x(:, k-1)
      ell = length3(dx)
      if (.not. (ell > tiny_len)) cycle
      t = dx/ell
      tt = outer3(t, t)
      p = identity3() - tt
      eps = ell/self%l0 - 1.0_dp
      if (eps > 0.0_dp) then
        dv = v(:, k) - v(:, k-1)
        ! the tension clipped at zero by a fast shortening keeps the law's
        ! derivative (the taut side of the kink; see the header)
        tk = max(0.0_dp, ea*eps + cd*dot_product(t, dv)/self%l0)
        pdv = matmul(p, dv)
        kb = (ea/self%l0)*tt + (cd/(self%l0*ell))*outer3(t, pdv) + (tk/ell)*p
        cb = (cd/self%l0)*tt
        ! f_(k-1) += T t and f_k -= T t, T t a function of x_k - x_(k-1)
        call add_segment_blocks(dfdx, k, kb, -kb)
        call add_segment_blocks(dfdv, k, cb, -cb)
      end if
      if (self%p%air) then
        u = self%p%wind - 0.5_dp*(v(:, k-1) + v(:, k))
        if (self%gust%active) then
          mid = 0.5_dp*(x(:, k-1) + x(:, k))
          u = u + gust_velocity(self%gust, mid)
        end if
        ud = dot_product(u, t)
        ut = ud*t
        un = u - ut
        rho_a = rho_lo
        if (log_slope /= 0.0_dp) rho_a = rho_lo*exp(log_slope*(0.5_dp*(x(2, k-1) + x(2, k)) - y_lo))
        un_n = length3(un)
        ut_n = length3(ut)
        ell_d = max(ell, self%l0)
        drag = rho_a*ell_d*(qn*un_n*un + qt*ut_n*ut)
        an = un_n*identity3()
        if (un_n > 0.0_dp) an = an + outer3(un, un)/un_n
        at = ut_n*identity3()
        if (ut_n > 0.0_dp) at = at + outer3(ut, ut)/ut_n
        gu = rho_a*ell_d*(qn*matmul(an, p) + qt*matmul(at, tt))
        ! du/dv_(k-1) = du/dv_k = -I/2, half of the drag to each node: -gu/4
        call add_segment_blocks(dfdv, k, -0.25_dp*gu, -0.25_dp*gu, same_sign=.true.)
        dut = outer3(t, u) + ud*identity3()
        ! the direction term (dt/d(dx) = P/ell) always; the area term D t^T/ell only
        ! while taut (a slack segment's area rho l0 does not depend on dx)
        ddx = rho_a*(ell_d/ell)*matmul(qt*at - qn*an, matmul(dut, p))
        if (ell > self%l0) ddx = ddx + outer3(drag, t)/ell
        call add_segment_blocks(dfdx, k, 0.5_dp*ddx, 0.5_dp*ddx)
        if (log_slope /= 0.0_dp) then
          ! d rho/d y_(k-1) = d rho/d y_k = rho s/2: a column along y in both blocks
          ddx = 0.0_dp
          ddx(:, 2) = 0.25_dp*log_slope*drag
          call add_segment_blocks(dfdx, k, ddx, ddx, same_sign=.true.)
        end if
      end if
    end do
  end subroutine model_force_jacobian

  !> Add the blocks of a segment force that depends on its two nodes k-1, k:
  !> node k-1 gets `a` (a function of x_k - x_(k-1): +a for x_k, -a for x_(k-1)),
  !> node k gets `b` likewise; with same_sign the force depends on the sum
  !> (x_(k-1) + x_k), +a and +b for both nodes.
  pure subroutine add_segment_blocks(d, k, a, b, same_sign)
    real(dp), intent(inout) :: d(:, :, -1:, 0:)   !< block tridiagonal derivative
    integer, intent(in) :: k                      !< segment (nodes k-1, k)
    real(dp), intent(in) :: a(3, 3), b(3, 3)      !< the two nodes' blocks
    logical, intent(in), optional :: same_sign    !< depends on the sum, not the difference
    real(dp) :: s
    s = -1.0_dp
    if (present(same_sign)) then
      if (same_sign) s = 1.0_dp
    end if
    d(:, :, 1, k-1) = d(:, :, 1, k-1) + a
    d(:, :, 0, k-1) = d(:, :, 0, k-1) + s*a
    d(:, :, 0, k) = d(:, :, 0, k) + b
    d(:, :, -1, k) = d(:, :, -1, k) + s*b
  end subroutine add_segment_blocks

  !> a b^T of two 3-vectors.
  pure function outer3(a, b) result(m)
    real(dp), intent(in) :: a(3), b(3)
    real(dp) :: m(3, 3)
    integer :: j
    do j = 1, 3
      m(:, j) = a*b(j)
    end do
  end function outer3

  !> The 3x3 identity.
  pure function identity3() result(m)
    real(dp) :: m(3, 3)
    m = 0.0_dp
    m(1, 1) = 1.0_dp
    m(2, 2) = 1.0_dp
    m(3, 3) = 1.0_dp
  end function identity3

  !> Length of a 3-vector, sqrt(a.a).  The NORM2 intrinsic guards against
  !> overflow by rescaling element by element (a division per element, three
  !> times per segment in model_forces: 30 % of its instructions); the squares of
  !> a line's lengths and velocities are far from overflow or underflow.
  pure real(dp) function length3(a) result(r)
    real(dp), intent(in) :: a(3)   !< vector
    r = sqrt(a(1)*a(1) + a(2)*a(2) + a(3)*a(3))
  end function length3

  !> Air density along the line: the ISA density at the lowest and the highest
  !> node, interpolated log-linearly in altitude (exact in an isothermal layer;
  !> in the troposphere the relative error grows as the square of the line's
  !> height span: ~1e-7 at 20 m, 2.7e-6 to 4.5e-6 at 100 m), so the
  !> standard is evaluated twice per call instead of once per segment.  A fixed
  !> `air_density` > 0 replaces the ISA.
  subroutine air_density_fit(self, x, y_lo, rho_lo, log_slope)
    class(line_model), intent(in) :: self   !< line
    real(dp), intent(in) :: x(:, 0:)        !< node positions
    real(dp), intent(out) :: y_lo           !< lowest node altitude [m]
    real(dp), intent(out) :: rho_lo         !< density at y_lo [kg/m^3]
    real(dp), intent(out) :: log_slope      !< d ln(rho)/dy [1/m]
    real(dp) :: rho_hi, y_hi
    type(air_state) :: a
    y_lo = minval(x(2, 0:self%n))
    y_hi = maxval(x(2, 0:self%n))
    log_slope = 0.0_dp
    if (self%p%air_density > 0.0_dp) then
      rho_lo = self%p%air_density
      return
    end if
    a = isa(y_lo)
    rho_lo = a%density
    if (y_hi - y_lo > 1.0e-3_dp) then
      a = isa(y_hi)
      rho_hi = a%density
      log_slope = log(rho_hi/rho_lo)/(y_hi - y_lo)
    end if
  end subroutine air_density_fit

  !> What stops a run whose node k is outside the atmosphere model
  !> (model_node_outside_atmosphere): node, altitude and the model's range.
  function outside_atmosphere_message(x, k) result(msg)
    real(dp), intent(in) :: x(:, 0:)   !< node positions [m]
    integer, intent(in) :: k           !< the node
    character(len=:), allocatable :: msg
    msg = "line node " // str(k) // " altitude " // str(x(2, k)) // " m is outside the atmosphere model (ISA, " // &
      str(isa_min_altitude) // " to " // str(isa_max_altitude) // " m; &line air_density = 0)"
  end function outside_atmosphere_message

  !> The first node (0..N) outside the atmosphere model where the air is the
  !> ISA's (air on, air_density 0: the model's range, isa_min_altitude to
  !> isa_max_altitude); -1: none, or a fixed density.  Its density is held at
  !> the range's end there (isa), so an owner that integrates the line stops
  !> instead of flying on in made-up air.
  pure integer function model_node_outside_atmosphere(self, x) result(k)
    class(line_model), intent(in) :: self   !< line
    real(dp), intent(in) :: x(:, 0:)        !< node positions [m]
    integer :: j
    k = -1
    if (.not. self%p%air .or. self%p%air_density > 0.0_dp) return
    do j = 0, self%n
      if (.not. (x(2, j) >= isa_min_altitude .and. x(2, j) <= isa_max_altitude)) then
        k = j
        return
      end if
    end do
  end function model_node_outside_atmosphere

  !> The line breaks at segment k (1..N; nothing if it has already parted
  !> there): from now on the segment carries no tension and no drag.
  subroutine model_part(self, k)
    class(line_model), intent(inout) :: self   !< line
    integer, intent(in) :: k                   !< segment
    if (self%parted(k)) return
    self%parted(k) = .true.
    self%n_parted = self%n_parted + 1
  end subroutine model_part

  !> Each segment's strength [N]: breaking_strength (0: the line never
  !> breaks), the weak link's weak_link_strength at weak_link_segment (0: no
  !> weak link); huge(1.0_dp) where a segment never parts.
  pure function segment_strengths(n_seg, breaking_strength, weak_link_strength, weak_link_segment) result(strength)
    integer, intent(in) :: n_seg               !< segments
    real(dp), intent(in) :: breaking_strength  !< the line's [N]
    real(dp), intent(in) :: weak_link_strength !< the weak link's [N]
    integer, intent(in) :: weak_link_segment   !< the weak link's segment
    real(dp) :: strength(n_seg)
    strength = huge(1.0_dp)
    if (breaking_strength > 0.0_dp) strength = breaking_strength
    if (weak_link_strength > 0.0_dp) strength(weak_link_segment) = weak_link_strength
  end function segment_strengths

  !> A line's smallest margin to breaking, strength(j) - tension(j), over its
  !> segments, and the segment k that has it (a parted segment carries no
  !> tension: its margin is its whole strength).  A continuous function of
  !> the state: the break's event function (a loop, no temporary array: it
  !> runs in the integrators' root functions).
  pure subroutine weakest_segment(strength, tension, margin, k)
    real(dp), intent(in) :: strength(:)   !< segment strengths [N]
    real(dp), intent(in) :: tension(:)    !< segment tensions [N]
    real(dp), intent(out) :: margin       !< the smallest margin [N]
    integer, intent(out) :: k             !< its segment
    integer :: j
    k = 1
    margin = strength(1) - tension(1)
    do j = 2, size(strength)
      if (strength(j) - tension(j) < margin) then
        k = j
        margin = strength(j) - tension(j)
      end if
    end do
  end subroutine weakest_segment

  !> The line parts where its tensions reached their strengths: the segment
  !> of the smallest margin (weakest_segment: the break event's root) and
  !> with it every other at or above its own strength; `first` is the former.
  subroutine model_part_reached(self, strength, tension, first)
    class(line_model), intent(inout) :: self   !< line
    real(dp), intent(in) :: strength(:)        !< segment strengths [N]
    real(dp), intent(in) :: tension(:)         !< segment tensions at the event [N]
    integer, intent(out) :: first              !< the segment of the smallest margin
    real(dp) :: margin
    integer :: j
    call weakest_segment(strength, tension, margin, first)
    call self%part(first)
    do j = 1, self%n
      if (tension(j) >= strength(j)) call self%part(j)
    end do
  end subroutine model_part_reached

  !> Kinetic, elastic and gravitational energy of the line's nodes.
  function model_energy(self, x, v) result(e)
    class(line_model), intent(in) :: self   !< line
    real(dp), intent(in) :: x(:, 0:)        !< node positions (3, 0:N) [m]
    real(dp), intent(in) :: v(:, 0:)        !< node velocities (3, 0:N) [m/s]
    type(line_energy) :: e
    integer :: k
    real(dp) :: eps
    do k = 0, self%n
      e%kinetic = e%kinetic + 0.5_dp*self%node_mass(k)*dot_product(v(:, k), v(:, k))
      if (self%p%gravity) e%potential = e%potential + self%node_mass(k)*g0*x(2, k)
    end do
    do k = 1, self%n
      eps = norm2(x(:, k) - x(:, k-1))/self%l0 - 1.0_dp
      if (self%n_parted > 0) then
        if (self%parted(k)) eps = 0.0_dp
      end if
      if (eps > 0.0_dp) e%elastic = e%elastic + 0.5_dp*self%p%ea*self%l0*eps**2
      ! 1/2 v^T M v of the mixed mass: the lumped sum less beta rho l0 |dv|^2 / 2 per segment
      if (self%mass_coupling > 0.0_dp) e%kinetic = e%kinetic - 0.5_dp*self%mass_coupling* &
        self%p%mass_per_length*self%l0*sum((v(:, k) - v(:, k-1))**2)
    end do
  end function model_energy

  !> Axial wave speed c = sqrt(EA/rho) in material coordinates [m/s].
  pure real(dp) function model_wave_speed(self) result(c)
    class(line_model), intent(in) :: self   !< line
    c = sqrt(self%p%ea/self%p%mass_per_length)
  end function model_wave_speed

  !> Largest stable step of the explicit (semi-implicit Euler) scheme [s]:
  !> the highest axial mode of the lumped chain has w = 2c/l0 (Gershgorin bound,
  !> also for a free end node of half mass) and damping ratio
  !> zeta = w c_d/(2 EA) + alpha/(2w); semi-implicit Euler with explicit
  !> damping is stable for h w <= 2 (sqrt(1 + zeta^2) - zeta).
  pure real(dp) function model_stable_step(self) result(h)
    class(line_model), intent(in) :: self   !< line
    h = marching_stable_step(self%p%ea, self%p%mass_per_length, self%l0, self%p%damping, self%p%settling_damping)
  end function model_stable_step

  !> model_stable_step from the parameters alone (an input check needs it
  !> before the line is built): EA [N], rho [kg/m], l0 [m], c_d [N s], alpha [1/s].
  pure real(dp) function marching_stable_step(ea, mass_per_length, l0, damping, settling_damping) result(h)
    real(dp), intent(in) :: ea, mass_per_length, l0, damping, settling_damping
    real(dp) :: w, zeta
    w = 2.0_dp*sqrt(ea/mass_per_length)/l0
    zeta = w*damping/(2.0_dp*ea) + settling_damping/(2.0_dp*w)
    h = 2.0_dp/w*(sqrt(1.0_dp + zeta**2) - zeta)
  end function marching_stable_step

  !> Total mass of the line rho*L [kg].
  pure real(dp) function model_total_mass(self) result(m)
    class(line_model), intent(in) :: self   !< line
    m = self%p%mass_per_length*self%p%length
  end function model_total_mass

  !> Unit tangent of the end segment at node 0 (which = 0) or node N (which = N),
  !> pointing along the line from node 0 to node N; zero for a degenerate segment.
  pure function model_end_tangent(self, x, which) result(t)
    class(line_model), intent(in) :: self   !< line
    real(dp), intent(in) :: x(:, 0:)        !< node positions (3, 0:N)
    integer, intent(in) :: which            !< 0 or N
    real(dp) :: t(3), dx(3), ell
    if (which == 0) then
      dx = x(:, 1) - x(:, 0)
    else
      dx = x(:, self%n) - x(:, self%n - 1)
    end if
    ell = norm2(dx)
    t = 0.0_dp
    if (ell > tiny_fraction*self%l0) t = dx/ell
  end function model_end_tangent

  !> What component j (1..6) of node k's state [x, v] is, e.g. "line node 7 velocity y".
  pure function node_state_name(k, j) result(name)
    integer, intent(in) :: k  !< node
    integer, intent(in) :: j  !< component of [x, v]
    character(len=:), allocatable :: name
    character(len=1), parameter :: xyz(3) = ["x", "y", "z"]
    character(len=12) :: buf
    write(buf, '(i0)') k
    name = "line node " // trim(buf) // merge(" position ", " velocity ", j <= 3) // xyz(modulo(j - 1, 3) + 1)
  end function node_state_name
  !> The summaries' word on a line that parted in more than one segment:
  !> every segment has the line's strength, so after the first break the count,
  !> the later peaks and the recoil depend on N (docs/model.md, "Line break").
  pure function cascade_note(n_parted) result(s)
    integer, intent(in) :: n_parted   !< segments parted
    character(len=:), allocatable :: s
    s = ""
    if (n_parted > 1) s = " (after the first, a cascade: every segment has the line's strength, so the " // &
      "count, the later peaks and the recoil depend on n_seg; docs/model.md, 'Line break')"
  end function cascade_note

end module airlaunch_line_model
