!> The specification: a time step allocates nothing (issue 7: no allocation in
!> right-hand sides; the same holds for what CVODE calls every step: the line's
!> forces, the difference-quotient Jacobian, the velocity-reduced band solver's
!> setup and solve).
!>
!> Issue 7's cable pendulum (60 m, EA 2 MN, 0.5 kg/m, 50 kg end mass, released
!> horizontal; N = 20, with and without air, and with the mixed mass matrix:
!> its tridiagonal solve in every right-hand side) is advanced
!> by the default scheme to t = 0.5 s (set-up and first Jacobians), the process's
!> heap allocations are counted (tests/unit/malloc_counter.c replaces malloc,
!> calloc and realloc), the line advanced to t = 2 s (hundreds of steps, each
!> with force evaluations and linear solves, several Jacobians and
!> factorizations; the line goes slack and taut), and the count must not have
!> changed.  A positive control first shows that the counter sees an allocation.
program test_line_step_allocations
  use, intrinsic :: iso_c_binding, only: c_int64_t
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type
  use airlaunch_strings, only: str
  use airlaunch_line
  use testing
  use heap_counter, only: heap_allocations, check_counter_sees_allocation
  implicit none

  call check_counter_sees_allocation()

  call steps_allocate_nothing(.false., "lumped")
  call steps_allocate_nothing(.true., "lumped")
  call steps_allocate_nothing(.true., "mixed")
  call finish()

contains

  subroutine steps_allocate_nothing(air, mass)
    logical, intent(in) :: air                      !< drag on (wind 30 m/s across the line)
    character(len=*), intent(in) :: mass            !< mass matrix
    integer, parameter :: n = 20
    real(dp), parameter :: length = 60.0_dp
    type(line_model) :: model
    class(line_scheme), allocatable :: scheme
    type(line_scheme_options) :: opts
    type(line_scheme_stats) :: s1, s2
    type(error_type), allocatable :: error
    real(dp) :: x(3, 0:n), v(3, 0:n)
    integer(c_int64_t) :: count0, count1
    integer :: k

    call section("pendulum N = " // str(n) // merge(", air   ", ", no air", air) // ", " // mass // " mass")
    call model%init(line_params(length=length, n_seg=n, ea=2.0e6_dp, mass_per_length=0.5_dp, damping=0.0_dp, &
      gravity=.true., air=air, air_density=merge(1.2_dp, 0.0_dp, air), wind=[0.0_dp, 0.0_dp, 30.0_dp], &
      mass=mass), error)
    call check(.not. allocated(error), "line model")
    if (allocated(error)) return
    do k = 0, n
      x(:, k) = [length*k/n, 0.0_dp, 0.0_dp]
    end do
    v = 0.0_dp
    opts%scheme = "cvode"
    opts%rtol = 1.0e-5_dp
    opts%atol = 1.0e-5_dp
    call new_line_scheme(scheme, model, line_end(kind=end_fixed, position=x(:, 0)), &
      line_end(kind=end_point_mass, mass=50.0_dp, position=x(:, n)), x, v, 0.0_dp, opts, error)
    call check(.not. allocated(error), "scheme created")
    if (allocated(error)) return
    call scheme%advance(0.5_dp, error)
    call check(.not. allocated(error), "warm-up to t = 0.5 s")
    s1 = scheme%stats()
    count0 = heap_allocations()
    call scheme%advance(2.0_dp, error)
    count1 = heap_allocations()   ! before any message is built
    s2 = scheme%stats()
    call check(.not. allocated(error), "advanced to t = 2 s")
    call check(s2%steps - s1%steps >= 100 .and. s2%jac_evals > s1%jac_evals, "work done: " // &
      str(int(s2%steps - s1%steps)) // " steps, " // str(int(s2%rhs_evals - s1%rhs_evals)) // &
      " force evaluations, " // str(int(s2%jac_evals - s1%jac_evals)) // " Jacobians")
    call check(count1 == count0, "no heap allocation in those steps: " // str(int(count1 - count0)))
    call scheme%get_state(x, v)
    call check(all(abs(x) <= 1.0e3_dp), "state finite and bounded")
    call scheme%free()
  end subroutine steps_allocate_nothing
end program test_line_step_allocations
