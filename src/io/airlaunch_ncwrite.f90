!> netCDF-4 files written through HDF5 (parallel build, used serially here).
!>
!> A netCDF-4 file is an HDF5 file whose dimensions are HDF5 dimension scales;
!> every dimension here has a coordinate variable of the same name, so
!> `xarray.open_dataset(path)` reads the file directly, with units and long
!> names.  Arrays are given in Fortran order (fastest index first); xarray
!> shows the dimensions reversed, e.g. Fortran position(xyz, time) reads as
!> position(time, xyz).
!>
!> The file is written under `<path>.part` and renamed to `<path>` by
!> `commit`, so a crash never leaves a truncated file under the final name.
module airlaunch_ncwrite
  use, intrinsic :: iso_c_binding, only: c_int, c_char, c_null_char, c_ptr, c_loc, c_null_ptr
  use hdf5
  use h5lt
  use h5ds
  use airlaunch_kinds, only: dp, i8
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_path, only: free_bytes, file_size_limit, delete_file, parent_directory
  implicit none
  private
  public :: nc_writer

  interface
    integer(c_int) function c_rename(old, new) bind(C, name="rename")
      import :: c_int, c_char
      implicit none
      character(kind=c_char), intent(in) :: old(*), new(*)
    end function c_rename
  end interface

  !> An open output file.
  type :: nc_writer
    integer(hid_t) :: fid = -1
    character(len=:), allocatable :: path, tmp_path
    character(len=32), allocatable :: dim_names(:)
    integer(hsize_t), allocatable :: dim_sizes(:)
  contains
    procedure :: create => nc_create
    procedure :: add_dim => nc_add_dim
    procedure :: add_var_1d => nc_add_var_1d
    procedure :: add_var_2d => nc_add_var_2d
    procedure :: add_var_3d => nc_add_var_3d
    procedure :: add_int_var_1d => nc_add_int_var_1d
    procedure :: add_int_dim => nc_add_int_dim
    procedure :: add_string_var_1d => nc_add_string_var_1d
    procedure :: add_ragged_string_var_1d => nc_add_ragged_string_var_1d
    procedure :: add_int_att => nc_add_int_att
    procedure :: add_text_att => nc_add_text_att
    procedure :: add_real_att => nc_add_real_att
    procedure :: commit => nc_commit
    procedure :: abort => nc_abort
    procedure :: finish => nc_finish
  end type nc_writer

