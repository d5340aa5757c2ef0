!> Minimal assertion helpers for the unit-test programs: each check prints one
!> line with the compared values and the tolerance, and `finish` ends the
!> program with a nonzero status if any check failed.
module testing
  use airlaunch_kinds, only: dp
  use airlaunch_strings, only: str
  implicit none
  private
  public :: check, check_close, finish, section, fixed_seed, paper_input, diag3, random_vector

  integer, save :: n_pass = 0, n_fail = 0

contains

  !> The 3x3 diagonal matrix diag(a, b, c) (a principal inertia tensor).
  pure function diag3(a, b, c) result(j)
    real(dp), intent(in) :: a, b, c
    real(dp) :: j(3, 3)
    j = 0.0_dp
    j(1, 1) = a; j(2, 2) = b; j(3, 3) = c
  end function diag3

  !> A random 3-vector, each component uniform in [-scale, scale].
  function random_vector(scale) result(v)
    real(dp), intent(in) :: scale
    real(dp) :: v(3)
    call random_number(v)
    v = scale*(2*v - 1)
  end function random_vector

  !> Seed the random numbers of a test with a fixed sequence: the same states
  !> in every run (gfortran seeds each run differently otherwise), so a test
  !> cannot pass or fail by the draw.
  subroutine fixed_seed()
    integer :: n, i
    call random_seed(size=n)
    call random_seed(put=[(12345 + 7*i, i = 1, n)])
  end subroutine fixed_seed

  !> The paper's input: $AIRLAUNCH_SOURCE_DIR/input/airlaunch_paper.nml (set by
  !> ctest), else relative to the working directory.
  function paper_input() result(p)
    character(len=:), allocatable :: p
    character(len=4096) :: dir
    integer :: n, stat
    call get_environment_variable("AIRLAUNCH_SOURCE_DIR", dir, n, stat)
    if (stat == 0 .and. n > 0) then
      p = trim(dir) // "/input/airlaunch_paper.nml"
    else
      p = "input/airlaunch_paper.nml"
    end if
  end function paper_input

  !> Print a heading.
  subroutine section(name)
    character(len=*), intent(in) :: name
    write(*, '(a)') "== " // name
  end subroutine section

  !> Assert a condition.
  subroutine check(cond, what)
    logical, intent(in) :: cond
    character(len=*), intent(in) :: what
    if (cond) then
      n_pass = n_pass + 1
      write(*, '(a)') "  ok    " // what
    else
      n_fail = n_fail + 1
      write(*, '(a)') "  FAIL  " // what
    end if
  end subroutine check

  !> Assert |actual - expected| <= max(abs_tol, rel_tol*|expected|).
  subroutine check_close(actual, expected, what, rel, abs)
    real(dp), intent(in) :: actual, expected
    character(len=*), intent(in) :: what
    real(dp), intent(in), optional :: rel, abs
    real(dp) :: tol, r, a
    r = 0.0_dp; a = 0.0_dp
    if (present(rel)) r = rel
    if (present(abs)) a = abs
    tol = max(a, r*abs_(expected))
    call check(abs_(actual - expected) <= tol .and. actual == actual, what // ": got " // str(actual) &
      // ", expected " // str(expected) // " (tol " // str(tol) // ")")
  contains
    pure real(dp) function abs_(x)
      real(dp), intent(in) :: x
      abs_ = merge(x, -x, x >= 0.0_dp)
    end function abs_
  end subroutine check_close

  !> Summary line; nonzero exit if anything failed.
  subroutine finish()
    write(*, '(a)') str(n_pass) // " passed, " // str(n_fail) // " failed"
    if (n_fail > 0) error stop 1
  end subroutine finish
end module testing
