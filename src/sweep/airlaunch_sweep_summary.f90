!> The summary of a sweep (netCDF-4): dimension `case`, the varied inputs,
!> `status` and `failure`, and one variable per metric (docs/sweep.md).  The
!> rows come sorted by case id whatever the order or the ranks that ran them;
!> the file is written under a temporary name and renamed (nc_writer).
module airlaunch_sweep_summary
  use, intrinsic :: iso_c_binding, only: c_ptr, c_loc, c_char, c_null_char, c_null_ptr
  use hdf5
  use h5lt
  use h5ds
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_ncwrite, only: nc_writer
  use airlaunch_version, only: code_version
  use airlaunch_sweep_definition, only: sweep_definition
  use airlaunch_sweep_table, only: case_table
  use airlaunch_sweep_case, only: base_scenario
  use airlaunch_sweep_row, only: sweep_row, n_metrics, metric_names, metric_units, metric_long_names, &
    metric_is_integer, status_ok, status_failed, status_invalid
  implicit none
  private
  public :: write_summary

contains

  !> Write the summary of `rows` (one per case, rows(k)%id = k - 1) to `path`.
  subroutine write_summary(path, def, table, base, rows, error)
    character(len=*), intent(in) :: path                  !< summary file
    type(sweep_definition), intent(in) :: def             !< the sweep
    type(case_table), intent(in) :: table                 !< its cases
    type(base_scenario), intent(in) :: base               !< its base scenario
    type(sweep_row), intent(in) :: rows(:)                !< the rows, by id
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    type(nc_writer) :: w
    integer :: k, n, j
    integer, allocatable :: ibuf(:)
    real(dp), allocatable :: rbuf(:)
    integer :: maxlen
    character(len=32) :: stamp
    integer :: v(8)

    n = size(rows)
    if (any(rows%id /= [(k, k = 0, n - 1)])) then
      call fatal_error(error, path // ": internal error: summary rows are not sorted by case id")
      return
    end if
    call w%create(path, error)
    if (allocated(error)) return
    call add_int_dim(w, "case", [(k, k = 0, n - 1)], "1", "case id (row of the case table)", error)
    allocate(rbuf(n), ibuf(n))
    do k = 1, size(def%inputs)
      rbuf = table%values(k, :)
      call w%add_var_1d(def%inputs(k)%name, ["case"], rbuf, units_of(def%inputs(k)%units), &
        "varied input " // def%inputs(k)%name // " (" // def%inputs(k)%distribution // ")", error)
      call w%add_text_att(def%inputs(k)%name, "distribution", def%inputs(k)%distribution, error)
    end do
    ibuf = rows%status
    call w%add_int_var_1d("status", ["case"], ibuf, "1", "case status", error)
    call add_int_atts(w, "status", "flag_values", [status_ok, status_failed, status_invalid], error)
    call w%add_text_att("status", "flag_meanings", "ok failed invalid_input", error)
    maxlen = 1
    do k = 1, n
      if (allocated(rows(k)%message)) maxlen = max(maxlen, len(rows(k)%message))
    end do
    block
      character(len=maxlen) :: messages(n)
      do k = 1, n
        messages(k) = ""
        if (allocated(rows(k)%message)) messages(k) = rows(k)%message
      end do
      call add_string_var(w, "failure", "case", messages, "failure message (empty if status = ok)", error)
    end block
    do k = 1, n_metrics
      rbuf = [(rows(j)%metrics(k), j = 1, n)]
      if (metric_is_integer(k)) then
        ibuf = nint(merge(rbuf, -1.0_dp, rbuf == rbuf))
        call w%add_int_var_1d(trim(metric_names(k)), ["case"], ibuf, trim(metric_units(k)), &
          trim(metric_long_names(k)) // " (-1: not run)", error)
      else
        call w%add_var_1d(trim(metric_names(k)), ["case"], rbuf, trim(metric_units(k)), &
          trim(metric_long_names(k)), error)
      end if
    end do
    call date_and_time(values=v)
    write(stamp, '(i4.4,"-",i2.2,"-",i2.2,"T",i2.2,":",i2.2,":",i2.2)') v(1), v(2), v(3), v(5), v(6), v(7)
    call w%add_text_att("/", "title", "airlaunch sweep summary: " // def%name, error)
    call w%add_text_att("/", "sweep_name", def%name, error)
    call w%add_text_att("/", "definition", def%path, error)
    call w%add_text_att("/", "design", def%design, error)
    call add_int_atts(w, "/", "seed", [def%seed], error)
    call add_int_atts(w, "/", "n_cases", [n], error)
    call add_int_atts(w, "/", "n_ok", [count(rows%status == status_ok)], error)
    call add_int_atts(w, "/", "n_failed", [count(rows%status == status_failed)], error)
    call add_int_atts(w, "/", "n_invalid_input", [count(rows%status == status_invalid)], error)
    call w%add_text_att("/", "inputs", input_list(def), error)
    call w%add_text_att("/", "base", def%base, error)
    call w%add_text_att("/", "base_namelist", base%echo, error)
    call w%add_real_att("/", "t_end_s", merge(def%t_end, base%t_end, def%t_end > 0.0_dp), error)
    call w%add_text_att("/", "table", def%table_path(), error)
    call w%add_text_att("/", "criteria", def%criteria, error)
    call w%add_text_att("/", "code_version", "airlaunch " // code_version, error)
    call w%add_text_att("/", "created", trim(stamp), error)
    call w%add_text_att("/", "conventions", "one row per case, sorted by case id; NaN: event not reached or " // &
      "value not defined; metrics of failed cases are those up to the failure; invalid_input: the scenario " // &
      "reader rejected the case's values (message in failure)", error)
    if (allocated(error)) then
      call w%abort()
      return
    end if
    call w%commit(error)
  end subroutine write_summary

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

  !> An integer dimension with its coordinate variable.
  subroutine add_int_dim(w, name, values, units, long_name, error)
    type(nc_writer), intent(inout) :: w
    character(len=*), intent(in) :: name, units, long_name
    integer, intent(in) :: values(:)
    type(error_type), allocatable, intent(inout) :: error
    integer :: hdferr
    integer(hid_t) :: did
    if (allocated(error)) return
    call h5ltmake_dataset_int_f(w%fid, name, 1, [size(values, kind=hsize_t)], values, hdferr)
    if (hdferr /= 0) then
      call fatal_error(error, w%tmp_path // ": cannot write variable " // name)
      return
    end if
    call h5dopen_f(w%fid, name, did, hdferr)
    call h5dsset_scale_f(did, hdferr, name)
    call h5dclose_f(did, hdferr)
    w%dim_names = [character(len=32) :: w%dim_names, name]
    w%dim_sizes = [w%dim_sizes, size(values, kind=hsize_t)]
    call w%add_text_att(name, "units", units, error)
    call w%add_text_att(name, "long_name", long_name, error)
  end subroutine add_int_dim

  !> Integer attribute(s) of a variable, or of the file if `var` is "/".
  subroutine add_int_atts(w, var, name, values, error)
    type(nc_writer), intent(inout) :: w
    character(len=*), intent(in) :: var, name
    integer, intent(in) :: values(:)
    type(error_type), allocatable, intent(inout) :: error
    integer :: hdferr
    if (allocated(error)) return
    call h5ltset_attribute_int_f(w%fid, var, name, values, size(values, kind=size_t), hdferr)
    if (hdferr /= 0) call fatal_error(error, w%tmp_path // ": cannot write attribute " // name // " of " // var)
  end subroutine add_int_atts

  !> A variable-length string variable over dimension `dim` (netCDF NC_STRING).
  subroutine add_string_var(w, name, dim, values, long_name, error)
    type(nc_writer), intent(inout) :: w
    character(len=*), intent(in) :: name, dim, long_name
    character(len=*), intent(in) :: values(:)
    type(error_type), allocatable, intent(inout) :: error
    character(kind=c_char, len=:), allocatable, target :: buf
    type(c_ptr), allocatable, target :: ptrs(:)
    integer(hid_t) :: tid, sid, did, scale
    integer :: hdferr, k, p, e
    integer(hsize_t) :: dims(1)
    integer, allocatable :: starts(:)
    if (allocated(error)) return
    ! all strings, each NUL-terminated, in one buffer; ptrs(k) points at string k
    allocate(starts(size(values)))
    buf = ""
    do k = 1, size(values)
      starts(k) = len(buf) + 1
      buf = buf // trim(values(k)) // c_null_char
    end do
    allocate(ptrs(size(values)))
    do k = 1, size(values)
      p = starts(k)
      ptrs(k) = c_loc(buf(p:p))
    end do
    if (size(values) == 0) ptrs = c_null_ptr
    dims = size(values)
    e = 0
    ! HDF5's Fortran H5T_STRING is the variable-length C string type
    call h5tcopy_f(H5T_STRING, tid, hdferr); e = e + abs(hdferr)
    call h5tset_strpad_f(tid, H5T_STR_NULLTERM_F, hdferr); e = e + abs(hdferr)
    call h5screate_simple_f(1, dims, sid, hdferr); e = e + abs(hdferr)
    call h5dcreate_f(w%fid, name, tid, sid, did, hdferr); e = e + abs(hdferr)
    call h5dwrite_f(did, tid, c_loc(ptrs), hdferr); e = e + abs(hdferr)
    call h5dopen_f(w%fid, dim, scale, hdferr); e = e + abs(hdferr)
    call h5dsattach_scale_f(did, scale, 1, hdferr); e = e + abs(hdferr)
    call h5dclose_f(scale, hdferr)
    call h5dclose_f(did, hdferr)
    call h5sclose_f(sid, hdferr)
    call h5tclose_f(tid, hdferr)
    if (e /= 0) then
      call fatal_error(error, w%tmp_path // ": cannot write the string variable " // name)
      return
    end if
    call w%add_text_att(name, "long_name", long_name, error)
  end subroutine add_string_var
end module airlaunch_sweep_summary
