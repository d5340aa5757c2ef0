!> The CVODE wrapper on problems with closed-form solutions: a harmonic
!> oscillator (dense, band and fixed-point solvers), an event located at the
!> analytic crossing, and a failing right-hand side reported with its time.
module oscillator_system
  use airlaunch_kinds, only: dp
  use airlaunch_ode, only: ode_system, rhs_ok, rhs_fatal
  implicit none
  private
  public :: oscillator, jacobian_failing_oscillator

  !> x'' = -w^2 x as [x, v]; event at x = 0 (or, with t_root set, at the
  !> time t_root: g = t - t_root, exactly 0 there); fails after t_fail if set;
  !> counts its right-hand side calls.
  type, extends(ode_system) :: oscillator
    real(dp) :: omega = 2.0_dp
    real(dp) :: t_fail = huge(1.0_dp)
    real(dp) :: t_root = -huge(1.0_dp)
    integer :: n_rhs = 0
  contains
    procedure :: rhs
    procedure :: nroots
    procedure :: roots
  end type oscillator

  !> The oscillator declaring an analytic Jacobian it does not have: the
  !> inherited ode_jacobian returns rhs_fatal (an unrecoverable setup failure).
  type, extends(oscillator) :: jacobian_failing_oscillator
  contains
    procedure :: has_jacobian => failing_has_jacobian
  end type jacobian_failing_oscillator
contains
  logical function failing_has_jacobian(self)
    class(jacobian_failing_oscillator), intent(in) :: self
    failing_has_jacobian = self%omega > -huge(1.0_dp)
  end function failing_has_jacobian

  subroutine rhs(self, t, y, ydot, status)
    class(oscillator), intent(inout) :: self
    real(dp), intent(in) :: t, y(:)
    real(dp), intent(out) :: ydot(:)
    integer, intent(out) :: status
    self%n_rhs = self%n_rhs + 1
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
    if (self%t_root > -huge(1.0_dp)) g(1) = t - self%t_root
    status = rhs_ok
    if (t < 0 .and. self%omega < 0) status = rhs_ok
  end subroutine roots
end module oscillator_system

!> A 3-D chain of point masses joined by linear springs and dashpots, the
!> first fixed: x' = v, v' = a(x, v), states node by node [x, v] (the layout
!> of the lumped line), for the velocity-reduced linear solver.
module spring_chain_system
  use airlaunch_kinds, only: dp
  use airlaunch_ode, only: ode_system, rhs_ok
  implicit none
  private
  public :: spring_chain

  type, extends(ode_system) :: spring_chain
    integer :: nodes = 8
    real(dp) :: k = 4.0e4_dp, c = 20.0_dp, m = 1.0_dp, l0 = 1.0_dp
  contains
    procedure :: rhs => chain_rhs
  end type spring_chain
contains
  subroutine chain_rhs(self, t, y, ydot, status)
    class(spring_chain), intent(inout) :: self
    real(dp), intent(in) :: t, y(:)
    real(dp), intent(out) :: ydot(:)
    integer, intent(out) :: status
    real(dp) :: xa(3), va(3), xb(3), vb(3), d(3), l, f(3), e(3)
    integer :: j
    ydot = 0.0_dp
    do j = 1, self%nodes
      ydot(6*j-5:6*j-3) = y(6*j-2:6*j)
      ydot(6*j-1) = -9.81_dp
    end do
    do j = 1, self%nodes
      xb = y(6*j-5:6*j-3); vb = y(6*j-2:6*j)
      if (j == 1) then
        xa = 0.0_dp; va = 0.0_dp
      else
        xa = y(6*j-11:6*j-9); va = y(6*j-8:6*j-6)
      end if
      d = xb - xa
      l = norm2(d)
      e = d/l
      f = (self%k*(l - self%l0) + self%c*dot_product(e, vb - va))*e   ! pull on a towards b
      ydot(6*j-2:6*j) = ydot(6*j-2:6*j) - f/self%m
      if (j > 1) ydot(6*j-8:6*j-6) = ydot(6*j-8:6*j-6) + f/self%m
    end do
    status = rhs_ok
    if (.false.) ydot(1) = t
  end subroutine chain_rhs
end module spring_chain_system

