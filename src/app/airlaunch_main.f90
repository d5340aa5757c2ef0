!> airlaunch: run one namelist-driven scenario.
!>
!>   airlaunch SCENARIO.nml [--output FILE] [--check]
!>
!> --check reads and validates the input (and the output's directory; for the
!> air-launch scene also the trim of the initial flight) and prints the
!> resolved input, defaults included, without running.
!>
!> Exit status 0 on success, 2 for bad input (one line on stderr naming file,
!> group, variable, value and what is allowed), 3 for a numerical failure (the
!> output written so far is kept, with status="failed"), 4 when the run
!> completed but its output file could not be written (a full disk): the
!> milestones are printed, nothing is left under the output's name; 4 also
!> when what it prints (the summary, --check's input, --help) did not reach
!> the standard output (a full disk, a closed descriptor); 130 or
!> 143 when SIGINT (Ctrl-C) or SIGTERM interrupted the integration (the output
!> written so far is kept, with status="interrupted"; a second signal ends the
!> process at once).
!>
!> While it runs, the program holds a lock on OUTPUT.part.lock (removed at its
!> end): a second run asked to write the same file is refused (exit 2) instead
!> of both writing OUTPUT.part at once.
program airlaunch
  use, intrinsic :: iso_fortran_env, only: error_unit
  use airlaunch_error, only: error_type, output_failure_note
  use airlaunch_version, only: code_version, code_digest, sundials_build
  use airlaunch_namelist, only: nml_file
  use airlaunch_run_config, only: run_config, read_run_config, run_echo, require_output_directory
  use airlaunch_drop_scene, only: drop_config, read_drop_config, run_drop
  use airlaunch_scenario_config, only: scenario_config, read_scenario_config
  use airlaunch_launch_scene, only: launch_result, run_launch, setup_launch
  use airlaunch_launch_history, only: ground_body_name, ground_point_name
  use airlaunch_launch_system, only: launch_system
  use airlaunch_kinds, only: dp
  use airlaunch_line_scene, only: line_scene_config, read_line_scene_config, run_line_scene
  use airlaunch_line_model, only: cascade_note
  use airlaunch_strings, only: str, escaped
  use airlaunch_blas_threads, only: use_one_blas_thread
  use airlaunch_path, only: file_lock, lock_held_elsewhere, ignore_file_size_signal, command_argument
  use airlaunch_interrupt, only: catch_interrupts
  use airlaunch_sweep_files, only: write_line
  use airlaunch_runtime_env, only: runtime_env, query_runtime_env
  implicit none
  type(nml_file) :: f
  type(run_config) :: run
  type(error_type), allocatable :: error
  type(error_type), allocatable :: stdout_error   !< the first line that did not reach stdout
  type(file_lock) :: output_lock
  character(len=:), allocatable :: path, echo, summary, output_override, check_note, arg
  integer :: i, nargs, n_run_echo
  logical :: written, kept, check_only
  logical :: options_done   !< "--" seen: the arguments after it are file names
  !> longest path the system takes (PATH_MAX less its NUL)
  integer, parameter :: path_max = 4095
  type(runtime_env) :: env   !< --version: the BLAS, libm, libraries of this process

  call use_one_blas_thread()   ! before any LAPACK call: small systems only
  call ignore_file_size_signal()   ! a file past ulimit -f is a failed write (exit 4), not SIGXFSZ
  ! Ctrl-C or SIGTERM during the integration ends the run with its output so far (exit 130, 143)
  call catch_interrupts()
  nargs = command_argument_count()
  path = ""
  output_override = ""
  check_only = .false.
  check_note = ""
  i = 1
  options_done = .false.
  do while (i <= nargs)
    arg = command_argument(i)
    if (options_done) then
      ! after "--" every argument is a file name, also one starting with "-"
      call take_scenario_path(arg)
      i = i + 1
      cycle
    end if
    select case (arg)
    case ("--")
      options_done = .true.
    case ("-h", "--help")
      call usage()
      call check_stdout("the usage is incomplete")
      stop
    case ("-V", "--version")
      env = query_runtime_env()
      call say("airlaunch " // code_version)
      call say("SUNDIALS: " // sundials_build)
      call say("code digest (sources and build settings): " // code_digest)
      call say("runtime numerical environment (the output files' attributes of these names):")
      call say(env%report(), newline=.false.)
      call check_stdout("the version is incomplete")
      stop
    case ("--check")
      check_only = .true.
    case ("-o", "--output")
      if (len(output_override) > 0) call fail_input("--output given more than once (give one output file)")
      i = i + 1
      if (i > nargs) call fail_input("--output needs a file name")
      arg = command_argument(i)
      if (len_trim(arg) == 0) call fail_input("--output needs a file name (it is empty)")
      ! Fortran pads a name with blanks: one ending in a blank would be written without it
      if (arg(len(arg):len(arg)) == " ") call fail_input("--output '" // arg // "' ends with a blank, " // &
        "which the file name would lose (give the name without trailing blanks)")
      ! a scenario cannot hold a line break in a string: --check's print of it would not read back
      if (scan(arg, achar(10) // achar(13)) > 0) call fail_input("--output '" // arg // "' holds a line " // &
        "break, which no scenario file can hold (give a name without newlines)")
      if (len(arg) > len(run%output)) call fail_input("--output is " // str(len(arg)) // &
        " characters long; at most " // str(len(run%output)) // " are allowed")
      output_override = trim(arg)
    case default
      if (len(arg) > 0) then
        if (arg(1:1) == "-") call fail_input("unknown option " // arg // &
          " (see airlaunch --help; a file whose name starts with '-' goes after --)")
      end if
      call take_scenario_path(arg)
    end select
    i = i + 1
  end do
  if (len(path) == 0) then
    call usage()
    call fail_input("no scenario file given")
  end if

  call f%load(path, error)
  if (.not. allocated(error)) call read_run_config(f, run, echo, error)
  if (allocated(error)) call fail_input(error%message)
  if (len(output_override) > 0) run%output = output_override
  n_run_echo = 0
  if (allocated(echo)) n_run_echo = len(echo)

  select case (trim(run%scene))
  case ("drop")
    block
      type(drop_config) :: cfg
      call f%check_groups([character(len=16) :: "run", "store"], error)
      if (.not. allocated(error)) call read_drop_config(f, cfg, echo, error)
      if (allocated(error)) call fail_input(error%message)
      call prepare_output_file()
      call run_drop(run, cfg, echo, summary, error)
    end block
  case ("line")
    block
      type(line_scene_config) :: cfg
      call f%check_groups([character(len=16) :: "run", "line", "line_scene", "parachute"], error)
      if (.not. allocated(error)) call read_line_scene_config(f, run, cfg, echo, error)
      if (allocated(error)) call fail_input(error%message)
      ! the line scheme's own defaults where &run does not set them (line.md §4)
      run%rtol = cfg%integration%rtol
      run%atol = cfg%integration%atol
      run%max_order = cfg%integration%max_order
      call prepare_output_file()
      call run_line_scene(run, cfg, echo, summary, error)
    end block
  case ("airlaunch")
    block
      type(scenario_config) :: cfg
      type(launch_result) :: res
      call read_scenario_config(f, cfg, echo, error, run%t_end)
      if (allocated(error)) call fail_input(error%message)
      if (check_only) call check_trim(cfg)
      call prepare_output_file()
      call run_launch(run, cfg, echo, res, error)
      ! a scenario the aircraft cannot fly (its trim) is bad input: one line, exit 2
      if (allocated(error) .and. res%status == "invalid_input") call fail_input(path // ": " // error%message)
      summary = launch_summary(res)
    end block
  case default
    call fail_input(path // ": &run: scene = '" // trim(run%scene) // "' is not available in this build")
  end select

  ! what the input asks for cannot be done (found once the run is set up): bad input, nothing written
  if (allocated(error)) then
    if (error%input) call fail_input(path // ": " // error%message)
  end if
  if (allocated(error)) then
    if (error%output) then
      ! the run completed: its milestones stand; the file could not be written
      if (allocated(summary)) call say(summary)
      write(error_unit, '(a)') "airlaunch: error: " // escaped(error%message)
      write(error_unit, '(a)') "airlaunch: no output written (the run completed; writing " // trim(run%output) // &
        " failed, and nothing is left under that name or " // trim(run%output) // ".part)"
      call output_lock%release()
      stop 4, quiet=.true.
    end if
    if (error%signal /= 0) call report_interrupt()
    write(error_unit, '(a)') "airlaunch: error: " // escaped(error%message)
    if (allocated(summary)) write(error_unit, '(a)') summary
    if (run%trajectory) then
      ! (a .part left: the writer could not rename it, and kept it)
      inquire(file=trim(run%output) // ".part", exist=kept)
      inquire(file=trim(run%output), exist=written)
      if (kept) then
        write(error_unit, '(a)') "airlaunch: output kept as " // trim(run%output) // ".part (it could not " // &
          "be renamed)"
      else if (written) then
        write(error_unit, '(a)') "airlaunch: output so far (status=failed): " // trim(run%output)
      else
        if (index(error%message, output_failure_note) > 0) then
          write(error_unit, '(a)') "airlaunch: no output written (writing it failed: above)"
        else
          write(error_unit, '(a)') "airlaunch: no output written (the run failed before its first record)"
        end if
      end if
    end if
    call output_lock%release()
    stop 3, quiet=.true.
  end if
  call say(summary)
  if (run%trajectory) call say("output: " // trim(run%output))
  if (run%trajectory) then
    call check_stdout("the run completed, its output is " // trim(run%output))
  else
    call check_stdout("the run completed")
  end if
  call output_lock%release()

contains

  !> One line (or lines) to the standard output, by write(2): gfortran's
  !> buffered unit 6 drops write errors (a full disk, a closed descriptor)
  !> without a word; the first failure is kept for check_stdout.  With
  !> newline = .false., `text` as it is (it ends its own lines).
  subroutine say(text, newline)
    character(len=*), intent(in) :: text
    logical, intent(in), optional :: newline
    call write_line(1, text, stdout_error, newline)
  end subroutine say

  !> A line that did not reach the standard output: one line on stderr saying
  !> what stands (`context`), exit 4 (as a run whose file could not be written).
  subroutine check_stdout(context)
    character(len=*), intent(in) :: context
    if (.not. allocated(stdout_error)) return
    write(error_unit, '(a)') "airlaunch: error: the standard output could not be written (" // &
      stdout_error%message // "; " // trim(context) // ")"
    call output_lock%release()
    stop 4, quiet=.true.
  end subroutine check_stdout

  !> The run was interrupted (SIGINT, SIGTERM caught between the integrator's
  !> steps): one line, then where its output so far is; exit 128 + the signal,
  !> as the signal's default action would have, with the lock released.
  subroutine report_interrupt()
    integer :: code
    write(error_unit, '(a)') "airlaunch: " // error%message
    if (run%trajectory) then
      inquire(file=trim(run%output), exist=written)
      if (written) then
        write(error_unit, '(a)') "airlaunch: output so far (status=interrupted): " // trim(run%output)
      else
        write(error_unit, '(a)') "airlaunch: no output written"
      end if
    end if
    call output_lock%release()
    code = 128 + error%signal
    stop code, quiet=.true.
  end subroutine report_interrupt

  !> The output file must be one that can be written: checked once the whole
  !> input is read (its own errors first), before the run; an old file of the same
  !> name is removed then: the run replaces it in any case (completed, or
  !> failed with what it computed), and one that fails before its first record
  !> must not leave an older result that passes for its own.  With --check: the
  !> resolved input is printed instead, nothing is removed, and the program ends.
  subroutine prepare_output_file()
    type(error_type), allocatable :: out_error
    integer :: u, ios
    character(len=:), allocatable :: what   ! where the output's name came from, for messages
    ! the resolved input records the settings the run uses (--output, a scene's defaults)
    echo = run_echo(run) // echo(n_run_echo + 1:)
    if (.not. run%trajectory .and. check_only) call print_resolved_input()
    if (.not. run%trajectory) return
    what = path // ": &run: output"
    if (len(output_override) > 0) what = "--output"
    call require_output_directory(what, run%output, out_error, input=path)
    if (allocated(out_error)) call fail_input(out_error%message)
    if (check_only) call print_resolved_input()
    ! one writer of OUTPUT.part at a time (a file system without locks: no lock)
    if (output_lock%acquire(trim(run%output) // ".part.lock") == lock_held_elsewhere) &
      call fail_input(what // " = '" // trim(run%output) // "' is not allowed now: another airlaunch run is " // &
        "running with this output (it holds " // trim(run%output) // ".part.lock); wait for it to end or choose " // &
        "another path")
    ! (a regular file or nothing: require_output_directory refused anything else)
    open(newunit=u, file=trim(run%output), status="old", action="read", iostat=ios)
    if (ios == 0) close(u, status="delete", iostat=ios)
    inquire(file=trim(run%output), exist=written)
    if (written) call fail_input(what // " = '" // trim(run%output) // "' is not allowed: an older file of " // &
      "that name cannot be removed (no permission; remove it or choose another path)")
  end subroutine prepare_output_file

  !> The milestones of an air-launch run, one per line.
  function launch_summary(r) result(s)
    type(launch_result), intent(in) :: r
    character(len=:), allocatable :: s
    character(len=1), parameter :: nl = new_line("a")
    s = "trim: alpha " // fx(r%trim_alpha_deg, 4) // " deg, elevator " // fx(r%trim_elevator_deg, 3) // &
      " deg, thrust " // force(r%trim_thrust_n, 1) // nl // &
      "release (Case 0->1):        " // at(r%release_time) // nl // &
      "edge (Case 1->2):           " // at(r%edge_time) // nl // &
      "separation (Case 2->3):     " // at(r%separation_time) // &
      trim(merge(" (early: edge normal force reached zero)", "                                        ", &
        r%early_separation)) // nl // &
      edge_note(r%edge_pull_time) // &
      separation_note(r) // &
      "first rocket pitch maximum: " // pitch_max_note(r) // nl // &
      "minimum rocket-empennage clearance after separation: " // clearance_note(r%min_clearance) // nl // &
      exit_clearance_note(r) // &
      tension_note(r) // &
      "largest aircraft pitch excursion: " // fx(r%max_aircraft_pitch_excursion_deg, 3) // " deg, " // &
      "load factor excursion " // fx(r%max_load_factor_excursion, 3) // nl // &
      ground_note(r) // &
      "integration: " // str(int(r%stats%steps)) // " steps, " // str(int(r%stats%rhs_evals)) // &
      " right-hand sides, " // str(int(r%stats%jac_evals)) // " Jacobians, " // &
      str(int(r%stats%nonlin_iters)) // " Newton iterations, " // str(int(r%stats%nonlin_fails)) // &
      " convergence failures, " // str(int(r%stats%err_test_fails)) // " error-test failures"
  end function launch_summary

  !> The peak line tension, or that the scene has no line.
  function tension_note(r) result(s)
    type(launch_result), intent(in) :: r
    character(len=:), allocatable :: s
    if (r%has_line) then
      s = "peak line tension: " // force(r%peak_tension, 2) // ", first reached at " // &
        at(r%peak_tension_time) // new_line("a") // line_clearance_note(r) // break_note(r)
    else
      s = "peak line tension: none (no line: &line enabled = .false.)" // new_line("a")
    end if
  end function tension_note

  !> The rocket's smallest clearance from the empennage over the whole exit
  !> (from the release on: every integrator step, refined between them).
  function exit_clearance_note(r) result(s)
    type(launch_result), intent(in) :: r
    character(len=:), allocatable :: s
    if (r%min_exit_clearance < huge(r%min_exit_clearance)) then
      s = fx(r%min_exit_clearance, 2) // " m at " // fx(r%min_exit_clearance_time, 2) // " s"
    else
      s = "none (not released)"
    end if
    s = "minimum rocket-empennage clearance over the exit (from the release): " // s // new_line("a")
  end function exit_clearance_note

  !> The line's smallest distance from the empennage point (over the direct
  !> coupling's steps and the rigidized coupling's line sub-steps).
  function line_clearance_note(r) result(s)
    type(launch_result), intent(in) :: r
    character(len=:), allocatable :: s, d
    d = fx(r%min_line_clearance, 2) // " m"
    if (.not. r%min_line_clearance < huge(r%min_line_clearance)) d = "none (no step was taken)"
    s = "minimum line-empennage clearance: " // d // new_line("a")
  end function line_clearance_note

  !> Whether a body reached &flight ground_altitude (the run ended there).
  function ground_note(r) result(s)
    type(launch_result), intent(in) :: r
    character(len=:), allocatable :: s, reached, point
    point = trim(ground_point_name(r%ground_point))
    if (point == "cg") point = "CG"
    reached = "ground: reached by the " // trim(ground_body_name(r%ground_body)) // "'s " // point // " at " // &
      at(r%ground_time) // ", speed " // fx(r%ground_speed, 2) // " m/s (the run ends there)" // new_line("a")
    s = "ground: not reached" // new_line("a")
    if (r%ground_time >= 0.0d0) s = reached
  end function ground_note

  !> Where and when the line parted (&line breaking_strength or break_time).
  function break_note(r) result(s)
    type(launch_result), intent(in) :: r
    character(len=:), allocatable :: s, parted
    parted = "line break: segment " // str(r%line_break_segment) // " parted at " // at(r%line_break_time) // &
      ", " // str(r%line_breaks) // " segment(s) in all" // &
      cascade_note(r%line_breaks) // new_line("a")
    s = "line break: none" // new_line("a")
    if (r%line_break_segment > 0) s = parted
  end function break_note

  ! The notes below format their numbers whether or not the milestone was
  ! reached, so that a run's summary costs the same heap allocations either way
  ! (tests/python/test_heap_per_step.py compares a short and a long run).

  !> "t = 3.875 s", or "not reached" for an event the run did not get to (t < 0).
  function at(t) result(s)
    double precision, intent(in) :: t
    character(len=:), allocatable :: s
    s = "t = " // fx(t, 3) // " s"
    if (t < 0.0d0) s = "not reached"
  end function at

  !> The rocket's pitch and pitch rate at separation (empty before it).
  function separation_note(r) result(s)
    type(launch_result), intent(in) :: r
    character(len=:), allocatable :: s
    s = "  rocket pitch " // fx(r%pitch_at_separation_deg, 2) // " deg, pitch rate " // &
      fx(r%pitch_rate_at_separation_deg_s, 2) // " deg/s" // new_line("a")
    if (r%separation_time < 0.0d0) s = ""
  end function separation_note

  !> Time, pitch and nose elevation of the rocket's first pitch maximum.
  function pitch_max_note(r) result(s)
    type(launch_result), intent(in) :: r
    character(len=:), allocatable :: s
    s = at(r%pitch_max_time) // ", pitch " // fx(r%pitch_max_deg, 2) // &
      " deg (nose elevation " // fx(r%nose_elevation_at_max_deg, 2) // " deg"
    ! the Euler pitch cannot exceed 90 deg: its maximum there is the nose passing the vertical
    if (r%pitch_max_deg > 89.99d0) s = s // ": the nose passes the vertical, where the Euler pitch peaks"
    s = s // ")"
    if (r%pitch_max_time < 0.0d0) s = "not reached"
  end function pitch_max_note

  !> The smallest rocket-empennage clearance [m] (none recorded: huge).
  function clearance_note(c) result(s)
    double precision, intent(in) :: c
    character(len=:), allocatable :: s
    s = fx(c, 2) // " m"
    if (.not. (c < 1.0d300)) s = "not reached (the rocket did not leave the bay)"
  end function clearance_note

  !> Note on a bilateral edge that had to pull (empty otherwise).
  function edge_note(t) result(s)
    double precision, intent(in) :: t
    character(len=:), allocatable :: s
    s = ""
    if (t >= 0.0d0) s = "  (bilateral edge: a one-sided edge would have released the rocket at t = " // &
      fx(t, 3) // " s)" // new_line("a")
  end function edge_note

  !> A force [N] with its unit: in kN with d decimals from 1 kN up (the paper
  !> scenario's 146.7 kN, 78.77 kN), in N with d decimals below (a small
  !> vehicle's 18.3 N, which "0.0 kN" hid).
  function force(newtons, d) result(s)
    double precision, intent(in) :: newtons
    integer, intent(in) :: d
    character(len=:), allocatable :: s
    if (abs(newtons) >= 1000.0d0) then
      s = fx(newtons/1000, d) // " kN"
    else
      s = fx(newtons, d) // " N"
    end if
  end function force

  !> Fixed-point number with d decimals (exponent form beyond 1e12, "NaN", "Inf").
  function fx(x, d) result(s)
    double precision, intent(in) :: x
    integer, intent(in) :: d
    character(len=:), allocatable :: s
    character(len=32) :: buf
    if (.not. (abs(x) < 1.0d12)) then
      write(buf, '(es12.4)') x
      s = trim(adjustl(buf))
      return
    end if
    ! literal formats: gfortran parses (and allocates for) a run-time format at every write
    select case (d)
    case (1)
      write(buf, '(f0.1)') x
    case (2)
      write(buf, '(f0.2)') x
    case (3)
      write(buf, '(f0.3)') x
    case default
      write(buf, '(f0.4)') x
    end select
    s = trim(adjustl(buf))
    if (s(1:1) == ".") s = "0" // s
    if (s(1:2) == "-.") s = "-0" // s(2:)
  end function fx

  !> --check: the input is valid; print it resolved (every group the scene
  !> reads, defaults included: what the output's `input_namelist` records) and end.
  subroutine print_resolved_input()
    call say("! " // escaped(path) // ": valid input (airlaunch --check; " // &
      "resolved, defaults included; the run was not started)")
    if (len(check_note) > 0) call say("! " // check_note)
    call say(echo)
    call check_stdout("the resolved input printed is incomplete")
    stop
  end subroutine print_resolved_input

  !> --check of an air-launch scenario: the set-up a run starts with (the trim
  !> of the Case 0 flight, the settled line), which is where a flight the
  !> aircraft cannot trim is found; as a run: bad input exit 2, a numerical
  !> failure exit 3.
  subroutine check_trim(cfg)
    type(scenario_config), intent(in) :: cfg
    type(launch_system) :: sys
    type(launch_result) :: res
    real(dp), allocatable :: y0(:)
    type(error_type), allocatable :: setup_error
    call setup_launch(cfg, sys, y0, res, setup_error)
    if (allocated(setup_error)) then
      if (res%status == "invalid_input") call fail_input(path // ": " // setup_error%message)
      write(error_unit, '(a)') "airlaunch: error: " // escaped(setup_error%message)
      stop 3, quiet=.true.
    end if
    check_note = "trim: alpha " // fx(res%trim_alpha_deg, 4) // " deg, elevator " // &
      fx(res%trim_elevator_deg, 3) // " deg, thrust " // force(res%trim_thrust_n, 1)
  end subroutine check_trim

  subroutine usage()
    call say("usage: airlaunch [-o FILE | --output FILE] [--check] [--] SCENARIO.nml")
    call say("       airlaunch -h | --help | -V | --version")
    call say("  runs the scenario of the namelist file; see docs/input.md")
    call say("  -o, --output FILE: write the output there instead of &run output")
    call say("  --check: validate the input and print it resolved (defaults included), without running")
    call say("  -V, --version: the code version, the SUNDIALS it was built with, and the libraries and")
    call say("                 processor it computes with here (BLAS kernel, libm, versions)")
    call say("  --: the arguments after it are file names (a scenario named -x.nml: airlaunch -- -x.nml)")
  end subroutine usage

  !> The scenario file's name from the command line (one, not empty, not
  !> longer than the system takes).
  subroutine take_scenario_path(arg)
    character(len=*), intent(in) :: arg
    if (len(arg) == 0) call fail_input("the scenario file's name is empty")
    if (len(path) > 0) call fail_input("more than one scenario file given")
    if (len(arg) > path_max) call fail_input("the scenario file's name is " // str(len(arg)) // &
      " characters long; the system takes at most " // str(path_max))
    path = arg
  end subroutine take_scenario_path

  subroutine fail_input(msg)
    character(len=*), intent(in) :: msg
    write(error_unit, '(a)') "airlaunch: error: " // escaped(msg)
    call output_lock%release()   ! (only a lock of this run's)
    stop 2, quiet=.true.
  end subroutine fail_input
end program airlaunch
