!> A SUNDIALS linear solver that factors CVODE's band Newton matrix with LAPACK
!> (dgbtrf/dgbtrs, OpenBLAS here).  Debian's SUNDIALS has no LAPACK band solver;
!> its own band LU (SUNDlsMat_bandGBTRF/GBTRS) took a third of the paper
!> scenario's run time (docs/performance.md).  SUNDIALS' band storage is
!> LAPACK's: column j holds A(i, j) at row smu + 1 + i - j with smu = mu + ml
!> and leading dimension smu + ml + 1 = 2 ml + mu + 1, so the matrix data is
!> factored in place.
module airlaunch_lapack_band
  use, intrinsic :: iso_c_binding
  use fsundials_context_mod
  use fsundials_linearsolver_mod
  use fsundials_matrix_mod
  use fsundials_nvector_mod
  use fnvector_serial_mod
  use fsunmatrix_band_mod
  implicit none
  private
  public :: new_lapack_band_solver, dgbtrf, dgbtrs

  !> What the solver keeps between setup and solve.
  type :: band_content
    integer :: n = 0, ml = 0, mu = 0, ldab = 0
    integer, allocatable :: ipiv(:)
    integer(c_long) :: last_flag = 0
  end type band_content

  interface
    subroutine dgbtrf(m, n, kl, ku, ab, ldab, ipiv, info)
      import :: c_double
      integer, intent(in) :: m, n, kl, ku, ldab
      real(c_double), intent(inout) :: ab(ldab, *)
      integer, intent(out) :: ipiv(*), info
    end subroutine dgbtrf
    subroutine dgbtrs(trans, n, kl, ku, nrhs, ab, ldab, ipiv, b, ldb, info)
      import :: c_double
      character, intent(in) :: trans
      integer, intent(in) :: n, kl, ku, nrhs, ldab, ldb, ipiv(*)
      real(c_double), intent(in) :: ab(ldab, *)
      real(c_double), intent(inout) :: b(ldb, *)
      integer, intent(out) :: info
    end subroutine dgbtrs
  end interface

contains

  !> A direct linear solver for CVODE with a band matrix A (FSUNBandMatrix).
  function new_lapack_band_solver(a, ctx) result(ls)
    type(SUNMatrix), intent(inout) :: a     !< the band matrix CVODE will fill
    type(c_ptr), intent(in) :: ctx          !< SUNDIALS context
    type(SUNLinearSolver), pointer :: ls
    type(SUNLinearSolver_Ops), pointer :: ops
    type(band_content), pointer :: c
    ls => FSUNLinSolNewEmpty(ctx)
    call c_f_pointer(ls%ops, ops)
    ops%gettype = c_funloc(band_gettype)
    ops%setup = c_funloc(band_setup)
    ops%solve = c_funloc(band_solve)
    ops%lastflag = c_funloc(band_lastflag)
    ops%free = c_funloc(band_free)
    allocate(c)
    c%n = int(FSUNBandMatrix_Columns(a))
    c%ml = int(FSUNBandMatrix_LowerBandwidth(a))
    c%mu = int(FSUNBandMatrix_UpperBandwidth(a))
    c%ldab = int(FSUNBandMatrix_LDim(a))
    allocate(c%ipiv(c%n))
    ls%content = c_loc(c)
  end function new_lapack_band_solver

  integer(c_int) function band_gettype(s) result(t) bind(C)
    type(SUNLinearSolver) :: s
    t = SUNLINEARSOLVER_DIRECT
    if (.false.) t = int(merge(1, 0, c_associated(s%content)), c_int)
  end function band_gettype

  !> LU factorisation in place (dgbtrf); a zero pivot is a recoverable failure
  !> (CVODE retries with a smaller step).
  integer(c_int) function band_setup(s, a) result(ierr) bind(C)
    type(SUNLinearSolver) :: s
    type(SUNMatrix) :: a
    type(band_content), pointer :: c
    real(c_double), pointer :: ab(:)
    integer :: info
    call c_f_pointer(s%content, c)
    ab => FSUNBandMatrix_Data(a)
    call dgbtrf(c%n, c%n, c%ml, c%mu, ab, c%ldab, c%ipiv, info)
    c%last_flag = int(info, c_long)
    ierr = SUNLS_SUCCESS
    if (info > 0) ierr = SUNLS_LUFACT_FAIL
  end function band_setup

  !> x = A^-1 b from the factors (dgbtrs).
  integer(c_int) function band_solve(s, a, x, b, tol) result(ierr) bind(C)
    type(SUNLinearSolver) :: s
    type(SUNMatrix) :: a
    type(N_Vector) :: x, b
    real(c_double), value :: tol
    type(band_content), pointer :: c
    real(c_double), pointer :: ab(:), xd(:), bd(:)
    integer :: info
    call c_f_pointer(s%content, c)
    ab => FSUNBandMatrix_Data(a)
    xd => FN_VGetArrayPointer(x)
    bd => FN_VGetArrayPointer(b)
    xd = bd
    call dgbtrs('N', c%n, c%ml, c%mu, 1, ab, c%ldab, c%ipiv, xd, c%n, info)
    c%last_flag = int(info, c_long)
    ierr = SUNLS_SUCCESS
    if (info /= 0) ierr = SUNLS_PACKAGE_FAIL_UNREC
    if (.false.) xd(1) = tol
  end function band_solve

  integer(c_long) function band_lastflag(s) result(f) bind(C)
    type(SUNLinearSolver) :: s
    type(band_content), pointer :: c
    call c_f_pointer(s%content, c)
    f = c%last_flag
  end function band_lastflag

  integer(c_int) function band_free(s) result(ierr) bind(C)
    type(SUNLinearSolver) :: s
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
