!> Dynamic load balancing of the sweep's cases over MPI ranks: a shared
!> counter in an MPI window on rank 0, taken with MPI_Fetch_and_op (passive
!> target, no master loop), so every rank - rank 0 included - computes cases
!> and takes the next one the moment it is free.  Two more counters (cases
!> done, cases failed) let rank 0 report progress; a stop flag lets any rank
!> end the pass (a file error): no rank takes a new case after it is set.
!>
!> With Open MPI on one node the window lives in shared memory (osc/sm) and
!> the atomics never wait for rank 0.  On a cluster the osc/ucx or osc/rdma
!> component gives the same; a component that needs the target's progress
!> (osc/pt2pt) still works but a rank may wait for rank 0 to finish its case.
module airlaunch_sweep_scheduler
  use, intrinsic :: iso_c_binding, only: c_ptr, c_f_pointer, c_int
  use mpi_f08
  use airlaunch_error, only: error_type, fatal_error
  implicit none
  private
  public :: sweep_scheduler

  integer, parameter :: slot_next = 0, slot_done = 1, slot_failed = 2, slot_stop = 3, n_slots = 4

  !> The shared counters of one pass over a list of cases.
  type :: sweep_scheduler
    type(MPI_Comm) :: comm
    type(MPI_Win) :: win
    integer :: rank = 0
    integer :: size = 1
    logical :: active = .false.
  contains
    procedure :: init => sched_init
    procedure :: next => sched_next
    procedure :: finished => sched_finished
    procedure :: counts => sched_counts
    procedure :: stop => sched_stop
    procedure :: stopped => sched_stopped
    procedure :: free => sched_free
  end type sweep_scheduler

contains

  !> Collective: create the counters (all zero) on rank 0 of `comm`.
  subroutine sched_init(self, comm, error)
    class(sweep_scheduler), intent(inout) :: self
    type(MPI_Comm), intent(in) :: comm                    !< communicator of the sweep
    type(error_type), allocatable, intent(inout) :: error !< set if MPI fails
    integer(MPI_ADDRESS_KIND) :: bytes
    type(c_ptr) :: base
    integer(c_int), pointer :: slots(:)
    integer :: ierr
    self%comm = comm
    call MPI_Comm_rank(comm, self%rank)
    call MPI_Comm_size(comm, self%size)
    bytes = 0
    if (self%rank == 0) bytes = 4*n_slots
    call MPI_Win_allocate(bytes, 4, MPI_INFO_NULL, comm, base, self%win, ierr)
    if (ierr /= MPI_SUCCESS) then
      call fatal_error(error, "MPI_Win_allocate failed: cannot share the case counter")
      return
    end if
    if (self%rank == 0) then
      call c_f_pointer(base, slots, [n_slots])
      slots = 0
    end if
    call MPI_Barrier(comm)
    call MPI_Win_lock_all(0, self%win)
    self%active = .true.
  end subroutine sched_init

  !> Take the next position in the list of cases (0, 1, 2, ... over all ranks);
  !> huge(0) once a rank has called `stop`.
  subroutine sched_next(self, position)
    class(sweep_scheduler), intent(inout) :: self
    integer, intent(out) :: position   !< 0-based position; >= list size means no work left
    if (self%stopped()) then
      position = huge(0)
      return
    end if
    call fetch_add(self, slot_next, 1, position)
  end subroutine sched_next

  !> End the pass for every rank: no case is taken after this (the cases in
  !> flight on the other ranks finish).
  subroutine sched_stop(self)
    class(sweep_scheduler), intent(inout) :: self
    integer :: old
    call fetch_add(self, slot_stop, 1, old)
  end subroutine sched_stop

  !> True once a rank has called `stop`.
  logical function sched_stopped(self)
    class(sweep_scheduler), intent(inout) :: self
    integer :: dummy, flag
    dummy = 0
    call MPI_Fetch_and_op(dummy, flag, MPI_INTEGER, 0, int(slot_stop, MPI_ADDRESS_KIND), MPI_NO_OP, self%win)
    call MPI_Win_flush(0, self%win)
    sched_stopped = flag > 0
  end function sched_stopped

  !> Count a finished case (and a failure).
  subroutine sched_finished(self, failed)
    class(sweep_scheduler), intent(inout) :: self
    logical, intent(in) :: failed   !< the case did not end ok
    integer :: old
    call fetch_add(self, slot_done, 1, old)
    if (failed) call fetch_add(self, slot_failed, 1, old)
  end subroutine sched_finished

  !> Cases finished and failed so far, over all ranks.
  subroutine sched_counts(self, done, failed)
    class(sweep_scheduler), intent(inout) :: self
    integer, intent(out) :: done, failed   !< counters
    integer :: dummy
    dummy = 0
    call MPI_Fetch_and_op(dummy, done, MPI_INTEGER, 0, int(slot_done, MPI_ADDRESS_KIND), MPI_NO_OP, self%win)
    call MPI_Fetch_and_op(dummy, failed, MPI_INTEGER, 0, int(slot_failed, MPI_ADDRESS_KIND), MPI_NO_OP, self%win)
    call MPI_Win_flush(0, self%win)
  end subroutine sched_counts

  !> Collective: release the counters.
  subroutine sched_free(self)
    class(sweep_scheduler), intent(inout) :: self
    if (.not. self%active) return
    call MPI_Win_unlock_all(self%win)
    call MPI_Win_free(self%win)
    self%active = .false.
  end subroutine sched_free

  subroutine fetch_add(self, slot, inc, old)
    type(sweep_scheduler), intent(inout) :: self
    integer, intent(in) :: slot, inc
    integer, intent(out) :: old
    call MPI_Fetch_and_op(inc, old, MPI_INTEGER, 0, int(slot, MPI_ADDRESS_KIND), MPI_SUM, self%win)
    call MPI_Win_flush(0, self%win)
  end subroutine fetch_add
end module airlaunch_sweep_scheduler
