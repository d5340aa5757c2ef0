!> airlaunch-sweep: run the cases of a sweep under MPI (docs/sweep.md).
!>
!>   mpirun -np K airlaunch-sweep SWEEP.nml [--restart]
!>   airlaunch-sweep SWEEP.nml --check
!>   airlaunch-sweep SWEEP.nml --case-namelist ID
!>
!> Every rank computes cases; the next case goes to the first free rank (a
!> shared counter).  Finished rows go to the journal at once; a rerun of the
!> same command skips them.  Rank 0 prints a progress line every few seconds,
!> writes the summary (sorted by case id) atomically and prints the tally.
!> Exit status: 0 done (failed cases are results, counted in the tally),
!> 2 bad input (one line on stderr, before any case runs), 4 a file or MPI
!> error while running, or printed lines (--check, --case-namelist, the
!> tally) that did not reach the standard output (run alone: under mpirun
!> the ranks write into its forwarding pipe, which takes every line).
!> --restart discards the journal and the kept trajectories of an earlier run.
program airlaunch_sweep
  use, intrinsic :: iso_fortran_env, only: error_unit
  use, intrinsic :: iso_c_binding, only: c_int
  use mpi_f08
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str, fixed, escaped
  use airlaunch_version, only: code_version, code_digest, sundials_build
  use airlaunch_sweep_definition, only: sweep_definition
  use airlaunch_sweep_files, only: delete_file, remove_case_files, lock_file, write_line, make_temp_file
  use airlaunch_path, only: ignore_file_size_signal, path_kind, kind_regular, command_argument
  use airlaunch_sweep_case, only: run_case, run_trajectory, case_namelist
  use airlaunch_sweep_row, only: sweep_row, status_ok, status_failed, status_invalid
  use airlaunch_sweep_journal, only: journal_writer, read_journals, check_fingerprint, check_ran_settings, remove_journal, &
    record_environments, read_environments, environment_len, fnv1a
  use airlaunch_runtime_env, only: runtime_env, query_runtime_env
  use airlaunch_sweep_summary, only: write_summary
  use airlaunch_sweep_scheduler, only: sweep_scheduler
  use airlaunch_sweep_plan, only: sweep_setup, load_sweep, fingerprint_text, trajectory_ids, make_output_dir
  use airlaunch_blas_threads, only: use_one_blas_thread
  implicit none

  interface
    integer(c_int) function c_usleep(usec) bind(C, name="usleep")
      import :: c_int
      implicit none
      integer(c_int), value, intent(in) :: usec
    end function c_usleep
  end interface

  integer, parameter :: exit_ok = 0, exit_input = 2, exit_runtime = 4
  type(sweep_setup) :: s
  type(error_type), allocatable :: error
  type(error_type), allocatable :: stdout_error   !< the first line that did not reach stdout
  character(len=:), allocatable :: path, scratch, check_file
  character(len=:), allocatable :: ran_digest   !< --case-namelist: the code digest the sweep ran, if another
  integer :: rank, nranks, status, case_id, n_resumed, k, n_written
  logical :: check_only, restart, summary_kept
  integer, allocatable :: pending(:), keep(:)
  type(sweep_row), allocatable :: rows(:)
  real(dp) :: t_start, t_run
  character(len=16) :: env_tag   !< this rank's runtime environment, as its rows name it

  call use_one_blas_thread()   ! before any LAPACK call: small systems only
  call MPI_Init()
  call ignore_file_size_signal()   ! a kept trajectory past ulimit -f is a file error, not SIGXFSZ
  call MPI_Comm_rank(MPI_COMM_WORLD, rank)
  call MPI_Comm_size(MPI_COMM_WORLD, nranks)
  call parse_arguments()
  t_start = MPI_Wtime()
  if (.not. check_only .and. case_id < 0 .and. nranks == 1) call check_slurm_tasks()

  ! --- rank 0 validates everything before any case runs
  status = exit_ok
  n_resumed = 0
  if (rank == 0) then
    ! --case-namelist is a query that scripts may run many at once, of a
    ! sweep that may be read-only (an archive): its check file is its own,
    ! a new file of a unique name in the temporary directory
    if (case_id >= 0) then
      call make_temp_file(temporary_dir(), "airlaunch_sweep_check_", ".nml", check_file, error)
      if (.not. allocated(error)) then
        call load_sweep(path, .not. check_only, "rank0", s, error, scratch_file=check_file)
        call delete_file(check_file)
      end if
    else
      call load_sweep(path, .not. check_only, "rank0", s, error)
    end if
    if (allocated(error)) status = exit_input
    if (status == exit_ok .and. case_id >= 0) then
      if (case_id >= s%table%n_cases) then
        call fatal_error(error, path // ": --case-namelist " // str(case_id) // " is not a case id (0 .. " // &
          str(s%table%n_cases - 1) // ")")
        status = exit_input
      end if
      ! the namelist is the case the sweep ran only if its settings are unchanged
      if (status == exit_ok) then
        call check_ran_settings(s%def%journal_dir(), fingerprint_text(s), error, ran_digest)
        if (allocated(error)) status = exit_input
      end if
    end if
    if (status == exit_ok .and. .not. check_only .and. case_id < 0) call prepare_run()
  end if
  call MPI_Bcast(status, 1, MPI_INTEGER, 0, MPI_COMM_WORLD)
  if (status /= exit_ok) then
    if (rank == 0) write(error_unit, '(a)') "airlaunch-sweep: error: " // escaped(error%message)
    call finish(status)
  end if
  if (check_only .or. case_id >= 0) then
    if (rank == 0) call report_check()
    call finish(exit_ok)
  end if

  ! --- every rank: the same sweep, the list of pending cases
  if (rank /= 0) then
    call load_sweep(path, .true., "rank" // str(rank), s, error)
    if (allocated(error)) call die("rank " // str(rank) // ": " // error%message)
  end if
  call broadcast_ids(pending)
  scratch = s%def%work_dir() // "/case_rank" // str(rank) // ".nml"
  call record_rank_environments()

  ! --- the cases
  t_run = MPI_Wtime()
  call run_pass(pending, .false., n_written)
  if (rank == 0) then
    call collect_rows()
    ! no case ran and the journal's summary is there (prepare_run removes one
    ! whenever a case is to run): written again, it would be the same rows
    ! with a new `created`, which makes the figures drawn from it stale
    summary_kept = path_kind(s%def%summary_path()) == kind_regular .and. size(pending) == 0
    if (.not. summary_kept) then
      call write_summary_file()
    else
      call say("summary: " // s%def%summary_path() // " is already the journal's (no case ran): left as it is")
    end if
    call report_tally(size(pending), MPI_Wtime() - t_run)
    keep = trajectory_ids(s%def, s%base%metrics, rows)
    ! a kept case's file that exists is not rewritten; anything else in its place is
    ! the writer's to report (a directory there: exit 4, naming it)
    keep = pack(keep, [(path_kind(s%def%trajectory_path(keep(k))) /= kind_regular, k = 1, size(keep))])
  end if

  ! --- full trajectories of the cases the definition keeps
  call broadcast_ids(keep)
  if (size(keep) > 0) then
    if (rank == 0) call make_output_dir(s%def, s%def%trajectory_dir(), error)
    if (allocated(error)) call die(error%message)
    call MPI_Barrier(MPI_COMM_WORLD)
    call run_pass(keep, .true., n_written)
    if (rank == 0) then
      call say("trajectories: " // str(n_written) // " written to " // s%def%trajectory_dir())
      if (n_written < size(keep)) call say("trajectories: " // str(size(keep) - n_written) // &
        " of the cases kept end before their first output record (no file; the summary has their failure)")
    end if
  end if
  call finish(exit_ok)

contains

  !> Run the cases ids(:) over all ranks (dynamic assignment).  With
  !> `trajectory`, each case writes its full output and nothing is journaled;
  !> `written` (on every rank) counts the files written over all ranks.
  !> A file error on any rank (a case's scratch namelist, the journal) stops
  !> the pass: no rank takes another case, the cases in flight finish, and
  !> every rank ends with exit status 4 after the first rank that met one has
  !> named it in one line.  Nothing is journaled for the case that met it.
  subroutine run_pass(ids, trajectory, written)
    integer, intent(in) :: ids(:)
    logical, intent(in) :: trajectory
    integer, intent(out) :: written
    type(sweep_scheduler) :: sched
    type(journal_writer) :: journal
    type(sweep_row) :: row
    type(error_type), allocatable :: file_error
    integer :: position, id, done, failed, first
    real(dp) :: t0, last, now
    logical :: file_written
    written = 0
    if (.not. trajectory) then
      call journal%open(s%def%journal_dir(), rank, error)
      if (allocated(error)) call die(error%message)
    end if
    ! every rank file exists before any row is written (journal invariant)
    call sched%init(MPI_COMM_WORLD, error)
    if (allocated(error)) call die(error%message)
    t0 = MPI_Wtime()
    last = t0
    do
      call sched%next(position)
      if (position >= size(ids)) exit
      id = ids(position + 1)
      if (trajectory) then
        call run_trajectory(s%def, s%base, id, s%table%values(:, id + 1), scratch, s%def%trajectory_path(id), &
          file_written, file_error)
        if (file_written) written = written + 1
        row%status = status_ok
      else
        call run_case(s%def, s%base, id, s%table%values(:, id + 1), scratch, "", row, file_error)
        row%environment = env_tag
        if (.not. allocated(file_error)) call journal%append(row, file_error)
      end if
      if (allocated(file_error)) then
        call sched%stop()
        exit
      end if
      call sched%finished(row%status /= status_ok)
      now = MPI_Wtime()
      if (rank == 0 .and. .not. trajectory .and. now - last >= s%def%progress_interval) then
        call sched%counts(done, failed)
        call report_progress(done, failed, size(ids), MPI_Wtime() - t0)
        last = MPI_Wtime()
      end if
    end do
    ! rank 0 keeps reporting while the others finish their last cases
    if (rank == 0 .and. .not. trajectory) then
      do
        call sched%counts(done, failed)
        if (done >= size(ids)) exit
        if (sched%stopped()) exit
        now = MPI_Wtime()
        if (now - last >= s%def%progress_interval) then
          call report_progress(done, failed, size(ids), MPI_Wtime() - t0)
          last = MPI_Wtime()
        end if
        if (c_usleep(100000_c_int) /= 0) continue
      end do
    end if
    ! each rank closes its journal before the collective end of the pass, so
    ! rank 0 reads the journal only after every rank has closed its file
    if (.not. trajectory) call journal%close(file_error)
    call sched%free()
    first = nranks
    if (allocated(file_error)) first = rank
    call MPI_Allreduce(MPI_IN_PLACE, first, 1, MPI_INTEGER, MPI_MIN, MPI_COMM_WORLD)
    call MPI_Allreduce(MPI_IN_PLACE, written, 1, MPI_INTEGER, MPI_SUM, MPI_COMM_WORLD)
    if (first < nranks) then
      if (rank == first) then
        write(error_unit, '(a)') "airlaunch-sweep: error: " // escaped(file_error%message)
        flush(error_unit)
      end if
      call finish(exit_runtime)
    end if
  end subroutine run_pass

  !> Rank 0, before any case: directories, --restart, fingerprint, resume.
  subroutine prepare_run()
    logical, allocatable :: done(:)
    type(sweep_row), allocatable :: old(:)
    integer :: duplicates, bad
    logical :: differs
    logical :: held_elsewhere
    call make_output_dir(s%def, s%def%journal_dir(), error)
    if (.not. allocated(error)) call make_output_dir(s%def, s%def%work_dir(), error)
    if (allocated(error)) then
      status = exit_runtime
      return
    end if
    ! one run per output directory: a second would interleave the journals
    ! (held until this process ends; only rank 0 writes the shared files)
    call lock_file(s%def%journal_dir() // "/lock", held_elsewhere, error)
    if (held_elsewhere) call fatal_error(error, s%def%journal_dir() // ": another airlaunch-sweep is " // &
      "running this sweep (its lock file 'lock' is held): wait for it to end, or give this run another " // &
      "output_dir")
    if (allocated(error)) then
      status = merge(exit_input, exit_runtime, held_elsewhere)
      return
    end if
    if (restart) then
      ! the rows and the kept trajectories of the earlier sweep go together
      call remove_journal(s%def%journal_dir())
      ! every case file, whatever the earlier sweep's case count was
      call remove_case_files(s%def%trajectory_dir(), error)
      if (allocated(error)) then
        status = exit_runtime
        return
      end if
    end if
    call check_fingerprint(s%def%journal_dir(), fingerprint_text(s), error, differs)
    if (allocated(error)) then
      status = merge(exit_input, exit_runtime, differs)   ! another sweep's journal, or a file error
      return
    end if
    call read_journals(s%def%journal_dir(), s%table%n_cases, s%base%metrics%size(), old, done, duplicates, bad, error)
    if (allocated(error)) then
      status = exit_runtime
      return
    end if
    n_resumed = count(done)
    pending = pack([(k - 1, k = 1, s%table%n_cases)], .not. done)
    if (restart .or. size(pending) > 0) then
      ! a summary exists only once every case has its row: one present now is
      ! an earlier sweep's, and so is the envelope made from it.  They go
      ! before any case runs, so a run killed now leaves neither behind for
      ! the envelope step to take as this sweep's (nor the verification of its cases).
      call delete_file(s%def%summary_path())
      call delete_file(s%def%envelope_path())
      call delete_file(s%def%verify_path())
    end if
    if (n_resumed > 0) call say("sweep " // s%def%name // ": resuming: " // str(n_resumed) // &
      " of " // str(s%table%n_cases) // " cases already in the journal")
    if (bad > 0) call say("sweep " // s%def%name // ": " // str(bad) // &
      " torn journal lines ignored (their cases run again)")
    call say("sweep " // s%def%name // ": " // str(size(pending)) // " cases to run on " // &
      str(nranks) // " rank" // trim(merge("s", " ", nranks > 1)) // " (" // s%def%design // ", " // &
      str(size(s%def%inputs)) // " inputs, t_end " // str(merge(s%def%t_end, s%base%t_end, s%def%t_end > 0)) // &
      " s)")
  end subroutine prepare_run

  !> Rank 0: all rows from the journal; every case must be there.
  subroutine collect_rows()
    logical, allocatable :: done(:)
    integer :: duplicates, bad
    call read_journals(s%def%journal_dir(), s%table%n_cases, s%base%metrics%size(), rows, done, duplicates, bad, error)
    if (allocated(error)) call die(error%message)
    if (.not. all(done)) call die(s%def%journal_dir() // ": " // str(count(.not. done)) // &
      " cases have no row after the run (a journal write was lost)")
  end subroutine collect_rows

  !> Every rank's runtime numerical environment (BLAS kernel, libm, libraries,
  !> processor: ranks may run on different node types) to rank 0, which adds
  !> the ones the journal does not name yet to journal/environments.txt before
  !> any case runs; each row then carries its rank's tag (env_tag).  One line
  !> per rank, once per run.
  subroutine record_rank_environments()
    character(len=environment_len) :: mine
    character(len=environment_len), allocatable :: every(:)
    type(runtime_env) :: env
    env = query_runtime_env(with_mpi=.true.)
    mine = env%line()
    env_tag = fnv1a(trim(mine))
    allocate(every(merge(nranks, 0, rank == 0)))
    call MPI_Gather(mine, environment_len, MPI_CHARACTER, every, environment_len, MPI_CHARACTER, 0, MPI_COMM_WORLD)
    if (rank == 0) then
      call record_environments(s%def%journal_dir(), every, error)
      if (allocated(error)) call die(error%message)
    end if
  end subroutine record_rank_environments

  !> Broadcast a list of case ids from rank 0.
  subroutine broadcast_ids(ids)
    integer, allocatable, intent(inout) :: ids(:)
    integer :: n
    n = 0
    if (rank == 0) n = size(ids)
    call MPI_Bcast(n, 1, MPI_INTEGER, 0, MPI_COMM_WORLD)
    if (rank /= 0) then
      if (allocated(ids)) deallocate(ids)
      allocate(ids(n))
    end if
    if (n > 0) call MPI_Bcast(ids, n, MPI_INTEGER, 0, MPI_COMM_WORLD)
  end subroutine broadcast_ids

  !> Rank 0: summary.nc from the rows, with the environments they were computed in.
  subroutine write_summary_file()
    character(len=16), allocatable :: env_tags(:)
    character(len=environment_len), allocatable :: env_texts(:)
    call read_environments(s%def%journal_dir(), env_tags, env_texts, error)
    if (.not. allocated(error)) call write_summary(s%def%summary_path(), s%def, s%table, s%base, rows, env_tags, &
      env_texts, error)
    if (allocated(error)) call die(error%message)
  end subroutine write_summary_file

  subroutine report_progress(done, failed, total, elapsed)
    integer, intent(in) :: done, failed, total
    real(dp), intent(in) :: elapsed
    real(dp) :: rate, eta
    rate = done/max(elapsed, 1.0e-9_dp)
    eta = -1.0_dp
    if (done > 0) eta = (total - done)/rate
    call say("sweep " // s%def%name // ": " // str(n_resumed + done) // "/" // &
      str(s%table%n_cases) // " done, " // str(failed) // " failed, " // fixed(rate, 2) // " cases/s, ETA " // &
      duration(eta))
  end subroutine report_progress

  subroutine report_tally(n_run, elapsed)
    integer, intent(in) :: n_run
    real(dp), intent(in) :: elapsed
    call say("sweep " // s%def%name // ": " // str(size(rows)) // " cases: " // &
      str(count(rows%status == status_ok)) // " ok, " // str(count(rows%status == status_failed)) // &
      " failed, " // str(count(rows%status == status_invalid)) // " invalid input; " // str(n_run) // &
      " run now on " // str(nranks) // " rank" // trim(merge("s", " ", nranks > 1)) // " in " // &
      fixed(elapsed, 2) // " s (" // fixed(n_run/max(elapsed, 1.0e-9_dp), 3) // " cases/s), " // str(n_resumed) // &
      " from the journal")
    call say("summary: " // s%def%summary_path())
  end subroutine report_tally

  subroutine report_check()
    integer :: j
    if (case_id >= 0) then
      call say(case_namelist(s%def, s%base, case_id, s%table%values(:, case_id + 1)), newline=.false.)
      if (len(ran_digest) > 0) write(error_unit, '(a)') "airlaunch-sweep: note: the sweep ran code digest " // &
        ran_digest // ", this build is " // code_digest // ": a run of this namelist may differ from the " // &
        "case's summary row in the last bits"
      return
    end if
    call say("airlaunch-sweep: " // path // ": ok: design " // s%def%design // ", " // &
      str(s%def%n_cases) // " cases, inputs:")
    do j = 1, size(s%def%inputs)
      call say("  " // s%def%inputs(j)%name // " (" // s%def%inputs(j)%distribution // ")")
    end do
    if (s%table%n_cases > 0) then
      call say("table: " // s%def%table_path() // " matches the definition")
    else
      call say("table: " // s%def%table_path() // " not made yet")
    end if
  end subroutine report_check

  subroutine parse_arguments()
    character(len=:), allocatable :: arg
    integer :: i, nargs, ios
    logical :: options_done   ! "--" seen: the arguments after it are file names
    path = ""
    check_only = .false.
    restart = .false.
    case_id = -1
    options_done = .false.
    nargs = command_argument_count()
    i = 1
    do while (i <= nargs)
      arg = command_argument(i)
      if (options_done) then
        call take_definition_path(arg)
        i = i + 1
        cycle
      end if
      select case (arg)
      case ("--")
        options_done = .true.
      case ("-h", "--help")
        if (rank == 0) call usage()
        call finish(exit_ok)
      case ("-V", "--version")
        if (rank == 0) call say("airlaunch-sweep " // code_version)
        if (rank == 0) call say("SUNDIALS: " // sundials_build)
        if (rank == 0) call say("code digest (sources and build settings): " // code_digest)
        if (rank == 0) call report_environment()
        call finish(exit_ok)
      case ("--check")
        check_only = .true.
      case ("--restart")
        restart = .true.
      case ("--case-namelist")
        if (case_id >= 0) call fail_input("--case-namelist given twice (one case id per call)")
        i = i + 1
        arg = ""
        if (i <= nargs) arg = command_argument(i)
        ! digits only: list-directed reading would take "1,2" or "0 0" as 1 and 0
        ios = 1
        if (len(arg) > 0 .and. len(arg) <= 9 .and. verify(arg, "0123456789") == 0) &
          read(arg, *, iostat=ios) case_id
        if (ios /= 0 .or. i > nargs) call fail_input("--case-namelist " // arg // &
          " is not allowed (a case id: an integer in [0, 999999999])")
      case default
        if (len(arg) > 0) then
          if (arg(1:1) == "-") call fail_input("unknown option " // arg // &
            " (see airlaunch-sweep --help; a file whose name starts with '-' goes after --)")
        end if
        call take_definition_path(arg)
      end select
      i = i + 1
    end do
    if (len(path) == 0) then
      if (rank == 0) call usage()
      call fail_input("no sweep definition given")
    end if
  end subroutine parse_arguments

  !> The sweep definition's name from the command line (one, not empty).
  subroutine take_definition_path(arg)
    character(len=*), intent(in) :: arg
    if (len(arg) == 0) call fail_input("the sweep definition's name is empty")
    if (len(path) > 0) call fail_input("more than one sweep definition given")
    path = arg
  end subroutine take_definition_path

  !> --version: this process's runtime numerical environment.
  subroutine report_environment()
    type(runtime_env) :: env
    env = query_runtime_env(with_mpi=.true.)
    call say("runtime numerical environment (summary.nc's attributes of these names):")
    call say(env%report(), newline=.false.)
  end subroutine report_environment

  subroutine usage()
    call say("usage: mpirun -np K airlaunch-sweep [--restart] [--] SWEEP.nml")
    call say("       airlaunch-sweep --check | --case-namelist ID [--] SWEEP.nml")
    call say("  runs the cases of the sweep's table (docs/sweep.md); a rerun resumes")
    call say("  --: the arguments after it are file names (a definition named -x.nml)")
  end subroutine usage

  !> Bad command line: one line, exit 2.
  subroutine fail_input(msg)
    character(len=*), intent(in) :: msg
    if (rank == 0) write(error_unit, '(a)') "airlaunch-sweep: error: " // escaped(msg)
    call finish(exit_input)
  end subroutine fail_input

  !> Under Slurm with several tasks but an MPI world of one rank, srun did not
  !> start one MPI job: each task would be an independent one-rank sweep on
  !> the same output directory.  Refused (the lock would also stop all but one).
  subroutine check_slurm_tasks()
    character(len=32) :: text
    integer :: n, stat, ios
    call get_environment_variable("SLURM_NTASKS", text, status=stat)
    if (stat /= 0) return
    read(text, *, iostat=ios) n
    if (ios /= 0 .or. n <= 1) return
    call fail_input("SLURM_NTASKS = " // trim(text) // " but MPI started one rank: srun did not start one " // &
      "MPI job (use srun --mpi=pmix or mpirun -np " // trim(text) // "; scripts/sweep.slurm)")
  end subroutine check_slurm_tasks

  !> A file or MPI failure while running: stop every rank.
  subroutine die(msg)
    character(len=*), intent(in) :: msg
    write(error_unit, '(a)') "airlaunch-sweep: error: " // escaped(msg)
    flush(error_unit)
    call MPI_Abort(MPI_COMM_WORLD, exit_runtime)
    stop exit_runtime, quiet=.true.
  end subroutine die

  !> $TMPDIR, or /tmp where it is unset or empty.
  function temporary_dir() result(dir)
    character(len=:), allocatable :: dir
    integer :: n, stat
    call get_environment_variable("TMPDIR", length=n, status=stat)
    if (stat /= 0 .or. n == 0) then
      dir = "/tmp"
      return
    end if
    allocate(character(len=n) :: dir)
    call get_environment_variable("TMPDIR", dir)
  end function temporary_dir

  !> End every rank with `code`; a rank whose printed lines did not all reach
  !> the standard output says so and ends with exit_runtime instead of exit_ok.
  subroutine finish(code)
    integer, intent(in) :: code
    call MPI_Finalize()
    if (code == exit_ok .and. allocated(stdout_error)) then
      write(error_unit, '(a)') "airlaunch-sweep: error: the standard output could not be written (" // &
        stdout_error%message // "; what it printed is incomplete)"
      stop exit_runtime, quiet=.true.
    end if
    if (code == exit_ok) stop, quiet=.true.
    stop code, quiet=.true.
  end subroutine finish

  !> Text to the standard output by write(2) (a line unless newline is false):
  !> gfortran's buffered unit 6 drops write errors without a word; the first
  !> failure is kept for finish.
  subroutine say(text, newline)
    character(len=*), intent(in) :: text
    logical, intent(in), optional :: newline
    call write_line(1, text, stdout_error, newline)
  end subroutine say

  !> "1 h 02 min", "3 min 07 s", "12 s"; "?" if unknown.
  function duration(t) result(r)
    real(dp), intent(in) :: t
    character(len=:), allocatable :: r
    character(len=40) :: buf
    integer :: sec
    if (t < 0.0_dp .or. t /= t .or. t > 1.0e8_dp) then
      r = "?"
      return
    end if
    sec = nint(t)
    if (sec >= 3600) then
      write(buf, '(i0," h ",i2.2," min")') sec/3600, mod(sec, 3600)/60
    else if (sec >= 60) then
      write(buf, '(i0," min ",i2.2," s")') sec/60, mod(sec, 60)
    else
      write(buf, '(i0," s")') sec
    end if
    r = trim(buf)
  end function duration
end program airlaunch_sweep
