!> Thin LAPACK wrappers: sizes come from the arrays, INFO and the reciprocal
!> condition number become an error value (STYLE.md habit 5).  No explicit
!> inverses anywhere in airlaunch: every linear system goes through here.
module airlaunch_linalg
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  implicit none
  private
  public :: solve_general, solve_spd, solve_banded, rcond_limit

  !> Smallest reciprocal condition number (1-norm) accepted: below it the
  !> solution has fewer than ~2 significant digits in double precision.
  real(dp), parameter :: rcond_limit = 1.0e-14_dp
  !> Largest system whose LAPACK work space lives on the stack (larger: heap)
  integer, parameter :: small_n = 32

  interface
    subroutine dgesv(n, nrhs, a, lda, ipiv, b, ldb, info)
      import :: dp
      implicit none
      integer, intent(in) :: n, nrhs, lda, ldb
      real(dp), intent(inout) :: a(lda, *), b(ldb, *)
      integer, intent(out) :: ipiv(*), info
    end subroutine dgesv
    subroutine dgetrf(m, n, a, lda, ipiv, info)
      import :: dp
      implicit none
      integer, intent(in) :: m, n, lda
      real(dp), intent(inout) :: a(lda, *)
      integer, intent(out) :: ipiv(*), info
    end subroutine dgetrf
    subroutine dgetrs(trans, n, nrhs, a, lda, ipiv, b, ldb, info)
      import :: dp
      implicit none
      character, intent(in) :: trans
      integer, intent(in) :: n, nrhs, lda, ldb, ipiv(*)
      real(dp), intent(in) :: a(lda, *)
      real(dp), intent(inout) :: b(ldb, *)
      integer, intent(out) :: info
    end subroutine dgetrs
    subroutine dgecon(norm, n, a, lda, anorm, rcond, work, iwork, info)
      import :: dp
      implicit none
      character, intent(in) :: norm
      integer, intent(in) :: n, lda
      real(dp), intent(in) :: a(lda, *), anorm
      real(dp), intent(out) :: rcond, work(*)
      integer, intent(out) :: iwork(*), info
    end subroutine dgecon
    subroutine dgbsv(n, kl, ku, nrhs, ab, ldab, ipiv, b, ldb, info)
      import :: dp
      implicit none
      integer, intent(in) :: n, kl, ku, nrhs, ldab, ldb
      real(dp), intent(inout) :: ab(ldab, *), b(ldb, *)
      integer, intent(out) :: ipiv(*), info
    end subroutine dgbsv
    subroutine dpotrf(uplo, n, a, lda, info)
      import :: dp
      implicit none
      character, intent(in) :: uplo
      integer, intent(in) :: n, lda
      real(dp), intent(inout) :: a(lda, *)
      integer, intent(out) :: info
    end subroutine dpotrf
    subroutine dpotrs(uplo, n, nrhs, a, lda, b, ldb, info)
      import :: dp
      implicit none
      character, intent(in) :: uplo
      integer, intent(in) :: n, nrhs, lda, ldb
      real(dp), intent(in) :: a(lda, *)
      real(dp), intent(inout) :: b(ldb, *)
      integer, intent(out) :: info
    end subroutine dpotrs
    subroutine dpocon(uplo, n, a, lda, anorm, rcond, work, iwork, info)
      import :: dp
      implicit none
      character, intent(in) :: uplo
      integer, intent(in) :: n, lda
      real(dp), intent(in) :: a(lda, *), anorm
      real(dp), intent(out) :: rcond, work(*)
      integer, intent(out) :: iwork(*), info
    end subroutine dpocon
  end interface