!> A step observer that keeps the end of every stretch it is shown (the
!> internal steps' ends, for a test that needs an event exactly at one).
module step_end_recorder
  use airlaunch_kinds, only: dp
  use airlaunch_cvode, only: step_observer, step_polynomial
  implicit none
  private
  public :: step_ends

  type, extends(step_observer) :: step_ends
    integer :: n = 0
    real(dp) :: t(4000) = 0.0_dp   ! (147 steps are used; 32 kB stays on the stack)
  contains
    procedure :: observe
  end type step_ends
contains
  subroutine observe(self, poly, t_start, t_end, restart, last)
    class(step_ends), intent(inout) :: self
    type(step_polynomial), intent(in) :: poly
    real(dp), intent(in) :: t_start, t_end
    logical, intent(in) :: restart, last
    if (self%n >= size(self%t) .or. .not. (t_end > t_start .or. restart .or. last) .or. poly%order < 0) return
    self%n = self%n + 1
    self%t(self%n) = t_end
  end subroutine observe
end module step_end_recorder

program test_cvode
  use airlaunch_kinds, only: dp, pi
  use airlaunch_error, only: error_type
  use airlaunch_strings, only: str
  use airlaunch_cvode
  use oscillator_system
  use spring_chain_system
  use step_end_recorder
  use, intrinsic :: iso_c_binding
  use fsundials_context_mod
  use fsundials_matrix_mod
  use fsundials_linearsolver_mod
  use fsundials_nvector_mod
  use fnvector_serial_mod
  use fsunmatrix_band_mod
  use airlaunch_lapack_band, only: new_lapack_band_solver, new_second_order_band_solver, band_data, &
    use_node_blocks, new_position_reduced_solver, partners_ok
  use airlaunch_ode, only: node_blocks
  use airlaunch_linalg, only: solve_general
  use testing
  implicit none
  type(oscillator), target :: osc
  type(cvode_solver) :: solver
  type(cvode_options) :: opts, saved_opts
  type(cvode_stats) :: st
  type(error_type), allocatable :: error
  character(len=16), parameter :: solvers(4) = [character(len=16) :: "dense", "band", "sundials_band", "none"]
  character(len=8), parameter :: methods(4) = [character(len=8) :: "bdf", "bdf", "bdf", "adams"]
  logical :: event
  integer :: which(1), k

  call fixed_seed()   ! the same random states in every run
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

  call section("the steps and the events do not depend on the output times")
  ! The oscillator to 5 s with its event x = 0 (at pi/4 + k pi/2: three), the
  ! events passed through without a restart, outputs every 0.5 s and every
  ! 1/128 s (binary fractions: the common output times are the same numbers; several per step: rtol 1e-6 takes steps of ~0.05 s, so events fall
  ! after an output inside the step that located them).  The same CVODE steps
  ! must be taken: equal step counts, event times and states bit for bit (with
  ! CVODE's CV_NORMAL mode they were not: its event search stops at each output
  ! time, its first step is sized by the first output time).
  block
    real(dp) :: t_ev(2, 8), y_half(2, 2, 11), y_end(2, 2)
    integer :: n_ev(2), c, n_half(2)
    integer(c_long) :: steps(2)
    logical :: ordered(2)
    real(dp), parameter :: dts(2) = [0.5_dp, 0.0078125_dp]
    real(dp) :: tout, t_prev
    integer :: k_out
    opts = cvode_options(rtol=1e-6_dp, atol=1e-8_dp, t_final=5.0_dp)
    do c = 1, 2
      call solver%init(osc, 0.0_dp, [1.0_dp, 0.0_dp], opts, error)
      n_ev(c) = 0
      n_half(c) = 0
      ordered(c) = .true.
      t_prev = 0.0_dp
      tout = 0.0_dp
      k_out = 0
      do while (tout < 5.0_dp - 1e-9_dp .and. .not. allocated(error))
        k_out = k_out + 1
        tout = min(5.0_dp, k_out*dts(c))
        do
          call solver%advance(tout, error, event, which)
          if (allocated(error)) exit
          ordered(c) = ordered(c) .and. solver%t >= t_prev
          t_prev = solver%t
          if (.not. event) exit
          n_ev(c) = n_ev(c) + 1
          if (n_ev(c) <= size(t_ev, 2)) t_ev(c, n_ev(c)) = solver%t
        end do
        if (abs(tout/0.5_dp - nint(tout/0.5_dp)) < 1e-9_dp .and. n_half(c) < size(y_half, 3)) then
          n_half(c) = n_half(c) + 1
          y_half(:, c, n_half(c)) = solver%y
        end if
      end do
      call check(.not. allocated(error), "outputs every " // str(dts(c)) // " s: no error")
      if (allocated(error)) deallocate(error)
      y_end(:, c) = solver%y
      steps(c) = solver%steps_taken()
      call solver%free()
    end do
    call check(n_ev(1) == 3 .and. n_ev(2) == 3, "three events either way (" // str(n_ev(1)) // ", " // &
      str(n_ev(2)) // ")")
    call check(ordered(1) .and. ordered(2), "events and outputs come in time order")
    ! rtol 1e-6 over ~100 steps: 1e-5 bounds the event times' error
    call check_close(t_ev(2, 1), pi/4, "first event at pi/4", abs=1e-5_dp)
    call check_close(t_ev(2, 3), 5*pi/4, "third event at 5 pi/4", abs=1e-5_dp)
    call check(steps(1) == steps(2), "the same number of steps (" // str(int(steps(1))) // ", " // &
      str(int(steps(2))) // ")")
    call check(all(t_ev(1, 1:3) == t_ev(2, 1:3)), "the same event times, bit for bit")
    call check(n_half(1) == 10 .and. n_half(2) == 10, "ten common output times")
    call check(all(y_half(:, 1, 1:10) == y_half(:, 2, 1:10)) .and. all(y_end(:, 1) == y_end(:, 2)), &
      "the same states at the common output times, bit for bit")
  end block

  call section("velocity-reduced band solver: the same linear solve as the full band LU")
  block
    ! M = I - gamma J with the [x, v]-per-node structure (position rows exactly
    ! [I, -gamma I]), velocity rows random 3x3 blocks to the neighbours; the
    ! reduced solve must give the full band LU's solution to round-off
    integer, parameter :: nn = 7, n = 6*nn
    type(c_ptr) :: ctx
    type(SUNMatrix), pointer :: m_full, m_red
    type(SUNLinearSolver), pointer :: ls_full, ls_red
    type(N_Vector), pointer :: nb, nx1, nx2
    real(c_double), pointer :: bd(:), x1(:), x2(:)
    real(dp) :: g, r, dense(n, n)
    integer :: j, k, p, q, ierr
    g = 0.013_dp
    dense = 0.0_dp
    do j = 1, nn
      do p = 1, 3
        dense(6*j-6+p, 6*j-6+p) = 1.0_dp
        dense(6*j-6+p, 6*j-3+p) = -g
        do k = max(1, j - 1), min(nn, j + 1)
          do q = 1, 6
            call random_number(r)
            dense(6*j-3+p, 6*k-6+q) = 2*r - 1
          end do
        end do
        dense(6*j-3+p, 6*j-3+p) = dense(6*j-3+p, 6*j-3+p) + 8.0_dp
      end do
    end do
    ierr = FSUNContext_Create(c_null_ptr, ctx)
    m_full => FSUNBandMatrix(int(n, c_long), 8_c_long, 11_c_long, ctx)
    m_red => FSUNBandMatrix(int(n, c_long), 8_c_long, 11_c_long, ctx)
    call fill_band(m_full, dense, 8, 11)
    call fill_band(m_red, dense, 8, 11)
    nb => FN_VNew_Serial(int(n, c_long), ctx)
    nx1 => FN_VNew_Serial(int(n, c_long), ctx)
    nx2 => FN_VNew_Serial(int(n, c_long), ctx)
    bd => FN_VGetArrayPointer(nb)
    x1 => FN_VGetArrayPointer(nx1)
    x2 => FN_VGetArrayPointer(nx2)
    call random_number(bd)
    ls_full => new_lapack_band_solver(m_full, ctx)
    ls_red => new_second_order_band_solver(m_red, ctx)
    ierr = FSUNLinSolSetup(ls_full, m_full)
    ierr = ierr + FSUNLinSolSolve(ls_full, m_full, nx1, nb, 0.0_c_double)
    ierr = ierr + FSUNLinSolSetup(ls_red, m_red)
    ierr = ierr + FSUNLinSolSolve(ls_red, m_red, nx2, nb, 0.0_c_double)
    call check(ierr == 0, "setup and solve succeed")
    call check_close(maxval(abs(x1 - x2)), 0.0_dp, "same solution (largest difference)", &
      abs=1e-12_dp*maxval(abs(x1)))
    call check_close(maxval(abs(matmul(dense, x2) - bd)), 0.0_dp, "residual of the reduced solve", &
      abs=1e-12_dp*maxval(abs(bd)))
    ! the same solver fed the Jacobian's node blocks and gamma instead of M
    ! (CVODE's linear-system hook): ax = -M_vx/gamma, av = (I - M_vv)/gamma
    blocks_path: block
      type(node_blocks), pointer :: blk
      real(dp) :: x3(n)
      integer :: d
      allocate(blk)
      allocate(blk%ax(3, 3, -1:1, nn), blk%av(3, 3, -1:1, nn), source=0.0_dp)
      blk%gamma = g
      do j = 1, nn
        do d = -1, 1
          k = j + d
          if (k < 1 .or. k > nn) cycle
          do q = 1, 3
            do p = 1, 3
              blk%ax(p, q, d, j) = -dense(6*j-3+p, 6*k-6+q)/g
              blk%av(p, q, d, j) = (merge(1.0_dp, 0.0_dp, j == k .and. p == q) - dense(6*j-3+p, 6*k-3+q))/g
            end do
          end do
        end do
      end do
      call solve_from_blocks(blk, n, ctx, nb, x3, ierr)
      call check(ierr == 0, "node blocks: setup and solve succeed")
      call check_close(maxval(abs(x1 - x3)), 0.0_dp, "node blocks: the full band LU's solution", &
        abs=1e-12_dp*maxval(abs(x1)))
      deallocate(blk)
    end block blocks_path
    ! a non-diagonal (tridiagonal, symmetric positive definite) mass matrix M:
    ! the accelerations' Jacobian is M^-1 [A, B], a full matrix, and the solver
    ! gets D^-1 A, D^-1 B and D^-1 M's off-diagonal (D = diag M); its solution
    ! must satisfy the full Newton system (I - gamma J) x = b with J formed
    ! densely (M^-1 by LAPACK's dgesv), to round-off
    mass_path: block
      type(node_blocks), pointer :: blk
      real(dp) :: x3(n)
      real(dp) :: mm(nn, nn), minv(nn, nn), a_blk(3*nn, 3*nn), b_blk(3*nn, 3*nn), newton(n, n), off
      integer :: d, i
      mm = 0.0_dp
      do j = 1, nn
        call random_number(r)
        mm(j, j) = 1.0_dp + r
      end do
      do j = 1, nn - 1
        call random_number(r)
        off = (0.05_dp + 0.1_dp*r)*min(mm(j, j), mm(j + 1, j + 1))
        mm(j, j + 1) = off
        mm(j + 1, j) = off
      end do
      allocate(blk)
      allocate(blk%ax(3, 3, -1:1, nn), blk%av(3, 3, -1:1, nn), blk%mass(-1:1, nn), source=0.0_dp)
      blk%gamma = g
      blk%mass_coupled = .true.
      a_blk = 0.0_dp
      b_blk = 0.0_dp
      do j = 1, nn
        do d = -1, 1
          k = j + d
          if (k < 1 .or. k > nn) cycle
          blk%mass(d, j) = mm(j, k)/mm(j, j)
          do q = 1, 3
            do p = 1, 3
              call random_number(r)
              a_blk(3*j-3+p, 3*k-3+q) = 50*(2*r - 1)
              call random_number(r)
              b_blk(3*j-3+p, 3*k-3+q) = 5*(2*r - 1)
              blk%ax(p, q, d, j) = a_blk(3*j-3+p, 3*k-3+q)/mm(j, j)
              blk%av(p, q, d, j) = b_blk(3*j-3+p, 3*k-3+q)/mm(j, j)
            end do
          end do
        end do
      end do
      ! J's velocity rows: (M (x) I3)^-1 [A, B], node by node and per component
      minv = 0.0_dp
      do j = 1, nn
        minv(j, j) = 1.0_dp
      end do
      block
        real(dp) :: mcopy(nn, nn)
        mcopy = mm
        call solve_general(mcopy, minv, error, "mass matrix")
      end block
      call check(.not. allocated(error), "mass matrix inverted")
      newton = 0.0_dp
      do j = 1, nn
        do p = 1, 3
          newton(6*j-6+p, 6*j-6+p) = 1.0_dp
          newton(6*j-6+p, 6*j-3+p) = -g
          newton(6*j-3+p, 6*j-3+p) = 1.0_dp
          do k = 1, nn
            do q = 1, 3
              do i = 1, nn
                newton(6*j-3+p, 6*k-6+q) = newton(6*j-3+p, 6*k-6+q) - g*minv(j, i)*a_blk(3*i-3+p, 3*k-3+q)
                newton(6*j-3+p, 6*k-3+q) = newton(6*j-3+p, 6*k-3+q) - g*minv(j, i)*b_blk(3*i-3+p, 3*k-3+q)
              end do
            end do
          end do
        end do
      end do
      call solve_from_blocks(blk, n, ctx, nb, x3, ierr)
      call check(ierr == 0, "mass-coupled node blocks: setup and solve succeed")
      call check_close(maxval(abs(matmul(newton, x3) - bd)), 0.0_dp, "mass-coupled node blocks: residual of " // &
        "the full Newton system with J = M^-1 [A, B]", abs=1e-11_dp*maxval(abs(bd)))
      deallocate(blk)
    end block mass_path
    ierr = FSUNLinSolFree(ls_full)
    ierr = FSUNLinSolFree(ls_red)
    call FSUNMatDestroy(m_full)
    call FSUNMatDestroy(m_red)
    call FN_VDestroy(nb)
    call FN_VDestroy(nx1)
    call FN_VDestroy(nx2)
    ierr = FSUNContext_Free(ctx)
  end block

  call section("position-reduced band solver: the same linear solve as the full band LU")
  block
    ! The air-launch scene's layout: two bodies [r(3), v(3), q(4), w(3)] and
    ! nn nodes [x(3), v(3)]; positions r and x with rows exactly [1, -g_x] (g_x
    ! per row, as CVODE's difference quotients of x' = v give it), every other
    ! row random within the band (ml = mu = 18).  Two matrices: one diagonally
    ! dominant, one whose velocity rows carry the line's stiff spring entries
    ! (100 times the diagonal, to neighbouring positions: the full system's LU
    ! must swap rows).  The reduced solve must give the full band LU's solution
    ! (1e-11 relative: both solves are backward stable, so they agree to about
    ! 2 cond eps; LAPACK's 1-norm estimates of cond are 69 and 9.5e3 for the two
    ! matrices, 2 cond eps <= 2e-12; measured 8e-16 and 3.5e-14) and a residual
    ! at round-off.  A declared position
    ! whose row holds anything else is refused at setup; partners_ok rejects a
    ! velocity that is itself a position or outside the band, and a system
    ! without positions.
    integer, parameter :: nn = 5, n = 26 + 6*nn, bw = 18
    type(c_ptr) :: ctx
    type(SUNMatrix), pointer :: m_full, m_red
    type(SUNLinearSolver), pointer :: ls_full, ls_red
    type(N_Vector), pointer :: nb, nx1, nx2
    real(c_double), pointer :: bd(:), x1(:), x2(:)
    real(dp) :: r, dense(n, n)
    integer :: partner(n), i, j, k, p, ierr, case
    integer(c_long) :: flag
    partner = 0
    do p = 1, 3
      partner(p) = 3 + p
      partner(13 + p) = 16 + p
      do k = 1, nn
        partner(26 + 6*(k - 1) + p) = 26 + 6*(k - 1) + 3 + p
      end do
    end do
    call check(partners_ok(partner, bw, bw), "the scene's positions are accepted")
    call check(.not. partners_ok(partner, 2, bw), "a velocity outside the band: refused")
    call check(.not. partners_ok([0, 0, 0], 2, 2), "no position: refused")
    call check(.not. partners_ok([2, 3, 0], 2, 2), "a velocity that is a position: refused")
    ierr = FSUNContext_Create(c_null_ptr, ctx)
    do case = 1, 2
      dense = 0.0_dp
      do i = 1, n
        if (partner(i) /= 0) then
          dense(i, i) = 1.0_dp
          dense(i, partner(i)) = -0.013_dp*(1.0_dp + 1.0e-9_dp*i)
          cycle
        end if
        do j = max(1, i - bw), min(n, i + bw)
          call random_number(r)
          dense(i, j) = 2*r - 1
          if (case == 2 .and. i > 26 .and. partner(j) /= 0 .and. abs(i - j) <= 9) dense(i, j) = 100*dense(i, j)
        end do
        dense(i, i) = dense(i, i) + 2.0_dp*bw
      end do
      m_full => FSUNBandMatrix(int(n, c_long), int(bw, c_long), int(bw, c_long), ctx)
      m_red => FSUNBandMatrixStorage(int(n, c_long), int(bw, c_long), int(bw, c_long), int(bw, c_long), ctx)
      call fill_band(m_full, dense, bw, bw)
      call fill_band(m_red, dense, bw, bw)
      nb => FN_VNew_Serial(int(n, c_long), ctx)
      nx1 => FN_VNew_Serial(int(n, c_long), ctx)
      nx2 => FN_VNew_Serial(int(n, c_long), ctx)
      bd => FN_VGetArrayPointer(nb)
      x1 => FN_VGetArrayPointer(nx1)
      x2 => FN_VGetArrayPointer(nx2)
      call random_number(bd)
      ls_full => new_lapack_band_solver(m_full, ctx)
      ls_red => new_position_reduced_solver(m_red, ctx, partner)
      ierr = FSUNLinSolSetup(ls_full, m_full)
      ierr = ierr + FSUNLinSolSolve(ls_full, m_full, nx1, nb, 0.0_c_double)
      ierr = ierr + FSUNLinSolSetup(ls_red, m_red)
      ierr = ierr + FSUNLinSolSolve(ls_red, m_red, nx2, nb, 0.0_c_double)
      call check(ierr == 0, merge("dominant: ", "stiff:    ", case == 1) // "setup and solve succeed")
      call check_close(maxval(abs(x1 - x2)), 0.0_dp, merge("dominant: ", "stiff:    ", case == 1) // &
        "the full band LU's solution", abs=1e-11_dp*maxval(abs(x1)))
      call check_close(maxval(abs(matmul(dense, x2) - bd)), 0.0_dp, merge("dominant: ", "stiff:    ", case == 1) // &
        "residual", abs=1e-11_dp*maxval(abs(bd))*maxval(abs(x2)))
      if (case == 2) then
        ! the first body's position row with a stray entry: not a position row
        call set_band(m_red, 2, 9, 1.0e-3_dp)
        ierr = FSUNLinSolSetup(ls_red, m_red)
        flag = FSUNLinSolLastFlag(ls_red)
        call check(ierr /= 0 .and. flag == -1, "a declared position that is not one: refused")
      end if
      ierr = FSUNLinSolFree(ls_full)
      ierr = FSUNLinSolFree(ls_red)
      call FSUNMatDestroy(m_full)
      call FSUNMatDestroy(m_red)
      call FN_VDestroy(nb)
      call FN_VDestroy(nx1)
      call FN_VDestroy(nx2)
    end do
    ierr = FSUNContext_Free(ctx)
  end block

  call section("band LU solve with and without row interchanges")
  block
    ! The solve takes two banded triangular solves when the factorisation swapped
    ! no rows, dgbtrs otherwise: a diagonally dominant matrix (no swap possible
    ! under partial pivoting) and one with a tiny diagonal (swaps forced) must both
    ! give a residual at round-off, checked against the dense product (tolerance
    ! 1e-11 relative to |b| |x|: ~5e4 eps, room for partial pivoting's growth on
    ! 40 unknowns; a wrong factor or a skipped swap gives O(1)).
    integer, parameter :: n = 40, ml = 3, mu = 2
    type(c_ptr) :: ctx
    type(SUNMatrix), pointer :: m
    type(SUNLinearSolver), pointer :: ls
    type(N_Vector), pointer :: nb, nx
    real(c_double), pointer :: bd(:), xd(:)
    real(dp) :: dense(n, n), r
    integer :: i, j, case, ierr
    character(len=*), parameter :: names(2) = [character(len=24) :: "diagonally dominant", "tiny diagonal (swaps)"]
    ierr = FSUNContext_Create(c_null_ptr, ctx)
    do case = 1, 2
      dense = 0.0_dp
      do j = 1, n
        do i = max(1, j - mu), min(n, j + ml)
          call random_number(r)
          dense(i, j) = 2*r - 1
        end do
        dense(j, j) = merge(real(ml + mu + 2, dp), 1.0e-3_dp, case == 1)
      end do
      m => FSUNBandMatrix(int(n, c_long), int(mu, c_long), int(ml, c_long), ctx)
      call fill_band(m, dense, mu, ml)
      nb => FN_VNew_Serial(int(n, c_long), ctx)
      nx => FN_VNew_Serial(int(n, c_long), ctx)
      bd => FN_VGetArrayPointer(nb)
      xd => FN_VGetArrayPointer(nx)
      call random_number(bd)
      ls => new_lapack_band_solver(m, ctx)
      ierr = FSUNLinSolSetup(ls, m)
      ierr = ierr + FSUNLinSolSolve(ls, m, nx, nb, 0.0_c_double)
      call check(ierr == 0, trim(names(case)) // ": setup and solve succeed")
      call check_close(maxval(abs(matmul(dense, xd) - bd)), 0.0_dp, trim(names(case)) // ": residual", &
        abs=1e-11_dp*maxval(abs(bd))*maxval(abs(xd)))
      ierr = FSUNLinSolFree(ls)
      call FSUNMatDestroy(m)
      call FN_VDestroy(nb)
      call FN_VDestroy(nx)
    end do
    ierr = FSUNContext_Free(ctx)
  end block

  call section("velocity-reduced band solver in CVODE (spring chain, 8 nodes)")
  saved_opts = opts
  block
    ! the Newton matrices differ only by the difference-quotient noise of
    ! J_xv = I (~1e-8), so the runs may take different steps: both must lie
    ! within their integration error of a tight reference
    type(spring_chain), target :: chain
    real(dp) :: y0(48), y_ref(48), y_band(48), y_red(48)
    integer :: j
    do j = 1, 8
      y0(6*j-5:6*j) = [1.02_dp*j*cos(0.3_dp), 1.02_dp*j*sin(0.3_dp), 0.05_dp*j, 0.0_dp, 0.0_dp, 0.1_dp]
    end do
    opts = cvode_options(linear_solver="band", upper_bandwidth=8, lower_bandwidth=11, rtol=1e-12_dp, &
      atol=1e-13_dp)
    call solver%init(chain, 0.0_dp, y0, opts, error)
    call solver%advance(2.0_dp, error)
    y_ref = solver%y
    call solver%free()
    opts = cvode_options(linear_solver="band", upper_bandwidth=8, lower_bandwidth=11, rtol=1e-7_dp, &
      atol=1e-9_dp, max_order=2)
    call solver%init(chain, 0.0_dp, y0, opts, error)
    call solver%advance(2.0_dp, error)
    y_band = solver%y
    call solver%free()
    opts%linear_solver = "second_order_band"
    call solver%init(chain, 0.0_dp, y0, opts, error)
    call solver%advance(2.0_dp, error)
    y_red = solver%y
    call solver%free()
    call check(.not. allocated(error), "the three runs complete")
    call check(maxval(abs(y_red - y_ref)) < 3*maxval(abs(y_band - y_ref)) + 1e-12_dp, &
      "error of the reduced solver's run within 3x that of the band solver's")
    print '(a, 2es10.2)', "  errors band / reduced: ", maxval(abs(y_band - y_ref)), maxval(abs(y_red - y_ref))
    opts%upper_bandwidth = 4
    call solver%init(chain, 0.0_dp, y0, opts, error)
    call check(allocated(error), "a band too narrow for the node structure is rejected")
    if (allocated(error)) deallocate(error)
    call solver%free()
  end block
  opts = saved_opts

  call section("step budget with no per-output limit (max_num_steps 0 and -1)")
  ! CVODE reads a step limit of 0 as its default 500 and a negative one as no
  ! limit; the wrapper must hand it what is left of the budget instead.  CVODE
  ! tests the limit before each step, so a budget of 20 allows exactly 20 steps
  ! (the oscillator over 1000 s at rtol 1e-10 needs thousands).
  block
    integer :: m
    integer(c_long) :: taken
    integer, parameter :: per_output(2) = [0, -1]
    do m = 1, 2
      opts = cvode_options(rtol=1e-10_dp, atol=1e-12_dp, max_num_steps=per_output(m), max_total_steps=20)
      call solver%init(osc, 0.0_dp, [1.0_dp, 0.0_dp], opts, error)
      call check(.not. allocated(error), "init with max_num_steps " // str(per_output(m)))
      call solver%set_roots(0, error)
      call solver%advance(1000.0_dp, error)
      call check(allocated(error), "max_num_steps " // str(per_output(m)) // ": the budget stops the run")
      if (allocated(error)) then
        call check(index(error%message, "budget is spent") > 0, "message: " // error%message)
        deallocate(error)
      end if
      st = solver%stats()
      taken = solver%steps_taken()
      call check(st%steps == 20 .and. taken == 20, "max_num_steps " // &
        str(per_output(m)) // ": exactly 20 steps (stats " // str(int(st%steps)) // ", steps_taken " // &
        str(int(taken)) // ")")
      call solver%free()
    end do
  end block

  call section("the step budget holds after an event exactly at a step's end")
  ! An event at the end of a step leaves nothing of that step to search: the
  ! next call must take a new step, and the budget counts it (the wrapper
  ! skipped its check after every event, and took one step too many).  The
  ! event g = t - t_k is placed exactly on the k-th step's end of a first run
  ! (the root function does not change CVODE's steps before it).
  block
    type(step_ends) :: ends
    integer, parameter :: k = 12
    integer(c_long) :: taken
    logical :: ev
    opts = cvode_options(rtol=1e-10_dp, atol=1e-12_dp)
    call solver%init(osc, 0.0_dp, [1.0_dp, 0.0_dp], opts, error)
    call solver%set_roots(0, error)
    call solver%advance(1.0_dp, error, observer=ends)   ! (the same tout: it sizes the first step)
    call check(.not. allocated(error) .and. ends%n > k, "first run: " // str(ends%n) // " steps to t = 1")
    call solver%free()
    osc%t_root = ends%t(k)
    opts%max_total_steps = k
    call solver%init(osc, 0.0_dp, [1.0_dp, 0.0_dp], opts, error)
    call solver%advance(1.0_dp, error, ev, which)
    taken = solver%steps_taken()
    call check(.not. allocated(error) .and. ev .and. solver%t == ends%t(k) .and. taken == k, &
      "the event at the 12th step's end t = " // str(ends%t(k)) // " (t = " // str(solver%t) // ", " // &
      str(int(taken)) // " steps)")
    call solver%advance(1.0_dp, error, ev, which)
    taken = solver%steps_taken()
    call check(allocated(error) .and. taken == k, "then the budget of " // str(k) // &
      " steps is spent with no step more (" // str(int(taken)) // " steps)")
    if (allocated(error)) then
      call check(index(error%message, "budget is spent") > 0, "message: " // error%message)
      deallocate(error)
    end if
    call solver%free()
    osc%t_root = -huge(1.0_dp)
  end block
  opts = saved_opts

  call section("a stop time behind the solver is an error; no stale CVODE text later")
  ! CVODE rejects (CV_ILL_INPUT) a stop time it has passed; the wrapper must say
  ! so.  Its message must not be attached to the next, unrelated failure (the
  ! budget's early exit, which involves no CVODE call).
  opts = cvode_options(rtol=1e-8_dp, atol=1e-10_dp)
  call solver%init(osc, 0.0_dp, [1.0_dp, 0.0_dp], opts, error)
  call solver%set_roots(0, error)
  call solver%advance(1.0_dp, error)
  call check(.not. allocated(error), "advance to t = 1")
  call solver%set_stop_time(0.5_dp, error)
  call check(allocated(error), "set_stop_time(0.5) at t = 1 is refused")
  if (allocated(error)) then
    call check(index(error%message, "stop time") > 0 .and. index(error%message, "tstop") > 0, &
      "message (with CVODE's reason): " // error%message)
    deallocate(error)
  end if
  call solver%set_stop_time(2.0_dp, error)
  call check(.not. allocated(error), "set_stop_time(2) at t = 1 is accepted")
  call solver%set_max_step(-1.0_dp, error)
  call check(allocated(error), "set_max_step(-1) is refused")
  if (allocated(error)) deallocate(error)
  ! a restart exactly at the stop time (an event there, like the release at t0
  ! of the launch scene): CVODE would refuse its first step (tstop - t = 0)
  call solver%reinit(2.0_dp, solver%y, error)
  call check(.not. allocated(error), "reinit at the stop time")
  call solver%advance(2.5_dp, error)
  call check(.not. allocated(error) .and. solver%t == 2.5_dp, "and on past it")
  if (allocated(error)) deallocate(error)
  ! a stop time is landed on exactly; an output before it is interpolated (a
  ! step that landed on the stop time returned the stop time's state for an
  ! earlier output: the rigidized coupling recorded wrong states, helper-34)
  call solver%set_stop_time(2.75_dp, error)
  call solver%advance(2.7_dp, error)
  call check(.not. allocated(error) .and. solver%t == 2.7_dp, "an output before the stop time: t = 2.7 (" // &
    str(solver%t) // ")")
  call check_close(solver%y(1), cos(2*1.7_dp), "x(2.7) = cos(3.4) (restarted at 2 from x(1))", abs=1e-6_dp)
  call solver%advance(3.0_dp, error)
  call check(.not. allocated(error) .and. solver%t == 2.75_dp, "the solver stops at the stop time exactly")
  call check_close(solver%y(1), cos(2*1.75_dp), "x(2.75) = cos(3.5)", abs=1e-6_dp)
  if (allocated(error)) deallocate(error)
  call solver%free()
  ! one step over both: the first step (0.3 s of a slow oscillator, omega 0.1)
  ! lands on the stop time 0.3 past the output time 0.1, which is read off it
  block
    integer(c_long) :: taken
    osc%omega = 0.1_dp
    opts = cvode_options(rtol=1e-2_dp, atol=1e-6_dp, initial_step=0.3_dp)
    call solver%init(osc, 0.0_dp, [1.0_dp, 0.0_dp], opts, error)
    call solver%set_roots(0, error)
    call solver%set_stop_time(0.3_dp, error)
    call solver%advance(0.1_dp, error)
    taken = solver%steps_taken()
    call check(.not. allocated(error) .and. solver%t == 0.1_dp .and. taken == 1, &
      "one step to the stop time 0.3, the output time 0.1 before it returned (t = " // str(solver%t) // &
      ", " // str(int(taken)) // " step)")
    ! v(0.1) = -0.1 sin(0.01) = -1.0e-3 against v(0.3) = -3.0e-3; the first (order 1)
    ! step's interpolant is linear in t, exact to O(h^2 omega^3) = 1e-5 here
    call check_close(solver%y(2), -0.1_dp*sin(0.01_dp), "v(0.1) = -0.1 sin(0.01), not v(0.3)", abs=2e-4_dp)
    osc%omega = 2.0_dp
    call solver%free()
  end block
  ! an event inside the step that lands on the stop time, the output at the
  ! stop time: the event, then the stop time, then on past it (the stop time was
  ! returned a second time, short of the next output, helper-36)
  block
    logical :: ev1, ev2, ev3
    opts = cvode_options(rtol=1e-3_dp, atol=1e-6_dp)
    call solver%init(osc, 0.0_dp, [1.0_dp, 0.0_dp], opts, error)
    call solver%set_stop_time(0.79_dp, error)
    call solver%advance(0.79_dp, error, ev1, which)
    call check(ev1 .and. abs(solver%t - pi/4) < 1e-3_dp, "the event at pi/4 first (" // str(solver%t) // ")")
    call solver%advance(0.79_dp, error, ev2, which)
    call check(.not. ev2 .and. solver%t == 0.79_dp, "then the stop time 0.79 (" // str(solver%t) // ")")
    call solver%advance(1.2_dp, error, ev3, which)
    call check(.not. ev3 .and. solver%t == 1.2_dp .and. .not. allocated(error), "then on to 1.2 (" // &
      str(solver%t) // ")")
    if (allocated(error)) deallocate(error)
    call solver%free()
  end block
  if (allocated(error)) deallocate(error)
  call solver%free()
  opts = cvode_options(rtol=1e-10_dp, atol=1e-12_dp, max_total_steps=20)
  call solver%init(osc, 0.0_dp, [1.0_dp, 0.0_dp], opts, error)
  call solver%set_roots(0, error)
  call solver%advance(1000.0_dp, error)
  call check(allocated(error), "the budget of 20 steps is spent")
  if (allocated(error)) deallocate(error)
  call solver%set_stop_time(0.0_dp, error)
  call check(allocated(error), "a stop time behind t is refused (CVODE keeps a message)")
  if (allocated(error)) deallocate(error)
  call solver%advance(1000.0_dp, error)
  call check(allocated(error), "advance with the budget spent fails")
  if (allocated(error)) then
    call check(index(error%message, "budget is spent") > 0 .and. index(error%message, "[CVODE") == 0, &
      "budget message without stale CVODE text: " // error%message)
    deallocate(error)
  end if
  call solver%free()

  call section("a failed init releases everything; init again and free twice")
  opts = cvode_options(rtol=1e-8_dp, atol=1e-10_dp)
  opts%atol_vector = [1e-10_dp, 1e-10_dp, 1e-10_dp]
  call solver%init(osc, 0.0_dp, [1.0_dp, 0.0_dp], opts, error)
  call check(allocated(error), "atol_vector of 3 entries for 2 states: refused")
  if (allocated(error)) deallocate(error)
  call check(.not. c_associated(solver%mem) .and. .not. c_associated(solver%ctx) .and. &
    .not. associated(solver%nv_y) .and. .not. associated(solver%y), &
    "no CVODE memory, context, vector or state left allocated")
  opts = cvode_options(rtol=1e-10_dp, atol=1e-12_dp, max_order=7)
  call solver%init(osc, 0.0_dp, [1.0_dp, 0.0_dp], opts, error)
  call check(allocated(error), "max_order 7 for BDF (at most 5): refused")
  if (allocated(error)) deallocate(error)
  call check(.not. c_associated(solver%mem), "and released")
  opts = cvode_options(rtol=1e-10_dp, atol=1e-12_dp)
  call solver%init(osc, 0.0_dp, [1.0_dp, 0.0_dp], opts, error)
  call solver%set_roots(0, error)
  call solver%advance(1.0_dp, error)
  call check(.not. allocated(error), "the next init on the same object works")
  call check_close(solver%y(1), cos(2.0_dp), "x(1) = cos(2)", abs=1e-7_dp)
  call solver%reinit(solver%t, [1.0_dp, 0.0_dp, 0.0_dp], error)
  call check(allocated(error), "reinit with 3 states for a 2-state solver: refused")
  if (allocated(error)) deallocate(error)
  call solver%free()
  call solver%free()
  call check(.not. c_associated(solver%mem), "free twice is safe")

  call section("an unrecoverable linear-solver setup is not called singular")
  ! a Jacobian callback returning fatal makes CVODE stop with CV_LSETUP_FAIL
  block
    type(jacobian_failing_oscillator), target :: jfo
    opts = cvode_options(linear_solver="band", upper_bandwidth=1, lower_bandwidth=1, rtol=1e-8_dp, atol=1e-10_dp)
    call solver%init(jfo, 0.0_dp, [1.0_dp, 0.0_dp], opts, error)
    call solver%set_roots(0, error)
    call check(.not. allocated(error), "init with the declared Jacobian")
    call solver%advance(1.0_dp, error)
    call check(allocated(error), "the fatal Jacobian stops the run")
    if (allocated(error)) then
      call check(index(error%message, "linear solver setup failed (unrecoverable") > 0 .and. &
        index(error%message, "linear solver flag") > 0 .and. index(error%message, "singular") == 0, &
        "message: " // error%message)
      deallocate(error)
    end if
    call solver%free()
  end block

  call section("counters are the run's totals over re-initialisations")
  ! Adams with the fixed-point solver: every call of the right-hand side is one
  ! of CVODE's counted evaluations (no difference-quotient Jacobian), so the
  ! system's own count is an independent total.  Re-initialise at each of the
  ! oscillator's events over 5 s (pi/4 + k pi/2: 3 events).
  block
    type(cvode_stats) :: before, after
    integer :: restarts
    logical :: same
    opts = cvode_options(method="adams", linear_solver="none", rtol=1e-8_dp, atol=1e-10_dp)
    call solver%init(osc, 0.0_dp, [1.0_dp, 0.0_dp], opts, error)
    osc%n_rhs = 0
    restarts = 0
    same = .true.
    do while (solver%t < 5.0_dp .and. .not. allocated(error))
      call solver%advance(5.0_dp, error, event, which)
      if (.not. event) exit
      before = solver%stats()
      call solver%reinit(solver%t, solver%y, error)
      after = solver%stats()
      same = same .and. after%steps == before%steps .and. after%rhs_evals == before%rhs_evals .and. &
        after%nonlin_iters == before%nonlin_iters .and. after%root_evals == before%root_evals
      restarts = restarts + 1
    end do
    call check(.not. allocated(error) .and. restarts == 3, "3 events and restarts over 5 s (" // str(restarts) // ")")
    call check(same, "a re-initialisation changes no counter")
    st = solver%stats()
    call check(st%steps == solver%steps_taken(), "stats%steps = steps_taken (" // &
      str(int(st%steps)) // ", " // str(int(solver%steps_taken())) // ")")
    call check(st%rhs_evals == osc%n_rhs, "stats%rhs_evals = the system's own count (" // &
      str(int(st%rhs_evals)) // ", " // str(osc%n_rhs) // ")")
    call solver%free()
  end block
  ! a band solver's Jacobian counter (restarted by CVODE at the step after a
  ! re-initialisation, not at it) is not counted twice
  block
    type(cvode_stats) :: before, after
    opts = cvode_options(linear_solver="band", upper_bandwidth=1, lower_bandwidth=1, rtol=1e-8_dp, atol=1e-10_dp)
    call solver%init(osc, 0.0_dp, [1.0_dp, 0.0_dp], opts, error)
    call solver%advance(2.0_dp, error, event, which)
    before = solver%stats()
    call solver%reinit(solver%t, solver%y, error)
    after = solver%stats()
    call check(before%jac_evals > 0 .and. after%jac_evals == before%jac_evals, &
      "Jacobian evaluations unchanged by the re-initialisation (" // str(int(after%jac_evals)) // ")")
    call solver%advance(2.0_dp, error, event, which)
    after = solver%stats()
    call check(after%jac_evals > before%jac_evals .and. after%steps > before%steps, "and growing after it")
    call solver%free()
  end block
  opts = saved_opts

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
contains

  !> x = M^-1 b by the velocity-reduced solver fed the node blocks `blk` (CVODE's
  !> linear-system hook: its band matrix is never filled); ierr: the sum of the
  !> SUNDIALS return codes.
  subroutine solve_from_blocks(blk, n, ctx, nb, x, ierr)
    type(node_blocks), pointer, intent(in) :: blk
    integer, intent(in) :: n
    type(c_ptr), intent(in) :: ctx
    type(N_Vector), intent(inout) :: nb
    real(dp), intent(out) :: x(n)
    integer, intent(out) :: ierr
    type(SUNMatrix), pointer :: m_unused
    type(SUNLinearSolver), pointer :: ls_blk
    type(N_Vector), pointer :: nx
    real(c_double), pointer :: xd(:)
    m_unused => FSUNBandMatrix(int(n, c_long), 8_c_long, 11_c_long, ctx)
    ls_blk => new_second_order_band_solver(m_unused, ctx)
    call use_node_blocks(ls_blk, blk)
    nx => FN_VNew_Serial(int(n, c_long), ctx)
    xd => FN_VGetArrayPointer(nx)
    ierr = FSUNLinSolSetup(ls_blk, m_unused)
    ierr = ierr + FSUNLinSolSolve(ls_blk, m_unused, nx, nb, 0.0_c_double)
    x = xd
    ierr = ierr + FSUNLinSolFree(ls_blk)
    call FSUNMatDestroy(m_unused)
    call FN_VDestroy(nx)
  end subroutine solve_from_blocks
  !> The band (mu above, ml below the diagonal) of the square `dense` into m.
  subroutine fill_band(m, dense, mu, ml)
    type(SUNMatrix), intent(inout) :: m
    real(dp), intent(in) :: dense(:, :)
    integer, intent(in) :: mu, ml
    integer :: i, j, n
    n = size(dense, 1)
    do j = 1, n
      do i = max(1, j - mu), min(n, j + ml)
        call set_band(m, i, j, dense(i, j))
      end do
    end do
  end subroutine fill_band

  !> M(i, j) = v in SUNDIALS band storage.
  subroutine set_band(m, i, j, v)
    type(SUNMatrix), intent(inout) :: m
    integer, intent(in) :: i, j
    real(dp), intent(in) :: v
    real(c_double), pointer :: ab(:)
    integer :: ldim, smu
    ldim = int(FSUNBandMatrix_LDim(m))
    smu = int(FSUNBandMatrix_StoredUpperBandwidth(m))
    ab => band_data(m, ldim)
    ab((j - 1)*ldim + smu + i - j + 1) = v
  end subroutine set_band
end program test_cvode
