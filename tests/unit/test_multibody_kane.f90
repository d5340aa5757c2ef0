!> Validation 1 of issue 4: Kane's equations (65) of the 1-, 2- and 3-body chain
!> against an independent Newton-Euler formulation with explicit joint forces,
!> for random states, masses, full inertia tensors, geometry and loads.
!>
!> Reference: unknowns a_k (earth), alpha_k (body axes) and the joint forces f_j,
!>   m_k a_k = F_k + f_{k-1} - f_k
!>   J_k alpha_k + w_k x J_k w_k = M_k + p_k x C_k^T f_{k-1} - d_k x C_k^T f_k
!>   a_j + C_j(alpha_j x d_j + w_j x (w_j x d_j)) = a_{j+1} + C_{j+1}(alpha_{j+1} x p_{j+1} + ...)
!> one dense LU solve of size 9n - 3.  Tolerance 1e-10 relative (issue): both are
!> exact up to round-off of ~1e-14 times the condition number of the systems.
program test_multibody_kane
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type
  use airlaunch_linalg, only: solve_general
  use airlaunch_rotation, only: skew, quat_normalize, quat_to_dcm
  use airlaunch_multibody, only: kane_chain, rigid_body, cross, newton_euler
  use testing
  implicit none
  integer :: n, trial
  real(dp) :: worst

  call fixed_seed()
  do n = 1, 3
    call section("Kane vs Newton-Euler with joint forces, " // achar(48 + n) // "-body chain")
    worst = 0.0_dp
    do trial = 1, 20
      worst = max(worst, compare(n))
    end do
    call check(worst <= 1.0e-10_dp, "max relative difference of udot over 20 random states: " // &
      fmt(worst) // " (tol 1e-10)")
  end do
  call section("probe wrench on the rocket = the same wrench added to its loads (CFA linearity)")
  call probe_linearity()
  call section("the rocket's proximal point is ignored (body 1 has no previous body)")
  call first_proximal_ignored()
  call section("Newton-Euler (47)-(48) of one body: gyroscopic term")
  call gyroscopic()
  call finish()

contains

  character(len=12) function fmt(x)
    real(dp), intent(in) :: x
    write(fmt, '(es12.3)') x
  end function fmt

  function random_rotation() result(c)
    real(dp) :: c(3, 3), q(4)
    call random_number(q)
    q = quat_normalize(q - 0.5_dp)
    c = quat_to_dcm(q)
  end function random_rotation

  function random_inertia() result(j)
    real(dp) :: j(3, 3), d(3), r(3, 3)
    integer :: i
    call random_number(d)
    d = 1.0_dp + d
    r = random_rotation()
    j = 0.0_dp
    do i = 1, 3
      j(i, i) = d(i)
    end do
    j = matmul(r, matmul(j, transpose(r)))
    j = 0.5_dp*(j + transpose(j))
  end function random_inertia

  !> One random state: returns max_i |udot_kane - udot_ne| / max|udot|.
  real(dp) function compare(n) result(rel)
    integer, intent(in) :: n
    type(kane_chain) :: chain
    type(rigid_body) :: bodies(n)
    type(error_type), allocatable :: error
    real(dp) :: y(6 + 7*n), f(3, n), m(3, n), pf(3, 1), pm(3, 1), mass(n), jin(3, 3, n)
    real(dp) :: prox(3, n), dist(3, n), q(4)
    real(dp), allocatable :: a(:, :), b(:, :), ref(:)
    integer :: k, nn, ra, rj, cf, nu
    call chain%init(n, 1, error)
    do k = 1, n
      call random_number(mass(k))
      mass(k) = 0.5_dp + 3*mass(k)
      jin(:, :, k) = random_inertia()
      prox(:, k) = random_vector(2.0_dp)
      dist(:, k) = random_vector(2.0_dp)
      if (k == 1) prox(:, k) = 0.0_dp
      call chain%set_link(k, "body", mass(k), jin(:, :, k), prox(:, k), dist(:, k), error)
      f(:, k) = random_vector(10.0_dp)
      m(:, k) = random_vector(10.0_dp)
    end do
    y(1:3) = random_vector(5.0_dp)
    y(4:6) = random_vector(5.0_dp)
    do k = 1, n
      call random_number(q)
      y(6+7*(k-1)+1:6+7*(k-1)+4) = quat_normalize(q - 0.5_dp)
      y(6+7*(k-1)+5:6+7*k) = random_vector(3.0_dp)
    end do
    call chain%load_bodies(y, bodies)
    pf = 0.0_dp; pm = 0.0_dp
    call chain%accelerations(bodies, f, m, pf, pm, 0, error)
    if (allocated(error)) then
      call check(.false., error%message)
      rel = huge(1.0_dp)
      return
    end if
    ! independent Newton-Euler with explicit joint forces
    nn = 9*n - 3
    allocate(a(nn, nn), b(nn, 1), ref(nn))
    a = 0.0_dp; b = 0.0_dp
    do k = 1, n
      ra = 6*(k - 1)
      a(ra+1:ra+3, ra+1:ra+3) = mass(k)*eye()
      a(ra+4:ra+6, ra+4:ra+6) = jin(:, :, k)
      b(ra+1:ra+3, 1) = f(:, k)
      b(ra+4:ra+6, 1) = m(:, k) - cross(bodies(k)%w, matmul(jin(:, :, k), bodies(k)%w))
      if (k > 1) then          ! f_{k-1} acts on body k at p_k
        cf = 6*n + 3*(k - 2)
        a(ra+1:ra+3, cf+1:cf+3) = -eye()
        a(ra+4:ra+6, cf+1:cf+3) = -matmul(skew(prox(:, k)), transpose(bodies(k)%c))
      end if
      if (k < n) then          ! -f_k acts on body k at d_k
        cf = 6*n + 3*(k - 1)
        a(ra+1:ra+3, cf+1:cf+3) = eye()
        a(ra+4:ra+6, cf+1:cf+3) = matmul(skew(dist(:, k)), transpose(bodies(k)%c))
      end if
    end do
    do k = 1, n - 1
      rj = 6*n + 3*(k - 1)
      ra = 6*(k - 1)
      a(rj+1:rj+3, ra+1:ra+3) = eye()
      a(rj+1:rj+3, ra+4:ra+6) = -matmul(bodies(k)%c, skew(dist(:, k)))
      a(rj+1:rj+3, ra+7:ra+9) = -eye()
      a(rj+1:rj+3, ra+10:ra+12) = matmul(bodies(k+1)%c, skew(prox(:, k+1)))
      b(rj+1:rj+3, 1) = matmul(bodies(k+1)%c, cross(bodies(k+1)%w, cross(bodies(k+1)%w, prox(:, k+1)))) &
        - matmul(bodies(k)%c, cross(bodies(k)%w, cross(bodies(k)%w, dist(:, k))))
    end do
    call solve_general(a, b, error, "Newton-Euler reference")
    ref = b(:, 1)
    nu = 3 + 3*n
    rel = 0.0_dp
    ! udot = [a_1, alpha_1, alpha_2, ...]
    rel = max(rel, maxval(abs(chain%rhs(1:3, 1) - ref(1:3))))
    do k = 1, n
      rel = max(rel, maxval(abs(chain%rhs(3+3*(k-1)+1:3+3*k, 1) - ref(6*(k-1)+4:6*(k-1)+6))))
    end do
    rel = rel/maxval(abs(chain%rhs(1:nu, 1)))
  end function compare

  pure function eye() result(e)
    real(dp) :: e(3, 3)
    e = 0.0_dp
    e(1, 1) = 1.0_dp; e(2, 2) = 1.0_dp; e(3, 3) = 1.0_dp
  end function eye

  subroutine probe_linearity()
    type(kane_chain) :: chain
    type(rigid_body) :: bodies(3)
    type(error_type), allocatable :: error
    real(dp) :: y(27), f(3, 3), m(3, 3), pf(3, 2), pm(3, 2), u1(12), q(4)
    integer :: k
    call chain%init(3, 3, error)
    do k = 1, 3
      call chain%set_link(k, "body", 1.0_dp + k, random_inertia(), random_vector(1.0_dp), random_vector(1.0_dp), error)
      f(:, k) = random_vector(5.0_dp); m(:, k) = random_vector(5.0_dp)
      call random_number(q)
      y(6+7*(k-1)+1:6+7*(k-1)+4) = quat_normalize(q - 0.5_dp)
      y(6+7*(k-1)+5:6+7*k) = random_vector(2.0_dp)
    end do
    y(1:6) = [random_vector(1.0_dp), random_vector(1.0_dp)]
    call chain%load_bodies(y, bodies)
    pf(:, 1) = random_vector(3.0_dp); pm(:, 1) = random_vector(3.0_dp)
    pf(:, 2) = 0.0_dp; pm(:, 2) = 0.0_dp
    call chain%accelerations(bodies, f, m, pf, pm, 1, error)
    u1 = chain%rhs(:, 1) + chain%rhs(:, 2)
    f(:, 1) = f(:, 1) + pf(:, 1)
    m(:, 1) = m(:, 1) + pm(:, 1)
    call chain%accelerations(bodies, f, m, pf, pm, 0, error)
    call check(maxval(abs(u1 - chain%rhs(:, 1))) <= 1.0e-12_dp*maxval(abs(u1)), &
      "udot(loads) + udot(probe) = udot(loads + probe): diff " // fmt(maxval(abs(u1 - chain%rhs(:, 1)))))
  end subroutine probe_linearity

  !> Body 1 has no previous body: its `proximal` is documented as ignored.  A chain
  !> whose link 1 carries a nonzero proximal point must be the same chain as with
  !> zero there (reference: the same chain with proximal_1 = 0, and the spherical
  !> joints' own closure, which is exact by construction: 1e-12 m is round-off).
  subroutine first_proximal_ignored()
    type(kane_chain) :: chain, ref
    type(rigid_body) :: bodies(3), rbodies(3)
    type(error_type), allocatable :: error
    real(dp) :: y(27), f(3, 3), m(3, 3), pf(3, 1), pm(3, 1), q(4), jk(3, 3), pk(3), dk(3), dr, du
    integer :: k
    call chain%init(3, 1, error)
    call ref%init(3, 1, error)
    do k = 1, 3
      jk = random_inertia()
      pk = random_vector(1.0_dp)
      dk = random_vector(1.0_dp)
      call chain%set_link(k, "body", 1.0_dp + k, jk, pk, dk, error)
      if (k == 1) pk = 0.0_dp
      call ref%set_link(k, "body", 1.0_dp + k, jk, pk, dk, error)
      f(:, k) = random_vector(5.0_dp); m(:, k) = random_vector(5.0_dp)
      call random_number(q)
      y(6+7*(k-1)+1:6+7*(k-1)+4) = quat_normalize(q - 0.5_dp)
      y(6+7*(k-1)+5:6+7*k) = random_vector(2.0_dp)
    end do
    y(1:6) = [random_vector(1.0_dp), random_vector(1.0_dp)]
    pf = 0.0_dp; pm = 0.0_dp
    call chain%load_bodies(y, bodies)
    call ref%load_bodies(y, rbodies)
    call check(chain%joint_residual(bodies) <= 1.0e-12_dp, "spherical joints closed: residual " // &
      fmt(chain%joint_residual(bodies)) // " m (tol 1e-12)")
    dr = 0.0_dp
    do k = 1, 3
      dr = max(dr, maxval(abs(bodies(k)%r - rbodies(k)%r)), maxval(abs(bodies(k)%v - rbodies(k)%v)))
    end do
    call check(dr <= 1.0e-14_dp, "positions and velocities as with proximal_1 = 0: diff " // fmt(dr))
    call chain%accelerations(bodies, f, m, pf, pm, 0, error)
    call ref%accelerations(rbodies, f, m, pf, pm, 0, error)
    du = maxval(abs(chain%rhs(:, 1) - ref%rhs(:, 1)))
    call check(du <= 1.0e-14_dp*maxval(abs(ref%rhs(:, 1))), "udot as with proximal_1 = 0: diff " // fmt(du))
  end subroutine first_proximal_ignored

  !> Torque-free symmetric top: J wdot = -w x J w, closed form for diagonal J.
  subroutine gyroscopic()
    type(rigid_body) :: b
    type(error_type), allocatable :: error
    real(dp) :: a(3, 1), wd(3, 1), expect(3)
    b%name = "top"
    b%mass = 2.0_dp
    b%inertia = 0.0_dp
    b%inertia(1, 1) = 1.0_dp; b%inertia(2, 2) = 2.0_dp; b%inertia(3, 3) = 3.0_dp
    b%w = [0.3_dp, -0.7_dp, 1.1_dp]
    call newton_euler(b, reshape([4.0_dp, 0.0_dp, -2.0_dp], [3, 1]), reshape([0.5_dp, 0.0_dp, 0.0_dp], &
      [3, 1]), [1.0_dp], a, wd, error)
    ! Euler's equations: J1 w1' = M1 - (J3 - J2) w2 w3, etc.
    expect = [(0.5_dp - (3.0_dp - 2.0_dp)*b%w(2)*b%w(3))/1.0_dp, &
              (0.0_dp - (1.0_dp - 3.0_dp)*b%w(3)*b%w(1))/2.0_dp, &
              (0.0_dp - (2.0_dp - 1.0_dp)*b%w(1)*b%w(2))/3.0_dp]
    call check(maxval(abs(wd(:, 1) - expect)) < 1.0e-14_dp, "Euler's equations of a free top")
    call check(maxval(abs(a(:, 1) - [2.0_dp, 0.0_dp, -1.0_dp])) < 1.0e-15_dp, "a = F/m in earth axes")
  end subroutine gyroscopic
end program test_multibody_kane