contains

  !> Solve A X = B for a general square A (LU with partial pivoting, dgetrf/dgetrs).
  !> A is overwritten by its factors, B by the solution.  A singular pivot or a
  !> reciprocal condition number below `rcond_limit` is an error naming `what`.
  !> With `estimate_condition = .false.` (right-hand sides: small systems solved
  !> thousands of times) LAPACK's estimate (dgecon, several times the cost of
  !> the solve) is replaced by the pivot ratio min|u_ii|/max|u_ii| against the
  !> same limit.
  subroutine solve_general(a, b, error, what, rcond, estimate_condition)
    real(dp), intent(inout), contiguous :: a(:, :)  !< n x n matrix; on exit its LU factors
    real(dp), intent(inout), contiguous :: b(:, :)  !< n x nrhs right-hand sides; on exit X
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    character(len=*), intent(in) :: what     !< name of the system, for the message
    real(dp), intent(out), optional :: rcond !< reciprocal condition number (1-norm)
    logical, intent(in), optional :: estimate_condition !< dgecon (default) or the pivot ratio
    ! work space on the stack for the small systems of the right-hand sides
    ! (no heap allocation per call), on the heap above small_n
    integer :: ipiv_s(small_n), iwork_s(small_n)
    real(dp) :: work_s(4*small_n)
    integer, allocatable :: ipiv_h(:), iwork_h(:)
    real(dp), allocatable :: work_h(:)
    integer :: n
    n = size(a, 1)
    if (.not. shapes_fit(a, b, what, error)) return
    if (n <= small_n) then
      call general_lu(ipiv_s, iwork_s, work_s)
    else
      allocate(ipiv_h(n), iwork_h(n), work_h(4*n))
      call general_lu(ipiv_h, iwork_h, work_h)
    end if
  contains
    subroutine general_lu(ipiv, iwork, work)
      integer, intent(out), contiguous :: ipiv(:), iwork(:)
      real(dp), intent(out), contiguous :: work(:)
      integer :: info, j
      real(dp) :: anorm, rc
      anorm = 0.0_dp
      if (wants_estimate(estimate_condition)) then
        do j = 1, n
          anorm = max(anorm, sum(abs(a(:, j))))
        end do
      end if
      call dgetrf(n, n, a, n, ipiv, info)
      if (info > 0) then
        call fatal_error(error, what // ": matrix is singular (zero pivot " // str(info) // " of " // str(n) // ")")
        return
      else if (info < 0) then
        call fatal_error(error, what // ": dgetrf illegal argument " // str(-info))
        return
      end if
      if (wants_estimate(estimate_condition)) then
        call dgecon('1', n, a, n, anorm, rc, work, iwork, info)
      else
        rc = pivot_ratio(a)
      end if
      if (.not. well_conditioned(rc, what, error, rcond)) return
      call dgetrs('N', n, size(b, 2), a, n, ipiv, b, n, info)
      if (info /= 0) call fatal_error(error, what // ": dgetrs illegal argument " // str(-info))
    end subroutine general_lu
  end subroutine solve_general

  !> Solve A X = B for a symmetric positive-definite A (Cholesky, dpotrf/dpotrs).
  !> Only the upper triangle of A is read.  A matrix that is not positive
  !> definite, or whose reciprocal condition number is below `rcond_limit`, is
  !> an error naming `what`.  `estimate_condition` as for solve_general (the
  !> pivot ratio is then that of the Cholesky factor, squared).
  subroutine solve_spd(a, b, error, what, rcond, estimate_condition)
    real(dp), intent(inout), contiguous :: a(:, :)  !< n x n SPD matrix; on exit its Cholesky factor
    real(dp), intent(inout), contiguous :: b(:, :)  !< n x nrhs right-hand sides; on exit X
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    character(len=*), intent(in) :: what     !< name of the system, for the message
    real(dp), intent(out), optional :: rcond !< reciprocal condition number (1-norm)
    logical, intent(in), optional :: estimate_condition !< dpocon (default) or the pivot ratio
    integer :: iwork_s(small_n)
    real(dp) :: work_s(3*small_n)
    integer, allocatable :: iwork_h(:)
    real(dp), allocatable :: work_h(:)
    integer :: n
    n = size(a, 1)
    if (.not. shapes_fit(a, b, what, error)) return
    if (n <= small_n) then
      call cholesky(iwork_s, work_s)
    else
      allocate(iwork_h(n), work_h(3*n))
      call cholesky(iwork_h, work_h)
    end if
  contains
    subroutine cholesky(iwork, work)
      integer, intent(out), contiguous :: iwork(:)
      real(dp), intent(out), contiguous :: work(:)
      integer :: info, i, j
      real(dp) :: anorm, rc, col
      ! 1-norm of the symmetric matrix from its upper triangle
      anorm = 0.0_dp
      if (wants_estimate(estimate_condition)) then
        do i = 1, n
          col = 0.0_dp
          do j = 1, n
            col = col + abs(a(min(i, j), max(i, j)))
          end do
          anorm = max(anorm, col)
        end do
      end if
      call dpotrf('U', n, a, n, info)
      if (info > 0) then
        call fatal_error(error, what // ": matrix is not positive definite (leading minor " &
          // str(info) // " of " // str(n) // ")")
        return
      else if (info < 0) then
        call fatal_error(error, what // ": dpotrf illegal argument " // str(-info))
        return
      end if
      if (wants_estimate(estimate_condition)) then
        call dpocon('U', n, a, n, anorm, rc, work, iwork, info)
      else
        rc = pivot_ratio(a)**2
      end if
      if (.not. well_conditioned(rc, what, error, rcond)) return
      call dpotrs('U', n, size(b, 2), a, n, b, n, info)
      if (info /= 0) call fatal_error(error, what // ": dpotrs illegal argument " // str(-info))
    end subroutine cholesky
  end subroutine solve_spd

  !> A X = B needs a square A and as many rows in B: false (and an error
  !> naming `what`) if the shapes do not fit.
  logical function shapes_fit(a, b, what, error) result(ok)
    real(dp), intent(in) :: a(:, :), b(:, :)              !< matrix and right-hand sides
    character(len=*), intent(in) :: what                  !< name of the system
    type(error_type), allocatable, intent(inout) :: error !< set if the shapes do not fit
    ok = size(a, 2) == size(a, 1) .and. size(b, 1) == size(a, 1)
    if (.not. ok) call fatal_error(error, what // ": matrix is " // str(size(a, 1)) // "x" // &
      str(size(a, 2)) // " and right-hand side has " // str(size(b, 1)) // " rows")
  end function shapes_fit

  !> rc at or above rcond_limit; else false and an error naming `what`.  rc is
  !> also returned in `rcond` when the caller asked for it.
  logical function well_conditioned(rc, what, error, rcond) result(ok)
    real(dp), intent(in) :: rc                            !< reciprocal condition number (or pivot ratio)
    character(len=*), intent(in) :: what                  !< name of the system
    type(error_type), allocatable, intent(inout) :: error !< set if ill-conditioned
    real(dp), intent(out), optional :: rcond              !< the caller's copy of rc
    if (present(rcond)) rcond = rc
    ok = .not. (rc < rcond_limit)
    if (.not. ok) call fatal_error(error, what // ": matrix is ill-conditioned (rcond = " // str(rc) // ")")
  end function well_conditioned

  !> True unless the caller asked for the cheap conditioning check.
  pure logical function wants_estimate(estimate_condition)
    logical, intent(in), optional :: estimate_condition  !< the caller's choice
    wants_estimate = .true.
    if (present(estimate_condition)) wants_estimate = estimate_condition
  end function wants_estimate

  !> min |d_ii| / max |d_ii| of a triangular factor: a cheap indicator of
  !> near-singularity (an upper bound of the factor's reciprocal condition number).
  pure real(dp) function pivot_ratio(f) result(r)
    real(dp), intent(in) :: f(:, :)  !< square factor (its diagonal is read)
    integer :: i
    real(dp) :: dmin, dmax
    dmin = huge(1.0_dp)
    dmax = 0.0_dp
    do i = 1, size(f, 1)
      dmin = min(dmin, abs(f(i, i)))
      dmax = max(dmax, abs(f(i, i)))
    end do
    r = 0.0_dp
    if (dmax > 0.0_dp) r = dmin/dmax
  end function pivot_ratio

  !> Solve A X = B for a band matrix A with kl sub- and ku super-diagonals
  !> (LU with partial pivoting, dgbsv).  `ab` is in LAPACK band storage with
  !> 2*kl + ku + 1 rows: A(i, j) = ab(kl + ku + 1 + i - j, j); on exit the factors.
  subroutine solve_banded(ab, kl, ku, b, error, what)
    real(dp), intent(inout) :: ab(:, :)      !< (2 kl + ku + 1) x n band storage
    integer, intent(in) :: kl, ku            !< lower and upper bandwidths
    real(dp), intent(inout) :: b(:, :)       !< n x nrhs right-hand sides; on exit X
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    character(len=*), intent(in) :: what     !< name of the system, for the message
    integer :: n, info, ipiv(size(ab, 2))
    n = size(ab, 2)
    if (size(ab, 1) /= 2*kl + ku + 1 .or. size(b, 1) /= n) then
      call fatal_error(error, what // ": band storage has " // str(size(ab, 1)) // " rows for kl = " // &
        str(kl) // ", ku = " // str(ku) // " and the right-hand side " // str(size(b, 1)) // " rows for n = " // str(n))
      return
    end if
    call dgbsv(n, kl, ku, size(b, 2), ab, size(ab, 1), ipiv, b, n, info)
    if (info > 0) then
      call fatal_error(error, what // ": matrix is singular (zero pivot " // str(info) // " of " // str(n) // ")")
    else if (info < 0) then
      call fatal_error(error, what // ": dgbsv illegal argument " // str(-info))
    end if
  end subroutine solve_banded
end module airlaunch_linalg
