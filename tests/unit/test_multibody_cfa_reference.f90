!> The cut joint + CFA (§3.3, Eqs. (43), (66)-(68)) and the Kane chain inside the
!> whole separation scene, against an independent constrained-dynamics reference
!> (audit, thirty-second session), for random states and loads in every phase and
!> joint type: Case 0 locked, Case 1 rail (frictionless, Coulomb sliding either
!> way, at rest in the Karnopp band: stick or slip), Case 2 ramp edge (bilateral:
!> frictionless, Coulomb, no-slip), Case 3 free; chains of 1, 2, 3 bodies.
!>
!> Reference: maximal coordinates (every body 6 speeds: earth CG velocity, body
!> angular velocity), Newton-Euler of each body, and every constraint -- the
!> chain's spherical joints and the cut joint of the phase -- written as a
!> position function Phi(r_k, C_k) from docs/multibody.md (Case 0: the contact
!> point fixed in aircraft axes and the relative attitude fixed; Case 1: the
!> contact point on the rail line, the relative attitude fixed, the slide e1.w
!> free; Case 2: the ramp edge on the rocket's contact line (rocket y, z), the
!> edge axis h1 turned with the rocket kept normal to e1 and e2, the slide eps_x
!> free).  Its Jacobian and velocity-product terms come from central second
!> differences of Phi along paths r + v h + a h^2/2, C exp(skew(w h + wdot h^2/2))
!> (exact to second order), Richardson-extrapolated (h = 2 ms, 1 ms); multipliers
!> from one dense KKT solve; friction lambda_1 = sigma mu |N| by fixed point on
!> |N| (N = the two other force multipliers), the Karnopp band as documented
!> (stick if |lambda_1| <= mu |N|, else slip against the sticking force).  The
!> constraint wrench on the rocket is J^T lambda of the cut joint's rows.
!> Tolerance 1e-6 relative (to the largest entry): the differences' truncation
!> and round-off (Python prototype and this test: 1e-8 to 4e-8).
module cfa_reference_cases
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type
  use airlaunch_linalg, only: solve_general
  use airlaunch_rotation, only: quat_from_euler
  use airlaunch_multibody
  use testing
  implicit none
  private
  public :: run_case
  real(dp), parameter :: contact(3) = [0.0_dp, -1.0_dp, 0.0_dp]  ! cut_joint_geometry default
  real(dp), parameter :: floor_pt(3) = [3.0_dp, -1.2_dp, 0.0_dp]
  real(dp), parameter :: rail(3) = [-1.0_dp, -0.05_dp, 0.0_dp]