contains

  !> Create `<path>.part`, empty.
  subroutine nc_create(self, path, error)
    class(nc_writer), intent(inout) :: self
    character(len=*), intent(in) :: path                  !< final file name
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    integer :: hdferr, create_err
    integer(hid_t) :: fcpl
    self%path = trim(path)
    self%tmp_path = trim(path) // ".part"
    allocate(self%dim_names(0), self%dim_sizes(0))
    ! no HDF5 clean-up at the program's exit: every file is closed here
    ! (commit or abort), and one whose close failed (a full disk) made HDF5's
    ! exit handler crash (SIGSEGV, the program's last lines lost).  Only
    ! possible before HDF5's first use in the process; later calls do nothing.
    call h5dont_atexit_f(hdferr)
    call h5open_f(hdferr)
    ! library code never prints: HDF5's own error stack goes silent, its
    ! failures come back as error values with the file's name
    call h5eset_auto_f(0, hdferr)
    ! netCDF-4 tracks link and attribute creation order; set it the same way.
    call h5pcreate_f(H5P_FILE_CREATE_F, fcpl, hdferr)
    call h5pset_link_creation_order_f(fcpl, ior(H5P_CRT_ORDER_TRACKED_F, H5P_CRT_ORDER_INDEXED_F), hdferr)
    call h5pset_attr_creation_order_f(fcpl, ior(H5P_CRT_ORDER_TRACKED_F, H5P_CRT_ORDER_INDEXED_F), hdferr)
    call h5fcreate_f(self%tmp_path, H5F_ACC_TRUNC_F, self%fid, create_err, creation_prp=fcpl)
    call h5pclose_f(fcpl, hdferr)
    if (create_err /= 0) then
      call write_failure(self, error, "cannot create the output file (directory missing or not writable?)")
      self%fid = -1
    end if
  end subroutine nc_create

  !> A dimension with its coordinate variable (values, units, long name).
  subroutine nc_add_dim(self, name, values, units, long_name, error)
    class(nc_writer), intent(inout) :: self
    character(len=*), intent(in) :: name, units, long_name  !< dimension name and metadata
    real(dp), intent(in) :: values(:)                       !< coordinate values
    type(error_type), allocatable, intent(inout) :: error   !< set on failure
    integer :: hdferr
    integer(hid_t) :: did
    if (allocated(error)) return
    call make_dataset(self, name, [size(values, kind=hsize_t)], values, error)
    if (allocated(error)) return
    call h5dopen_f(self%fid, name, did, hdferr)
    call h5dsset_scale_f(did, hdferr, name)
    call h5dclose_f(did, hdferr)
    call describe(self, name, units, long_name, error)
    self%dim_names = [character(len=32) :: self%dim_names, name]
    self%dim_sizes = [self%dim_sizes, size(values, kind=hsize_t)]
  end subroutine nc_add_dim

  !> A variable over one dimension.
  subroutine nc_add_var_1d(self, name, dims, data, units, long_name, error)
    class(nc_writer), intent(inout) :: self
    character(len=*), intent(in) :: name, units, long_name
    character(len=*), intent(in) :: dims(1)
    real(dp), intent(in) :: data(:)
    type(error_type), allocatable, intent(inout) :: error
    if (allocated(error)) return
    call make_dataset(self, name, shape(data, kind=hsize_t), data, error)
    call finish_var(self, name, dims, shape(data, kind=hsize_t), units, long_name, error)
  end subroutine nc_add_var_1d

  !> A variable over two dimensions (Fortran order).
  subroutine nc_add_var_2d(self, name, dims, data, units, long_name, error)
    class(nc_writer), intent(inout) :: self
    character(len=*), intent(in) :: name, units, long_name
    character(len=*), intent(in) :: dims(2)
    real(dp), intent(in) :: data(:, :)
    type(error_type), allocatable, intent(inout) :: error
    if (allocated(error)) return
    call make_dataset(self, name, shape(data, kind=hsize_t), data, error)
    call finish_var(self, name, dims, shape(data, kind=hsize_t), units, long_name, error)
  end subroutine nc_add_var_2d

  !> A variable over three dimensions (Fortran order).
  subroutine nc_add_var_3d(self, name, dims, data, units, long_name, error)
    class(nc_writer), intent(inout) :: self
    character(len=*), intent(in) :: name, units, long_name
    character(len=*), intent(in) :: dims(3)
    real(dp), intent(in) :: data(:, :, :)
    type(error_type), allocatable, intent(inout) :: error
    if (allocated(error)) return
    call make_dataset(self, name, shape(data, kind=hsize_t), data, error)
    call finish_var(self, name, dims, shape(data, kind=hsize_t), units, long_name, error)
  end subroutine nc_add_var_3d

  !> An integer variable over one dimension.
  subroutine nc_add_int_var_1d(self, name, dims, data, units, long_name, error)
    class(nc_writer), intent(inout) :: self
    character(len=*), intent(in) :: name, units, long_name
    character(len=*), intent(in) :: dims(1)
    integer, intent(in) :: data(:)
    type(error_type), allocatable, intent(inout) :: error
    integer :: hdferr
    if (allocated(error)) return
    call h5ltmake_dataset_int_f(self%fid, name, 1, shape(data, kind=hsize_t), data, hdferr)
    if (hdferr /= 0) then
      call write_failure(self, error, "cannot write variable " // name)
      return
    end if
    call finish_var(self, name, dims, shape(data, kind=hsize_t), units, long_name, error)
  end subroutine nc_add_int_var_1d

  !> A text attribute of a variable, or of the file if `var` is "/".
  subroutine nc_add_text_att(self, var, name, value, error)
    class(nc_writer), intent(inout) :: self
    character(len=*), intent(in) :: var, name, value
    type(error_type), allocatable, intent(inout) :: error
    integer :: hdferr
    if (allocated(error)) return
    if (len(value) == 0) then
      call h5ltset_attribute_string_f(self%fid, var, name, " ", hdferr)
    else
      call h5ltset_attribute_string_f(self%fid, var, name, value, hdferr)
    end if
    if (hdferr /= 0) call write_failure(self, error, "cannot write attribute " // name // " of " // var)
  end subroutine nc_add_text_att

  !> A real attribute of a variable, or of the file if `var` is "/".
  subroutine nc_add_real_att(self, var, name, value, error)
    class(nc_writer), intent(inout) :: self
    character(len=*), intent(in) :: var, name
    real(dp), intent(in) :: value
    type(error_type), allocatable, intent(inout) :: error
    integer :: hdferr
    real(dp) :: buf(1)
    if (allocated(error)) return
    buf(1) = value
    call h5ltset_attribute_double_f(self%fid, var, name, buf, 1_size_t, hdferr)
    if (hdferr /= 0) call write_failure(self, error, "cannot write attribute " // name // " of " // var)
  end subroutine nc_add_real_att

  !> Close the file and rename it to its final name.
  subroutine nc_commit(self, error)
    class(nc_writer), intent(inout) :: self
    type(error_type), allocatable, intent(inout) :: error
    integer :: hdferr
    if (self%fid < 0) return
    call h5fclose_f(self%fid, hdferr)
    self%fid = -1
    if (hdferr /= 0) then
      ! its last data did not reach the disk: an incomplete file, not kept
      call write_failure(self, error, "cannot finish writing the output file, removed")
      call delete_file(self%tmp_path)
      return
    end if
    ! a failed rename keeps the complete file under its .part name (the
    ! result is not lost; the program names it)
    if (c_rename(self%tmp_path // c_null_char, self%path // c_null_char) /= 0) &
      call fatal_error(error, self%path // ": cannot rename " // self%tmp_path // " to it; the complete " // &
        "output is kept as " // self%tmp_path)
  end subroutine nc_commit

  !> End of writing: commit the file if every write succeeded (error not
  !> set), otherwise discard it, keeping the first error.
  subroutine nc_finish(self, error)
    class(nc_writer), intent(inout) :: self
    type(error_type), allocatable, intent(inout) :: error  !< errors of the writes so far
    if (allocated(error)) then
      call self%abort()
    else
      call self%commit(error)
    end if
  end subroutine nc_finish

  !> Close and delete the temporary file (nothing is left under any name).
  subroutine nc_abort(self)
    class(nc_writer), intent(inout) :: self
    integer :: hdferr
    if (self%fid < 0) return
    call h5fclose_f(self%fid, hdferr)
    self%fid = -1
    call delete_file(self%tmp_path)
  end subroutine nc_abort

  !> A failed write to the file: the error names the file and what failed,
  !> adds the likely reason - HDF5 tells none: its file system full when it
  !> (nearly) is, else the file size limit when the process has one, else a
  !> disk quota (what a cluster's scratch space runs out of with room left on
  !> the device) - and marks the error as the output's (error_type%output).
  subroutine write_failure(self, error, what)
    type(nc_writer), intent(in) :: self
    type(error_type), allocatable, intent(inout) :: error
    character(len=*), intent(in) :: what
    real(dp) :: free, limit
    integer(i8) :: written
    character(len=24) :: kb
    character(len=:), allocatable :: note
    note = ""
    free = free_bytes(self%tmp_path)
    if (free < 0.0_dp) free = free_bytes(parent_directory(self%tmp_path))
    limit = file_size_limit()
    inquire(file=self%tmp_path, size=written)
    if (free >= 0.0_dp .and. free < 1048576.0_dp) then
      write (kb, "(i0)") nint(free/1024.0_dp)
      note = " (no space left on the device: " // trim(kb) // " kB free)"
    else if (limit >= 0.0_dp .and. real(written, dp) >= min(0.5_dp*limit, limit - 1048576.0_dp)) then
      ! (the file has reached the limit, or half of it: a write that would
      ! have crossed it failed)
      write (kb, "(i0)") nint(limit/1024.0_dp)
      note = " (the process has a file size limit, ulimit -f, of " // trim(kb) // " kB)"
    else if (free >= 0.0_dp) then
      write (kb, "(i0)") nint(free/1048576.0_dp)
      note = " (" // trim(kb) // " MB free on the device: a disk quota may be full, see quota -s)"
    end if
    call fatal_error(error, self%tmp_path // ": " // what // note)
    error%output = .true.
  end subroutine write_failure

  !> An integer dimension with its coordinate variable.
  subroutine nc_add_int_dim(self, name, values, units, long_name, error)
    class(nc_writer), intent(inout) :: self
    character(len=*), intent(in) :: name, units, long_name
    integer, intent(in) :: values(:)
    type(error_type), allocatable, intent(inout) :: error
    integer :: hdferr
    integer(hid_t) :: did
    if (allocated(error)) return
    call h5ltmake_dataset_int_f(self%fid, name, 1, [size(values, kind=hsize_t)], values, hdferr)
    if (hdferr /= 0) then
      call write_failure(self, error, "cannot write variable " // name)
      return
    end if
    call h5dopen_f(self%fid, name, did, hdferr)
    call h5dsset_scale_f(did, hdferr, name)
    call h5dclose_f(did, hdferr)
    self%dim_names = [character(len=32) :: self%dim_names, name]
    self%dim_sizes = [self%dim_sizes, size(values, kind=hsize_t)]
    call self%add_text_att(name, "units", units, error)
    call self%add_text_att(name, "long_name", long_name, error)
  end subroutine nc_add_int_dim

  !> Integer attribute(s) of a variable, or of the file if `var` is "/".
  subroutine nc_add_int_att(self, var, name, values, error)
    class(nc_writer), intent(inout) :: self
    character(len=*), intent(in) :: var, name
    integer, intent(in) :: values(:)
    type(error_type), allocatable, intent(inout) :: error
    integer :: hdferr
    if (allocated(error)) return
    call h5ltset_attribute_int_f(self%fid, var, name, values, size(values, kind=size_t), hdferr)
    if (hdferr /= 0) call write_failure(self, error, "cannot write attribute " // name // " of " // var)
  end subroutine nc_add_int_att

  !> A variable-length string variable over dimension `dim` (netCDF NC_STRING),
  !> one string per element of `values`, its trailing blanks left out.
  subroutine nc_add_string_var_1d(self, name, dim, values, long_name, error)
    class(nc_writer), intent(inout) :: self
    character(len=*), intent(in) :: name, dim, long_name
    character(len=*), intent(in) :: values(:)
    type(error_type), allocatable, intent(inout) :: error
    character(len=:), allocatable :: text
    integer, allocatable :: ends(:)
    integer :: k, p
    allocate(ends(size(values)))
    p = 0
    do k = 1, size(values)
      p = p + len_trim(values(k))
      ends(k) = p
    end do
    allocate(character(len=p) :: text)
    p = 0
    do k = 1, size(values)
      text(p+1:ends(k)) = values(k)(:ends(k)-p)
      p = ends(k)
    end do
    call self%add_ragged_string_var_1d(name, dim, text, ends, long_name, error)
  end subroutine nc_add_string_var_1d

  !> A variable-length string variable over dimension `dim` (netCDF NC_STRING)
  !> of strings of any lengths, given one after the other: string k is
  !> text(ends(k-1)+1:ends(k)), ends(0) = 0.  The NUL-terminated C strings are
  !> made in one buffer of the total length, in one pass: the strings' count
  !> does not multiply the bytes copied (appended one by one, the buffer was
  !> copied for every string: O(n^2) bytes, 88 s for the summary of 50 000
  !> failed cases).
  subroutine nc_add_ragged_string_var_1d(self, name, dim, text, ends, long_name, error)
    class(nc_writer), intent(inout) :: self
    character(len=*), intent(in) :: name, dim, long_name
    character(len=*), intent(in) :: text    !< the strings, one after the other
    integer, intent(in) :: ends(:)          !< where each string ends in `text`
    type(error_type), allocatable, intent(inout) :: error
    character(kind=c_char, len=:), allocatable, target :: buf
    type(c_ptr), allocatable, target :: ptrs(:)
    integer(hid_t) :: tid, sid, did, scale
    integer :: hdferr, k, p, q, e
    integer(hsize_t) :: dims(1)
    if (allocated(error)) return
    ! all strings, each NUL-terminated, in one buffer; ptrs(k) points at string k
    allocate(character(kind=c_char, len=len(text) + size(ends)) :: buf)
    allocate(ptrs(size(ends)))
    p = 0
    do k = 1, size(ends)
      q = p + k   ! string k starts at q in buf (k - 1 NULs before it)
      buf(q:q+ends(k)-p-1) = text(p+1:ends(k))
      buf(q+ends(k)-p:q+ends(k)-p) = c_null_char
      ptrs(k) = c_loc(buf(q:q))
      p = ends(k)
    end do
    if (size(ends) == 0) ptrs = c_null_ptr
    dims = size(ends)
    e = 0
    ! HDF5's Fortran H5T_STRING is the variable-length C string type
    call h5tcopy_f(H5T_STRING, tid, hdferr); e = e + abs(hdferr)
    call h5tset_strpad_f(tid, H5T_STR_NULLTERM_F, hdferr); e = e + abs(hdferr)
    call h5screate_simple_f(1, dims, sid, hdferr); e = e + abs(hdferr)
    call h5dcreate_f(self%fid, name, tid, sid, did, hdferr); e = e + abs(hdferr)
    call h5dwrite_f(did, tid, c_loc(ptrs), hdferr); e = e + abs(hdferr)
    call h5dopen_f(self%fid, dim, scale, hdferr); e = e + abs(hdferr)
    call h5dsattach_scale_f(did, scale, 1, hdferr); e = e + abs(hdferr)
    call h5dclose_f(scale, hdferr)
    call h5dclose_f(did, hdferr)
    call h5sclose_f(sid, hdferr)
    call h5tclose_f(tid, hdferr)
    if (e /= 0) then
      call write_failure(self, error, "cannot write the string variable " // name)
      return
    end if
    call self%add_text_att(name, "long_name", long_name, error)
  end subroutine nc_add_ragged_string_var_1d

  ! ---------------------------------------------------------------------

  subroutine make_dataset(self, name, dims, data, error)
    type(nc_writer), intent(inout) :: self
    character(len=*), intent(in) :: name
    integer(hsize_t), intent(in) :: dims(:)
    real(dp), intent(in) :: data(*)
    type(error_type), allocatable, intent(inout) :: error
    integer :: hdferr
    if (self%fid < 0) then
      call fatal_error(error, "output file is not open")
      return
    end if
    call h5ltmake_dataset_double_f(self%fid, name, size(dims), dims, data, hdferr)
    if (hdferr /= 0) call write_failure(self, error, "cannot write variable " // name)
  end subroutine make_dataset

  !> Attach dimension scales and write units/long_name.
  subroutine finish_var(self, name, dims, shp, units, long_name, error)
    type(nc_writer), intent(inout) :: self
    character(len=*), intent(in) :: name, units, long_name
    character(len=*), intent(in) :: dims(:)
    integer(hsize_t), intent(in) :: shp(:)
    type(error_type), allocatable, intent(inout) :: error
    integer :: k, j, hdferr, r
    integer(hid_t) :: did, sid
    if (allocated(error)) return
    r = size(dims)
    call h5dopen_f(self%fid, name, did, hdferr)
    do k = 1, r
      j = findloc(self%dim_names, dims(k), dim=1)
      if (j == 0) then
        call fatal_error(error, "output variable " // name // ": unknown dimension " // dims(k))
        exit
      end if
      if (self%dim_sizes(j) /= shp(k)) then
        call fatal_error(error, "output variable " // name // ": size does not match dimension " // dims(k))
        exit
      end if
      call h5dopen_f(self%fid, trim(dims(k)), sid, hdferr)
      ! h5dsattach_scale_f takes the dimension in C order (1-based): the
      ! Fortran dimension k of a rank-r dataset is C dimension r - k + 1.
      call h5dsattach_scale_f(did, sid, r - k + 1, hdferr)
      call h5dclose_f(sid, hdferr)
    end do
    call h5dclose_f(did, hdferr)
    call describe(self, name, units, long_name, error)
  end subroutine finish_var

  subroutine describe(self, name, units, long_name, error)
    type(nc_writer), intent(inout) :: self
    character(len=*), intent(in) :: name, units, long_name
    type(error_type), allocatable, intent(inout) :: error
    call self%add_text_att(name, "units", units, error)
    call self%add_text_att(name, "long_name", long_name, error)
  end subroutine describe
end module airlaunch_ncwrite
