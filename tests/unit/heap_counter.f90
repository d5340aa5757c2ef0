!> The heap-allocation counter of tests/unit/malloc_counter.c for the Fortran
!> tests that are linked with it (test_rhs_allocations, test_line_step_allocations).
module heap_counter
  use, intrinsic :: iso_c_binding, only: c_int64_t
  use airlaunch_kinds, only: dp
  use airlaunch_strings, only: str
  use testing, only: check, section
  implicit none
  private
  public :: heap_allocations, check_counter_sees_allocation

  interface
    !> malloc + calloc + realloc calls of the process so far (malloc_counter.c).
    integer(c_int64_t) function heap_allocations() bind(C, name="airlaunch_test_heap_allocations")
      import :: c_int64_t
    end function heap_allocations
  end interface

contains

  !> Positive control: the counter sees an ordinary allocate.
  subroutine check_counter_sees_allocation()
    integer(c_int64_t) :: before
    real(dp), allocatable :: probe(:)
    call section("the counter sees an allocation (positive control)")
    before = heap_allocations()
    allocate(probe(command_argument_count() + 1000))
    probe = 1.0_dp
    call check(heap_allocations() > before, "allocate(probe(1000)) counted: " // &
      str(int(heap_allocations() - before)) // " allocation(s), sum " // str(sum(probe)))
  end subroutine check_counter_sees_allocation
end module heap_counter
