!> SUNDIALS linear solvers on CVODE's Newton matrix, factored by LAPACK
!> (OpenBLAS here): the full band LU (dgbtrf/dgbtrs), the velocity-reduced and
!> position-reduced band solves (below) and the dense LU (dgetrf/dgetrs, for
!> the small rigid systems: Debian's SUNDIALS has no LAPACK solvers, and its
!> own dense LU is not LAPACK); one content type and one set of SUNDIALS
!> callbacks (type, last flag, free) for all.
!>
!> The full band LU.  Debian's SUNDIALS has no LAPACK band solver;
!> its own band LU (SUNDlsMat_bandGBTRF/GBTRS) took a third of the paper
!> scenario's run time (docs/performance.md).  SUNDIALS' band storage is
!> LAPACK's: column j holds A(i, j) at row smu + 1 + i - j with smu = mu + ml
!> and leading dimension smu + ml + 1 = 2 ml + mu + 1, so the matrix data is
!> factored in place.
!>
!> The velocity-reduced solver, for second-order systems stored node by node,
!> y = [x_1, v_1, x_2, v_2, ...] with three positions and three velocities per
!> node and x' = v (the lumped line, airlaunch_line_cvode).  CVODE's Newton
!> matrix M = I - gamma J then has, in the position rows, exactly
!> M_xx = I, M_xv = -gamma I (J_xx = 0, J_xv = I), so
!>     dx - gamma dv = r_x,      M_vx dx + M_vv dv = r_v
!> reduces to the velocity system
!>     (M_vv + gamma M_vx) dv = r_v - M_vx r_x,      dx = r_x + gamma dv,
!> i.e. (I - gamma B - gamma^2 A) dv = ... with A = da/dx, B = da/dv: half the
!> unknowns, and block tridiagonal with 3x3 blocks (band 5/5 instead of the
!> full system's 11/8).  Factored by LAPACK (dgbtrf/dgbtrs); the full band
!> matrix M is CVODE's (its difference-quotient Jacobian), read, not changed.
!>
!> gamma is read from M itself (M(x, v) of the first node = -gamma), so the
!> solve is exact for the M that CVODE built, whatever gamma it used.
!>
!> The position-reduced solver, for systems in which only some states are
!> positions with x' = v (another state): the air-launch scene's bodies carry
!> quaternions and rates besides their positions, its line nodes are pure
!> positions and velocities.  The rows of such a position in CVODE's M are
!> exactly dx - g_x dv = r_x (M(x, x) = 1, M(x, v) = -g_x, nothing else: a
!> difference quotient of x' = v perturbs nothing else), so every position
!> is eliminated, dx = r_x + g_x dv, and the remaining rows keep their band:
!>     sum_j R(i, j) d_j = r_i - sum_x M(i, x) r_x,
!>     R(i, j) = M(i, j) + g_x M(i, x) for j = v(x), M(i, j) otherwise,
!> over the kept states only, numbered from the last to the first.  That order
!> eliminates the line's nodes before the bodies they pull on: a node's velocity
!> column has its large diagonal (1 + gamma^2 k/m) on the row itself, and LAPACK's
!> partial pivoting, which swapped the rocket's rows for the node rows whose
!> stiff springs dominate its columns in the full system, finds nothing to swap.
!> Each g_x is read from M, so the solve is exact for the M that CVODE built.
!> R's rows are scaled to a unit largest entry (LAPACK's dgbequ) before dgbtrf:
!> a heavy node (the parachute) otherwise loses its own column's pivot to the
!> lighter neighbour's row.
module airlaunch_lapack_band
  use, intrinsic :: iso_c_binding
  use fsundials_context_mod
  use fsundials_linearsolver_mod
  use fsundials_matrix_mod
  use fsundials_nvector_mod
  use fnvector_serial_mod
  use fsunmatrix_band_mod
  use fsunmatrix_dense_mod
  use airlaunch_ode, only: node_blocks
  implicit none
  private
  public :: new_lapack_band_solver, new_second_order_band_solver, second_order_band_ok, band_data, &
    use_node_blocks, new_position_reduced_solver, partners_ok, new_lapack_dense_solver

  !> Half-bandwidths of the reduced velocity matrix (3x3 blocks, neighbours only).
  integer, parameter :: kr = 5
  !> The solvers (new_solver): full band LU, velocity-reduced, position-reduced.
  integer, parameter :: kind_full = 1, kind_velocity = 2, kind_position = 3

  !> What a solver keeps between setup and solve: the full band LU uses n, ml,
  !> mu, ldab, ipiv; the velocity-reduced solve uses nodes, ldab, ipiv and its
  !> reduced matrix (s), the M_vx blocks and gamma.
  type :: band_content
    integer :: n = 0, ml = 0, mu = 0, ldab = 0
    logical :: dense = .false.                        !< full LU of a dense matrix (dgetrf/dgetrs)
    integer, allocatable :: ipiv(:)
    integer(c_long) :: last_flag = 0
    logical :: no_interchange = .false.               !< the last factorisation swapped no rows
    integer :: nodes = 0                              !< reduced: number of nodes (n = 6 nodes)
    real(c_double) :: gamma = 0.0_c_double            !< reduced: gamma of the factored matrix
    real(c_double), allocatable :: s(:, :)            !< reduced matrix, LAPACK band storage (ldab, 3 nodes)
    real(c_double), allocatable :: mvx(:, :, :, :)    !< M_vx blocks (3, 3, -1:1, nodes)
    real(c_double), allocatable :: rv(:)              !< work: reduced right-hand side (3 nodes)
    !> reduced: the Jacobian as node blocks (use_node_blocks), read instead of M
    type(node_blocks), pointer :: blocks => null()
    ! position-reduced: the map of the states and the terms of the eliminated positions
    integer :: nr = 0, klr = 0, kur = 0               !< kept states, their half-bandwidths
    integer, allocatable :: partner(:)                !< (n) velocity of an eliminated position, else 0
    integer, allocatable :: rmap(:)                   !< (n) index of a kept state in R, 0 if eliminated
    real(c_double), allocatable :: g(:)               !< (n) -M(x, v(x)) of an eliminated position x
    integer, allocatable :: mx_first(:)               !< (n + 1) kept row i's M(i, x) at mx_first(i) ..
    integer, allocatable :: mx_col(:)                 !<   .. mx_first(i + 1) - 1: their columns x
    real(c_double), allocatable :: mx_val(:)          !<   and values
    real(c_double), allocatable :: rowscale(:)        !< (nr) R's row scaling (dgbequ)
    real(c_double), allocatable :: colscale(:)        !< (nr) dgbequ's column scaling (not applied)
  end type band_content

  interface
    subroutine dgbtrf(m, n, kl, ku, ab, ldab, ipiv, info)
      import :: c_double
      implicit none
      integer, intent(in) :: m, n, kl, ku, ldab
      real(c_double), intent(inout) :: ab(ldab, *)
      integer, intent(out) :: ipiv(*), info
    end subroutine dgbtrf
    subroutine dgbtrs(trans, n, kl, ku, nrhs, ab, ldab, ipiv, b, ldb, info)
      import :: c_double
      implicit none
      character, intent(in) :: trans
      integer, intent(in) :: n, kl, ku, nrhs, ldab, ldb, ipiv(*)
      real(c_double), intent(in) :: ab(ldab, *)
      real(c_double), intent(inout) :: b(ldb, *)
      integer, intent(out) :: info
    end subroutine dgbtrs
    subroutine dgetrf(m, n, a, lda, ipiv, info)
      import :: c_double
      implicit none
      integer, intent(in) :: m, n, lda
      real(c_double), intent(inout) :: a(lda, *)
      integer, intent(out) :: ipiv(*), info
    end subroutine dgetrf
    subroutine dgetrs(trans, n, nrhs, a, lda, ipiv, b, ldb, info)
      import :: c_double
      implicit none
      character, intent(in) :: trans
      integer, intent(in) :: n, nrhs, lda, ldb, ipiv(*)
      real(c_double), intent(in) :: a(lda, *)
      real(c_double), intent(inout) :: b(ldb, *)
      integer, intent(out) :: info
    end subroutine dgetrs
    subroutine dgbequ(m, n, kl, ku, ab, ldab, r, c, rowcnd, colcnd, amax, info)
      import :: c_double
      implicit none
      integer, intent(in) :: m, n, kl, ku, ldab
      real(c_double), intent(in) :: ab(ldab, *)
      real(c_double), intent(out) :: r(*), c(*), rowcnd, colcnd, amax
      integer, intent(out) :: info
    end subroutine dgbequ
    subroutine dtbsv(uplo, trans, diag, n, k, a, lda, x, incx)
      import :: c_double
      implicit none
      character, intent(in) :: uplo, trans, diag
      integer, intent(in) :: n, k, lda, incx
      real(c_double), intent(in) :: a(lda, *)
      real(c_double), intent(inout) :: x(*)
    end subroutine dtbsv
  end interface

contains

  !> A direct linear solver for CVODE with a band matrix A (FSUNBandMatrix).
  function new_lapack_band_solver(a, ctx) result(ls)
    type(SUNMatrix), intent(inout) :: a     !< the band matrix CVODE will fill
    type(c_ptr), intent(in) :: ctx          !< SUNDIALS context
    type(SUNLinearSolver), pointer :: ls
    type(band_content), pointer :: c
    ls => new_solver(ctx, kind_full, c)
    c%n = int(FSUNBandMatrix_Columns(a))
    c%ml = int(FSUNBandMatrix_LowerBandwidth(a))
    c%mu = int(FSUNBandMatrix_UpperBandwidth(a))
    c%ldab = int(FSUNBandMatrix_LDim(a))
    allocate(c%ipiv(c%n))
  end function new_lapack_band_solver

  integer(c_int) function band_gettype(s) result(t) bind(C)
    type(SUNLinearSolver), intent(inout) :: s
    t = SUNLINEARSOLVER_DIRECT
    if (.false.) t = int(merge(1, 0, c_associated(s%content)), c_int)
  end function band_gettype

  !> LU factorisation in place (dgbtrf, or dgetrf for a dense matrix); a zero
  !> pivot is a recoverable failure (CVODE retries with a smaller step).
  integer(c_int) function band_setup(s, a) result(ierr) bind(C)
    type(SUNLinearSolver), intent(inout) :: s
    type(SUNMatrix), intent(inout) :: a
    type(band_content), pointer :: c
    real(c_double), pointer :: ab(:)
    integer :: info
    call c_f_pointer(s%content, c)
    if (c%dense) then
      ab => FSUNDenseMatrix_Data(a)
      call dgetrf(c%n, c%n, ab, c%ldab, c%ipiv, info)
      ierr = factor_flag(c, info)
    else
      ab => FSUNBandMatrix_Data(a)
      ierr = band_lu_factor(c, c%n, c%ml, c%mu, ab)
    end if
  end function band_setup

  !> x = A^-1 b from the factors (band: band_lu_solve; dense: dgetrs).
  integer(c_int) function band_solve(s, a, x, b, tol) result(ierr) bind(C)
    type(SUNLinearSolver), intent(inout) :: s
    type(SUNMatrix), intent(inout) :: a
    type(N_Vector), intent(inout) :: x, b
    real(c_double), value, intent(in) :: tol
    type(band_content), pointer :: c
    real(c_double), pointer :: ab(:), xd(:)
    integer :: info
    call c_f_pointer(s%content, c)
    xd => FN_VGetArrayPointer(x)
    ! x = b by an N_Vector copy: xd = bd between two pointers that may alias
    ! would go through a heap temporary (once per Newton iteration)
    call FN_VScale(1.0_c_double, b, x)
    if (c%dense) then
      ab => FSUNDenseMatrix_Data(a)
      call dgetrs('N', c%n, 1, ab, c%ldab, c%ipiv, xd, c%n, info)
    else
      ab => FSUNBandMatrix_Data(a)
      call band_lu_solve(c%n, c%ml, c%mu, ab, c%ldab, c%ipiv, c%no_interchange, xd, info)
    end if
    ierr = solve_flag(c, info)
    if (.false.) xd(1) = tol
  end function band_solve

  !> LU factorisation in place (dgbtrf) of the n x n band matrix ab (kl, ku;
  !> leading dimension and pivots from the content c, which also records
  !> LAPACK's flag and whether rows were swapped); a zero pivot is a recoverable
  !> failure (CVODE retries with a smaller step).
  integer(c_int) function band_lu_factor(c, n, kl, ku, ab) result(ierr)
    type(band_content), intent(inout) :: c          !< ldab, ipiv in; last_flag, no_interchange out
    integer, intent(in) :: n, kl, ku                !< order and half-bandwidths
    real(c_double), intent(inout) :: ab(c%ldab, *)  !< the matrix in, its factors out
    integer :: info
    call dgbtrf(n, n, kl, ku, ab, c%ldab, c%ipiv, info)
    c%no_interchange = no_row_interchange(c%ipiv(1:n))
    ierr = factor_flag(c, info)
  end function band_lu_factor

  !> True if the pivots of a factorisation (dgbtrf's ipiv) swapped no rows.
  pure logical function no_row_interchange(ipiv) result(none)
    integer, intent(in) :: ipiv(:)   !< row i was interchanged with row ipiv(i)
    integer :: i
    none = .true.
    do i = 1, size(ipiv)
      if (ipiv(i) /= i) then
        none = .false.
        return
      end if
    end do
  end function no_row_interchange

  !> b = A^-1 b from dgbtrf's factors of the n x n band matrix A (kl, ku).
  !> Without row interchanges the unit lower factor L is itself banded (kl
  !> multipliers per column, rows kl+ku+2 .. 2kl+ku+1 of LAPACK's storage), so
  !> L^-1 b is one BLAS banded triangular solve (dtbsv), as U^-1 b is in dgbtrs:
  !> the same operations as dgbtrs's column-by-column dger updates, without a
  !> BLAS call per column (those calls were 20 % of a line run's instructions).
  !> Without interchanges U also keeps the matrix's own upper bandwidth ku (the
  !> kl rows above it that dgbtrf reserves for the fill of interchanges stay
  !> exactly zero), so U^-1 b skips them: half the multiply-adds of the
  !> line's solve, the same result bit for bit.
  !> With interchanges, L is not banded in any one row order: dgbtrs.
  subroutine band_lu_solve(n, kl, ku, ab, ldab, ipiv, no_interchange, b, info)
    integer, intent(in) :: n, kl, ku, ldab             !< order, half-bandwidths, leading dimension
    real(c_double), intent(in) :: ab(ldab, *)          !< dgbtrf's factors
    integer, intent(in) :: ipiv(*)                     !< dgbtrf's pivots
    logical, intent(in) :: no_interchange              !< ipiv(i) == i for all i
    real(c_double), intent(inout) :: b(*)              !< right-hand side in, solution out
    integer, intent(out) :: info                       !< LAPACK's info (0: success)
    if (no_interchange) then
      call dtbsv('L', 'N', 'U', n, kl, ab(kl + ku + 1, 1), ldab, b, 1)
      call dtbsv('U', 'N', 'N', n, ku, ab(kl + 1, 1), ldab, b, 1)
      info = 0
    else
      call dgbtrs('N', n, kl, ku, 1, ab, ldab, ipiv, b, n, info)
    end if
  end subroutine band_lu_solve

  !> True if a band matrix of n states and half-bandwidths mu, ml can carry the
  !> structure (6 states per node, neighbours only: mu >= 8, ml >= 11).
  pure logical function second_order_band_ok(n, mu, ml) result(ok)
    integer, intent(in) :: n, mu, ml  !< states, upper and lower half-bandwidths
    ok = n > 0 .and. mod(n, 6) == 0 .and. mu >= 8 .and. ml >= 11
  end function second_order_band_ok

  !> The solver for CVODE's band matrix `a` (FSUNBandMatrix, n = 6 nodes states,
  !> mu >= 8, ml >= 11: check with second_order_band_ok first).
  function new_second_order_band_solver(a, ctx) result(ls)
    type(SUNMatrix), intent(inout) :: a     !< the band matrix CVODE fills
    type(c_ptr), intent(in) :: ctx          !< SUNDIALS context
    type(SUNLinearSolver), pointer :: ls
    type(band_content), pointer :: c
    ls => new_solver(ctx, kind_velocity, c)
    c%nodes = int(FSUNBandMatrix_Columns(a))/6
    c%ldab = 3*kr + 1
    allocate(c%s(c%ldab, 3*c%nodes), c%mvx(3, 3, -1:1, c%nodes), c%rv(3*c%nodes), c%ipiv(3*c%nodes))
  end function new_second_order_band_solver

  !> Let the velocity-reduced solver `ls` build its matrix from the node blocks
  !> `blocks` (filled, with gamma, by CVODE's linear-system callback before every
  !> setup) instead of from CVODE's band matrix, which then stays unused: CVODE
  !> neither zeroes, copies nor scales it.
  subroutine use_node_blocks(ls, blocks)
    type(SUNLinearSolver), intent(inout) :: ls         !< from new_second_order_band_solver
    type(node_blocks), pointer, intent(in) :: blocks   !< for as many nodes as the solver
    type(band_content), pointer :: c
    call c_f_pointer(ls%content, c)
    c%blocks => blocks
  end subroutine use_node_blocks

  !> An empty SUNDIALS linear solver with the setup and solve of the full band LU
  !> or of the velocity-reduced system, the shared type, last-flag and free
  !> callbacks, and a new content `c` attached.  (The callbacks are chosen here:
  !> a c_funloc constant passed as an actual argument lands in .rodata with a
  !> run-time relocation, DT_TEXTREL in the PIE executable.)
  function new_solver(ctx, kind, c) result(ls)
    type(c_ptr), intent(in) :: ctx                  !< SUNDIALS context
    integer, intent(in) :: kind                     !< kind_full, kind_velocity or kind_position
    type(band_content), pointer, intent(out) :: c   !< its content (to be filled by the caller)
    type(SUNLinearSolver), pointer :: ls
    type(SUNLinearSolver_Ops), pointer :: ops
    ls => FSUNLinSolNewEmpty(ctx)
    call c_f_pointer(ls%ops, ops)
    ops%gettype = c_funloc(band_gettype)
    select case (kind)
    case (kind_velocity)
      ops%setup = c_funloc(reduced_setup)
      ops%solve = c_funloc(reduced_solve)
    case (kind_position)
      ops%setup = c_funloc(position_setup)
      ops%solve = c_funloc(position_solve)
    case default
      ops%setup = c_funloc(band_setup)
      ops%solve = c_funloc(band_solve)
    end select
    ops%lastflag = c_funloc(band_lastflag)
    ops%free = c_funloc(band_free)
    allocate(c)
    ls%content = c_loc(c)
  end function new_solver

  !> The whole band storage of `a` (ldim x columns); the Fortran interface's
  !> FSUNBandMatrix_Data carries no length.
  function band_data(a, ldim) result(ab)
    type(SUNMatrix), intent(inout) :: a
    integer, intent(in) :: ldim
    real(c_double), pointer :: ab(:)
    real(c_double), pointer :: first(:)
    first => FSUNBandMatrix_Data(a)
    call c_f_pointer(c_loc(first(1)), ab, [ldim*int(FSUNBandMatrix_Columns(a))])
  end function band_data

  !> Entry M(i, j) of SUNDIALS' band storage (column-major, smu = mu + ml rows above).
  pure real(c_double) function band_entry(ab, ldim, smu, i, j) result(m)
    real(c_double), intent(in) :: ab(:)
    integer, intent(in) :: ldim, smu, i, j
    m = ab((j - 1)*ldim + smu + i - j + 1)
  end function band_entry

  !> Build the reduced velocity matrix from M and factor it (dgbtrf); a zero
  !> pivot is a recoverable failure (CVODE retries with a smaller step).
  integer(c_int) function reduced_setup(s, a) result(ierr) bind(C)
    type(SUNLinearSolver), intent(inout) :: s
    type(SUNMatrix), intent(inout) :: a
    type(band_content), pointer :: c
    real(c_double), pointer :: ab(:)
    integer :: ldim, smu, j, k, p, q, row, col, n3
    real(c_double) :: g
    call c_f_pointer(s%content, c)
    n3 = 3*c%nodes
    if (associated(c%blocks)) then
      call setup_from_blocks(c, c%blocks)
      ierr = band_lu_factor(c, n3, kr, kr, c%s)
      return
    end if
    ldim = int(FSUNBandMatrix_LDim(a))
    smu = int(FSUNBandMatrix_StoredUpperBandwidth(a))
    ab => band_data(a, ldim)
    g = -band_entry(ab, ldim, smu, 1, 4)
    c%gamma = g
    c%s = 0.0_c_double
    c%mvx = 0.0_c_double
    do j = 1, c%nodes
      do k = max(1, j - 1), min(c%nodes, j + 1)
        do q = 1, 3
          do p = 1, 3
            row = 6*(j - 1) + 3 + p
            col = 6*(k - 1) + q
            c%mvx(p, q, k - j, j) = band_entry(ab, ldim, smu, row, col)
            ! S(3(j-1)+p, 3(k-1)+q) = M_vv + gamma M_vx, LAPACK band storage (kl = ku = kr)
            c%s(2*kr + 1 + 3*(j - k) + p - q, 3*(k - 1) + q) = &
              band_entry(ab, ldim, smu, row, col + 3) + g*c%mvx(p, q, k - j, j)
          end do
        end do
      end do
    end do
    ierr = band_lu_factor(c, n3, kr, kr, c%s)
  end function reduced_setup

  !> The reduced matrix S = I - gamma av - gamma^2 ax and M_vx = -gamma ax from the
  !> node blocks (the same matrices reduced_setup reads from M = I - gamma J).
  !> With a mass matrix (b%mass_coupled) the velocity rows are multiplied by
  !> D^-1 M (D its diagonal; ax, av are then D^-1 df/dx, D^-1 df/dv):
  !> Newton's velocity rows -gamma M^-1 A dx + (I - gamma M^-1 B) dv = r_v
  !> become -gamma D^-1 A dx + D^-1 (M - gamma B) dv = D^-1 M r_v, so S gains
  !> D^-1 M - I = b%mass off the diagonal, and reduced_solve multiplies r_v by
  !> D^-1 M.  Every block stays tridiagonal (M^-1 A itself is full).
  subroutine setup_from_blocks(c, b)
    type(band_content), intent(inout) :: c   !< s, mvx, gamma out
    type(node_blocks), intent(in) :: b       !< the Jacobian's blocks and gamma
    integer :: j, k, p, q
    real(c_double) :: g
    g = b%gamma
    c%gamma = g
    c%s = 0.0_c_double
    do j = 1, c%nodes
      do k = max(1, j - 1), min(c%nodes, j + 1)
        do q = 1, 3
          do p = 1, 3
            c%mvx(p, q, k - j, j) = -g*b%ax(p, q, k - j, j)
            c%s(2*kr + 1 + 3*(j - k) + p - q, 3*(k - 1) + q) = -g*(b%av(p, q, k - j, j) + g*b%ax(p, q, k - j, j))
          end do
        end do
      end do
    end do
    c%s(2*kr + 1, 1:3*c%nodes) = c%s(2*kr + 1, 1:3*c%nodes) + 1.0_c_double   ! the identity: the diagonal row
    if (.not. b%mass_coupled) return
    do j = 1, c%nodes
      do k = max(1, j - 1), min(c%nodes, j + 1)
        if (k == j) cycle
        do p = 1, 3
          c%s(2*kr + 1 + 3*(j - k), 3*(k - 1) + p) = c%s(2*kr + 1 + 3*(j - k), 3*(k - 1) + p) + b%mass(k - j, j)
        end do
      end do
    end do
  end subroutine setup_from_blocks

  !> x = M^-1 b through the velocity system.
  integer(c_int) function reduced_solve(s, a, x, b, tol) result(ierr) bind(C)
    type(SUNLinearSolver), intent(inout) :: s
    type(SUNMatrix), intent(inout) :: a
    type(N_Vector), intent(inout) :: x, b
    real(c_double), value, intent(in) :: tol
    type(band_content), pointer :: c
    real(c_double), pointer :: xd(:), bd(:)
    integer :: j, k, p, q, i0, info
    real(c_double) :: r(3)
    logical :: coupled
    call c_f_pointer(s%content, c)
    xd => FN_VGetArrayPointer(x)
    bd => FN_VGetArrayPointer(b)
    coupled = .false.
    if (associated(c%blocks)) coupled = c%blocks%mass_coupled
    ! r = r_v - M_vx r_x (explicit loops: no temporaries in the solve; the three
    ! rows of a node together, p innermost along the contiguous M_vx columns)
    do j = 1, c%nodes
      i0 = 6*(j - 1)
      r = bd(i0 + 4:i0 + 6)
      if (coupled) then   ! D^-1 M r_v (setup_from_blocks)
        do k = max(1, j - 1), min(c%nodes, j + 1)
          if (k == j) cycle
          do p = 1, 3
            r(p) = r(p) + c%blocks%mass(k - j, j)*bd(6*(k - 1) + 3 + p)
          end do
        end do
      end if
      do k = max(1, j - 1), min(c%nodes, j + 1)
        do q = 1, 3
          do p = 1, 3
            r(p) = r(p) - c%mvx(p, q, k - j, j)*bd(6*(k - 1) + q)
          end do
        end do
      end do
      c%rv(3*(j - 1) + 1:3*j) = r
    end do
    call band_lu_solve(3*c%nodes, kr, kr, c%s, c%ldab, c%ipiv, c%no_interchange, c%rv, info)
    ! element by element: x and b are pointers that may alias (a section
    ! expression would go through a heap temporary, two per node and solve)
    do j = 1, c%nodes
      i0 = 6*(j - 1)
      do q = 1, 3
        xd(i0 + 3 + q) = c%rv(3*(j - 1) + q)
        xd(i0 + q) = bd(i0 + q) + c%gamma*c%rv(3*(j - 1) + q)
      end do
    end do
    ierr = solve_flag(c, info)
    if (.false.) xd(1) = tol + real(FSUNBandMatrix_Columns(a), c_double)
  end function reduced_solve

  !> A direct linear solver for CVODE with a dense matrix A (FSUNDenseMatrix),
  !> factored in place by LAPACK (dgetrf/dgetrs; SUNDIALS' dense storage is
  !> LAPACK's column-major n x n).
  function new_lapack_dense_solver(a, ctx) result(ls)
    type(SUNMatrix), intent(inout) :: a     !< the dense matrix CVODE will fill
    type(c_ptr), intent(in) :: ctx          !< SUNDIALS context
    type(SUNLinearSolver), pointer :: ls
    type(band_content), pointer :: c
    ls => new_solver(ctx, kind_full, c)
    c%dense = .true.
    c%n = int(FSUNDenseMatrix_Columns(a))
    c%ldab = int(FSUNDenseMatrix_Rows(a))
    allocate(c%ipiv(c%n))
  end function new_lapack_dense_solver


  !> True if `partner` describes positions the position-reduced solver can
  !> eliminate from a band matrix of half-bandwidths mu, ml: at least one, each
  !> partner a state that is not a position and within the band of its row.
  pure logical function partners_ok(partner, mu, ml) result(ok)
    integer, intent(in) :: partner(:)   !< velocity state of a position, 0 otherwise
    integer, intent(in) :: mu, ml       !< upper and lower half-bandwidths of M
    integer :: i
    ok = any(partner /= 0)
    do i = 1, size(partner)
      if (partner(i) == 0) cycle
      if (partner(i) < 1 .or. partner(i) > size(partner) .or. partner(i) - i > mu .or. i - partner(i) > ml) then
        ok = .false.
      else if (partner(partner(i)) /= 0) then
        ok = .false.
      end if
    end do
  end function partners_ok

  !> The position-reduced solver for CVODE's band matrix `a` (FSUNBandMatrix,
  !> with or without the LU fill rows: only read) of a system whose state i is a
  !> position with derivative state partner(i) (> 0), or not (0); check with
  !> partners_ok first.  The kept states' half-bandwidths in R follow from M's
  !> and the map.
  function new_position_reduced_solver(a, ctx, partner) result(ls)
    type(SUNMatrix), intent(inout) :: a     !< the band matrix CVODE fills
    type(c_ptr), intent(in) :: ctx          !< SUNDIALS context
    integer, intent(in) :: partner(:)       !< (n) velocity state of a position, 0 otherwise
    type(SUNLinearSolver), pointer :: ls
    type(band_content), pointer :: c
    integer :: i, col, j, k
    ls => new_solver(ctx, kind_position, c)
    c%n = int(FSUNBandMatrix_Columns(a))
    c%ml = int(FSUNBandMatrix_LowerBandwidth(a))
    c%mu = int(FSUNBandMatrix_UpperBandwidth(a))
    c%partner = partner
    c%nr = count(partner == 0)
    allocate(c%rmap(c%n), c%g(c%n), c%mx_first(c%n + 1))
    ! kept states numbered from the last to the first (see the module header)
    k = c%nr + 1
    do i = 1, c%n
      c%rmap(i) = 0
      if (partner(i) == 0) then
        k = k - 1
        c%rmap(i) = k
      end if
    end do
    ! R's half-bandwidths: every entry of a kept row within M's band lands at
    ! (rmap(i), rmap(j)) with j the column or, for a position, its velocity
    c%klr = 0
    c%kur = 0
    j = 0
    do i = 1, c%n
      if (partner(i) /= 0) cycle
      do col = max(1, i - c%ml), min(c%n, i + c%mu)
        k = col
        if (partner(col) /= 0) then
          k = partner(col)
          j = j + 1
        end if
        c%klr = max(c%klr, c%rmap(i) - c%rmap(k))
        c%kur = max(c%kur, c%rmap(k) - c%rmap(i))
      end do
    end do
    allocate(c%mx_col(max(1, j)), c%mx_val(max(1, j)))
    c%ldab = 2*c%klr + c%kur + 1
    allocate(c%s(c%ldab, c%nr), c%rv(c%nr), c%ipiv(c%nr), c%rowscale(c%nr), c%colscale(c%nr))
  end function new_position_reduced_solver

  !> Build R from M (see the module header) and factor it (dgbtrf); the terms
  !> M(i, x) of the kept rows are kept for the solve.  A position row of M that
  !> is not exactly dx - g dv is an unrecoverable failure (the system declared
  !> a position that is not one; last flag -1).
  integer(c_int) function position_setup(s, a) result(ierr) bind(C)
    type(SUNLinearSolver), intent(inout) :: s
    type(SUNMatrix), intent(inout) :: a
    type(band_content), pointer :: c
    real(c_double), pointer :: ab(:)
    real(c_double) :: m
    integer :: ldim, smu, i, col, k, nnz, p, q, info
    real(c_double) :: rowcnd, colcnd, amax
    call c_f_pointer(s%content, c)
    ldim = int(FSUNBandMatrix_LDim(a))
    smu = int(FSUNBandMatrix_StoredUpperBandwidth(a))
    ab => band_data(a, ldim)
    ierr = SUNLS_SUCCESS
    do i = 1, c%n
      if (c%partner(i) == 0) cycle
      c%g(i) = -band_entry(ab, ldim, smu, i, c%partner(i))
      do col = max(1, i - c%ml), min(c%n, i + c%mu)
        if (col == c%partner(i)) cycle
        if (band_entry(ab, ldim, smu, i, col) /= merge(1.0_c_double, 0.0_c_double, col == i)) then
          c%last_flag = -1_c_long
          ierr = SUNLS_PACKAGE_FAIL_UNREC
          return
        end if
      end do
    end do
    c%s = 0.0_c_double
    nnz = 0
    do i = 1, c%n
      c%mx_first(i) = nnz + 1
      if (c%partner(i) /= 0) cycle
      do col = max(1, i - c%ml), min(c%n, i + c%mu)
        m = band_entry(ab, ldim, smu, i, col)
        if (m == 0.0_c_double) cycle
        if (c%partner(col) == 0) then
          k = c%rmap(col)
        else
          k = c%rmap(c%partner(col))
          nnz = nnz + 1
          c%mx_col(nnz) = col
          c%mx_val(nnz) = m
          m = c%g(col)*m
        end if
        ! R(p, q), p = rmap(i), q = k, in LAPACK band storage with kl = klr, ku = kur
        c%s(c%klr + c%kur + 1 + c%rmap(i) - k, k) = c%s(c%klr + c%kur + 1 + c%rmap(i) - k, k) + m
      end do
    end do
    c%mx_first(c%n + 1) = nnz + 1
    ! rows scaled to unit largest entry (dgbequ's row scaling; the solve scales
    ! the right-hand side alike)
    call dgbequ(c%nr, c%nr, c%klr, c%kur, c%s(c%klr + 1, 1), c%ldab, c%rowscale, c%colscale, rowcnd, colcnd, &
      amax, info)
    if (info /= 0) then
      c%last_flag = int(info, c_long)
      ierr = SUNLS_LUFACT_FAIL
      return
    end if
    do q = 1, c%nr
      do p = max(1, q - c%kur), min(c%nr, q + c%klr)
        c%s(c%klr + c%kur + 1 + p - q, q) = c%rowscale(p)*c%s(c%klr + c%kur + 1 + p - q, q)
      end do
    end do
    ierr = band_lu_factor(c, c%nr, c%klr, c%kur, c%s)
  end function position_setup

  !> x = M^-1 b through the kept states: r = b_kept - M(kept, x) b_x, R d = r,
  !> then every position from its velocity.
  integer(c_int) function position_solve(s, a, x, b, tol) result(ierr) bind(C)
    type(SUNLinearSolver), intent(inout) :: s
    type(SUNMatrix), intent(inout) :: a
    type(N_Vector), intent(inout) :: x, b
    real(c_double), value, intent(in) :: tol
    type(band_content), pointer :: c
    real(c_double), pointer :: xd(:), bd(:)
    real(c_double) :: r
    integer :: i, k, info
    call c_f_pointer(s%content, c)
    xd => FN_VGetArrayPointer(x)
    bd => FN_VGetArrayPointer(b)
    do i = 1, c%n
      if (c%partner(i) /= 0) cycle
      r = bd(i)
      do k = c%mx_first(i), c%mx_first(i + 1) - 1
        r = r - c%mx_val(k)*bd(c%mx_col(k))
      end do
      c%rv(c%rmap(i)) = c%rowscale(c%rmap(i))*r
    end do
    call band_lu_solve(c%nr, c%klr, c%kur, c%s, c%ldab, c%ipiv, c%no_interchange, c%rv, info)
    ! positions first (they read b, which x may alias), then the kept states
    do i = 1, c%n
      if (c%partner(i) /= 0) xd(i) = bd(i) + c%g(i)*c%rv(c%rmap(c%partner(i)))
    end do
    do i = 1, c%n
      if (c%partner(i) == 0) xd(i) = c%rv(c%rmap(i))
    end do
    ierr = solve_flag(c, info)
    if (.false.) xd(1) = tol + real(FSUNBandMatrix_Columns(a), c_double)
  end function position_solve

  !> SUNDIALS' flag of a factorisation with LAPACK's info (kept as the last
  !> flag): a zero pivot (info > 0) is a recoverable failure, CVODE retries
  !> with a smaller step.
  integer(c_int) function factor_flag(c, info) result(ierr)
    type(band_content), intent(inout) :: c   !< last_flag out
    integer, intent(in) :: info              !< LAPACK's info
    c%last_flag = int(info, c_long)
    ierr = SUNLS_SUCCESS
    if (info > 0) ierr = SUNLS_LUFACT_FAIL
  end function factor_flag

  !> SUNDIALS' flag of a solve with LAPACK's info (kept as the last flag):
  !> any nonzero info is unrecoverable.
  integer(c_int) function solve_flag(c, info) result(ierr)
    type(band_content), intent(inout) :: c   !< last_flag out
    integer, intent(in) :: info              !< LAPACK's info
    c%last_flag = int(info, c_long)
    ierr = SUNLS_SUCCESS
    if (info /= 0) ierr = SUNLS_PACKAGE_FAIL_UNREC
  end function solve_flag

  integer(c_long) function band_lastflag(s) result(f) bind(C)
    type(SUNLinearSolver), intent(inout) :: s
    type(band_content), pointer :: c
    call c_f_pointer(s%content, c)
    f = c%last_flag
  end function band_lastflag

  integer(c_int) function band_free(s) result(ierr) bind(C)
    type(SUNLinearSolver), intent(inout) :: s
    type(band_content), pointer :: c
    if (c_associated(s%content)) then
      call c_f_pointer(s%content, c)
      deallocate(c)
      s%content = c_null_ptr
    end if
    call FSUNLinSolFreeEmpty(s)
    ierr = 0
  end function band_free
end module airlaunch_lapack_band
