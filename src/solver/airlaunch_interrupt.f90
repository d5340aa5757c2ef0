!> When a run stops before its end on the user's behalf: a request to stop
!> (SIGINT, SIGTERM; below) and the wall clock of the integrators' wall-time
!> budget (&run max_wall_time, wall_clock).
!>
!> A request to stop the run (SIGINT, SIGTERM): caught by the program that
!> asks for it (catch_interrupts: airlaunch_main only) and polled by the
!> integrators between their steps (interrupt_signal), which then return an
!> error marked with the signal (interrupted_error); the scene writes its
!> output so far with status "interrupted" and the program exits 128 + the
!> signal.  The caught signal is the process's (a C variable set by the
!> handler, airlaunch_interrupt.c), not the physics' state: a program that does
!> not catch interrupts always polls 0.
module airlaunch_interrupt
  use, intrinsic :: iso_c_binding, only: c_int
  use airlaunch_kinds, only: dp, i8
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  implicit none
  private
  public :: catch_interrupts, interrupt_signal, interrupted_error, signal_name, wall_clock

  interface
    !> Catch SIGINT and SIGTERM from now on (once each: a second one ends the process).
    subroutine catch_interrupts() bind(c, name="airlaunch_catch_interrupts")
      implicit none
    end subroutine catch_interrupts
    !> The signal caught so far (0: none).
    integer(c_int) function c_interrupt_signal() bind(c, name="airlaunch_interrupt_signal")
      import :: c_int
      implicit none
    end function c_interrupt_signal
    integer(c_int) function c_sigint() bind(c, name="airlaunch_sigint")
      import :: c_int
      implicit none
    end function c_sigint
    integer(c_int) function c_sigterm() bind(c, name="airlaunch_sigterm")
      import :: c_int
      implicit none
    end function c_sigterm
  end interface

contains

  !> The signal caught so far (0: none, or interrupts not caught).
  integer function interrupt_signal()
    interrupt_signal = int(c_interrupt_signal())
  end function interrupt_signal

  !> A monotonic wall clock [s] (system_clock's 64-bit count: the
  !> integrators' wall-time budget, &run max_wall_time).
  real(dp) function wall_clock()
    integer(i8) :: count, rate
    call system_clock(count, rate)
    wall_clock = real(count, dp)/real(rate, dp)
  end function wall_clock

  !> "SIGINT", "SIGTERM", or "signal N".
  function signal_name(signo) result(name)
    integer, intent(in) :: signo
    character(len=:), allocatable :: name
    if (signo == int(c_sigint())) then
      name = "SIGINT"
    else if (signo == int(c_sigterm())) then
      name = "SIGTERM"
    else
      name = "signal " // str(signo)
    end if
  end function signal_name

  !> The error of an integrator that stopped at time t [s] for a caught signal.
  subroutine interrupted_error(error, signo, t)
    type(error_type), allocatable, intent(inout) :: error
    integer, intent(in) :: signo
    real(dp), intent(in) :: t
    call fatal_error(error, "interrupted by " // signal_name(signo) // " at t = " // str(t) // " s")
    error%signal = signo
  end subroutine interrupted_error
end module airlaunch_interrupt
