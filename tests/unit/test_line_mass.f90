!> The line's mass matrices (airlaunch_line_model, "Mass matrix"; airlaunch_line_mass).
!>
!> 1. Dispersion.  A taut line (pre-strain 1 %, no gravity, no air, no damping)
!>    between two fixed ends is released from its first axial mode shape,
!>    u_j = A sin(pi j/N).  The chain is linear (every segment stays taut) and
!>    M and K share the sampled sines as eigenvectors, so the mid node moves
!>    as A cos(w t) with the discrete frequency
!>        (w l0/c)^2 = 2 (1 - cos theta) / (1 - 2 beta (1 - cos theta)),  theta = pi/N
!>    (beta = 0 lumped, 1/12 mixed), against the continuum's w = pi c/L.  The
!>    period is measured from the mid node's zero crossings over three periods
!>    (CVODE BDF5 at rtol 1e-10, outputs every T/400: linear interpolation of a
!>    crossing errs by ~(2 pi/400)^3 of a step, 1e-7 of T) and must match the
!>    discrete formula to 1e-6 relative - the mass matrix is assembled and solved
!>    as stated.  The continuum period error must fall with N at order 2 for the
!>    lumped and at order 4 for the mixed mass (N = 8 -> 16: log2 ratio within
!>    0.15 of 2 and of 4; the next terms of the expansions are (pi/N)^2 smaller,
!>    4 % at N = 8).
!>    The same for the first transverse (string) mode, w_j = A sin(pi j/N) across
!>    the line: the pre-tension T0 = EA eps0 acting on the segment's stretched
!>    length l = l0 (1 + eps0) is the chain's transverse stiffness T0/l (the
!>    tension's geometric stiffness), so
!>        w^2 = T0/(rho l0 l) 2 (1 - cos theta) / (1 - 2 beta (1 - cos theta)),
!>    against the taut string's w = (pi/L) sqrt(T0/(rho (1 + eps0))) (wave speed
!>    sqrt(T0/rho_s) over the stretched length, rho_s = rho/(1 + eps0)).  The
!>    amplitude is 1e-5 L: the stretch a transverse mode adds, ~(pi A/L)^2/4,
!>    raises the frequency by ~(EA/T0)(pi A/L)^2/4 = 2.5e-8, below the 1e-6
!>    tolerance (at A = 1e-3 L it would be 2.5e-4).
!> 2. Newton's law of the semi-discrete line.  For a line with a prescribed end
!>    (sinusoid) at node 0 and a point mass at node N, and the other way round,
!>    at an arbitrary state, the
!>    accelerations of the right-hand side must satisfy M a = f, with M
!>    assembled here from the segment matrices rho l0 [[1/2 - beta, beta],
!>    [beta, 1/2 - beta]] (and the point mass), a_0 the prescribed end's
!>    analytic acceleration and f the line's forces plus the point mass's
!>    weight: to 1e-12 of the largest force (round-off of a tridiagonal solve).
!>    And the node blocks handed to the Newton solve: D^-1 M (D = diag M) times
!>    the central-difference Jacobian of the right-hand side equals the blocks,
!>    and the blocks' mass coupling is M(j, j+1)/M(j, j) (newton_blocks).
!> 3. Bad input: the mixed mass with the paper's marching scheme or with
!>    difference-quotient Jacobians is refused with one line.
program test_line_mass
  use airlaunch_kinds, only: dp, g0, pi
  use airlaunch_error, only: error_type
  use airlaunch_strings, only: str
  use airlaunch_line
  use airlaunch_ode, only: node_blocks
  use testing
  implicit none
  real(dp), parameter :: length = 10.0_dp, ea = 1.0e5_dp, rho = 1.0_dp, eps0 = 0.01_dp
  real(dp), parameter :: beta_mixed = 1.0_dp/12.0_dp
  real(dp) :: c, t_cont, err(2, 2), order
  integer :: im, in, dir
  character(len=10), parameter :: directions(2) = ["axial     ", "transverse"]
  character(len=6), parameter :: masses(2) = ["lumped", "mixed "]
  integer, parameter :: ns(2) = [8, 16]

  c = sqrt(ea/rho)
  do dir = 1, 2
    if (dir == 1) then
      t_cont = 2.0_dp*length/c
    else
      t_cont = 2.0_dp*length*sqrt(rho*(1.0_dp + eps0)/(ea*eps0))
    end if
    do im = 1, 2
      call section("first " // trim(directions(dir)) // " mode of a fixed-fixed line, " // trim(masses(im)) // &
        " mass, continuum period " // str(t_cont) // " s")
      do in = 1, 2
        err(in, im) = mode_period(ns(in), masses(im), dir)/t_cont - 1.0_dp
      end do
      order = log(abs(err(1, im))/abs(err(2, im)))/log(2.0_dp)
      print '(a, 2es12.4, a, f7.3)', "  relative period errors N = 8, 16:", err(:, im), "; order", order
      call check_close(order, merge(2.0_dp, 4.0_dp, im == 1), trim(masses(im)) // " mass: order of the " // &
        trim(directions(dir)) // " period error in N", abs=0.15_dp)
    end do
  end do
  call newtons_law(0)
  call newtons_law(6)
  call refusals()
  call finish()

contains

  !> Discrete period of the first mode of N segments with coupling beta [s],
  !> axial (dir = 1) or transverse (dir = 2).
  pure real(dp) function discrete_period(n, beta, dir) result(t)
    integer, intent(in) :: n, dir
    real(dp), intent(in) :: beta
    real(dp) :: q, w, l0
    l0 = length/n
    q = 1.0_dp - cos(pi/n)
    if (dir == 1) then
      w = c/l0*sqrt(2.0_dp*q/(1.0_dp - 2.0_dp*beta*q))
    else   ! transverse stiffness T0/l of each segment, l = l0 (1 + eps0)
      w = sqrt(ea*eps0/(rho*l0*l0*(1.0_dp + eps0)))*sqrt(2.0_dp*q/(1.0_dp - 2.0_dp*beta*q))
    end if
    t = 2.0_dp*pi/w
  end function discrete_period

  !> Measured period of the mid node [s], axial (dir = 1) or transverse (dir = 2);
  !> checked against the discrete formula.
  real(dp) function mode_period(n, mass, dir) result(period)
    integer, intent(in) :: n, dir
    character(len=*), intent(in) :: mass
    type(line_model) :: model
    class(line_scheme), allocatable :: scheme
    type(line_scheme_options) :: opts
    type(error_type), allocatable :: error
    real(dp) :: x(3, 0:n), v(3, 0:n), t_d, dt, u_prev, u, t_prev, t_first, t_last, l0, amp
    integer :: j, i, crossings, n_out
    call model%init(line_params(length=length, n_seg=n, ea=ea, mass_per_length=rho, gravity=.false., &
      air=.false., mass=mass), error)
    call check(.not. allocated(error), "line model, N = " // str(n))
    if (allocated(error)) then
      period = 0
      return
    end if
    l0 = length/n
    amp = 0.02_dp*eps0*length   ! axial: peak strain change pi amp/L = 6e-4 < eps0: always taut
    if (dir == 2) amp = 1.0e-5_dp*length   ! transverse: header
    do j = 0, n
      x(:, j) = [j*l0*(1 + eps0), 0.0_dp, 0.0_dp]
      x(dir, j) = x(dir, j) + amp*sin(pi*j/n)
    end do
    v = 0.0_dp
    opts%rtol = 1.0e-10_dp
    opts%atol = 1.0e-12_dp
    opts%max_order = 5
    call new_line_scheme(scheme, model, line_end(kind=end_fixed, position=x(:, 0)), &
      line_end(kind=end_fixed, position=x(:, n)), x, v, 0.0_dp, opts, error)
    call check(.not. allocated(error), "scheme, N = " // str(n))
    if (allocated(error)) then
      period = 0
      return
    end if
    t_d = discrete_period(n, merge(beta_mixed, 0.0_dp, mass == "mixed"), dir)
    dt = t_d/400
    n_out = 1200   ! three periods
    u_prev = amp
    t_prev = 0.0_dp
    crossings = 0
    t_first = 0.0_dp
    t_last = 0.0_dp
    do i = 1, n_out
      call scheme%advance(i*dt, error)
      if (allocated(error)) exit
      call scheme%get_state(x, v)
      u = x(dir, n/2) - merge((n/2)*l0*(1 + eps0), 0.0_dp, dir == 1)
      if ((u_prev > 0.0_dp) .neqv. (u > 0.0_dp)) then
        crossings = crossings + 1
        t_last = t_prev + u_prev/(u_prev - u)*(i*dt - t_prev)
        if (crossings == 1) t_first = t_last
      end if
      u_prev = u
      t_prev = i*dt
    end do
    call check(.not. allocated(error) .and. crossings == 6, "N = " // str(n) // ": three periods, " // &
      str(crossings) // " zero crossings")
    period = 2.0_dp*(t_last - t_first)/(crossings - 1)
    call check_close(period, t_d, "N = " // str(n) // ": measured period [s] against the discrete formula", &
      rel=1.0e-6_dp)
    call scheme%free()
  end function mode_period

  !> Part 2: M a = f at an arbitrary state, M assembled here, with the prescribed
  !> end at node `moving` (0 or N) and the point mass at the other; and the node
  !> blocks of the Newton matrix against central differences of the right-hand side.
  subroutine newtons_law(moving)
    integer, intent(in) :: moving
    integer, parameter :: n = 6
    real(dp), parameter :: m_end = 3.0_dp, t = 0.37_dp
    type(line_model) :: model
    type(line_system) :: sys
    type(line_end) :: ends(2)
    type(error_type), allocatable :: error
    real(dp) :: x(3, 0:n), v(3, 0:n), f(3, 0:n), tension(n), mm(0:n, 0:n), acc(3, 0:n), r(3)
    real(dp) :: xe(3), ve(3), ae(3), me, worst, scale
    real(dp), allocatable :: y(:), ydot(:)
    integer :: j, k, st, fixed_node, mass_node, first
    fixed_node = moving
    mass_node = n - moving
    call section("Newton's law of the mixed-mass line: M a = f (prescribed end at node " // str(fixed_node) // &
      ", point mass at node " // str(mass_node) // ", 6 segments)")
    call model%init(line_params(length=length, n_seg=n, ea=ea, mass_per_length=rho, damping=30.0_dp, &
      gravity=.true., air=.false., mass="mixed"), error)
    ends(1 + fixed_node/n) = line_end(kind=end_prescribed, position=[fixed_node*length/n, 0.0_dp, 0.0_dp], &
      amplitude=[0.3_dp, 0.5_dp, 0.2_dp], frequency=1.3_dp, phase_deg=20.0_dp)
    ends(1 + mass_node/n) = line_end(kind=end_point_mass, mass=m_end, position=[mass_node*length/n, 0.0_dp, 0.0_dp])
    call sys%setup(model, ends(1), ends(2), error)
    call check(.not. allocated(error), "system built")
    call ends(1 + fixed_node/n)%motion(t, xe, ve, ae)
    ! A state away from the law's kinks (slack, the clipped dashpot), where the
    ! central differences below are meaningful (checked below): axial spacing
    ! 1.01 l0, random offsets across the line only, a fixed seed.  With random
    ! axial offsets and the run's own seed about 2 % of the runs sampled a
    ! segment at a kink and the Jacobian check failed.
    call fixed_seed()
    do j = 0, n
      call random_number(r)
      x(:, j) = [j*length*1.01_dp/n, 0.1_dp*sin(1.0_dp*j), 0.0_dp] + 0.05_dp*(r - 0.5_dp)*[0.0_dp, 1.0_dp, 1.0_dp]
      call random_number(r)
      v(:, j) = 2.0_dp*(r - 0.5_dp)
    end do
    x(:, fixed_node) = xe
    v(:, fixed_node) = ve
    allocate(y(sys%n_state()), ydot(sys%n_state()))
    call sys%pack(x, v, y)
    call sys%rhs(t, y, ydot, st)
    call check(st == 0, "right-hand side evaluated")
    first = merge(1, 0, fixed_node == 0)
    acc(:, fixed_node) = ae
    do k = first, first + n - 1
      acc(:, k) = ydot(6*(k - first) + 4:6*(k - first) + 6)
    end do
    call model%forces(x, v, f, tension, st)
    block   ! every segment away from a kink by far more than the differences' steps (~1e-5 in strain)
      real(dp) :: ell, eps, epsdot, dist, closest
      closest = huge(1.0_dp)
      do k = 1, n
        ell = norm2(x(:, k) - x(:, k - 1))
        eps = ell/model%l0 - 1.0_dp
        epsdot = dot_product((x(:, k) - x(:, k - 1))/ell, v(:, k) - v(:, k - 1))/model%l0
        dist = abs(eps)
        if (eps > 0.0_dp) dist = min(eps, abs(ea*eps + model%p%damping*epsdot)/ea)
        closest = min(closest, dist)
      end do
      call check(closest > 1.0e-4_dp, "no segment at a kink of the tension law (closest " // str(closest) // &
        " in strain)")
    end block
    f(2, mass_node) = f(2, mass_node) - m_end*g0
    me = rho*length/n
    mm = 0.0_dp
    do k = 1, n   ! segment k joins nodes k - 1 and k
      mm(k - 1, k - 1) = mm(k - 1, k - 1) + me*(0.5_dp - beta_mixed)
      mm(k, k) = mm(k, k) + me*(0.5_dp - beta_mixed)
      mm(k - 1, k) = mm(k - 1, k) + me*beta_mixed
      mm(k, k - 1) = mm(k, k - 1) + me*beta_mixed
    end do
    mm(mass_node, mass_node) = mm(mass_node, mass_node) + m_end
    worst = 0.0_dp
    scale = maxval(abs(f))
    do k = first, first + n - 1
      worst = max(worst, maxval(abs(matmul(acc, mm(:, k)) - f(:, k))))
    end do
    call check_close(worst, 0.0_dp, "largest |(M a)_k - f_k| over the state nodes [N]", abs=1.0e-12_dp*scale)
    call newton_blocks(sys, t, y, mm, first)
  end subroutine newtons_law

  !> The node blocks the system hands the velocity-reduced Newton solve: for
  !> each state node j, D^-1 M times the central-difference Jacobian of the
  !> accelerations (a full matrix: M^-1 df/dy) must be block tridiagonal and
  !> equal [ax, av] of the blocks, and blk%mass(d, j) = M(j, j + d)/M(j, j) -
  !> with M assembled here (mm, nodes 0..N) and D its diagonal.  Tolerance 1e-8
  !> of the largest entry, as in test_line_jacobian: central differences with
  !> h = 1e-6 err by O(h^2) truncation and ~eps/h round-off, both far below it
  !> (measured 1e-10).
  subroutine newton_blocks(sys, t, y, mm, first)
    type(line_system), intent(inout) :: sys
    real(dp), intent(in) :: t, y(:), mm(0:, 0:)
    integer, intent(in) :: first
    type(node_blocks) :: blk
    real(dp), allocatable :: jac(:, :), yp(:), fp(:), fm(:), ydot(:)
    real(dp) :: h, big, err, want, got, err_mass
    integer :: ns, nodes, i, j, k, p, q, d, st, kj
    logical :: fresh
    ns = size(y)
    nodes = ns/6
    allocate(jac(ns, ns), yp(ns), fp(ns), fm(ns), ydot(ns))
    do i = 1, ns
      h = 1.0e-6_dp*max(1.0_dp, abs(y(i)))
      yp = y
      yp(i) = y(i) + h
      call sys%rhs(t, yp, fp, st)
      yp(i) = y(i) - h
      call sys%rhs(t, yp, fm, st)
      jac(:, i) = (fp - fm)/(2*h)
    end do
    call sys%rhs(t, y, ydot, st)   ! the tensions at y, for the blocks' slack/taut pattern
    allocate(blk%ax(3, 3, -1:1, nodes), blk%av(3, 3, -1:1, nodes), blk%mass(-1:1, nodes), source=0.0_dp)
    call sys%node_jacobian(t, y, .false., blk, fresh, st)
    call check(st == 0 .and. fresh .and. blk%mass_coupled, "node blocks formed, mass-coupled")
    big = maxval(abs(jac))
    err = 0.0_dp
    err_mass = 0.0_dp
    do j = 1, nodes
      kj = first + j - 1   ! the line node of state node j
      do d = -1, 1
        want = 0.0_dp
        if (j + d >= 1 .and. j + d <= nodes) want = mm(kj, kj + d)/mm(kj, kj)
        if (d /= 0) err_mass = max(err_mass, abs(blk%mass(d, j) - want))
      end do
      do k = 1, nodes
        do q = 1, 6
          do p = 1, 3
            ! row p of node j's velocity rows of D^-1 M J, column q of node k
            got = 0.0_dp
            do i = max(1, j - 1), min(nodes, j + 1)
              got = got + mm(kj, first + i - 1)/mm(kj, kj)*jac(6*(i - 1) + 3 + p, 6*(k - 1) + q)
            end do
            want = 0.0_dp
            if (abs(k - j) <= 1) then
              if (q <= 3) want = blk%ax(p, q, k - j, j)
              if (q > 3) want = blk%av(p, q - 3, k - j, j)
            end if
            err = max(err, abs(got - want))
          end do
        end do
      end do
    end do
    call check_close(err_mass, 0.0_dp, "blocks' mass coupling M(j, j+d)/M(j, j)", abs=1.0e-14_dp)
    call check_close(err, 0.0_dp, "D^-1 M (central-difference Jacobian) against the blocks [ax, av]", &
      abs=1.0e-8_dp*big)
  end subroutine newton_blocks

  !> Part 3: the combinations the mixed mass cannot take.
  subroutine refusals()
    type(line_model) :: model
    class(line_scheme), allocatable :: scheme
    type(line_scheme_options) :: opts
    type(error_type), allocatable :: error
    real(dp) :: x(3, 0:4), v(3, 0:4)
    integer :: j
    call section("the mixed mass is refused where it cannot work")
    call model%init(line_params(length=length, n_seg=4, ea=ea, mass_per_length=rho, mass="mixed"), error)
    do j = 0, 4
      x(:, j) = [j*length/4, 0.0_dp, 0.0_dp]
    end do
    v = 0.0_dp
    opts%scheme = "marching"
    opts%dt = 1.0e-5_dp
    call new_line_scheme(scheme, model, line_end(kind=end_fixed, position=x(:, 0)), &
      line_end(kind=end_free, position=x(:, 4)), x, v, 0.0_dp, opts, error)
    call check(allocated(error), "marching scheme refused")
    if (allocated(error)) call check(index(error%message, "mass = 'mixed'") > 0 .and. &
      index(error%message, "lumped") > 0, "message names mass and the remedy: " // error%message)
    deallocate(error)
    opts%scheme = "cvode"
    opts%analytic_jacobian = .false.
    call new_line_scheme(scheme, model, line_end(kind=end_fixed, position=x(:, 0)), &
      line_end(kind=end_free, position=x(:, 4)), x, v, 0.0_dp, opts, error)
    call check(allocated(error), "difference-quotient Jacobian refused")
    if (allocated(error)) call check(index(error%message, "analytic Jacobian") > 0, "message: " // error%message)
    call model%init(line_params(length=length, n_seg=4, ea=ea, mass_per_length=rho, mass="consist"), error)
    call check(allocated(error), "unknown mass matrix refused")
    if (allocated(error)) call check(index(error%message, "mass = 'consist'") > 0, "message: " // error%message)
  end subroutine refusals
end program test_line_mass
