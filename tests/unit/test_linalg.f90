!> LAPACK wrappers against systems with known solutions, and the errors for
!> singular, ill-conditioned and indefinite matrices.
program test_linalg
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type
  use airlaunch_linalg
  use testing
  implicit none
  type(error_type), allocatable :: error
  real(dp) :: a(3, 3), x(3, 1), b(3, 1), h(12, 12), hb(12, 1), s(4, 4), sb(4, 1), xs(4), rc
  integer :: i, j

  call section("general solve")
  a = reshape([4.0_dp, -2.0_dp, 1.0_dp, 3.0_dp, 6.0_dp, -4.0_dp, 2.0_dp, 1.0_dp, 8.0_dp], [3, 3])
  x(:, 1) = [1.0_dp, -2.0_dp, 0.5_dp]
  b = matmul(a, x)
  call solve_general(a, b, error, "test 3x3")
  call check(.not. allocated(error), "no error for a well-conditioned matrix")
  call check(maxval(abs(b - x)) < 1e-14_dp, "recovers the solution to round-off")

  call section("singular and ill-conditioned")
  a = reshape([1.0_dp, 2.0_dp, 3.0_dp, 2.0_dp, 4.0_dp, 6.0_dp, 0.0_dp, 1.0_dp, 1.0_dp], [3, 3])
  b = 1
  call solve_general(a, b, error, "rank-2 matrix")
  call check(allocated(error), "a rank-deficient matrix is an error")
  if (allocated(error)) call check(index(error%message, "rank-2 matrix") == 1, "message names the system: " // error%message)
  deallocate(error)
  do j = 1, 12
    do i = 1, 12
      h(i, j) = 1.0_dp/(i + j - 1)   ! Hilbert matrix, cond ~ 1.6e16 at n = 12
    end do
  end do
  hb = 1
  call solve_general(h, hb, error, "Hilbert-12", rcond=rc)
  call check(allocated(error), "Hilbert(12) is reported ill-conditioned (rcond " // trim(fmt(rc)) // ")")
  if (allocated(error)) deallocate(error)

  call section("symmetric positive definite")
  s = reshape([4.0_dp, 1.0_dp, 0.5_dp, 0.0_dp, 1.0_dp, 3.0_dp, 0.2_dp, 0.1_dp, &
               0.5_dp, 0.2_dp, 2.0_dp, 0.3_dp, 0.0_dp, 0.1_dp, 0.3_dp, 1.5_dp], [4, 4])
  xs = [1.0_dp, 2.0_dp, -1.0_dp, 0.25_dp]
  sb(:, 1) = matmul(s, xs)
  call solve_spd(s, sb, error, "SPD 4x4")
  call check(.not. allocated(error), "no error for an SPD matrix")
  call check(maxval(abs(sb(:, 1) - xs)) < 1e-14_dp, "Cholesky solve recovers the solution")
  s = 0; s(1, 1) = 1; s(2, 2) = -1; s(3, 3) = 1; s(4, 4) = 1
  call solve_spd(s, sb, error, "indefinite")
  call check(allocated(error), "an indefinite matrix is an error")
  if (allocated(error)) deallocate(error)

  call section("cheap conditioning check (right-hand sides): pivot ratio")
  ! the pivot ratio of a triangular factor is an upper bound of its rcond: a
  ! well-conditioned system passes, a graded near-singular one (pivots 1 and
  ! 1e-16) is rejected like dgecon would, and the solution is unchanged
  a = reshape([4.0_dp, -2.0_dp, 1.0_dp, 3.0_dp, 6.0_dp, -4.0_dp, 2.0_dp, 1.0_dp, 8.0_dp], [3, 3])
  x(:, 1) = [1.0_dp, -2.0_dp, 0.5_dp]
  b = matmul(a, x)
  call solve_general(a, b, error, "test 3x3", rcond=rc, estimate_condition=.false.)
  call check(.not. allocated(error) .and. maxval(abs(b - x)) < 1e-14_dp, "well-conditioned: solved")
  call check(rc > 0.1_dp .and. rc <= 1.0_dp, "pivot ratio of order one (" // trim(fmt(rc)) // ")")
  a = 0; a(1, 1) = 1; a(2, 2) = 1e-16_dp; a(3, 3) = 1; b = 1
  call solve_general(a, b, error, "graded", estimate_condition=.false.)
  call check(allocated(error), "near-singular general matrix rejected")
  if (allocated(error)) deallocate(error)
  s = 0; s(1, 1) = 1; s(2, 2) = 1e-20_dp; s(3, 3) = 1; s(4, 4) = 1; sb = 1
  call solve_spd(s, sb, error, "graded SPD", rcond=rc, estimate_condition=.false.)
  call check(allocated(error), "near-singular SPD matrix rejected (rcond " // trim(fmt(rc)) // ")")
  call finish()
contains
  function fmt(v) result(t)
    real(dp), intent(in) :: v
    character(len=24) :: t
    write(t, '(es10.3)') v
  end function fmt
end program test_linalg
