!> Errors as values: library code fills an error_type and returns; only the
!> programs in src/app report it (tblite's pattern, STYLE.md habit 4).
module airlaunch_error
  implicit none
  private
  public :: error_type, fatal_error, has_error, add_output_error, output_failure_note, run_status

  !> An error: a one-line message for the user.
  type :: error_type
    character(len=:), allocatable :: message
    !> the input asks for what cannot be done (found only once the run is set
    !> up, e.g. more trajectory records than memory holds): the program
    !> reports it as bad input (exit 2), not as a numerical failure
    logical :: input = .false.
    !> the run's output file could not be written (a full disk, an I/O
    !> error): the program reports it apart from a failure of the run itself
    logical :: output = .false.
    !> the run was interrupted by this signal (SIGINT, SIGTERM: airlaunch_interrupt);
    !> 0: not.  The program exits 128 + it after writing the output so far
    integer :: signal = 0
  end type error_type

  !> What add_output_error adds to a run's error (airlaunch_main looks for it).
  character(len=*), parameter :: output_failure_note = "; its output so far could not be written either: "

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

  !> The error a run reports once its output's writer has finished
  !> (`output_error`, consumed): the run's own failure, which then says that
  !> its output could not be written either, or, after a completed run, the
  !> writer's error.
  subroutine add_output_error(run_error, output_error)
    type(error_type), allocatable, intent(inout) :: run_error     !< the run's failure, if any
    type(error_type), allocatable, intent(inout) :: output_error  !< the writer's, if any
    if (.not. allocated(output_error)) return
    if (allocated(run_error)) then
      run_error%message = run_error%message // output_failure_note // output_error%message
      deallocate(output_error)
    else
      call move_alloc(output_error, run_error)
    end if
  end subroutine add_output_error

  !> A run's status for its output: "completed" (no error), "interrupted" (a
  !> caught signal, error%signal) or "failed".
  pure function run_status(error) result(status)
    type(error_type), allocatable, intent(in) :: error  !< the run's error, if any
    character(len=:), allocatable :: status
    status = "completed"
    if (.not. allocated(error)) return
    status = "failed"
    if (error%signal /= 0) status = "interrupted"
  end function run_status

  !> True if `error` holds an error.
  logical pure function has_error(error)
    type(error_type), allocatable, intent(in) :: error  !< error to test
    has_error = allocated(error)
  end function has_error
end module airlaunch_error
