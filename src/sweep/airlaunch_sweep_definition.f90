!> The sweep definition: a namelist file with one &sweep group (what to run,
!> where to write, the design) and one &input group per varied input (the
!> scenario variable group%variable and its distribution), docs/sweep.md.
!>
!> postproc/sweep/definition.py applies the same rules when it draws the case
!> table; here they are applied again so that airlaunch-sweep never runs a
!> table against a definition it does not satisfy.
module airlaunch_sweep_definition
  use airlaunch_kinds, only: dp, i8
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str, lower
  use airlaunch_namelist, only: nml_file, nml_var, unset_real, unset_int, max_list_items
  use airlaunch_run_config, only: run_config
  implicit none
  private
  public :: sweep_input, sweep_fixed, sweep_definition, read_sweep_definition
  public :: design_names, distribution_names, worst_by_names, max_list_values, whole_and_element, both_note

  !> Largest number of values of a 'list' input and of keep_ids.
  integer, parameter :: max_list_values = max_list_items
  !> Most cases of a sweep (case ids are default integers; the table of 1e7
  !> cases takes about 5 s to make)
  integer, parameter :: max_cases = 10000000
  character(len=*), parameter :: owned_note = "the sweep sets it for every case (the scene is the base's " // &
    "scene; the output and whether there is one are the sweep's: summary mode, keep_failed, keep_worst)"
  character(len=8), parameter :: design_names(3) = [character(len=8) :: "lhs", "sobol", "grid"]
  character(len=16), parameter :: distribution_names(4) = [character(len=16) :: "uniform", "normal", &
    "truncnorm", "list"]
  !> Summary variables that can rank the worst cases (keep_worst), with the
  !> direction in which they get worse.
  !> (the airlaunch scene's five, then the line scene's own: load_sweep checks
  !> that it is one of the base scene's)
  !> (ground_speed_m_s, the touchdown speed, is both scenes' and comes last:
  !> a scene's default is its first)
  character(len=40), parameter :: worst_by_names(11) = [character(len=40) :: "min_clearance_m", &
    "min_line_clearance_m", "min_exit_clearance_m", "peak_line_tension_N", "max_aircraft_pitch_excursion_deg", "max_load_factor_excursion", &
    "max_end_tension_a_N", "max_end_tension_b_N", "line_recoil_speed_m_s", "final_tip_speed_m_s", "ground_speed_m_s"]

  !> One varied input.
  type :: sweep_input
    character(len=:), allocatable :: name          !< group%variable or group%variable(i) (lower case)
    character(len=:), allocatable :: group         !< namelist group of the scenario
    character(len=:), allocatable :: variable      !< variable inside the group (without the index)
    integer :: element = 0                         !< the varied element i of a vector (0: the variable)
    character(len=:), allocatable :: distribution  !< uniform, normal, truncnorm or list
    character(len=:), allocatable :: units         !< units (documentation only)
    character(len=:), allocatable :: description   !< description (long_name of table and summary)
    real(dp) :: lower = unset_real, upper = unset_real   !< bounds (uniform, truncnorm)
    real(dp) :: mean = unset_real, std = unset_real      !< normal, truncnorm
    real(dp), allocatable :: values(:)                   !< list
    integer :: levels = 0                                !< grid levels (design = 'grid')
    logical :: levels_given = .false.                    !< levels was assigned (refused but by 'grid')
    integer :: line = 0                                  !< line of the group in the file
  end type sweep_input

  !> A scenario variable set to the same value in every case (&fixed).
  type :: sweep_fixed
    character(len=:), allocatable :: name       !< group%variable or group%variable(i) (lower case)
    character(len=:), allocatable :: group      !< namelist group of the scenario
    character(len=:), allocatable :: variable   !< variable inside the group (without the index)
    integer :: element = 0                      !< the element i of a vector it sets (0: the variable)
    character(len=:), allocatable :: value      !< value as namelist text, e.g. 'fly' or 0.3656
    integer :: line = 0                         !< line of the group in the file
  end type sweep_fixed

  !> A validated sweep definition.
  type :: sweep_definition
    character(len=:), allocatable :: path        !< the definition file
    character(len=:), allocatable :: name        !< label of the sweep
    character(len=:), allocatable :: base        !< base scenario file
    character(len=:), allocatable :: output_dir  !< table, journal, summary, trajectories
    character(len=:), allocatable :: design      !< lhs, sobol or grid
    !> summary variable ranking the worst cases ('' as read: the base scene's
    !> default, which load_sweep sets: min_clearance_m, for a line scene
    !> peak_line_tension_N)
    character(len=:), allocatable :: worst_by
    character(len=:), allocatable :: criteria    !< criteria file of the envelope step
    integer :: n_cases = 0                       !< number of cases
    integer :: seed = 0                          !< seed of the design
    integer :: keep_worst = 0                    !< keep the trajectories of the k worst cases
    logical :: keep_failed = .false.             !< keep the trajectories of failed cases
    integer, allocatable :: keep_ids(:)          !< keep the trajectories of these cases
    real(dp) :: t_end = 0.0_dp                   !< simulated time per case [s] (0: the base's)
    real(dp) :: progress_interval = 5.0_dp       !< seconds between progress lines
    type(sweep_input), allocatable :: inputs(:)  !< the varied inputs
    type(sweep_fixed), allocatable :: fixed(:)   !< variables set in every case
  contains
    procedure :: table_path => def_table_path
    procedure :: summary_path => def_summary_path
    procedure :: envelope_path => def_envelope_path
    procedure :: verify_path => def_verify_path
    procedure :: journal_dir => def_journal_dir
    procedure :: work_dir => def_work_dir
    procedure :: trajectory_dir => def_trajectory_dir
    procedure :: trajectory_path => def_trajectory_path
  end type sweep_definition

contains

  !> Read and validate the sweep definition `path`.
  subroutine read_sweep_definition(path, def, error)
    character(len=*), intent(in) :: path                  !< definition file
    type(sweep_definition), intent(out) :: def            !< validated definition
    type(error_type), allocatable, intent(inout) :: error !< set on bad input
    type(nml_file) :: f
    integer :: i, n_sweep, n_input, n_fixed

    call f%load(path, error)
    if (allocated(error)) return
    def%path = path
    n_sweep = 0
    n_input = 0
    n_fixed = 0
    do i = 1, size(f%groups)
      select case (trim(f%groups(i)))
      case ("sweep")
        n_sweep = n_sweep + 1
      case ("input")
        n_input = n_input + 1
      case ("fixed")
        n_fixed = n_fixed + 1
      case default
        call fatal_error(error, path // ":" // str(f%group_lines(i)) // ": unknown group &" // &
          trim(f%groups(i)) // " (allowed: sweep, input, fixed)" // scenario_hint(f%groups(i)))
        return
      end select
    end do
    if (n_sweep /= 1) then
      call fatal_error(error, path // ": the group &sweep must appear once (found " // str(n_sweep) // ")")
      return
    end if
    if (n_input == 0) then
      call fatal_error(error, path // ": no &input group (at least one varied input is needed)")
      return
    end if
    call read_inputs(f, def, n_input, error)
    if (allocated(error)) return
    call read_fixed(f, def, n_fixed, error)
    if (allocated(error)) return
    call read_sweep_group(f, def, error)
    if (.not. allocated(error)) call check_t_end_once(def, error)
  end subroutine read_sweep_definition

  !> &sweep t_end > 0 sets run%t_end for every case: an &input or &fixed of
  !> run%t_end beside it would assign it twice in every case's namelist
  !> (each case invalid input).
  subroutine check_t_end_once(def, error)
    type(sweep_definition), intent(in) :: def             !< the sweep
    type(error_type), allocatable, intent(inout) :: error !< set if both set it
    integer :: k
    if (.not. (def%t_end > 0.0_dp)) return
    do k = 1, size(def%inputs)
      if (def%inputs(k)%name == "run%t_end") call fatal_error(error, def%path // ":" // str(def%inputs(k)%line) // &
        ": &input #" // str(k) // " 'run%t_end': run%t_end is also set by &sweep t_end = " // str(def%t_end) // &
        " (vary it here and leave &sweep t_end out, or fix it there)")
    end do
    do k = 1, size(def%fixed)
      if (def%fixed(k)%name == "run%t_end") call fatal_error(error, def%path // ":" // str(def%fixed(k)%line) // &
        ": &fixed #" // str(k) // " 'run%t_end': run%t_end is also set by &sweep t_end = " // str(def%t_end) // &
        " (give it once: &sweep t_end)")
    end do
  end subroutine check_t_end_once

  !> The &fixed groups: name = 'group%variable', value = 'namelist text'.
  subroutine read_fixed(f, def, n_fixed, error)
    type(nml_file), intent(in) :: f
    type(sweep_definition), intent(inout) :: def
    integer, intent(in) :: n_fixed
    type(error_type), allocatable, intent(inout) :: error
    character(len=128) :: name
    character(len=1024) :: value
    integer :: u, ios, k, j
    integer, allocatable :: lines(:)
    character(len=512) :: msg
    character(len=:), allocatable :: where
    namelist /fixed/ name, value
    type(nml_var), parameter :: vars(2) = [nml_var("name", "string", len(name)), nml_var("value", "string", len(value))]
    allocate(def%fixed(n_fixed))
    if (n_fixed == 0) return
    call f%check_group("fixed", vars, error)
    if (allocated(error)) return
    lines = pack(f%group_lines, f%groups == "fixed")
    call f%open_text(u, error)
    if (allocated(error)) return
    do k = 1, n_fixed
      name = ""
      value = ""
      read(u, nml=fixed, iostat=ios, iomsg=msg)
      if (ios /= 0) then
        call f%diagnose("fixed", vars, msg, error)
        exit
      end if
      where = f%path // ":" // str(lines(k)) // ": &fixed #" // str(k) // ": "
      associate(x => def%fixed(k))
        x%line = lines(k)
        call parse_name(lower_trim(name), where, "'flight%trim_mode'", x%name, x%group, x%variable, x%element, &
          error)
        if (allocated(error)) exit
        if (owned_by_sweep(x%group // "%" // x%variable)) then
          call fatal_error(error, where // "name = '" // x%name // "' is not allowed: " // owned_note)
          exit
        end if
        x%value = trim(adjustl(value))
        if (len(x%value) == 0) then
          call fatal_error(error, where // "missing required value value (the value as namelist text: " // &
            "a number, or a string with its own quotes)")
          exit
        end if
      end associate
      do j = 1, size(def%inputs)
        if (def%inputs(j)%name == def%fixed(k)%name) then
          call fatal_error(error, where // def%fixed(k)%name // " is also a varied input (&input #" // str(j) // ")")
          exit
        end if
      end do
      if (allocated(error)) exit
      do j = 1, k - 1
        if (def%fixed(j)%name == def%fixed(k)%name) then
          call fatal_error(error, where // def%fixed(k)%name // " is fixed twice")
          exit
        end if
      end do
      if (allocated(error)) exit
    end do
    close(u)
  end subroutine read_fixed

  !> The &sweep group (after the inputs: grid sizes need them).
  subroutine read_sweep_group(f, def, error)
    type(nml_file), intent(in) :: f
    type(sweep_definition), intent(inout) :: def
    type(error_type), allocatable, intent(inout) :: error
    character(len=256) :: name, base, output_dir, design, worst_by, criteria
    integer :: n_cases, seed, keep_worst, keep_ids(max_list_values), u, ios, i, n_ids
    real(dp) :: t_end, progress_interval
    logical :: keep_failed, present, exists, is_dir
    character(len=512) :: msg
    character(len=:), allocatable :: where, longest
    type(run_config) :: single_run
    namelist /sweep/ name, base, output_dir, design, n_cases, seed, t_end, keep_failed, keep_worst, &
      worst_by, keep_ids, criteria, progress_interval
    type(nml_var), parameter :: vars(13) = [nml_var("name", "string", len(name)), &
      nml_var("base", "string", len(base)), nml_var("output_dir", "string", len(output_dir)), &
      nml_var("design", "string", len(design)), nml_var("n_cases", "integer"), &
      nml_var("seed", "integer"), nml_var("t_end", "real"), nml_var("keep_failed", "logical"), &
      nml_var("keep_worst", "integer"), nml_var("worst_by", "string", len(worst_by)), &
      nml_var("keep_ids", "integer_list"), nml_var("criteria", "string", len(criteria)), &
      nml_var("progress_interval", "real")]

    where = f%path // ": &sweep: "
    name = ""; base = ""; output_dir = ""; design = ""; worst_by = ""; criteria = ""
    n_cases = unset_int; seed = unset_int; keep_worst = 0; keep_ids = unset_int
    t_end = 0.0_dp; progress_interval = 5.0_dp; keep_failed = .false.
    call f%check_group("sweep", vars, error)
    if (allocated(error)) return
    call f%position("sweep", u, present, error)
    if (allocated(error)) return
    read(u, nml=sweep, iostat=ios, iomsg=msg)
    close(u)
    if (ios /= 0) then
      call f%diagnose("sweep", vars, msg, error)
      return
    end if
    def%design = lower(trim(design))
    if (len_trim(design) == 0) then
      call fatal_error(error, where // "missing required value design (one of: lhs, sobol, grid)")
      return
    end if
    if (.not. any(design_names == def%design)) then
      call fatal_error(error, where // "design = '" // def%design // "' is not allowed (one of: lhs, sobol, grid)")
      return
    end if
    if (len_trim(base) == 0) then
      call fatal_error(error, where // "missing required value base (the base scenario file)")
      return
    end if
    def%base = trim(base)
    ! an existing regular file, as the table step requires (check_base in
    ! postproc/sweep/definition.py); a relative path is taken from the current
    ! directory.  Its content is read and checked by load_base_scenario.
    inquire(file=def%base, exist=exists)
    inquire(file=def%base // "/.", exist=is_dir)
    if (.not. exists .or. is_dir) then
      call fatal_error(error, where // "base = '" // def%base // "' is not allowed: the file " // &
        trim(merge("is a directory", "does not exist", is_dir)) // " (allowed: an existing regular file, " // &
        "the base scenario; a relative path is taken from the current directory)")
      return
    end if
    def%name = trim(name)
    if (len(def%name) == 0) def%name = stem(f%path)
    def%output_dir = trim(output_dir)
    if (len(def%output_dir) == 0 .and. f%is_set("sweep", "output_dir")) then
      call fatal_error(error, where // "output_dir = '' is not allowed (a directory, e.g. 'output/sweep_" // &
        def%name // "', or leave it out for that default)")
      return
    end if
    if (len(def%output_dir) == 0) def%output_dir = "output/sweep_" // def%name
    call check_levels_use(f, def, error)
    if (allocated(error)) return
    call resolve_case_count(f, def, where, n_cases, seed, error)
    if (allocated(error)) return
    if (t_end < 0.0_dp .or. t_end /= t_end) then
      call fatal_error(error, where // "t_end = " // str(t_end) // " is not allowed (must be > 0 s, or 0 for " // &
        "the base scenario's)")
      return
    end if
    if (keep_worst < 0) then
      call fatal_error(error, where // "keep_worst = " // str(keep_worst) // " is not allowed (must be >= 0)")
      return
    end if
    if (len_trim(worst_by) > 0 .and. .not. any(worst_by_names == worst_by)) then
      call fatal_error(error, where // "worst_by = '" // trim(worst_by) // "' is not allowed (one of: " // &
        join(worst_by_names) // ")")
      return
    end if
    if (.not. (progress_interval > 0.0_dp)) then
      call fatal_error(error, where // "progress_interval = " // str(progress_interval) // &
        " is not allowed (must be > 0 s)")
      return
    end if
    n_ids = count_set(keep_ids)
    do i = 1, n_ids
      if (keep_ids(i) < 0 .or. keep_ids(i) >= n_cases) then
        call fatal_error(error, where // "keep_ids: " // str(keep_ids(i)) // " is not allowed (case ids are " // &
          "integers in [0, " // str(n_cases - 1) // "])")
        return
      end if
    end do
    def%n_cases = n_cases
    ! The kept trajectories are written by the single run's output, a
    ! character(len=256) variable: a longer file name was cut short (the files
    ! went to OUTPUT_DIR/trajectories/case_NNNNNN.n, the count said "end before
    ! their first output record").  The longest such name is the largest case
    ! id's trajectory (the verification's OUTPUT_DIR/verify/case_NNNNNN.nc, an
    ! airlaunch --output of the same limit, is shorter).  A sweep that keeps
    ! no trajectory writes none: its output_dir is not limited so.
    longest = def%trajectory_path(n_cases - 1)
    if ((keep_failed .or. keep_worst > 0 .or. n_ids > 0) .and. len(longest) > len(single_run%output)) then
      call fatal_error(error, where // "output_dir = '" // def%output_dir // "' is not allowed: it is " // &
        str(len(def%output_dir)) // " characters long, and the longest file the sweep writes through a " // &
        "single run's output, <output_dir>" // longest(len(def%output_dir) + 1:) // ", would be " // str(len(longest)) // " characters; a run's " // &
        "output holds at most " // str(len(single_run%output)) // " (allowed: an output_dir of at most " // &
        str(len(single_run%output) - (len(longest) - len(def%output_dir))) // " characters for " // &
        str(n_cases) // " cases)")
      return
    end if
    def%seed = seed
    def%t_end = t_end
    def%keep_failed = keep_failed
    def%keep_worst = keep_worst
    def%worst_by = trim(worst_by)
    def%keep_ids = keep_ids(1:n_ids)
    def%criteria = trim(criteria)
    def%progress_interval = progress_interval
  end subroutine read_sweep_group

  !> `levels` is the grid's: refused on a 'list' input (its values are the
  !> levels) and with a design other than 'grid'.
  subroutine check_levels_use(f, def, error)
    type(nml_file), intent(in) :: f
    type(sweep_definition), intent(in) :: def
    type(error_type), allocatable, intent(inout) :: error
    integer :: i

    do i = 1, size(def%inputs)
      associate(s => def%inputs(i))
        if (s%levels_given .and. s%distribution == "list") then
          call fatal_error(error, f%path // ":" // str(s%line) // ": &input #" // str(i) // " '" // s%name // &
            "': levels is not used by distribution = 'list' (its values are the grid's levels)")
          return
        else if (s%levels_given .and. def%design /= "grid") then
          call fatal_error(error, f%path // ":" // str(s%line) // ": &input #" // str(i) // " '" // s%name // &
            "': levels is not used with design = '" // def%design // "' (only with 'grid')")
          return
        end if
      end associate
    end do
  end subroutine check_levels_use

  !> The number of cases and the seed: a grid's are the product of its levels
  !> (n_cases, if given, must equal it; the seed defaults to 0), the random
  !> designs' are required; then both in range.
  subroutine resolve_case_count(f, def, where, n_cases, seed, error)
    type(nml_file), intent(in) :: f
    type(sweep_definition), intent(in) :: def
    character(len=*), intent(in) :: where                 !< "<file>: &sweep: "
    integer, intent(inout) :: n_cases, seed               !< as read (unset_int: not given); resolved
    type(error_type), allocatable, intent(inout) :: error
    integer :: i
    integer(i8) :: n_grid

    if (def%design == "grid") then
      n_grid = 1
      do i = 1, size(def%inputs)
        associate(s => def%inputs(i))
          if (s%distribution == "list") then
            n_grid = n_grid*size(s%values, kind=i8)
          else if (s%levels < 1) then
            call fatal_error(error, f%path // ":" // str(s%line) // ": &input #" // str(i) // " '" // s%name // &
              "': missing required value levels (design = 'grid' needs levels >= 1 or a list of values)")
            return
          else
            n_grid = n_grid*s%levels
          end if
          n_grid = min(n_grid, int(max_cases, i8) + 1)   ! no overflow in the next product
        end associate
      end do
      if (n_grid > max_cases) then
        call fatal_error(error, where // "design = 'grid' is not allowed with these levels (the grid has " // &
          "more than " // str(max_cases) // " points, the most a sweep may have)")
        return
      end if
      if (n_cases == unset_int) n_cases = int(n_grid)
      if (n_cases /= n_grid) then
        call fatal_error(error, where // "n_cases = " // str(n_cases) // " is not allowed (the grid has " // &
          str(int(n_grid)) // " points: the product of the levels)")
        return
      end if
      if (seed == unset_int) seed = 0
    else
      if (n_cases == unset_int) then
        call fatal_error(error, where // "missing required value n_cases")
        return
      end if
      if (seed == unset_int) then
        call fatal_error(error, where // "missing required value seed")
        return
      end if
    end if
    if (n_cases < 1) then
      call fatal_error(error, where // "n_cases = " // str(n_cases) // " is not allowed (must be >= 1: zero cases)")
      return
    end if
    if (n_cases > max_cases) then
      call fatal_error(error, where // "n_cases = " // str(n_cases) // " is not allowed (at most " // &
        str(max_cases) // ")")
      return
    end if
    if (seed < 0) then
      call fatal_error(error, where // "seed = " // str(seed) // " is not allowed (must be in [0, 2147483647])")
      return
    end if
  end subroutine resolve_case_count

  !> The &input groups, in the order of the file.
  subroutine read_inputs(f, def, n_input, error)
    type(nml_file), intent(in) :: f
    type(sweep_definition), intent(inout) :: def
    integer, intent(in) :: n_input
    type(error_type), allocatable, intent(inout) :: error
    character(len=128) :: name, distribution, units
    character(len=1024) :: description
    real(dp) :: lower, upper, mean, std, values(max_list_values)
    integer :: levels, u, ios, k, j, nv
    integer, allocatable :: lines(:)
    character(len=512) :: msg
    character(len=:), allocatable :: where
    namelist /input/ name, distribution, lower, upper, mean, std, values, levels, units, description
    type(nml_var), parameter :: vars(10) = [nml_var("name", "string", len(name)), &
      nml_var("distribution", "string", len(distribution)), &
      nml_var("lower", "real"), nml_var("upper", "real"), nml_var("mean", "real"), nml_var("std", "real"), &
      nml_var("values", "real_list"), nml_var("levels", "integer"), nml_var("units", "string", len(units)), &
      nml_var("description", "string", len(description))]

    call f%check_group("input", vars, error)
    if (allocated(error)) return
    lines = pack(f%group_lines, f%groups == "input")
    allocate(def%inputs(n_input))
    call f%open_text(u, error)
    if (allocated(error)) return
    do k = 1, n_input
      name = ""; distribution = ""; units = ""; description = ""
      lower = unset_real; upper = unset_real; mean = unset_real; std = unset_real
      values = unset_real; levels = -huge(1)   ! -huge: not assigned
      read(u, nml=input, iostat=ios, iomsg=msg)
      if (ios /= 0) then
        close(u)
        call f%diagnose("input", vars, msg, error)
        return
      end if
      where = f%path // ":" // str(lines(k)) // ": &input #" // str(k) // ": "
      if (len_trim(name) == 0) then
        call fatal_error(error, where // "missing required value name (group%variable, e.g. 'bay%release_time')")
        exit
      end if
      associate(s => def%inputs(k))
        s%line = lines(k)
        where = f%path // ":" // str(lines(k)) // ": &input #" // str(k) // " '" // lower_trim(name) // "': "
        call parse_name(lower_trim(name), where, "'bay%release_time'", s%name, s%group, s%variable, s%element, &
          error)
        if (allocated(error)) exit
        where = f%path // ":" // str(lines(k)) // ": &input #" // str(k) // " '" // s%name // "': "
        if (owned_by_sweep(s%group // "%" // s%variable)) then
          call fatal_error(error, where // "name = '" // s%name // "' is not allowed: " // owned_note)
          exit
        end if
        s%distribution = lower_trim(distribution)
        s%units = trim(units)
        s%description = trim(description)
        s%levels_given = levels /= -huge(1)
        if (.not. s%levels_given) levels = 0
        s%levels = levels
        if (len(s%distribution) == 0) then
          call fatal_error(error, where // "missing required value distribution (one of: uniform, normal, " // &
            "truncnorm, list)")
          exit
        end if
        if (.not. any(distribution_names == s%distribution)) then
          call fatal_error(error, where // "distribution = '" // s%distribution // "' is not allowed (one of: " // &
            "uniform, normal, truncnorm, list)")
          exit
        end if
        if (levels < 0) then
          call fatal_error(error, where // "levels = " // str(levels) // " is not allowed (must be >= 1)")
          exit
        end if
        if (s%distribution == "uniform" .or. s%distribution == "truncnorm") then
          if (lower == unset_real .or. upper == unset_real) then
            call fatal_error(error, where // "missing required value " // trim(merge("lower", "upper", &
              lower == unset_real)))
            exit
          end if
          if (.not. (upper > lower)) then
            call fatal_error(error, where // "upper = " // str(upper) // " is not allowed (must be > lower = " // &
              str(lower) // ": reversed or empty bounds)")
            exit
          end if
          s%lower = lower
          s%upper = upper
        else if (lower /= unset_real .or. upper /= unset_real) then
          call fatal_error(error, where // trim(merge("lower", "upper", lower /= unset_real)) // &
            " is not used by distribution = '" // s%distribution // "' (only by uniform and truncnorm)")
          exit
        end if
        if (s%distribution == "normal" .or. s%distribution == "truncnorm") then
          if (mean == unset_real .or. std == unset_real) then
            call fatal_error(error, where // "missing required value " // trim(merge("mean", "std ", &
              mean == unset_real)))
            exit
          end if
          if (.not. (std > 0.0_dp)) then
            call fatal_error(error, where // "std = " // str(std) // " is not allowed (must be > 0)")
            exit
          end if
          s%mean = mean
          s%std = std
        else if (mean /= unset_real .or. std /= unset_real) then
          call fatal_error(error, where // trim(merge("mean", "std ", mean /= unset_real)) // &
            " is not used by distribution = '" // s%distribution // "' (only by normal and truncnorm)")
          exit
        end if
        nv = count_set_real(values)
        if (s%distribution == "list") then
          if (nv == 0) then
            call fatal_error(error, where // "missing required value values (the list of values)")
            exit
          end if
          s%values = values(1:nv)
        else
          if (nv > 0) then
            call fatal_error(error, where // "values is only used by distribution = 'list'")
            exit
          end if
          allocate(s%values(0))
        end if
      end associate
      do j = 1, k - 1
        if (def%inputs(j)%name == def%inputs(k)%name) then
          call fatal_error(error, f%path // ":" // str(lines(k)) // ": &input #" // str(k) // " '" // &
            def%inputs(k)%name // "': the input is varied twice")
          exit
        end if
      end do
      if (allocated(error)) exit
    end do
    close(u)
  end subroutine read_inputs

  ! ---------------------------------------------------------------------

  !> OUTPUT_DIR/table.nc
  function def_table_path(self) result(p)
    class(sweep_definition), intent(in) :: self
    character(len=:), allocatable :: p
    p = self%output_dir // "/table.nc"
  end function def_table_path

  !> OUTPUT_DIR/summary.nc
  function def_summary_path(self) result(p)
    class(sweep_definition), intent(in) :: self
    character(len=:), allocatable :: p
    p = self%output_dir // "/summary.nc"
  end function def_summary_path

  !> OUTPUT_DIR/envelope.nc (written by the envelope step, postproc/sweep)
  function def_envelope_path(self) result(p)
    class(sweep_definition), intent(in) :: self
    character(len=:), allocatable :: p
    p = self%output_dir // "/envelope.nc"
  end function def_envelope_path

  !> OUTPUT_DIR/verify.nc (written by python -m postproc.sweep verify).
  function def_verify_path(self) result(p)
    class(sweep_definition), intent(in) :: self
    character(len=:), allocatable :: p
    p = self%output_dir // "/verify.nc"
  end function def_verify_path

  !> OUTPUT_DIR/journal: one append-only file of finished rows per rank.
  function def_journal_dir(self) result(p)
    class(sweep_definition), intent(in) :: self
    character(len=:), allocatable :: p
    p = self%output_dir // "/journal"
  end function def_journal_dir

  !> OUTPUT_DIR/work: the per-rank case namelists.
  function def_work_dir(self) result(p)
    class(sweep_definition), intent(in) :: self
    character(len=:), allocatable :: p
    p = self%output_dir // "/work"
  end function def_work_dir

  !> OUTPUT_DIR/trajectories
  function def_trajectory_dir(self) result(p)
    class(sweep_definition), intent(in) :: self
    character(len=:), allocatable :: p
    p = self%output_dir // "/trajectories"
  end function def_trajectory_dir

  !> OUTPUT_DIR/trajectories/case_NNNNNN.nc
  function def_trajectory_path(self, id) result(p)
    class(sweep_definition), intent(in) :: self
    integer, intent(in) :: id   !< case id
    character(len=:), allocatable :: p
    character(len=16) :: buf
    write(buf, '(i0.6)') id   ! at least 6 digits (i6.6 wrote ****** from id 1000000 on)
    p = self%trajectory_dir() // "/case_" // trim(buf) // ".nc"
  end function def_trajectory_path

  ! ---------------------------------------------------------------------

  !> group%variable with letters, digits and underscores on both sides,
  !> optionally followed by an element index (i), i of 1 to 9 digits.
  pure logical function valid_name(s)
    character(len=*), intent(in) :: s
    integer :: p, q
    q = len(s) + 1
    if (len(s) > 0) then
      if (s(len(s):) == ")") then
        q = index(s, "(")
        valid_name = q > 0 .and. q < len(s) - 1 .and. len(s) - 1 - q <= 9
        if (.not. valid_name) return
        valid_name = verify(s(q+1:len(s)-1), "0123456789") == 0
        if (.not. valid_name) return
      end if
    end if
    p = index(s(:q-1), "%")
    valid_name = p > 1 .and. p < q - 1 .and. index(s(p+1:q-1), "%") == 0 .and. &
      verify(s(:q-1), "abcdefghijklmnopqrstuvwxyz0123456789_%") == 0
  end function valid_name

  !> An input's name as written (lower case) checked and taken apart: its
  !> group, variable and element index (0: none), and the name rejoined
  !> ('wind(01)' is 'wind(1)'); `example` is a scalar's name for the message.
  subroutine parse_name(raw, where, example, name, group, variable, element, error)
    character(len=*), intent(in) :: raw       !< the name, lower case
    character(len=*), intent(in) :: where     !< the message's start: file, line, group
    character(len=*), intent(in) :: example   !< a scalar's name, quoted
    character(len=:), allocatable, intent(out) :: name, group, variable
    integer, intent(out) :: element
    type(error_type), allocatable, intent(inout) :: error
    name = raw
    element = 0
    if (.not. valid_name(raw)) then
      call fatal_error(error, where // "name = '" // raw // "' is not allowed (write group%variable, " // &
        "or group%variable(i) for element i of a vector, e.g. " // example // ", 'line%wind(1)')")
      return
    end if
    call split_name(raw, group, variable, element)
    if (index(raw, "(") > 0 .and. element == 0) then
      call fatal_error(error, where // "name = '" // raw // "' is not allowed (an element index " // &
        "starts at 1: group%variable(1), (2), ...)")
      return
    end if
    name = joined_name(group, variable, element)
  end subroutine parse_name

  !> The group, variable and element index (0: none) of a valid name.
  pure subroutine split_name(s, group, variable, element)
    character(len=*), intent(in) :: s                          !< a valid_name
    character(len=:), allocatable, intent(out) :: group, variable
    integer, intent(out) :: element
    integer :: p, q
    p = index(s, "%")
    q = index(s, "(")
    element = 0
    if (q == 0) then
      q = len(s) + 1
    else
      read(s(q+1:len(s)-1), *) element
    end if
    group = s(:p-1)
    variable = s(p+1:q-1)
  end subroutine split_name

  !> group%variable, or group%variable(i) for element i > 0 (the index
  !> without leading zeros: 'wind(01)' and 'wind(1)' are one name).
  pure function joined_name(group, variable, element) result(s)
    character(len=*), intent(in) :: group, variable
    integer, intent(in) :: element
    character(len=:), allocatable :: s
    s = group // "%" // variable
    if (element > 0) s = s // "(" // str(element) // ")"
  end function joined_name

  !> One of two names is a whole vector and the other an element of it.
  pure logical function whole_and_element(g1, v1, e1, g2, v2, e2)
    character(len=*), intent(in) :: g1, v1, g2, v2
    integer, intent(in) :: e1, e2
    whole_and_element = g1 == g2 .and. v1 == v2 .and. (e1 == 0 .neqv. e2 == 0)
  end function whole_and_element

  !> The end of the message for a vector set whole and by an element.
  pure function both_note(vector) result(s)
    character(len=*), intent(in) :: vector
    character(len=:), allocatable :: s
    s = ", whole and one element (allowed: the whole vector once, or its elements one by one, " // &
      vector // "(1), " // vector // "(2), ...)"
  end function both_note

  !> Lower case without trailing blanks; a leading blank stays (and makes a
  !> name invalid), as in the table step, which takes strings as written.
  pure function lower_trim(s) result(t)
    character(len=*), intent(in) :: s
    character(len=:), allocatable :: t
    t = trim(lower(s))
  end function lower_trim

  !> Variables the sweep sets itself for every case: the scene (always the
  !> base's airlaunch scene), the output file and whether there is one.
  pure logical function owned_by_sweep(name)
    character(len=*), intent(in) :: name  !< group%variable, lower case
    owned_by_sweep = name == "run%scene" .or. name == "run%output" .or. name == "run%trajectory"
  end function owned_by_sweep

  !> File name without directory and extension.
  pure function stem(path) result(s)
    character(len=*), intent(in) :: path
    character(len=:), allocatable :: s
    integer :: i, j
    i = index(path, "/", back=.true.)
    s = path(i+1:)
    j = index(s, ".", back=.true.)
    if (j > 1) s = s(:j-1)
  end function stem

  !> Number of leading set entries of a sentinel-filled integer array.
  pure integer function count_set(a) result(n)
    integer, intent(in) :: a(:)
    n = 0
    do while (n < size(a))
      if (a(n+1) == unset_int) exit
      n = n + 1
    end do
  end function count_set

  !> Number of leading set entries of a sentinel-filled real array.
  pure integer function count_set_real(a) result(n)
    real(dp), intent(in) :: a(:)
    n = 0
    do while (n < size(a))
      if (a(n+1) == unset_real) exit
      n = n + 1
    end do
  end function count_set_real

  pure function join(names) result(s)
    character(len=*), intent(in) :: names(:)
    character(len=:), allocatable :: s
    integer :: i
    s = ""
    do i = 1, size(names)
      if (i > 1) s = s // ", "
      s = s // trim(names(i))
    end do
  end function join
  !> For a sweep definition's unknown group that is a scenario's, what the
  !> file is and where it goes ("" otherwise).
  pure function scenario_hint(group) result(hint)
    character(len=*), intent(in) :: group   !< the group's name, lower case
    character(len=:), allocatable :: hint
    select case (trim(group))
    case ("run", "flight", "aircraft", "bay", "rocket", "parachute", "line", "gust", "line_scene", "store")
      hint = ": this looks like a scenario, run by airlaunch, or named as a sweep's &sweep base (docs/sweep.md)"
    case ("criteria")
      hint = ": this is a criteria file, named by a sweep's &sweep criteria (docs/sweep.md)"
    case default
      hint = ""
    end select
  end function scenario_hint
end module airlaunch_sweep_definition