contains

  character(len=10) function fmt(x)
    real(dp), intent(in) :: x
    write(fmt, '(es10.2)') x
  end function fmt

  pure function sk(a) result(s)
    real(dp), intent(in) :: a(3)
    real(dp) :: s(3, 3)
    s = reshape([0.0_dp, a(3), -a(2), -a(3), 0.0_dp, a(1), a(2), -a(1), 0.0_dp], [3, 3])
  end function sk

  pure function xprod(a, b) result(c)
    real(dp), intent(in) :: a(3), b(3)
    real(dp) :: c(3)
    c = [a(2)*b(3) - a(3)*b(2), a(3)*b(1) - a(1)*b(3), a(1)*b(2) - a(2)*b(1)]
  end function xprod

  !> exp(skew(th)), Rodrigues.
  pure function rodrigues(th) result(r)
    real(dp), intent(in) :: th(3)
    real(dp) :: r(3, 3), a, k(3, 3)
    integer :: i
    a = norm2(th)
    r = 0.0_dp
    do i = 1, 3
      r(i, i) = 1.0_dp
    end do
    if (a == 0.0_dp) return
    k = sk(th/a)
    r = r + sin(a)*k + (1.0_dp - cos(a))*matmul(k, k)
  end function rodrigues

  pure function vee(r) result(v)
    real(dp), intent(in) :: r(3, 3)
    real(dp) :: v(3)
    v = 0.5_dp*[r(3, 2) - r(2, 3), r(1, 3) - r(3, 1), r(2, 1) - r(1, 2)]
  end function vee

  subroutine run_case(label, phase, n, mu_rail, mu_edge, no_slip, slide_rate)
    character(len=*), intent(in) :: label
    integer, intent(in) :: phase, n
    real(dp), intent(in) :: mu_rail, mu_edge, slide_rate
    logical, intent(in) :: no_slip
    type(separation_system), target :: sys
    type(error_type), allocatable :: error
    type(rigid_body) :: aircraft, rocket
    type(cut_joint_geometry) :: geo
    type(cut_joint_options) :: opt
    type(constant_load_source) :: src
    real(dp), allocatable :: y(:), ms(:), jb(:, :, :), r(:, :), v(:, :), c(:, :, :), w(:, :), f(:, :), mo(:, :)
    real(dp), allocatable :: prox(:, :), dist(:, :), k0(:), phid(:), phi0(:), jac(:, :), ud(:), ej(:)
    real(dp), allocatable :: vtmp(:)
    real(dp), allocatable :: kkt(:, :), rhs(:, :), q(:), jc(:, :), kc(:), lam(:), gen(:), ref(:), got(:)
    real(dp) :: e(3, 3), rel_ref(3, 3), w_ref(3), h1(3), sc, mu, lam1, sigma, nmag, kd, kp, err_a, err_r, srate
    real(dp) :: wrench(6)
    real(dp), parameter :: load_scale(0:3) = [3.0e5_dp, 1.0e5_dp, 3.0e2_dp, 3.0e2_dp]
    real(dp), parameter :: point_scale(0:3) = [4.0_dp, 0.5_dp, 0.5_dp, 0.5_dp]
    integer :: k, nb, nu, nrow, ncut, i, it, nc, ic
    logical :: stick, slide_row, friction
    nb = n + 1
    nu = 6*nb
    aircraft = new_rigid_body("aircraft", 89000.0_dp, diag3(540740.0_dp, 737480.0_dp, 117030.0_dp), error)
    rocket = new_rigid_body("rocket", 28000.0_dp, diag3(7870.0_dp, 545000.0_dp, 545000.0_dp), error)
    geo%rail_direction = rail
    geo%floor_point = floor_pt
    geo%edge_point = geo%floor_point + 14.0_dp*geo%rail_direction
    opt%mu_rail = mu_rail
    opt%mu_edge = mu_edge
    opt%edge_no_slip = no_slip
    call sys%init(aircraft, rocket, [9.25_dp, 0.0_dp, 0.0_dp], n, geo, opt, 5.0_dp, error)
    if (n == 3) then
      call sys%set_line_body(2, 20.0_dp, [6000.0_dp, 6000.0_dp, 0.0_dp], 30.0_dp, error)
      call sys%chain%set_link(3, "parachute", 40.0_dp, diag3(30.0_dp, 40.0_dp, 30.0_dp), &
        [0.0_dp, 0.0_dp, 4.0_dp], [0.0_dp, 0.0_dp, 0.0_dp], error)
    else if (n == 2) then
      call sys%chain%set_link(2, "parachute", 40.0_dp, diag3(30.0_dp, 40.0_dp, 30.0_dp), &
        [0.1_dp, 0.2_dp, 4.0_dp], [0.0_dp, 0.0_dp, 0.0_dp], error)
    end if
    sys%edge_bilateral = .true.   ! the edge may pull: the phase stays for any loads
    sys%bodies(0)%r = random_vector(5.0_dp)
    call sys%bodies(0)%set_attitude(quat_from_euler(random_vector(0.2_dp)))
    sys%bodies(0)%v = random_vector(3.0_dp)
    sys%bodies(0)%w = random_vector(0.08_dp)
    if (phase == phase_rotation) then
      call sys%joint%place_on_edge(sys%bodies(0), 2.0_dp, 0.1_dp, slide_rate, 0.2_dp, sys%bodies(1))
    else
      call sys%joint%place_on_rail(sys%bodies(0), 6.0_dp, slide_rate, sys%bodies(1))
    end if
    if (phase == phase_free) sys%bodies(1)%w = sys%bodies(1)%w + random_vector(0.3_dp)
    do k = 2, n
      call sys%bodies(k)%set_attitude(quat_from_euler(random_vector(1.0_dp)))
      sys%bodies(k)%w = random_vector(0.6_dp)
    end do
    do k = 0, n
      sc = load_scale(k)
      src%body = k
      src%force = random_vector(sc)
      src%point = random_vector(point_scale(k))
      src%moment = random_vector(sc)
      call sys%add_source(src)
    end do
    allocate(y(sys%state_size()))
    call sys%pack_state(y)
    call sys%start(0.0_dp, y, phase, error)
    if (.not. allocated(error)) call sys%evaluate(0.0_dp, y, error)
    call check(.not. allocated(error) .and. sys%phase == phase, label // ": scene starts in its phase")
    if (allocated(error)) then
      print '(a)', error%message
      return
    end if

    ! ---- the reference, from the bodies' states and loads only
    allocate(ms(0:n), jb(3, 3, 0:n), r(3, 0:n), v(3, 0:n), c(3, 3, 0:n), w(3, 0:n), f(3, 0:n), mo(3, 0:n))
    allocate(prox(3, n), dist(3, n))
    do k = 0, n
      ms(k) = sys%bodies(k)%mass
      jb(:, :, k) = sys%bodies(k)%inertia
      r(:, k) = sys%bodies(k)%r
      v(:, k) = sys%bodies(k)%v
      c(:, :, k) = sys%bodies(k)%c
      w(:, k) = sys%bodies(k)%w
      f(:, k) = sys%force(:, k)
      mo(:, k) = sys%moment(:, k)
    end do
    do k = 1, n
      prox(:, k) = sys%chain%link(k)%proximal
      dist(:, k) = sys%chain%link(k)%distal
    end do
    ! joint frame and references from the geometry and the start state
    e(:, 1) = rail/norm2(rail)
    e(:, 2) = [0.0_dp, 1.0_dp, 0.0_dp] - e(2, 1)*e(:, 1)
    e(:, 2) = e(:, 2)/norm2(e(:, 2))
    e(:, 3) = xprod(e(:, 1), e(:, 2))
    rel_ref = matmul(transpose(c(:, :, 0)), c(:, :, 1))
    w_ref = matmul(transpose(c(:, :, 0)), r(:, 1) + matmul(c(:, :, 1), contact) - r(:, 0))
    h1 = matmul(transpose(rel_ref), e(:, 3))
    ncut = 3*(n - 1)
    select case (phase)
    case (phase_preparation)
      nc = 6
    case (phase_extraction)
      nc = 5
    case (phase_rotation)
      nc = 4
    case default
      nc = 0
    end select
    nrow = ncut + nc + 1                 ! the last row: the slide coordinate
    allocate(k0(nrow), phid(nrow), phi0(nrow), jac(nrow, nu), ud(nu), ej(nu), vtmp(nrow))
    ud = 0.0_dp
    call derivatives(ud, k0, phid)
    phi0 = phis(0.0_dp, ud)
    do i = 1, nu
      ej = 0.0_dp
      ej(i) = 1.0_dp
      call derivatives(ej, jac(:, i), vtmp)
      jac(:, i) = jac(:, i) - k0
    end do
    ! Newton-Euler of every body: M u' = Q + J^T lambda
    allocate(q(nu))
    do k = 0, n
      q(6*k+1:6*k+3) = f(:, k)
      q(6*k+4:6*k+6) = mo(:, k) - xprod(w(:, k), matmul(jb(:, :, k), w(:, k)))
    end do
    kd = 2.0_dp*opt%baumgarte_zeta*opt%baumgarte_omega
    kp = opt%baumgarte_omega**2
    mu = 0.0_dp
    if (phase == phase_extraction) mu = mu_rail
    if (phase == phase_rotation) mu = mu_edge
    srate = phid(nrow)
    stick = .false.
    friction = .false.
    sigma = 0.0_dp
    lam1 = 0.0_dp
    ! the slide row is constrained in Case 0 (inside its six rows), for the no-slip
    ! edge and while trying to stick in the band
    slide_row = (phase == phase_rotation .and. no_slip) .or. &
      (mu > 0.0_dp .and. abs(srate) < opt%stick_velocity .and. (phase == phase_extraction .or. phase == phase_rotation))
    if (slide_row) then
      call kkt_solve(.true., 0.0_dp)
      stick = .true.
      if (.not. (phase == phase_rotation .and. no_slip)) then
        nmag = hypot(lam(ncut+1), lam(ncut+2))
        if (abs(lam(size(lam))) > mu*nmag) then
          stick = .false.
          friction = .true.
          sigma = sign(1.0_dp, lam(size(lam)))
        end if
      end if
    else if (mu > 0.0_dp .and. (phase == phase_extraction .or. phase == phase_rotation)) then
      friction = .true.
      sigma = -sign(1.0_dp, srate)
    end if
    if (.not. stick) then
      call kkt_solve(.false., 0.0_dp)
      if (friction) then
        do it = 1, 300
          nmag = hypot(lam(ncut+1), lam(ncut+2))
          lam1 = sigma*mu*nmag
          call kkt_solve(.false., lam1)
        end do
      end if
    end if
    ! constraint wrench on the rocket (body 1): the cut joint's rows of J^T lambda
    allocate(gen(nu))
    gen = 0.0_dp
    do ic = ncut + 1, size(lam)
      if (ic <= ncut + nc) then
        gen = gen + lam(ic)*jac(ic, :)
      else
        gen = gen + lam(ic)*jac(nrow, :)
      end if
    end do
    if (friction .and. .not. stick) gen = gen + lam1*jac(nrow, :)
    allocate(ref(6 + 3 + 3*n), got(6 + 3 + 3*n))
    ref(1:6) = ud(1:6)
    ref(7:12) = ud(7:12)
    do k = 2, n
      ref(10+3*(k-1):12+3*(k-1)) = ud(6*k+4:6*k+6)
    end do
    got(1:3) = sys%a0
    got(4:6) = sys%wdot0
    got(7:) = sys%udot
    err_a = maxval(abs(got - ref))/maxval(abs(ref))
    wrench = [sys%rh_force, sys%rh_moment]
    err_r = maxval(abs(wrench - gen(7:12)))/max(maxval(abs(gen(7:12))), 1.0_dp)
    call check(err_a <= 1.0e-6_dp, label // ": accelerations, rel. diff " // fmt(err_a) // " (tol 1e-6)")
    call check(err_r <= 1.0e-6_dp, label // ": wrench on the rocket, rel. diff " // fmt(err_r) // " (tol 1e-6)")
    if (phase == phase_extraction .or. phase == phase_rotation) &
      call check(stick .eqv. sys%stick, label // ": stick decision " // merge("stick", "slip ", stick))

  contains

    !> KKT solve: the cut rows (and the slide row if constrained) with Baumgarte,
    !> lambda_1 = l1 on the slide row's Jacobian if it is free.
    subroutine kkt_solve(with_slide, l1)
      logical, intent(in) :: with_slide
      real(dp), intent(in) :: l1
      integer :: m, j
      m = ncut + nc
      if (with_slide) m = m + 1
      if (allocated(kkt)) deallocate(kkt, rhs, jc, kc, lam)
      allocate(kkt(nu + m, nu + m), rhs(nu + m, 1), jc(m, nu), kc(m), lam(m))
      jc(1:ncut+nc, :) = jac(1:ncut+nc, :)
      kc(1:ncut+nc) = k0(1:ncut+nc) + kd*phid(1:ncut+nc) + kp*phi0(1:ncut+nc)
      if (with_slide) then
        jc(m, :) = jac(nrow, :)
        kc(m) = k0(nrow) + opt%stick_rate*phid(nrow)
      end if
      kkt = 0.0_dp
      do j = 0, n
        kkt(6*j+1, 6*j+1) = ms(j)
        kkt(6*j+2, 6*j+2) = ms(j)
        kkt(6*j+3, 6*j+3) = ms(j)
        kkt(6*j+4:6*j+6, 6*j+4:6*j+6) = jb(:, :, j)
      end do
      kkt(1:nu, nu+1:nu+m) = -transpose(jc)
      kkt(nu+1:nu+m, 1:nu) = jc
      rhs(1:nu, 1) = q
      if (.not. with_slide) rhs(1:nu, 1) = q + l1*jac(nrow, :)
      rhs(nu+1:nu+m, 1) = -kc
      call solve_general(kkt, rhs, error, "reference KKT system")
      ud = rhs(1:nu, 1)
      lam = rhs(nu+1:nu+m, 1)
    end subroutine kkt_solve

    !> Second (acc) and first (vel) time derivatives of Phi along the path with
    !> accelerations a, Richardson-extrapolated.
    subroutine derivatives(a, acc, vel)
      real(dp), intent(in) :: a(:)
      real(dp), intent(out) :: acc(:), vel(:)
      real(dp), parameter :: h = 2.0e-3_dp
      real(dp) :: p0(nrow), d1(nrow), d2(nrow), v1(nrow), v2(nrow)
      p0 = phis(0.0_dp, a)
      d1 = (phis(h, a) - 2*p0 + phis(-h, a))/h**2
      d2 = (phis(0.5_dp*h, a) - 2*p0 + phis(-0.5_dp*h, a))/(0.5_dp*h)**2
      v1 = (phis(h, a) - phis(-h, a))/(2*h)
      v2 = (phis(0.5_dp*h, a) - phis(-0.5_dp*h, a))/h
      acc = (4*d2 - d1)/3
      vel = (4*v2 - v1)/3
    end subroutine derivatives

    !> The constraint functions at time h on the path with accelerations a.
    function phis(h, a) result(p)
      real(dp), intent(in) :: h, a(:)
      real(dp) :: p(nrow), rr(3, 0:n), cc(3, 3, 0:n), wv(3), rel(3, 3), eps(3), rh1(3), at(3)
      integer :: j, o
      do j = 0, n
        rr(:, j) = r(:, j) + v(:, j)*h + 0.5_dp*a(6*j+1:6*j+3)*h*h
        cc(:, :, j) = matmul(c(:, :, j), rodrigues(w(:, j)*h + 0.5_dp*a(6*j+4:6*j+6)*h*h))
      end do
      p = 0.0_dp
      do j = 1, n - 1
        p(3*j-2:3*j) = rr(:, j) + matmul(cc(:, :, j), dist(:, j)) - rr(:, j+1) - matmul(cc(:, :, j+1), prox(:, j+1))
      end do
      o = ncut
      wv = matmul(transpose(cc(:, :, 0)), rr(:, 1) + matmul(cc(:, :, 1), contact) - rr(:, 0))
      rel = matmul(transpose(cc(:, :, 0)), cc(:, :, 1))
      at = vee(matmul(rel, transpose(rel_ref)))
      select case (phase)
      case (phase_preparation)
        p(o+1:o+3) = matmul(transpose(e), wv - w_ref)
        p(o+4:o+6) = matmul(transpose(e), at)
      case (phase_extraction)
        p(o+1) = dot_product(e(:, 2), wv - floor_pt)
        p(o+2) = dot_product(e(:, 3), wv - floor_pt)
        p(o+3:o+5) = matmul(transpose(e), at)
        p(nrow) = dot_product(e(:, 1), wv)
      case (phase_rotation)
        eps = matmul(transpose(cc(:, :, 1)), rr(:, 0) + matmul(cc(:, :, 0), floor_pt + 14.0_dp*rail) - rr(:, 1))
        rh1 = matmul(rel, h1)
        p(o+1) = eps(2) - contact(2)
        p(o+2) = eps(3) - contact(3)
        p(o+3) = dot_product(rh1, e(:, 1))
        p(o+4) = dot_product(rh1, e(:, 2))
        p(nrow) = eps(1)
      end select
    end function phis
  end subroutine run_case
end module cfa_reference_cases

program test_multibody_cfa_reference
  use cfa_reference_cases, only: run_case
  use airlaunch_kinds, only: dp
  use airlaunch_multibody, only: phase_preparation, phase_extraction, phase_rotation, phase_free
  use testing, only: fixed_seed, section, finish
  implicit none
  integer :: trial

  call fixed_seed()
  do trial = 1, 3
    call section("trial " // achar(48 + trial))
    call run_case("Case 0 locked, 3 bodies", phase_preparation, 3, 0.0_dp, 0.0_dp, .false., 0.0_dp)
    call run_case("Case 1 frictionless, 1 body", phase_extraction, 1, 0.0_dp, 0.0_dp, .false., 0.8_dp)
    call run_case("Case 1 frictionless, 3 bodies", phase_extraction, 3, 0.0_dp, 0.0_dp, .false., 0.8_dp)
    call run_case("Case 1 mu 0.2 sliding out, 3 bodies", phase_extraction, 3, 0.2_dp, 0.0_dp, .false., 0.8_dp)
    call run_case("Case 1 mu 0.2 sliding back, 2 bodies", phase_extraction, 2, 0.2_dp, 0.0_dp, .false., -0.5_dp)
    call run_case("Case 1 mu 0.9 at rest, 1 body", phase_extraction, 1, 0.9_dp, 0.0_dp, .false., 0.0_dp)
    call run_case("Case 1 mu 0.3 at rest, 3 bodies", phase_extraction, 3, 0.3_dp, 0.0_dp, .false., 0.0_dp)
    call run_case("Case 1 mu 0.9 inside the band, 1 body", phase_extraction, 1, 0.9_dp, 0.0_dp, .false., 5.0e-5_dp)
    call run_case("Case 2 frictionless, 3 bodies", phase_rotation, 3, 0.0_dp, 0.0_dp, .false., 0.8_dp)
    call run_case("Case 2 mu 0.1 sliding, 3 bodies", phase_rotation, 3, 0.0_dp, 0.1_dp, .false., 0.8_dp)
    call run_case("Case 2 mu 0.6 at rest, 2 bodies", phase_rotation, 2, 0.0_dp, 0.6_dp, .false., 0.0_dp)
    call run_case("Case 2 no-slip, 3 bodies", phase_rotation, 3, 0.0_dp, 0.0_dp, .true., 0.0_dp)
    call run_case("Case 3 free, 3 bodies", phase_free, 3, 0.0_dp, 0.0_dp, .false., 0.8_dp)
  end do
  call finish()

end program test_multibody_cfa_reference
