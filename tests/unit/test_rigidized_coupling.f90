!> Coupling (a) of DESIGN §4, the paper's equivalent rigidization inside the
!> Kane chain (src/scene/airlaunch_rigidized_coupling.f90), each part against
!> something independent:
!>  1. Rigidization consistency (§2.4, Steps 1 and 3): a taut straight line in
!>     rigid motion (translation + rotation about the tie-down point normal to
!>     the line) gives the virtual body the line's mass, its chord length and
!>     the inertia of the node masses (m L^2/12 plus lumping), the chain's
!>     parachute B3 lands on node N with node N's velocity, and the chain's
!>     linear and angular momentum equal those of the lumped line + bodies
!>     (the direct model's state, whose half segment m_0 at node 0 is kept
!>     here).  Exact identities: 1e-12 relative (rounding only).
!>  2. Loads of the virtual line body against closed forms: uniform cross-flow
!>     and axial flow (and the line model's own drag summed over its nodes),
!>     the damping moment of a rod rotating about its centre, which the
!>     midpoint rule over m strips per half gives exactly as
!>     rho Cd d w^2 L^4/64 (1 - 1/(2 m^2)), and the canopy drag with the
!>     line's deformation velocity V_eps (Eq. (26)).  1e-12 relative.
!>  3. Conservation with gravity and air off: a free aircraft and the chain
!>     rocket - line - parachute tumbling in free flight (the rocket's tumbling
!>     makes the line ring), 100 outer steps of 0.01 s.  The chain's loads
!>     are all internal, so its linear and angular momentum and its kinetic
!>     energy change only at the refreshes (Step 3), by the amounts the
!>     coupling books: P(t) - P(0) - sum(jumps) <= 1e-9 sum|m v| (CVODE rtol
!>     1e-11), likewise H; T to 1e-7 of T.  The jumps themselves are the
!>     momentum the rigid body cannot carry (the line's stretch and bending
!>     change d_rigid, m_rigid, J_rigid between refreshes): measured 2e-8 of
!>     sum|m v| here, checked below 1e-6; a 100 times stiffer line only halves
!>     them (bending, not stretch, dominates once the line is taut; each line
!>     starts stretched by the steady centrifugal tension, so it stays taut).
!>  4. far_end = 'chain' (both end motions from the chain) keeps d_rigid
!>     exactly constant (to 1e-12): why the default puts the parachute on the
!>     line's node N (the far-end force condition of §2.3).
!>  5. The line subsystem's Jacobian as node blocks (what its velocity-reduced
!>     solver is given) against central differences of its right-hand side, on
!>     a line with taut and slack segments, drag, damping and weight, its
!>     node N carrying an open canopy (drag, apparent mass) at 200 m/s: every
!>     block, and zero beyond the neighbours, to 1e-8 of the largest entry
!>     (central differences, h = 1e-6: truncation and round-off both far below;
!>     without the canopy drag's derivative the largest difference is 56, 6e-4).  The one term
!>     the blocks leave out by design - the air density's change with the
!>     canopy's altitude - is taken from central differences of the canopy's
!>     acceleration alone (line force held) and added before comparing.  The
!>     keep/renew rule: kept at the same state when allowed, renewed when a
!>     segment goes slack.
!>  6. The paper's marching as the line's sub-stepper (inner_scheme =
!>     'marching', §2.3 Steps 1-5): a towed line (node 0 on a curved body path,
!>     the canopy at node N with drag and apparent mass, weight, axial damping,
!>     taut throughout) against CVODE at rtol 1e-10 (BDF5) on the same
!>     subsystem: the tip's error falls at first order with the sub-step
!>     (semi-implicit Euler: slope 1 +- 0.2 over 0.8, 0.4, 0.2 of the stability
!>     limit); an output time inside the outer step changes no sub-step (the
!>     end state bit for bit the same); a sub-step above the stability limit and
!>     a used-up step budget are errors naming the limit and the time.
program test_rigidized_coupling
  use airlaunch_kinds, only: dp, g0, pi
  use airlaunch_error, only: error_type
  use airlaunch_strings, only: str
  use airlaunch_rotation, only: quat_from_euler
  use airlaunch_atmosphere, only: isa, air_state
  use airlaunch_multibody
  use airlaunch_line, only: line_model, line_params, line_end, line_band_upper, line_band_lower
  use airlaunch_parachute, only: parachute, canopy_node_acceleration
  use airlaunch_ode, only: node_blocks
  use airlaunch_cvode, only: cvode_solver, cvode_options
  use airlaunch_rigidized_coupling
  use testing
  implicit none
  real(dp), parameter :: boost = 200.0_dp, h_ref = 1000.0_dp, line_length = 30.0_dp
  integer, parameter :: nseg = 20

  call fixed_seed()   ! the same random states in every run
  call test_consistency()
  call test_loads()
  call test_conservation()
  call test_far_end()
  call test_bad_settings()
  call test_line_node_blocks()
  call test_marching_line()
  call finish()

contains

  character(len=11) function fmt(x)
    real(dp), intent(in) :: x
    write(fmt, '(es11.3)') x
  end function fmt

  !> The scene of tests 1, 3, 4: a free aircraft, the rocket tumbling in free
  !> flight, a straight line of stiffness ea from the tie-down point in rigid
  !> rotation w2 (normal to it) about it, a 40 kg parachute; gravity and air off.
  subroutine build(cpl, ea, far_end, x, v, model, chute, error)
    type(rigidized_coupling), intent(inout) :: cpl
    real(dp), intent(in) :: ea
    character(len=*), intent(in) :: far_end
    real(dp), intent(out) :: x(3, 0:nseg), v(3, 0:nseg)
    type(line_model), intent(out) :: model
    type(parachute), intent(out) :: chute
    type(error_type), allocatable, intent(inout) :: error
    type(separation_system) :: sep
    type(rigid_body) :: aircraft, rocket
    type(cut_joint_geometry) :: geo
    type(cut_joint_options) :: opt
    type(rigidized_loads) :: rl
    type(rigidized_settings) :: s
    real(dp) :: e(3), w2(3), x0(3), v0(3), tie(3), stretch
    integer :: k
    tie = [9.25_dp, 0.0_dp, 0.0_dp]
    aircraft = new_rigid_body("aircraft", 89000.0_dp, diag3(540740.0_dp, 737480.0_dp, 117030.0_dp), error)
    rocket = new_rigid_body("rocket", 28000.0_dp, diag3(7870.0_dp, 545000.0_dp, 545000.0_dp), error)
    geo%rail_direction = [-1.0_dp, -0.05_dp, 0.0_dp]
    geo%floor_point = [3.0_dp, -1.2_dp, 0.0_dp]
    geo%edge_point = geo%floor_point + 14.0_dp*geo%rail_direction
    call sep%init(aircraft, rocket, tie, 3, geo, opt, 5.0_dp, error)
    if (allocated(error)) return
    sep%bodies(0)%r = [0.0_dp, h_ref, 0.0_dp]
    call sep%bodies(0)%set_attitude(quat_from_euler([0.02_dp, 0.03_dp, -0.01_dp]))
    sep%bodies(0)%v = [boost, 1.0_dp, -0.5_dp]
    sep%bodies(0)%w = [0.01_dp, -0.02_dp, 0.03_dp]
    call sep%joint%place_on_rail(sep%bodies(0), 6.0_dp, 0.8_dp, sep%bodies(1))
    sep%bodies(1)%v = sep%bodies(1)%v + [-3.0_dp, 1.0_dp, 0.5_dp]
    sep%bodies(1)%w = sep%bodies(1)%w + [0.1_dp, 0.3_dp, -0.2_dp]
    call model%init(line_params(length=line_length, n_seg=nseg, ea=ea, mass_per_length=0.5_dp, damping=0.0_dp, &
      gravity=.false., air=.false.), error)
    if (allocated(error)) return
    chute%mass = 40.0_dp
    chute%added_mass_factor = 0.0_dp
    rl%gravity = .false.
    rl%air = .false.
    rl%line_mass = model%total_mass()
    rl%chute = chute
    call sep%add_source(rl)
    ! the line: straight aft and down from the tie-down point, turning about it
    ! at w2 (normal to the line), stretched by the steady centrifugal tension
    ! at its root, w^2 (m_chute L + rho L^2/2), so that it stays taut
    x0 = sep%bodies(1)%point_position(tie)
    v0 = sep%bodies(1)%point_velocity(tie)
    e = [-1.0_dp, -0.3_dp, 0.2_dp]
    e = e/norm2(e)
    w2 = cross(e, [0.0_dp, 0.5_dp, 0.4_dp])
    stretch = dot_product(w2, w2)*(chute%mass*line_length + 0.5_dp*0.5_dp*line_length**2)/ea
    do k = 0, nseg
      x(:, k) = x0 + k*model%l0*(1.0_dp + stretch)*e
      v(:, k) = v0 + cross(w2, x(:, k) - x0)
    end do
    s%outer_dt = 0.01_dp
    s%chain_rtol = 1.0e-11_dp
    s%chain_atol = 1.0e-12_dp
    s%inner_rtol = 1.0e-8_dp
    s%inner_atol = 1.0e-8_dp
    s%far_end = far_end
    call cpl%init(sep, 0, 1, model, chute, x, v, boost, h_ref, 0.0_dp, phase_free, s, error)
  end subroutine build

  !> Momentum of the lumped line + parachute (node N) + aircraft + rocket.
  subroutine lumped_momentum(cpl, model, chute, x, v, p, h)
    type(rigidized_coupling), intent(in) :: cpl
    type(line_model), intent(in) :: model
    type(parachute), intent(in) :: chute
    real(dp), intent(in) :: x(3, 0:nseg), v(3, 0:nseg)
    real(dp), intent(out) :: p(3), h(3)
    integer :: k
    p = 0.0_dp
    h = 0.0_dp
    do k = 0, 1
      p = p + cpl%chain%sep%bodies(k)%linear_momentum()
      h = h + cpl%chain%sep%bodies(k)%angular_momentum()
    end do
    do k = 0, nseg
      p = p + model%node_mass(k)*v(:, k)
      h = h + cross(x(:, k), model%node_mass(k)*v(:, k))
    end do
    p = p + chute%mass*v(:, nseg)
    h = h + cross(x(:, nseg), chute%mass*v(:, nseg))
  end subroutine lumped_momentum

  subroutine test_consistency()
    type(rigidized_coupling) :: cpl
    type(line_model) :: model
    type(parachute) :: chute
    type(error_type), allocatable :: error
    real(dp) :: x(3, 0:nseg), v(3, 0:nseg), p(3), h(3), pc(3), hc(3), jg, mid(3), pscale, hscale, d
    integer :: k
    call section("1. rigidization consistency: taut straight line in rigid motion")
    call build(cpl, 2.0e6_dp, "parachute", x, v, model, chute, error)
    call check(.not. allocated(error), "scene built")
    if (allocated(error)) then
      print '(a)', error%message
      return
    end if
    d = norm2(x(:, nseg) - x(:, 0))
    mid = 0.5_dp*(x(:, 0) + x(:, nseg))
    jg = 0.0_dp
    do k = 0, nseg
      jg = jg + model%node_mass(k)*sum((x(:, k) - mid)**2)
    end do
    call check_close(cpl%vl%mass, model%total_mass(), "m_rigid (31) = line mass [kg]", rel=1.0e-12_dp)
    call check_close(cpl%vl%length, d, "d_rigid (20) = stretched chord [m]", rel=1.0e-12_dp)
    call check(cpl%vl%length > line_length, "  the line is stretched: d_rigid - L = " // fmt(cpl%vl%length - line_length) // " m")
    call check_close(cpl%vl%inertia, jg, "J_rigid (32) = inertia of the node masses [kg m^2]", rel=1.0e-12_dp)
    call check_close(jg, model%total_mass()*d**2/12*(1.0_dp + 2.0_dp/nseg**2), &
      "  which is m d^2/12 (1 + 2/N^2) for the lumped line [kg m^2]", rel=1.0e-12_dp)
    call check(.not. cpl%vl%mass_guarded .and. .not. cpl%vl%inertia_guarded, "no guard engaged")
    call cpl%chain%prepare(0.0_dp, cpl%chain_solver%y)
    associate(b => cpl%chain%sep%bodies)
      call check(norm2(b(3)%r - x(:, nseg)) <= 1.0e-12_dp*d, "B3 at node N: " // fmt(norm2(b(3)%r - x(:, nseg))) // " m")
      call check(norm2(b(3)%v - v(:, nseg)) <= 1.0e-12_dp*norm2(v(:, nseg)), "B3 velocity = node N's: " // &
        fmt(norm2(b(3)%v - v(:, nseg))) // " m/s")
      call check(norm2(b(1)%point_position(cpl%chain%sep%tie_down) - x(:, 0)) <= 1.0e-12_dp*d, "tie-down = node 0")
      call check_close(b(2)%mass + b(3)%mass, model%total_mass() + chute%mass, "B2 + B3 mass [kg]", rel=1.0e-14_dp)
    end associate
    call lumped_momentum(cpl, model, chute, x, v, p, h)
    pc = cpl%chain%sep%linear_momentum()
    hc = cpl%chain%sep%angular_momentum()
    pscale = 0.0_dp
    hscale = 0.0_dp
    do k = 0, 3
      pscale = pscale + norm2(cpl%chain%sep%bodies(k)%linear_momentum())
      hscale = hscale + norm2(cpl%chain%sep%bodies(k)%angular_momentum())
    end do
    call check(norm2(pc - p) <= 1.0e-12_dp*pscale, "chain P = lumped line + bodies P: " // fmt(norm2(pc - p)/pscale) // &
      " relative")
    call check(norm2(hc - h) <= 1.0e-12_dp*hscale, "chain H = lumped line + bodies H: " // fmt(norm2(hc - h)/hscale) // &
      " relative")
    ! the direct model (nodes 1..N integrated, node 0's half segment neglected)
    ! differs by exactly m_0 v_0
    call check(norm2(pc - (p - model%node_mass(0)*v(:, 0)) - model%node_mass(0)*v(:, 0)) <= 1.0e-12_dp*pscale, &
      "chain P = direct model's P + m_0 v_0 (m_0 = " // fmt(model%node_mass(0)) // " kg)")
    call cpl%free()
  end subroutine test_consistency

  subroutine test_loads()
    type(rigidized_loads) :: rl
    type(rigid_body) :: b(0:3)
    type(error_type), allocatable :: error
    type(line_model) :: model
    type(air_state) :: air
    real(dp) :: force(3, 0:3), moment(3, 0:3), l, rho, qn, qt, vel(3), expect(3), w, m, u(3)
    real(dp), allocatable :: x(:, :), vv(:, :), f(:, :), ten(:)
    integer :: k, st, ns
    call section("2. loads of the virtual line body and the parachute")
    l = 40.0_dp
    ns = 16
    rl%length = l
    rl%diameter = 0.025_dp
    rl%cd_normal = 1.2_dp
    rl%cd_tangential = 0.01_dp
    rl%gravity = .false.
    rl%air = .true.
    rl%drag_strips = ns
    rl%chute%drag_area = 10.0_dp
    rl%chute%deploy_time = -1.0_dp
    qn = 0.5_dp*rl%cd_normal*rl%diameter
    qt = 0.5_dp*rl%cd_tangential*pi*rl%diameter
    ! a horizontal rod along x at 5 km, its parachute 1 km away (any place works)
    b(2)%r = [0.0_dp, 5000.0_dp, 0.0_dp]
    call b(2)%set_attitude(line_body_attitude([l, 0.0_dp, 0.0_dp]))
    b(3)%r = [100.0_dp, 6000.0_dp, 0.0_dp]
    air = isa(b(2)%r(2))
    rho = air%density
    ! (i) uniform cross-flow and (ii) axial flow
    call model%init(line_params(length=l, n_seg=25, gravity=.false., air=.true., diameter=rl%diameter, &
      cd_normal=rl%cd_normal, cd_tangential=rl%cd_tangential), error)
    allocate(x(3, 0:25), vv(3, 0:25), f(3, 0:25), ten(25))
    do k = 0, 25
      x(:, k) = b(2)%r + [-0.5_dp*l + k*l/25, 0.0_dp, 0.0_dp]
    end do
    do k = 1, 2
      vel = merge([0.0_dp, 3.0_dp, 40.0_dp], [150.0_dp, 0.0_dp, 0.0_dp], k == 1)
      b(2)%v = vel
      b(2)%w = 0.0_dp
      b(3)%v = 0.0_dp
      force = 0.0_dp; moment = 0.0_dp
      call rl%add_loads(0.0_dp, b, force, moment, error)
      call check(.not. allocated(error), "loads evaluated")
      expect = -rho*l*merge(qn, qt, k == 1)*norm2(vel)*vel
      call check(norm2(force(:, 2) - expect) <= 1.0e-12_dp*norm2(expect), merge("cross-flow", "axial     ", k == 1) // &
        " drag = 1/2 rho Cd A |v| v: " // fmt(norm2(force(:, 2) - expect)/norm2(expect)) // " relative")
      call check(norm2(moment(:, 2)) <= 1.0e-12_dp*norm2(expect)*l, "  no moment about the CG")
      do st = 0, 25
        vv(:, st) = vel
      end do
      call model%forces(x, vv, f, ten, st)
      u = sum(f, dim=2)
      call check(norm2(force(:, 2) - u) <= 1.0e-12_dp*norm2(u), "  = the line model's drag summed over its nodes: " // &
        fmt(norm2(force(:, 2) - u)/norm2(u)) // " relative")
    end do
    ! (iii) rotation about the centre, normal to the axis (body x)
    w = 0.3_dp
    b(2)%v = 0.0_dp
    b(2)%w = [w, 0.0_dp, 0.0_dp]
    force = 0.0_dp; moment = 0.0_dp
    call rl%add_loads(0.0_dp, b, force, moment, error)
    m = ns/2
    expect = [-rho*2*qn*w**2*l**4/64*(1.0_dp - 1.0_dp/(2*m**2)), 0.0_dp, 0.0_dp]
    call check(norm2(moment(:, 2) - expect) <= 1.0e-12_dp*norm2(expect), "rotating rod: damping moment = rho Cd d " // &
      "w^2 L^4/64 (1 - 1/(2 m^2)): " // fmt(norm2(moment(:, 2) - expect)/norm2(expect)) // " relative")
    call check(norm2(force(:, 2)) <= 1.0e-12_dp*norm2(expect)/l, "  no net force")
    ! (iv) the canopy with the deformation velocity V_eps (Eq. (26))
    b(2)%w = 0.0_dp
    b(3)%v = [-50.0_dp, 3.0_dp, 1.0_dp]
    rl%v_eps = [0.5_dp, -0.2_dp, 0.0_dp]
    force = 0.0_dp; moment = 0.0_dp
    call rl%add_loads(0.0_dp, b, force, moment, error)
    air = isa(b(3)%r(2))
    u = b(3)%v + rl%v_eps
    expect = -0.5_dp*air%density*10.0_dp*norm2(u)*u
    call check(norm2(force(:, 3) - expect) <= 1.0e-12_dp*norm2(expect), "canopy drag on V_3 + V_eps: " // &
      fmt(norm2(force(:, 3) - expect)/norm2(expect)) // " relative")
    ! weights: the line's true weight on B2, the canopy's on B3
    rl%gravity = .true.
    rl%air = .false.
    rl%line_mass = 24.0_dp
    rl%chute%mass = 1.8_dp
    b(2)%mass = 30.0_dp   ! an m_rigid different from the line mass: the weight is not m_rigid g
    force = 0.0_dp; moment = 0.0_dp
    call rl%add_loads(0.0_dp, b, force, moment, error)
    call check_close(force(2, 2), -24.0_dp*g0, "B2 weight = rho L g (not m_rigid g) [N]", rel=1.0e-14_dp)
    call check_close(force(2, 3), -1.8_dp*g0, "B3 weight = canopy only (no weight on the apparent mass) [N]", &
      rel=1.0e-14_dp)
  end subroutine test_loads

  !> Chain momentum, angular momentum, kinetic energy at the coupling's time.
  subroutine chain_invariants(cpl, p, h, e)
    type(rigidized_coupling), intent(inout) :: cpl
    real(dp), intent(out) :: p(3), h(3), e
    call cpl%chain%prepare(cpl%t, cpl%chain_solver%y)
    p = cpl%chain%sep%linear_momentum()
    h = cpl%chain%sep%angular_momentum()
    e = cpl%chain%sep%kinetic_energy()
  end subroutine chain_invariants

  !> Run 1 s of outer steps; return the bookkeeping residuals and the jumps.
  subroutine conserve(ea, rp, rh, re, jump_p, jump_h, ok)
    real(dp), intent(in) :: ea
    real(dp), intent(out) :: rp, rh, re, jump_p, jump_h
    logical, intent(out) :: ok
    type(rigidized_coupling) :: cpl
    type(line_model) :: model
    type(parachute) :: chute
    type(error_type), allocatable :: error
    real(dp) :: x(3, 0:nseg), v(3, 0:nseg), p0(3), h0(3), e0, p(3), h(3), e, pscale, hscale
    integer :: k, which(rigidized_nroots)
    logical :: event
    ok = .false.
    call build(cpl, ea, "parachute", x, v, model, chute, error)
    if (allocated(error)) then
      print '(a)', error%message
      return
    end if
    call chain_invariants(cpl, p0, h0, e0)
    pscale = 0.0_dp
    hscale = 0.0_dp
    do k = 0, 3
      pscale = pscale + norm2(cpl%chain%sep%bodies(k)%linear_momentum())
      hscale = hscale + norm2(cpl%chain%sep%bodies(k)%angular_momentum())
    end do
    do k = 1, 100
      call cpl%outer_step(0.01_dp*k, event, which, error)
      if (allocated(error) .or. event) exit
    end do
    if (allocated(error)) then
      print '(a)', error%message
      return
    end if
    ok = .not. event .and. abs(cpl%t - 1.0_dp) < 1.0e-12_dp .and. cpl%n_refresh == 100
    call chain_invariants(cpl, p, h, e)
    rp = norm2(p - p0 - cpl%momentum_jump)/pscale
    rh = norm2(h - h0 - cpl%angular_momentum_jump)/hscale
    re = abs(e - e0 - cpl%kinetic_energy_jump)/e0
    jump_p = norm2(cpl%momentum_jump)/pscale
    jump_h = norm2(cpl%angular_momentum_jump)/hscale
    call cpl%free()
  end subroutine conserve

  subroutine test_conservation()
    real(dp) :: rp, rh, re, jp, jh, rp2, rh2, re2, jp2, jh2
    logical :: ok, ok2
    call section("3. conservation, gravity and air off (free flight, 100 outer steps)")
    call conserve(2.0e6_dp, rp, rh, re, jp, jh, ok)
    call check(ok, "1 s in 100 outer steps, 100 refreshes, no event")
    call check(rp <= 1.0e-9_dp, "P(t) - P(0) - refresh jumps: " // fmt(rp) // " of sum|m v| (tol 1e-9)")
    call check(rh <= 1.0e-9_dp, "H(t) - H(0) - refresh jumps: " // fmt(rh) // " of sum|h| (tol 1e-9)")
    call check(re <= 1.0e-7_dp, "T(t) - T(0) - refresh jumps: " // fmt(re) // " of T (tol 1e-7)")
    call conserve(2.0e8_dp, rp2, rh2, re2, jp2, jh2, ok2)
    call check(ok2 .and. max(rp2, rh2) <= 1.0e-9_dp .and. re2 <= 1.0e-7_dp, "the same with a 100x stiffer line: " // &
      fmt(rp2) // ", " // fmt(rh2) // ", " // fmt(re2))
    call check(max(jp, jh, jp2, jh2) <= 1.0e-6_dp, "refresh jumps (summed) small: P " // fmt(jp) // ", H " // fmt(jh) // &
      "; stiff line: P " // fmt(jp2) // ", H " // fmt(jh2) // " (tol 1e-6)")
  end subroutine test_conservation

  subroutine test_far_end()
    type(rigidized_coupling) :: cpl
    type(line_model) :: model
    type(parachute) :: chute
    type(error_type), allocatable :: error
    real(dp) :: x(3, 0:nseg), v(3, 0:nseg), d0, dmax, dchain
    integer :: k, which(rigidized_nroots)
    logical :: event
    call section("4. far_end = 'chain': both end motions from the chain freeze d_rigid")
    call build(cpl, 2.0e6_dp, "chain", x, v, model, chute, error)
    call check(.not. allocated(error), "scene built")
    if (allocated(error)) return
    d0 = cpl%vl%length
    dchain = 0.0_dp
    do k = 1, 50
      call cpl%outer_step(0.01_dp*k, event, which, error)
      if (allocated(error)) exit
      dchain = max(dchain, abs(cpl%vl%length - d0))
    end do
    call check(.not. allocated(error), "0.5 s")
    call cpl%free()
    call check(dchain <= 1.0e-12_dp*d0, "d_rigid constant: largest change " // fmt(dchain) // " m")
    call build(cpl, 2.0e6_dp, "parachute", x, v, model, chute, error)
    dmax = 0.0_dp
    do k = 1, 50
      call cpl%outer_step(0.01_dp*k, event, which, error)
      if (allocated(error)) exit
      dmax = max(dmax, abs(cpl%vl%length - d0))
    end do
    call cpl%free()
    call check(dmax > 1.0e-3_dp, "far_end = 'parachute': the line's stretch reaches the chain, d_rigid changes by " // &
      fmt(dmax) // " m")
  end subroutine test_far_end

  subroutine test_bad_settings()
    type(rigidized_coupling) :: cpl
    type(line_model) :: model
    type(parachute) :: chute
    type(error_type), allocatable :: error
    type(separation_system) :: sep
    type(rigidized_settings) :: s
    real(dp) :: x(3, 0:1), v(3, 0:1)
    call section("bad settings")
    call model%init(line_params(length=10.0_dp, n_seg=1), error)
    x = 0.0_dp; v = 0.0_dp
    s%outer_dt = 0.0_dp
    call cpl%init(sep, 0, 0, model, chute, x, v, 0.0_dp, 0.0_dp, 0.0_dp, phase_free, s, error)
    call check(allocated(error), "outer_dt = 0 rejected")
    if (allocated(error)) print '(a)', "  " // error%message
    if (allocated(error)) deallocate(error)
    s%outer_dt = 0.01_dp
    call cpl%init(sep, 0, 0, model, chute, x, v, 0.0_dp, 0.0_dp, 0.0_dp, phase_free, s, error)
    call check(allocated(error), "a chain without rocket - line - parachute rejected")
    if (allocated(error)) print '(a)', "  " // error%message
  end subroutine test_bad_settings

  subroutine test_line_node_blocks()
    integer, parameter :: m = 8
    real(dp), parameter :: h = 1.0e-6_dp, t = 0.3_dp
    type(rigidized_line) :: line
    type(line_model) :: model
    type(parachute) :: chute
    type(node_blocks) :: blk
    type(error_type), allocatable :: error
    real(dp) :: x(3, 0:m), v(3, 0:m), r(3), dir(3), y(6*m), yp(6*m), fp(6*m), fm(6*m), col(6*m)
    real(dp) :: big, err, outside, rho_term(3), ap(3), am(3), drag(3), fn(3)
    integer :: k, j, q, d, st, n_taut
    logical :: fresh, ok, along_v
    call section("5. the line subsystem's node blocks against central differences of its right-hand side")
    call model%init(line_params(length=2.0_dp*m, n_seg=m, ea=1.0e5_dp, mass_per_length=0.5_dp, damping=200.0_dp, &
      diameter=0.05_dp, cd_normal=1.2_dp, cd_tangential=0.01_dp, gravity=.true., air=.true., air_density=0.9_dp), &
      error)
    call check(.not. allocated(error), "line model")
    if (allocated(error)) return
    chute%mass = 40.0_dp
    chute%drag_area = 20.0_dp
    chute%added_mass_factor = 1.0_dp
    call line%setup(model, chute, .false., boost, h_ref)
    ! node 0 on a body path; nodes 1..m stretched +2 % / -5 % by pairs (taut and
    ! slack), moving at about the frame's speed (absolute ~200 m/s)
    call line%near%set_body_motion(0.0_dp, [0.0_dp, 0.0_dp, 0.0_dp], [1.0_dp, -2.0_dp, 0.5_dp], 1.0_dp, &
      [1.0_dp, -2.0_dp, 0.5_dp], [1.0_dp, -2.0_dp, 0.5_dp])
    call line%near%motion(t, x(:, 0), v(:, 0))
    x(:, 0) = x(:, 0) + [boost*t, h_ref, 0.0_dp]
    do k = 1, m
      call random_number(r)
      dir = [-1.0_dp, 0.4_dp*(r(1) - 0.5_dp), 0.4_dp*(r(2) - 0.5_dp)]
      dir = dir/norm2(dir)
      x(:, k) = x(:, k - 1) + merge(1.02_dp, 0.95_dp, mod((k - 1)/2, 2) == 0)*model%l0*dir
    end do
    call random_number(v)
    v = 2.0_dp*(v - 0.5_dp)
    v(1, :) = v(1, :) + boost
    call line%pack(t, x, v, y)
    call line%rhs(t, y, fp, st)
    call check(st == 0, "right-hand side")
    n_taut = count(line%tension > 0.0_dp)
    call check(n_taut >= 3 .and. m - n_taut >= 3, "taut and slack segments: " // str(n_taut) // " / " // &
      str(m - n_taut))
    call check(line%has_node_jacobian(), "the line has node blocks")
    allocate(blk%ax(3, 3, -1:1, m), blk%av(3, 3, -1:1, m))
    call line%node_jacobian(t, y, .false., blk, fresh, st)
    call check(st == 0 .and. fresh, "blocks evaluated")
    ! the canopy's acceleration's change with altitude through the air density
    ! alone (line force held), which the blocks leave out
    fn = line%f(:, m)
    block
      real(dp) :: xs(3)
      xs = line%x(:, m); xs(2) = xs(2) + h
      call canopy_node_acceleration(chute, t, xs, line%v(:, m), model%node_mass(m), fn, .true., .true., ap, drag, ok)
      xs(2) = xs(2) - 2*h
      call canopy_node_acceleration(chute, t, xs, line%v(:, m), model%node_mass(m), fn, .true., .true., am, drag, ok)
    end block
    rho_term = (ap - am)/(2*h)
    big = max(maxval(abs(blk%ax)), maxval(abs(blk%av)))
    err = 0.0_dp
    outside = 0.0_dp
    do k = 1, m
      do q = 1, 6
        along_v = q > 3
        yp = y
        yp(6*(k - 1) + q) = y(6*(k - 1) + q) + h
        call line%rhs(t, yp, fp, st)
        yp(6*(k - 1) + q) = y(6*(k - 1) + q) - h
        call line%rhs(t, yp, fm, st)
        col = (fp - fm)/(2*h)
        if (k == m .and. q == 2) col(6*(m - 1) + 4:6*m) = col(6*(m - 1) + 4:6*m) - rho_term
        do j = 1, m
          d = k - j
          if (abs(d) > 1) then
            outside = max(outside, maxval(abs(col(6*(j - 1) + 4:6*j))))
          else if (along_v) then
            err = max(err, maxval(abs(col(6*(j - 1) + 4:6*j) - blk%av(:, q - 3, d, j))))
          else
            err = max(err, maxval(abs(col(6*(j - 1) + 4:6*j) - blk%ax(:, q, d, j))))
          end if
        end do
      end do
    end do
    call check(big > 1.0e4_dp .and. maxval(abs(rho_term)) > 0.0_dp, "blocks and density term not trivially zero")
    call check_close(err, 0.0_dp, "every node block", abs=1.0e-8_dp*big)
    call check_close(outside, 0.0_dp, "no coupling beyond the neighbours", abs=1.0e-8_dp*big)
    ! keep / renew
    call line%rhs(t, y, fp, st)
    call line%node_jacobian(t, y, .true., blk, fresh, st)
    call check(.not. fresh, "same state, reuse allowed: kept")
    yp = y
    yp(1:3) = y(1:3) + 0.1_dp*(x(:, 0) - x(:, 1))   ! node 1 towards node 0: segment 1 slack
    call line%rhs(t, yp, fp, st)
    call check(line%tension(1) == 0.0_dp, "segment 1 slack")
    call line%node_jacobian(t, yp, .true., blk, fresh, st)
    call check(fresh, "a taut segment gone slack: renewed although reuse is allowed")
  end subroutine test_line_node_blocks
  subroutine test_marching_line()
    integer, parameter :: m = 8
    real(dp), parameter :: t_end = 0.2_dp
    type(rigidized_line), pointer :: line
    type(line_model) :: model
    type(parachute) :: chute
    type(rigidized_settings) :: s
    type(line_marcher) :: mar, mar2
    type(cvode_solver) :: ref
    type(cvode_options) :: opt
    type(error_type), allocatable :: error
    real(dp) :: x(3, 0:m), v(3, 0:m), y0(6*m), dir(3), tip_ref(3), errs(3), frac(3), limit, slope
    integer :: k, j
    call section("6. the paper's marching as the line's sub-stepper against CVODE")
    call model%init(line_params(length=2.0_dp*m, n_seg=m, ea=1.0e7_dp, mass_per_length=0.5_dp, damping=200.0_dp, &
      diameter=0.02_dp, cd_normal=1.2_dp, cd_tangential=0.01_dp, gravity=.true., air=.true.), error)
    call check(.not. allocated(error), "line model")
    if (allocated(error)) return
    chute%mass = 40.0_dp
    chute%drag_area = 20.0_dp
    chute%added_mass_factor = 1.0_dp
    allocate(line)
    call line%setup(model, chute, .false., boost, h_ref)
    ! node 0 on a curved path (relative frame), the line straight aft, stretched
    ! about as the canopy's drag at 200 m/s stretches it, moving with the frame
    call line%near%set_body_motion(0.0_dp, [0.0_dp, 0.0_dp, 0.0_dp], [1.0_dp, -2.0_dp, 0.5_dp], t_end, &
      [0.3_dp, -0.2_dp, 0.1_dp], [-2.0_dp, 3.0_dp, -1.0_dp])
    call line%near%motion(0.0_dp, x(:, 0), v(:, 0))
    x(:, 0) = x(:, 0) + [0.0_dp, h_ref, 0.0_dp]
    v(:, 0) = v(:, 0) + [boost, 0.0_dp, 0.0_dp]
    dir = [-1.0_dp, -0.1_dp, 0.05_dp]
    dir = dir/norm2(dir)
    do k = 1, m
      x(:, k) = x(:, 0) + k*model%l0*1.04_dp*dir
      v(:, k) = [boost, 0.0_dp, 0.0_dp]
    end do
    call line%pack(0.0_dp, x, v, y0)
    ! the reference: CVODE BDF5 at rtol 1e-10 on the same subsystem
    opt = cvode_options(method="bdf", linear_solver="second_order_band", upper_bandwidth=line_band_upper, &
      lower_bandwidth=line_band_lower, rtol=1.0e-10_dp, atol=1.0e-10_dp, max_order=5, max_num_steps=1000000)
    call ref%init(line, 0.0_dp, y0, opt, error)
    if (.not. allocated(error)) call ref%set_stop_time(t_end, error)
    if (.not. allocated(error)) call ref%advance(t_end, error)
    call check(.not. allocated(error), "CVODE reference")
    if (allocated(error)) return
    tip_ref = ref%y(6*(m - 1) + 1:6*(m - 1) + 3)
    call line%rhs(t_end, ref%y, y0, j)   ! (y0 as scratch: the tensions at the end)
    call check(all(line%tension > 0.0_dp), "the line stays taut (no kink spoils the order)")
    call line%pack(0.0_dp, x, v, y0)
    limit = model%stable_step()
    frac = [0.8_dp, 0.4_dp, 0.2_dp]
    do j = 1, 3
      s%inner_dt = frac(j)*limit
      call mar%init(line, 0.0_dp, y0, s%inner_dt, s%inner_force_tol, s%inner_max_iterations, s%max_steps, error)
      call mar%set_stop_time(t_end)
      if (.not. allocated(error)) call mar%advance(line, t_end, error)
      call check(.not. allocated(error), "march at " // fmt(frac(j)) // " of the limit")
      if (allocated(error)) return
      errs(j) = norm2(mar%y(6*(m - 1) + 1:6*(m - 1) + 3) - tip_ref)
      print '(a, f4.2, a, es10.3, a, i6, a, es10.3, a)', "  dt = ", frac(j), " x limit: tip error ", errs(j), &
        " m, ", mar%steps, " sub-steps, ", real(mar%iterations, dp)/mar%steps, " far-end iterations per sub-step"
    end do
    slope = log(errs(1)/errs(3))/log(frac(1)/frac(3))
    print '(a, f6.3)', "  order (log-log slope of the tip error against the sub-step): ", slope
    call check(errs(3) > 0.0_dp .and. errs(3) < 1.0e-2_dp*model%p%length, "the march follows the reference")
    call check_close(slope, 1.0_dp, "first order in the sub-step", abs=0.2_dp)
    ! an output inside the outer step changes no sub-step
    s%inner_dt = 0.0_dp
    call mar%init(line, 0.0_dp, y0, s%inner_dt, s%inner_force_tol, s%inner_max_iterations, s%max_steps, error)
    call mar2%init(line, 0.0_dp, y0, s%inner_dt, s%inner_force_tol, s%inner_max_iterations, s%max_steps, error)
    call mar%set_stop_time(t_end)
    call mar2%set_stop_time(t_end)
    call mar%advance(line, t_end, error)
    call mar2%advance(line, t_end/3.0_dp, error)
    call check(abs(mar2%t - t_end/3.0_dp) < 1.0e-15_dp, "state at the output time")
    call mar2%advance(line, t_end, error)
    call check(.not. allocated(error) .and. all(mar%y == mar2%y) .and. mar%steps == mar2%steps, &
      "the same sub-steps and end state with an output inside (" // str(int(mar%steps)) // " sub-steps, dt = " // &
      "0.9 of the limit by default: " // fmt(mar%dt) // " s)")
    call check_close(mar%dt, 0.9_dp*limit, "default sub-step 0.9 of the limit", rel=1.0e-14_dp)
    ! bad settings
    s%inner_dt = 1.01_dp*limit
    call mar%init(line, 0.0_dp, y0, s%inner_dt, s%inner_force_tol, s%inner_max_iterations, s%max_steps, error)
    call check(allocated(error), "a sub-step above the stability limit refused")
    if (allocated(error)) then
      print '(a)', "  " // error%message
      call check(index(error%message, "stability limit") > 0, "the message names the limit")
      deallocate(error)
    end if
    s%inner_dt = 0.0_dp
    s%max_steps = 10
    call mar%init(line, 0.0_dp, y0, s%inner_dt, s%inner_force_tol, s%inner_max_iterations, s%max_steps, error)
    call mar%set_stop_time(t_end)
    call mar%advance(line, t_end, error)
    call check(allocated(error) .and. mar%steps == 10, "the step budget stops the march after 10 sub-steps")
    if (allocated(error)) print '(a)', "  " // error%message
    call mar%free()
    call mar2%free()
    call ref%free()
    deallocate(line)
  end subroutine test_marching_line
end program test_rigidized_coupling
