!> One BLAS thread: after use_one_blas_thread the process runs a single thread
!> (OpenBLAS starts a worker per core when it is loaded; its idle workers spin,
!> src/solver/airlaunch_blas_threads.c), and LAPACK still solves afterwards.
!> Reference: the thread count of the process in /proc/self/status (Linux).
program test_blas_threads
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type
  use airlaunch_linalg, only: solve_spd
  use airlaunch_strings, only: str
  use airlaunch_blas_threads, only: use_one_blas_thread
  use testing
  implicit none
  type(error_type), allocatable :: error
  character(len=64) :: user
  integer :: before, after, status
  real(dp) :: a(3, 3), b(3, 1)

  call get_environment_variable("OPENBLAS_NUM_THREADS", user, status=status)
  if (status == 0 .and. len_trim(user) > 0 .and. trim(user) /= "1") then
    ! the user's explicit choice is left alone by design: nothing to test
    write(*, '(a)') "OPENBLAS_NUM_THREADS = " // trim(user) // " is set: skipped"
    call finish()
    stop
  end if

  call section("worker threads")
  before = thread_count()
  call use_one_blas_thread()
  after = thread_count()
  write(*, '(a)') "  threads before: " // str(before) // " (OpenBLAS starts one per core unless told), after: " // &
    str(after)
  call check(before >= 1, "the thread count is readable from /proc/self/status")
  call check(after == 1, "one thread after use_one_blas_thread: got " // str(after))

  call section("LAPACK afterwards")
  ! the 1-D Laplacian (SPD, tridiagonal 2, -1): A x = (1, 0, 1) has x = (1, 1, 1)
  a = reshape([2.0_dp, -1.0_dp, 0.0_dp, -1.0_dp, 2.0_dp, -1.0_dp, 0.0_dp, -1.0_dp, 2.0_dp], [3, 3])
  b(:, 1) = [1.0_dp, 0.0_dp, 1.0_dp]
  call solve_spd(a, b, error, "Laplacian after the shutdown")
  call check(.not. allocated(error), "solves without error")
  call check(maxval(abs(b(:, 1) - 1.0_dp)) < 1e-14_dp, "recovers x = (1, 1, 1) to round-off")
  call check(thread_count() == 1, "still one thread after a LAPACK call")
  call finish()

contains

  !> Threads of this process ("Threads:" in /proc/self/status), -1 if unreadable.
  integer function thread_count() result(n)
    integer :: u, ios
    character(len=256) :: line
    n = -1
    open(newunit=u, file="/proc/self/status", status="old", action="read", iostat=ios)
    if (ios /= 0) return
    do
      read(u, '(a)', iostat=ios) line
      if (ios /= 0) exit
      if (line(1:8) == "Threads:") then
        read(line(9:), *, iostat=ios) n
        exit
      end if
    end do
    close(u)
  end function thread_count
end program test_blas_threads
