!> A sweep ready to run: its definition, base scenario and case table, all
!> validated together before any case runs; what its journal must match; and
!> which cases keep a trajectory.
module airlaunch_sweep_plan
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_version, only: code_digest
  use airlaunch_sweep_definition, only: sweep_definition, read_sweep_definition, worst_by_names
  use airlaunch_sweep_table, only: case_table, read_case_table
  use airlaunch_sweep_case, only: base_scenario, load_base_scenario, check_varied_inputs, check_common_settings
  use airlaunch_sweep_files, only: make_dir
  use airlaunch_sweep_journal, only: fnv1a
  use airlaunch_sweep_row, only: sweep_row, status_ok, status_failed, status_invalid, metric_set
  implicit none
  private
  public :: sweep_setup, load_sweep, fingerprint_text, trajectory_ids, make_output_dir

  !> Everything a rank needs to run cases.
  type :: sweep_setup
    type(sweep_definition) :: def    !< the definition
    type(base_scenario) :: base      !< its base scenario
    type(case_table) :: table        !< its cases
  end type sweep_setup

contains

  !> Read and check definition, base scenario and table; `need_table` false
  !> skips a missing table (for --check before the table step).  The base's
  !> check goes through a scratch namelist check_TAG.nml in the output
  !> directory's work/ (made if missing: a run needs it), or `scratch_file`
  !> when given (a query of a sweep that may be read-only; nothing is made).
  subroutine load_sweep(path, need_table, tag, setup, error, scratch_file)
    character(len=*), intent(in) :: path                  !< sweep definition
    logical, intent(in) :: need_table                     !< the table must exist
    character(len=*), intent(in) :: tag                   !< names this process's scratch file
    type(sweep_setup), intent(out) :: setup               !< the sweep
    type(error_type), allocatable, intent(inout) :: error !< set on bad input
    character(len=*), intent(in), optional :: scratch_file !< a writable file of the caller's
    logical :: exists
    call read_sweep_definition(path, setup%def, error)
    if (allocated(error)) return
    call load_base_scenario(setup%def%base, setup%base, error)
    if (allocated(error)) return
    call check_varied_inputs(setup%def, setup%base, error)
    if (allocated(error)) return
    call settle_worst_by(setup%def, setup%base, error)
    if (allocated(error)) return
    if (present(scratch_file)) then
      call check_common_settings(setup%def, setup%base, scratch_file, error)
    else
      call make_output_dir(setup%def, setup%def%work_dir(), error)
      if (allocated(error)) return
      call check_common_settings(setup%def, setup%base, setup%def%work_dir() // "/check_" // tag // ".nml", &
        error)
    end if
    if (allocated(error)) return
    inquire(file=setup%def%table_path(), exist=exists)
    if (.not. need_table .and. .not. exists) return
    call read_case_table(setup%def%table_path(), setup%def, setup%table, error)
  end subroutine load_sweep

  !> What the journal's rows depend on: a row is reused only if all of this
  !> is unchanged.
  function fingerprint_text(setup) result(s)
    type(sweep_setup), intent(in) :: setup
    character(len=:), allocatable :: s
    character(len=1), parameter :: nl = new_line("a")
    character(len=:), allocatable :: bytes
    integer :: k
    real(dp), allocatable :: flat(:)
    flat = reshape(setup%table%values, [size(setup%table%values)])
    allocate(character(len=8*max(1, size(flat))) :: bytes)
    bytes = transfer(flat, bytes)
    ! the code by the digest of its sources and build settings, not by its git
    ! description: an edited input or document ("-dirty") would refuse the resume
    s = "code_digest = " // code_digest // nl // &
      "base = " // setup%def%base // nl // &
      "base_text_fnv1a = " // fnv1a(setup%base%text) // nl // &
      "t_end = " // str(setup%def%t_end) // nl // &
      "n_cases = " // str(setup%table%n_cases) // nl // "inputs ="
    do k = 1, size(setup%def%inputs)
      s = s // " " // setup%def%inputs(k)%name
    end do
    s = s // nl
    do k = 1, size(setup%def%fixed)
      s = s // "fixed " // setup%def%fixed(k)%name // " = " // setup%def%fixed(k)%value // nl
    end do
    s = s // "table_values_fnv1a = " // fnv1a(bytes) // nl
  end function fingerprint_text

  !> Cases that keep a full trajectory: failed ones (keep_failed), the
  !> keep_worst worst by worst_by among the ok ones, and keep_ids; sorted,
  !> each once.  An invalid_input case is never one: its input cannot run,
  !> so it can have no trajectory.
  function trajectory_ids(def, metrics, rows) result(ids)
    type(sweep_definition), intent(in) :: def   !< the sweep
    type(metric_set), intent(in) :: metrics     !< its scene's summary variables (worst_by is one: load_sweep)
    type(sweep_row), intent(in) :: rows(:)      !< all rows, by id
    integer, allocatable :: ids(:)
    logical :: keep(size(rows))
    real(dp) :: key(size(rows)), sgn
    integer :: m, k, j, best
    logical :: clearance
    keep = .false.
    if (def%keep_failed) keep = rows%status == status_failed
    do k = 1, size(def%keep_ids)
      keep(def%keep_ids(k) + 1) = .true.
    end do
    if (def%keep_worst > 0) then
      m = metrics%index(def%worst_by)
      ! smaller clearances are worse; larger loads, excursions and speeds are worse
      clearance = def%worst_by == "min_clearance_m" .or. def%worst_by == "min_line_clearance_m" .or. &
        def%worst_by == "min_exit_clearance_m"
      sgn = merge(1.0_dp, -1.0_dp, clearance)
      do k = 1, size(rows)
        key(k) = huge(1.0_dp)
        if (rows(k)%status /= status_ok) cycle
        if (rows(k)%metrics(m) == rows(k)%metrics(m)) then
          key(k) = sgn*rows(k)%metrics(m)
        else if (clearance) then
          ! a clearance never reached (the rocket never separated): the worst,
          ! as the envelope ranks it (its margin NaN fails); a NaN load or
          ! speed is no event (no break: no recoil; no touchdown before t_end)
          ! and is not kept
          key(k) = -huge(1.0_dp)
        end if
      end do
      do j = 1, min(def%keep_worst, size(rows))
        best = minloc(key, dim=1)
        if (key(best) == huge(1.0_dp)) exit
        keep(best) = .true.
        key(best) = huge(1.0_dp)
      end do
    end if
    keep = keep .and. rows%status /= status_invalid
    ids = pack([(k - 1, k = 1, size(rows))], keep)
  end function trajectory_ids

  !> keep_worst ranks the cases by worst_by: a summary variable of the base's
  !> scene (the airlaunch scene's clearance, say, is not one of the line
  !> scene's).  Not set, it is the scene's first of worst_by_names:
  !> min_clearance_m, for a line scene peak_line_tension_N.
  subroutine settle_worst_by(def, base, error)
    type(sweep_definition), intent(inout) :: def          !< the sweep
    type(base_scenario), intent(in) :: base               !< its base scenario
    type(error_type), allocatable, intent(inout) :: error !< set if it is not
    character(len=:), allocatable :: allowed
    integer :: k
    if (len(def%worst_by) == 0) then
      do k = 1, size(worst_by_names)
        if (base%metrics%index(trim(worst_by_names(k))) > 0) then
          def%worst_by = trim(worst_by_names(k))
          exit
        end if
      end do
    end if
    if (def%keep_worst == 0 .or. base%metrics%index(def%worst_by) > 0) return
    allowed = ""
    do k = 1, size(worst_by_names)
      if (base%metrics%index(trim(worst_by_names(k))) > 0) allowed = allowed // trim(worst_by_names(k)) // ", "
    end do
    call fatal_error(error, def%path // ": &sweep: worst_by = '" // def%worst_by // "' is not allowed with a " // &
      "base scenario of scene '" // trim(base%scene) // "' (with keep_worst > 0 it must be one of its summary " // &
      "variables: " // allowed(:len(allowed)-2) // ")")
  end subroutine settle_worst_by

  !> Make a directory under the definition's output_dir; a failure names
  !> &sweep output_dir (a file in its way, no permission).
  subroutine make_output_dir(def, dir, error)
    type(sweep_definition), intent(in) :: def             !< the sweep
    character(len=*), intent(in) :: dir                   !< a directory under def%output_dir
    type(error_type), allocatable, intent(inout) :: error !< set if it cannot be made
    call make_dir(dir, error)
    if (allocated(error)) error%message = def%path // ": &sweep: output_dir = '" // def%output_dir // &
      "' is not usable: " // error%message // " (a file in the way, or no permission)"
  end subroutine make_output_dir
end module airlaunch_sweep_plan
