!> netCDF string variables (nc_writer%add_string_var_1d, the sweep summary's
!> `failure`): the heap allocations of writing n strings do not grow with n
!> (the C strings are made in one buffer; appended one by one, each string
!> reallocated and copied the whole buffer: O(n^2) bytes, the summary of 50 000
!> failed cases took 88 s), and every string reads back as written (HDF5's
!> own reader: lengths 0 to 40, trailing blanks left out).
program test_ncwrite_strings
  use, intrinsic :: iso_c_binding, only: c_int64_t, c_ptr, c_loc, c_f_pointer, c_char, c_size_t
  use hdf5
  use airlaunch_error, only: error_type
  use airlaunch_strings, only: str
  use airlaunch_ncwrite, only: nc_writer
  use heap_counter, only: heap_allocations, check_counter_sees_allocation
  use testing
  implicit none
  interface
    integer(c_size_t) function c_strlen(s) bind(C, name="strlen")
      import :: c_size_t, c_ptr
      type(c_ptr), value :: s
    end function c_strlen
  end interface
  integer(c_int64_t) :: few, many

  call check_counter_sees_allocation()
  call section("allocations of a string variable do not grow with its length")
  few = allocations_writing(10)   ! HDF5's first write sets up its free lists: not counted
  few = allocations_writing(10)
  many = allocations_writing(2000)
  ! HDF5's own allocations grow a little with the bytes (its global heap collections);
  ! one allocation per string or more (the appending buffer: ~5 per string) is the fault
  call check(many - few < 100, "2000 strings: " // str(int(many)) // " allocations, 10 strings: " // &
    str(int(few)) // " (difference < 100, not one or more per string)")
  call section("the strings read back as written")
  call check_read_back(2000)
  call finish()

contains

  !> The string of case k: k mod 41 characters, and blanks after them.
  function value_of(k) result(s)
    integer, intent(in) :: k
    character(len=40) :: s
    integer :: i
    s = ""
    do i = 1, mod(k, 41)
      s(i:i) = achar(iachar("a") + mod(k + i, 26))
    end do
  end function value_of

  function file_of(n) result(path)
    integer, intent(in) :: n
    character(len=:), allocatable :: path
    path = "test_ncwrite_strings_" // str(n) // ".nc"
  end function file_of

  !> Heap allocations of add_string_var_1d for n strings (the file is kept).
  function allocations_writing(n) result(count)
    integer, intent(in) :: n
    integer(c_int64_t) :: count
    type(nc_writer) :: w
    type(error_type), allocatable :: error
    character(len=40) :: values(n)
    integer :: k
    integer(c_int64_t) :: before
    do k = 1, n
      values(k) = value_of(k)
    end do
    call w%create(file_of(n), error)
    call w%add_int_dim("case", [(k, k = 0, n - 1)], "1", "case", error)
    before = heap_allocations()
    call w%add_string_var_1d("failure", "case", values, "message", error)
    count = heap_allocations() - before
    call w%commit(error)
    call check(.not. allocated(error), "file with " // str(n) // " strings written")
  end function allocations_writing

  !> Read `failure` of the file of n strings with HDF5 and compare.
  subroutine check_read_back(n)
    integer, intent(in) :: n
    integer(hid_t) :: fid, did, tid
    integer :: hdferr, k, bad
    type(c_ptr), allocatable, target :: ptrs(:)
    type(c_ptr) :: buf
    character(kind=c_char), pointer :: chars(:)
    character(len=40) :: got
    integer :: length
    allocate(ptrs(n))
    call h5open_f(hdferr)
    call h5fopen_f(file_of(n), H5F_ACC_RDONLY_F, fid, hdferr)
    call h5dopen_f(fid, "failure", did, hdferr)
    call h5tcopy_f(H5T_STRING, tid, hdferr)
    buf = c_loc(ptrs)
    call h5dread_f(did, tid, buf, hdferr)
    call check(hdferr == 0, "read " // str(n) // " strings")
    bad = 0
    do k = 1, n
      length = int(c_strlen(ptrs(k)))
      call c_f_pointer(ptrs(k), chars, [max(length, 1)])
      got = ""
      if (length > 0) got = transfer(chars(1:length), got(1:length))
      if (length /= len_trim(value_of(k)) .or. got /= value_of(k)) bad = bad + 1
    end do
    call check(bad == 0, str(n - bad) // " of " // str(n) // " strings read back as written (lengths 0 to 40)")
    call h5tclose_f(tid, hdferr)
    call h5dclose_f(did, hdferr)
    call h5fclose_f(fid, hdferr)
  end subroutine check_read_back
end program test_ncwrite_strings
