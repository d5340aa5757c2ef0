!> Errors as values: library code fills an error_type and returns; only the
!> programs in src/app report it (tblite's pattern, STYLE.md habit 4).
module airlaunch_error
  use airlaunch_kinds, only: dp
  implicit none
  private
  public :: error_type, fatal_error, has_error, refuse_records

  !> An error: a one-line message for the user.
  type :: error_type
    character(len=:), allocatable :: message
    !> the input asks for what cannot be done (found only once the run is set
    !> up, e.g. more trajectory records than memory holds): the program
    !> reports it as bad input (exit 2), not as a numerical failure
    logical :: input = .false.
  end type error_type

contains

  !> Allocate `error` with `message`.
  subroutine fatal_error(error, message, input)
    type(error_type), allocatable, intent(inout) :: error  !< error to raise
    character(len=*), intent(in) :: message               !< what went wrong
    logical, intent(in), optional :: input                !< an input error (error_type%input)
    if (allocated(error)) deallocate(error)
    allocate(error)
    error%message = message
    if (present(input)) error%input = input
  end subroutine fatal_error

  !> The trajectory's records could not be allocated: an input error naming
  !> &run output_dt, the record count and the memory they need.
  subroutine refuse_records(error, output_dt, records, bytes)
    type(error_type), allocatable, intent(inout) :: error  !< error to raise
    real(dp), intent(in) :: output_dt             !< &run output_dt [s]
    integer, intent(in) :: records                         !< records asked for
    real(dp), intent(in) :: bytes                 !< their memory [bytes]
    character(len=64) :: a, b, c
    write(a, '(es10.3)') output_dt
    write(b, '(i0)') records
    write(c, '(i0)') nint(min(bytes/1.0e6_dp, 1.0e15_dp), kind=8)
    call fatal_error(error, "&run: output_dt = " // trim(adjustl(a)) // " is not allowed here: the trajectory's " // &
      trim(b) // " records need " // trim(c) // " MB, more than can be allocated (raise output_dt, or set " // &
      "trajectory = .false.)", input=.true.)
  end subroutine refuse_records

  !> True if `error` holds an error.
  logical pure function has_error(error)
    type(error_type), allocatable, intent(in) :: error  !< error to test
    has_error = allocated(error)
  end function has_error
end module airlaunch_error
