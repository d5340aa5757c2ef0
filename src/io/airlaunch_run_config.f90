!> The &run group, common to every scene: which scene, how long, how often to
!> write, where, and the integrator's tolerances.
module airlaunch_run_config
  use airlaunch_kinds, only: dp, i8
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_namelist
  use airlaunch_path, only: path_kind, same_file, process_id, kind_directory, kind_other
  use airlaunch_strings, only: str
  implicit none
  private
  public :: run_config, read_run_config, run_echo, echo_buffer, echo_record, scene_names, &
    require_output_directory, &
    refuse_records

  !> Characters per record of a namelist group's echo (gfortran wraps its
  !> namelist output well inside it: one value list per record or so).
  integer, parameter :: echo_record = 1024

  !> A namelist group echoed into memory: the caller writes the group into
  !> `lines` until `another_try` is false, then appends it to the resolved
  !> input with `append_to`:
  !>
  !>     do while (buffer%another_try())
  !>       write(buffer%lines, nml=group, iostat=buffer%ios)
  !>     end do
  !>     call buffer%append_to(echo)
  !>
  !> The group is written where its namelist lives, not through a procedure
  !> argument: an internal procedure passed as an argument needs a trampoline
  !> on the stack, and gfortran then marks the whole program's stack
  !> executable.  (It was a scratch file before: gfortran puts those in
  !> $TMPDIR and loses their lines without an error when it is full, which left
  !> the resolved input empty.)
  type :: echo_buffer
    !> internal file of echo_record-character records, blank before each try
    character(len=echo_record), allocatable :: lines(:)
    !> the last write's iostat: nonzero, too few records
    integer :: ios = 0
  contains
    procedure :: another_try
    procedure :: append_to
  end type echo_buffer

  !> Scenes the main program knows.
  character(len=16), parameter :: scene_names(3) = [character(len=16) :: "airlaunch", "line", "drop"]

  !> Default step budget of a run: the paper scenario takes 858 steps, its
  !> converged reference (N = 240, rtol 1e-9) 150 399, the stress suite's
  !> longest run 71 176; the longest benchmark runs (undamped cable pendulum,
  !> N = 120, rtol 1e-6: 2.3 million) set their own.  A chattering run at
  !> 100-170 us per step stops after 1-1.5 min (2e6 took 4-10 min).
  integer, parameter :: default_max_steps = 500000
  !> Most output times a run may ask for (t_end / output_dt).
  real(dp), parameter :: max_output_times = 1.0e7_dp

  !> Settings of one run.
  type :: run_config
    character(len=16) :: scene = "airlaunch"   !< which simulation
    real(dp) :: t_end = 15.0_dp                !< simulated time [s]
    real(dp) :: output_dt = 0.01_dp            !< output cadence [s]
    character(len=256) :: output = "output/airlaunch.nc"  !< output file
    real(dp) :: rtol = 1.0e-6_dp               !< CVODE relative tolerance
    real(dp) :: atol = 1.0e-8_dp               !< CVODE absolute tolerance (scaled per state)
    logical :: trajectory = .true.             !< write the time history (false: summary only)
    integer :: max_order = 0                   !< largest BDF order (0: the scene's default)
    !> End the run as soon as its milestones are final (sweeps in summary mode):
    !> the scene decides when (airlaunch: see docs/input.md).
    logical :: stop_when_final = .false.
    !> The most steps the run's integrator may take (a run that cannot make
    !> progress stops with a message instead of crawling on); 0 = no limit.
    integer :: max_steps = default_max_steps
    !> The most wall-clock time the run's integration may take from its start,
    !> one budget for all its CVODE integrators [s] (a run that crawls stops
    !> with a message); 0 = no limit.
    real(dp) :: max_wall_time = 0.0_dp
  end type run_config

