!> Errors as values: library code fills an error_type and returns; only the
!> programs in src/app report it (tblite's pattern, STYLE.md habit 4).
module airlaunch_error
  implicit none
  private
  public :: error_type, fatal_error, has_error, note_output_failure, output_failure_note

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
  end type error_type

  !> What note_output_failure adds to a run's error (airlaunch_main looks for it).
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

  !> A run that failed and whose output could not be written either: the
  !> run's error, the one reported, says so too (nothing else is left of the
  !> output's error).
  subroutine note_output_failure(run_error, output_error)
    type(error_type), allocatable, intent(inout) :: run_error  !< the run's failure
    type(error_type), intent(in) :: output_error              !< the writer's
    if (.not. allocated(run_error)) return
    run_error%message = run_error%message // output_failure_note // output_error%message
  end subroutine note_output_failure

  !> True if `error` holds an error.
  logical pure function has_error(error)
    type(error_type), allocatable, intent(in) :: error  !< error to test
    has_error = allocated(error)
  end function has_error
end module airlaunch_error
