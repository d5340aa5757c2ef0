!> The summary of a sweep (netCDF-4): dimension `case`, the varied inputs,
!> `status` and `failure`, one variable per metric, and `environment`: which
!> runtime numerical environment (the `environments` attribute) computed each
!> case (docs/sweep.md).  The
!> rows come sorted by case id whatever the order or the ranks that ran them;
!> the file is written under a temporary name and renamed (nc_writer).
module airlaunch_sweep_summary
  use hdf5
  use h5lt
  use h5ds
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_ncwrite, only: nc_writer
  use airlaunch_version, only: code_version, code_digest
  use airlaunch_output_meta, only: creation_time
  use airlaunch_sweep_definition, only: sweep_definition
  use airlaunch_sweep_table, only: case_table
  use airlaunch_sweep_case, only: base_scenario
  use airlaunch_sweep_row, only: sweep_row, status_ok, status_failed, status_invalid
  use airlaunch_sweep_journal, only: fnv1a, environment_len
  use airlaunch_runtime_env, only: query_runtime_env, write_runtime_env
  implicit none
  private
  public :: write_summary

contains

  !> Write the summary of `rows` (one per case, rows(k)%id = k - 1) to `path`;
  !> env_tags(k) names the environment env_texts(k) (the journal's
  !> environments.txt) that the rows' tags refer to.
  subroutine write_summary(path, def, table, base, rows, env_tags, env_texts, error)
    character(len=*), intent(in) :: path                  !< summary file
    type(sweep_definition), intent(in) :: def             !< the sweep
    type(case_table), intent(in) :: table                 !< its cases
    type(base_scenario), intent(in) :: base               !< its base scenario
    type(sweep_row), intent(in) :: rows(:)                !< the rows, by id
    character(len=16), intent(in) :: env_tags(:)          !< environment tags
    character(len=environment_len), intent(in) :: env_texts(:) !< their environments
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    type(nc_writer) :: w
    integer :: k, n, j
    integer, allocatable :: ibuf(:)
    real(dp), allocatable :: rbuf(:)
    character(len=16), allocatable :: used(:)   !< the rows' distinct tags, in case order
    integer, allocatable :: ends(:)
    integer :: total
    character(len=:), allocatable :: messages

    n = size(rows)
    if (any(rows%id /= [(k, k = 0, n - 1)])) then
      call fatal_error(error, path // ": internal error: summary rows are not sorted by case id")
      return
    end if
    call w%create(path, error)
    if (allocated(error)) return
    call w%add_int_dim("case", [(k, k = 0, n - 1)], "1", "case id (row of the case table)", error)
    allocate(rbuf(n), ibuf(n))
    do k = 1, size(def%inputs)
      rbuf = table%values(k, :)
      ! long_name: the input's description when it has one, as in the table
      ! (input_attrs in postproc/sweep/table.py)
      if (len(def%inputs(k)%description) > 0) then
        call w%add_var_1d(def%inputs(k)%name, ["case"], rbuf, units_of(def%inputs(k)%units), &
          def%inputs(k)%description, error)
      else
        call w%add_var_1d(def%inputs(k)%name, ["case"], rbuf, units_of(def%inputs(k)%units), &
          "varied input " // def%inputs(k)%name // " (" // def%inputs(k)%distribution // ")", error)
      end if
      call w%add_text_att(def%inputs(k)%name, "distribution", def%inputs(k)%distribution, error)
    end do
    ibuf = rows%status
    call w%add_int_var_1d("status", ["case"], ibuf, "1", "case status", error)
    call w%add_int_att("status", "flag_values", [status_ok, status_failed, status_invalid], error)
    call w%add_text_att("status", "flag_meanings", "ok failed invalid_input", error)
    ! the messages one after the other (no array padded to the longest: n times its length)
    allocate(ends(n))
    total = 0
    do k = 1, n
      if (allocated(rows(k)%message)) total = total + len_trim(rows(k)%message)
      ends(k) = total
    end do
    allocate(character(len=total) :: messages)
    total = 0
    do k = 1, n
      if (ends(k) > total) messages(total+1:ends(k)) = rows(k)%message
      total = ends(k)
    end do
    call w%add_ragged_string_var_1d("failure", "case", messages, ends, "failure message (empty if status = ok)", &
      error)
    associate(m => base%metrics)
      do k = 1, m%size()
        rbuf = [(rows(j)%metrics(k), j = 1, n)]
        if (m%is_integer(k)) then
          ibuf = nint(merge(rbuf, -1.0_dp, rbuf == rbuf))
          call w%add_int_var_1d(trim(m%names(k)), ["case"], ibuf, trim(m%units(k)), &
            trim(m%long_names(k)) // " (-1: not run)", error)
        else
          call w%add_var_1d(trim(m%names(k)), ["case"], rbuf, trim(m%units(k)), trim(m%long_names(k)), error)
        end if
      end do
    end associate
    ! the environment of each case: an index into the distinct ones (-1: the row has none)
    allocate(used(0))
    do k = 1, n
      if (len_trim(rows(k)%environment) == 0) then
        ibuf(k) = -1
        cycle
      end if
      if (.not. any(used == rows(k)%environment)) used = [used, rows(k)%environment]
      ibuf(k) = findloc(used, rows(k)%environment, dim=1) - 1
    end do
    call w%add_int_var_1d("environment", ["case"], ibuf, "1", "runtime numerical environment that computed " // &
      "the case: its line in the global attribute environments (-1: not recorded)", error)
    call w%add_text_att("/", "environments", environment_list(used, env_tags, env_texts), error)
    call w%add_text_att("/", "title", "airlaunch sweep summary: " // def%name, error)
    call w%add_text_att("/", "sweep_name", def%name, error)
    call w%add_text_att("/", "definition", def%path, error)
    call w%add_text_att("/", "design", def%design, error)
    call w%add_int_att("/", "seed", [def%seed], error)
    call w%add_int_att("/", "n_cases", [n], error)
    call w%add_int_att("/", "n_ok", [count(rows%status == status_ok)], error)
    call w%add_int_att("/", "n_failed", [count(rows%status == status_failed)], error)
    call w%add_int_att("/", "n_invalid_input", [count(rows%status == status_invalid)], error)
    call w%add_text_att("/", "inputs", input_list(def), error)
    call w%add_text_att("/", "base", def%base, error)
    call w%add_text_att("/", "base_namelist", base%echo, error)
    ! what the envelope and verify steps check against the definition as it is now
    call w%add_text_att("/", "base_text_fnv1a", fnv1a(base%text), error)
    call w%add_text_att("/", "fixed", fixed_text(def), error)
    call w%add_text_att("/", "scene", trim(base%scene), error)
    call w%add_real_att("/", "t_end_s", merge(def%t_end, base%t_end, def%t_end > 0.0_dp), error)
    call w%add_text_att("/", "table", def%table_path(), error)
    call w%add_text_att("/", "criteria", def%criteria, error)
    call w%add_text_att("/", "code_version", "airlaunch " // code_version, error)
    call w%add_text_att("/", "code_digest", code_digest, error)
    ! the writer's own (rank 0's); the cases' are in `environment`
    call write_runtime_env(w, query_runtime_env(with_mpi=.true.), error)
    call w%add_text_att("/", "created", creation_time(), error)
    call w%add_text_att("/", "comment", "one row per case, sorted by case id; NaN: event not reached or " // &
      "value not defined; metrics of failed cases are those up to the failure; invalid_input: the scenario " // &
      "reader rejected the case's values (message in failure)", error)
    if (allocated(error)) then
      call w%abort()
      return
    end if
    call w%commit(error)
  end subroutine write_summary

  !> "0: <environment>", one line per tag of `used` (its text from the
  !> journal's, "unknown" for a tag it does not hold).
  function environment_list(used, env_tags, env_texts) result(s)
    character(len=16), intent(in) :: used(:)       !< tags, in the order of their index
    character(len=16), intent(in) :: env_tags(:)   !< the journal's tags
    character(len=environment_len), intent(in) :: env_texts(:) !< their environments
    character(len=:), allocatable :: s
    integer :: k, j
    s = ""
    do k = 1, size(used)
      if (k > 1) s = s // new_line("a")
      j = findloc(env_tags, used(k), dim=1)
      if (j > 0) then
        s = s // str(k - 1) // ": " // trim(env_texts(j))
      else
        s = s // str(k - 1) // ": unknown (tag " // used(k) // " is not in journal/environments.txt)"
      end if
    end do
  end function environment_list

  !> The definition's &fixed, one "name = value" per line ('' for none).
  function fixed_text(def) result(s)
    type(sweep_definition), intent(in) :: def   !< the sweep
    character(len=:), allocatable :: s
    integer :: k
    s = ""
    do k = 1, size(def%fixed)
      if (k > 1) s = s // new_line("a")
      s = s // def%fixed(k)%name // " = " // def%fixed(k)%value
    end do
  end function fixed_text

  !> Space-separated names of the varied inputs.
  function input_list(def) result(s)
    type(sweep_definition), intent(in) :: def
    character(len=:), allocatable :: s
    integer :: k
    s = ""
    do k = 1, size(def%inputs)
      if (k > 1) s = s // " "
      s = s // def%inputs(k)%name
    end do
  end function input_list

  function units_of(u) result(s)
    character(len=*), intent(in) :: u
    character(len=:), allocatable :: s
    s = u
    if (len_trim(u) == 0) s = "1"
  end function units_of

end module airlaunch_sweep_summary