contains

  !> Read and validate &run from `f`; `echo` receives the resolved group.
  subroutine read_run_config(f, cfg, echo, error)
    type(nml_file), intent(in) :: f                       !< scanned input
    type(run_config), intent(out) :: cfg                  !< resolved settings
    character(len=:), allocatable, intent(inout) :: echo  !< resolved input text
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    character(len=16) :: scene
    real(dp) :: t_end, output_dt, rtol, atol, max_wall_time
    character(len=256) :: output
    logical :: trajectory, present, stop_when_final
    integer :: unit, ios, max_order, max_steps
    character(len=256) :: msg
    namelist /run/ scene, t_end, output_dt, output, rtol, atol, trajectory, max_order, stop_when_final, max_steps, &
      max_wall_time
    type(nml_var), parameter :: vars(11) = [nml_var("scene", "string", len(scene)), nml_var("t_end", "real"), &
      nml_var("output_dt", "real"), nml_var("output", "string", len(output)), nml_var("rtol", "real"), &
      nml_var("atol", "real"), nml_var("trajectory", "logical"), nml_var("max_order", "integer"), &
      nml_var("stop_when_final", "logical"), nml_var("max_steps", "integer"), nml_var("max_wall_time", "real")]

    scene = cfg%scene; t_end = cfg%t_end; output_dt = cfg%output_dt; output = cfg%output
    rtol = cfg%rtol; atol = cfg%atol; trajectory = cfg%trajectory; max_order = cfg%max_order
    stop_when_final = cfg%stop_when_final; max_steps = cfg%max_steps; max_wall_time = cfg%max_wall_time
    call f%check_group("run", vars, error)
    if (allocated(error)) return
    call f%position("run", unit, present, error)
    if (allocated(error)) return
    if (present) then
      read(unit, nml=run, iostat=ios, iomsg=msg)
      close(unit)
      if (ios /= 0) then
        call f%diagnose("run", vars, msg, error)
        return
      end if
    end if
    call require_choice(f, "run", "scene", scene, scene_names, error)
    call require_positive(f, "run", "t_end", t_end, "s", error)
    call require_positive(f, "run", "output_dt", output_dt, "s", error)
    call require_range(f, "run", "rtol", rtol, 1.0e-14_dp, 1.0e-1_dp, "", error)
    call require_range(f, "run", "atol", atol, 1.0e-16_dp, 1.0_dp, "", error)
    call require_int_range(f, "run", "max_order", max_order, 0, 5, error)
    call require_int_range(f, "run", "max_steps", max_steps, 0, huge(1), error)
    call require_nonnegative(f, "run", "max_wall_time", max_wall_time, "s (0: no limit)", error)
    if (allocated(error)) return
    if (t_end/output_dt > max_output_times) then
      call fatal_error(error, f%path // ": &run: t_end / output_dt = " // str(t_end) // " s / " // &
        str(output_dt) // " s is not allowed (" // str(t_end/output_dt) // " output times; at most " // &
        str(nint(max_output_times)) // ": raise output_dt or shorten t_end)")
      return
    end if
    if (len_trim(output) == 0) then
      call fatal_error(error, f%path // ": &run: output = '' is not allowed (a file name, e.g. 'output/run.nc')")
      return
    end if

    cfg = run_config(scene, t_end, output_dt, output, rtol, atol, trajectory, max_order, stop_when_final, &
      max_steps, max_wall_time)
    if (.not. allocated(echo)) echo = ""
    echo = echo // run_echo(cfg)
  end subroutine read_run_config

  !> The &run group of `cfg` as namelist text (the resolved input's first
  !> group; the program writes it again from the settings the run really
  !> uses: a command-line output, a scene's own default tolerances).
  function run_echo(cfg) result(text)
    type(run_config), intent(in) :: cfg   !< settings
    character(len=:), allocatable :: text
    character(len=16) :: scene
    real(dp) :: t_end, output_dt, rtol, atol, max_wall_time
    character(len=256) :: output
    logical :: trajectory, stop_when_final
    integer :: max_order, max_steps
    type(echo_buffer) :: buffer
    namelist /run/ scene, t_end, output_dt, output, rtol, atol, trajectory, max_order, stop_when_final, max_steps, &
      max_wall_time
    scene = cfg%scene; t_end = cfg%t_end; output_dt = cfg%output_dt; output = cfg%output
    rtol = cfg%rtol; atol = cfg%atol; trajectory = cfg%trajectory; max_order = cfg%max_order
    stop_when_final = cfg%stop_when_final; max_steps = cfg%max_steps; max_wall_time = cfg%max_wall_time
    text = ""
    do while (buffer%another_try())
      write(buffer%lines, nml=run, iostat=buffer%ios)
    end do
    call buffer%append_to(text)
  end function run_echo

  !> The trajectory's records could not be allocated: an input error naming
  !> &run output_dt, the record count and the memory they need.
  subroutine refuse_records(error, output_dt, records, bytes)
    type(error_type), allocatable, intent(inout) :: error  !< error to raise
    real(dp), intent(in) :: output_dt                      !< &run output_dt [s]
    integer, intent(in) :: records                         !< records asked for
    real(dp), intent(in) :: bytes                          !< their memory [bytes]
    character(len=64) :: a, b, c
    write(a, '(es10.3)') output_dt
    write(b, '(i0)') records
    write(c, '(i0)') nint(min(bytes/1.0e6_dp, 1.0e15_dp), kind=i8)
    call fatal_error(error, "&run: output_dt = " // trim(adjustl(a)) // " is not allowed here: the trajectory's " // &
      trim(b) // " records need " // trim(c) // " MB, more than can be allocated (raise output_dt, or set " // &
      "trajectory = .false.)", input=.true.)
  end subroutine refuse_records

  !> The output file must be one that can be created: not a directory nor a
  !> device, FIFO or socket (which the run would replace or block on), not the
  !> scenario file itself, in an existing directory where a file can be
  !> written, with a name short enough for the files the run makes beside it
  !> (`output`.part and `output`.part.lock: 10 bytes more, within the file
  !> system's 255).  Checked before the run (by the program, after any
  !> command-line override), not found missing after it: a probe file of this
  !> process's own (DIR/.airlaunch-probe-PID, whatever the output's name) is
  !> created and removed, so that no other file (another run's `output`.part)
  !> is touched.  `what` names where the value
  !> came from, e.g. "case.nml: &run: output"; `input`, the scenario file.
  subroutine require_output_directory(what, output, error, input)
    character(len=*), intent(in) :: what                  !< origin of the value, for the message
    character(len=*), intent(in) :: output                !< output file name
    type(error_type), allocatable, intent(inout) :: error !< set if no file can be written there
    character(len=*), intent(in), optional :: input       !< the scenario file (must not be the output)
    character(len=:), allocatable :: name, dir, probe
    character(len=1024) :: msg
    !> NAME_MAX of Linux's file systems, less the longest suffix the run adds (.part.lock)
    integer, parameter :: longest_name = 255 - len(".part.lock")
    integer :: slash, u, ios, what_is_there
    logical :: exists
    name = trim(output)
    slash = index(name, "/", back=.true.)
    what_is_there = path_kind(name)
    if (slash == len(name) .or. what_is_there == kind_directory) then
      dir = name
      if (slash /= len(name)) dir = name // "/"
      call fatal_error(error, what // " = '" // name // "' is not allowed: it names a directory (give a " // &
        "file name, e.g. '" // dir // "run.nc')")
      return
    end if
    if (what_is_there == kind_other) then
      call fatal_error(error, what // " = '" // name // "' is not allowed: it names a device, FIFO or socket, " // &
        "not a file (give the name of a regular file)")
      return
    end if
    if (present(input)) then
      if (same_file(name, input)) then
        call fatal_error(error, what // " = '" // name // "' is not allowed: it is the scenario file itself " // &
          "(give another name, e.g. 'output/run.nc')")
        return
      end if
    end if
    if (slash > 1) then
      dir = name(1:slash-1)
      inquire(file=dir // "/.", exist=exists)
      if (.not. exists) then
        inquire(file=dir, exist=exists)
        if (exists) then
          call fatal_error(error, what // " = '" // name // "' is not allowed: '" // dir // &
            "' is not a directory (choose another path)")
        else
          call fatal_error(error, what // " = '" // name // "' is not allowed: its directory '" // dir // &
            "' does not exist (create it, or choose another path)")
        end if
        return
      end if
    end if
    if (len(name) - slash > longest_name) then
      call fatal_error(error, what // " = '" // name // "' is not allowed: its file name is " // &
        str(len(name) - slash) // " bytes long; at most " // str(longest_name) // " are allowed (the run " // &
        "also writes it with '.part' and '.part.lock' appended, within the file system's 255)")
      return
    end if
    probe = name(1:slash) // ".airlaunch-probe-" // str(int(process_id()))
    open(newunit=u, file=probe, status="new", action="write", iostat=ios, iomsg=msg)
    if (ios /= 0) then
      call fatal_error(error, what // " = '" // name // "' is not allowed: no file can be written there (" // &
        trim(msg) // ")")
      return
    end if
    close(u, status="delete")
  end subroutine require_output_directory

  !> Whether the group is to be written (again): first into 64 blank
  !> records, then, while the write fails for want of records, into 8 times
  !> more, up to 32 768 (a list of 4 096 values takes ~100).
  logical function another_try(self)
    class(echo_buffer), intent(inout) :: self   !< the group's buffer
    integer :: n
    if (allocated(self%lines)) then
      another_try = self%ios /= 0 .and. size(self%lines) < 32768
      if (.not. another_try) return
      n = 8*size(self%lines)
      deallocate(self%lines)
    else
      another_try = .true.
      n = 64
    end if
    allocate(self%lines(n))
    self%lines = ""
  end function another_try

  !> Append the written group to `echo`, its records up to the closing "/",
  !> with the padding of its strings removed.
  subroutine append_to(self, echo)
    class(echo_buffer), intent(in) :: self                 !< the written group
    character(len=:), allocatable, intent(inout) :: echo  !< text so far
    integer :: k
    if (.not. allocated(echo)) echo = ""
    if (.not. allocated(self%lines)) return
    do k = 1, size(self%lines)
      if (len_trim(self%lines(k)) == 0) exit
      echo = echo // squeeze_string_padding(trim(self%lines(k))) // new_line("a")
      if (trim(self%lines(k)) == "/") exit
    end do
  end subroutine append_to

  !> Remove the blank padding the runtime writes inside quoted strings
  !> ("drop      " -> "drop"): only the blanks just before a string's closing
  !> quote go.  A doubled quote ("") inside a string is one quote character of
  !> the value, not the string's end: blanks before it are the value's own and
  !> stay ("a ""b"" c" is written back as it was read).  Trailing blanks of a
  !> value cannot be told from the padding of its character variable, which
  !> Fortran does not distinguish either.
  pure function squeeze_string_padding(line) result(s)
    character(len=*), intent(in) :: line
    character(len=:), allocatable :: s
    integer :: i, n
    logical :: in_string
    s = ""
    in_string = .false.
    i = 1
    n = len(line)
    do while (i <= n)
      if (line(i:i) == '"') then
        if (in_string .and. i < n) then
          if (line(i+1:i+1) == '"') then    ! doubled quote: a quote of the value
            s = s // '""'
            i = i + 2
            cycle
          end if
        end if
        if (in_string) s = trim(s)          ! closing quote: drop the padding before it
        in_string = .not. in_string
      end if
      s = s // line(i:i)
      i = i + 1
    end do
  end function squeeze_string_padding
end module airlaunch_run_config
