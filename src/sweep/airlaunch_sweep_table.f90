!> The case table (netCDF-4, written by postproc/sweep/table.py): dimension
!> `case`, one variable per varied input, the design and the distributions as
!> attributes.  Reading it checks that it is the table of the definition: same
!> inputs in the same order, same design, seed and case count, same
!> distribution parameters, and every value inside its distribution's support.
module airlaunch_sweep_table
  use hdf5
  use h5lt
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_namelist, only: unset_real
  use airlaunch_sweep_definition, only: sweep_definition, sweep_input
  implicit none
  private
  public :: case_table, read_case_table

  !> The cases: values(input, case) of the varied inputs.
  type :: case_table
    character(len=:), allocatable :: path     !< the table file
    integer :: n_cases = 0                    !< number of cases
    integer :: n_inputs = 0                   !< number of varied inputs
    integer, allocatable :: ids(:)            !< case ids 0 .. n_cases-1
    real(dp), allocatable :: values(:, :)     !< (n_inputs, n_cases)
    character(len=:), allocatable :: scipy_version  !< SciPy that drew it (attribute)
  end type case_table

contains

  !> Read the table `path` and check it against `def`.
  subroutine read_case_table(path, def, table, error)
    character(len=*), intent(in) :: path                  !< table file
    type(sweep_definition), intent(in) :: def             !< its definition
    type(case_table), intent(out) :: table                !< the cases
    type(error_type), allocatable, intent(inout) :: error !< set if missing or not matching
    integer(hid_t) :: fid
    integer :: hdferr, k, n, i
    logical :: exists
    character(len=:), allocatable :: design, names, want, where
    integer :: ibuf(1)
    integer, allocatable :: ids(:)
    real(dp), allocatable :: col(:)

    table%path = path
    inquire(file=path, exist=exists)
    if (.not. exists) then
      call fatal_error(error, path // ": case table does not exist (make it first: " // &
        "python -m postproc.sweep table " // def%path // ")")
      return
    end if
    ! (as airlaunch_ncwrite: no HDF5 clean-up at exit, where a file whose
    ! close failed on a full disk crashed it; the table is HDF5's first use here)
    call h5dont_atexit_f(hdferr)
    call h5open_f(hdferr)
    call h5eset_auto_f(0, hdferr)
    call h5fopen_f(path, H5F_ACC_RDONLY_F, fid, hdferr)
    if (hdferr /= 0) then
      call fatal_error(error, path // ": cannot open the case table (not a netCDF-4 file?)")
      return
    end if
    where = path // ": the case table does not match " // def%path // ": "
    checks: block
      ! global attributes: design, seed, n_cases, the list of inputs
      call get_text_att(fid, ".", "design", where, design, error)
      if (allocated(error)) exit checks
      if (design /= def%design) then
        call fatal_error(error, where // "design is '" // design // "' in the table, '" // def%design // &
          "' in the definition (make the table again)")
        exit checks
      end if
      if (def%design /= "grid") then
        call get_int_att(fid, ".", "seed", where, ibuf, error)
        if (allocated(error)) exit checks
        if (ibuf(1) /= def%seed) then
          call fatal_error(error, where // "seed is " // str(ibuf(1)) // " in the table, " // str(def%seed) // &
            " in the definition (make the table again)")
          exit checks
        end if
      end if
      call get_text_att(fid, ".", "inputs", where, names, error)
      if (allocated(error)) exit checks
      want = ""
      do k = 1, size(def%inputs)
        if (k > 1) want = want // " "
        want = want // def%inputs(k)%name
      end do
      if (names /= want) then
        call fatal_error(error, where // "its inputs are '" // names // "', the definition varies '" // want // "'")
        exit checks
      end if
      call dataset_size(fid, "case", where, n, error)
      if (allocated(error)) exit checks
      if (n /= def%n_cases) then
        call fatal_error(error, where // "it has " // str(n) // " cases, the definition asks for " // &
          str(def%n_cases) // " (make the table again)")
        exit checks
      end if
      allocate(ids(n))
      call h5ltread_dataset_int_f(fid, "case", ids, [int(n, hsize_t)], hdferr)
      if (hdferr /= 0) then
        call fatal_error(error, path // ": cannot read the variable case")
        exit checks
      end if
      if (any(ids /= [(i, i = 0, n - 1)])) then
        call fatal_error(error, path // ": the case ids are not 0, 1, ..., " // str(n - 1))
        exit checks
      end if
      table%n_cases = n
      table%n_inputs = size(def%inputs)
      table%ids = ids
      allocate(table%values(table%n_inputs, n), col(n))
      do k = 1, size(def%inputs)
        call read_input(fid, def, def%inputs(k), n, where, col, error)
        if (allocated(error)) exit checks
        table%values(k, :) = col
      end do
      if (allocated(error)) exit checks
      table%scipy_version = ""
      call get_text_att(fid, ".", "scipy_version", where, table%scipy_version, error)
      if (allocated(error)) deallocate(error)
    end block checks
    call h5fclose_f(fid, hdferr)
  end subroutine read_case_table

    !> One input: its distribution attributes and its values.
    subroutine read_input(fid, def, s, n, where, col, error)
      integer(hid_t), intent(in) :: fid
      type(sweep_definition), intent(in) :: def
      type(sweep_input), intent(in) :: s
      character(len=*), intent(in) :: where
      integer, intent(in) :: n
      real(dp), intent(out) :: col(:)
      type(error_type), allocatable, intent(inout) :: error
      character(len=:), allocatable :: dist, w
      real(dp), allocatable :: vals(:)
      integer :: nn, hdferr, i, lev(1)
      w = where // "input " // s%name // ": "
      call dataset_size(fid, s%name, where, nn, error)
      if (allocated(error)) return
      if (nn /= n) then
        call fatal_error(error, w // "it has " // str(nn) // " values for " // str(n) // " cases")
        return
      end if
      call h5ltread_dataset_double_f(fid, s%name, col, [int(n, hsize_t)], hdferr)
      if (hdferr /= 0) then
        call fatal_error(error, where // "cannot read the variable " // s%name)
        return
      end if
      call get_text_att(fid, s%name, "distribution", where, dist, error)
      if (allocated(error)) return
      if (dist /= s%distribution) then
        call fatal_error(error, w // "distribution is '" // dist // "' in the table, '" // s%distribution // &
          "' in the definition")
        return
      end if
      if (s%lower /= unset_real) call same_att(fid, s%name, "lower", s%lower, w, error)
      if (s%upper /= unset_real) call same_att(fid, s%name, "upper", s%upper, w, error)
      if (s%mean /= unset_real) call same_att(fid, s%name, "mean", s%mean, w, error)
      if (s%std /= unset_real) call same_att(fid, s%name, "std", s%std, w, error)
      if (allocated(error)) return
      if (def%design == "grid" .and. s%distribution /= "list") then
        call get_int_att(fid, s%name, "levels", where, lev, error)
        if (allocated(error)) return
        if (lev(1) /= s%levels) then
          call fatal_error(error, w // "levels is " // str(lev(1)) // " in the table, " // str(s%levels) // &
            " in the definition")
          return
        end if
      end if
      if (s%distribution == "list") then
        call get_real_atts(fid, s%name, "values", where, vals, error)
        if (allocated(error)) return
        if (size(vals) /= size(s%values)) then
          call fatal_error(error, w // "the list has " // str(size(vals)) // " values in the table, " // &
            str(size(s%values)) // " in the definition")
          return
        end if
        if (any(vals /= s%values)) then
          call fatal_error(error, w // "the list of values differs from the definition's")
          return
        end if
      end if
      do i = 1, n
        if (.not. (abs(col(i)) <= huge(1.0_dp))) then
          call fatal_error(error, w // "case " // str(i - 1) // " has the value " // str(col(i)) // " (not finite)")
          return
        end if
        if (s%distribution == "uniform" .or. s%distribution == "truncnorm") then
          if (col(i) < s%lower .or. col(i) > s%upper) then
            call fatal_error(error, w // "case " // str(i - 1) // " has the value " // str(col(i)) // &
              ", outside [" // str(s%lower) // ", " // str(s%upper) // "]")
            return
          end if
        else if (s%distribution == "list") then
          if (.not. any(s%values == col(i))) then
            call fatal_error(error, w // "case " // str(i - 1) // " has the value " // str(col(i)) // &
              ", not in the list of values")
            return
          end if
        end if
      end do
    end subroutine read_input

    !> A real attribute of the table must equal the definition's value.
    subroutine same_att(fid, obj, name, want_value, w, error)
      integer(hid_t), intent(in) :: fid
      character(len=*), intent(in) :: obj, name, w
      real(dp), intent(in) :: want_value
      type(error_type), allocatable, intent(inout) :: error
      real(dp), allocatable :: have(:)
      if (allocated(error)) return
      call get_real_atts(fid, obj, name, w, have, error)
      if (allocated(error)) return
      if (size(have) /= 1) then
        call fatal_error(error, w // "attribute " // name // " is not one number")
      else if (have(1) /= want_value) then
        call fatal_error(error, w // name // " is " // str(have(1)) // " in the table, " // str(want_value) // &
          " in the definition (make the table again)")
      end if
    end subroutine same_att

    subroutine get_text_att(fid, obj, name, where, value, error)
      integer(hid_t), intent(in) :: fid
      character(len=*), intent(in) :: obj, name, where
      character(len=:), allocatable, intent(out) :: value
      type(error_type), allocatable, intent(inout) :: error
      integer(hsize_t) :: dims(1)
      integer(size_t) :: tsize
      integer :: tclass, hdferr, z
      logical :: exists
      character(len=:), allocatable :: buf
      value = ""
      call h5aexists_by_name_f(fid, obj, name, exists, hdferr)
      if (hdferr /= 0 .or. .not. exists) then
        call fatal_error(error, where // "attribute " // name // " of " // trim(obj) // " is missing")
        return
      end if
      dims = 0
      call h5ltget_attribute_info_f(fid, obj, name, dims, tclass, tsize, hdferr)
      if (hdferr /= 0 .or. tclass /= H5T_STRING_F) then
        call fatal_error(error, where // "attribute " // name // " of " // trim(obj) // " is not a text")
        return
      end if
      allocate(character(len=int(tsize)) :: buf)
      buf(:) = ""
      call h5ltget_attribute_string_f(fid, obj, name, buf, hdferr)
      z = index(buf, achar(0))
      if (z > 0) buf = buf(:z-1)
      value = trim(buf)
    end subroutine get_text_att

    subroutine get_int_att(fid, obj, name, where, value, error)
      integer(hid_t), intent(in) :: fid
      character(len=*), intent(in) :: obj, name, where
      integer, intent(out) :: value(1)
      type(error_type), allocatable, intent(inout) :: error
      integer :: hdferr
      logical :: exists
      value = 0
      call h5aexists_by_name_f(fid, obj, name, exists, hdferr)
      if (hdferr /= 0 .or. .not. exists) then
        call fatal_error(error, where // "attribute " // name // " of " // trim(obj) // " is missing")
        return
      end if
      call h5ltget_attribute_int_f(fid, obj, name, value, hdferr)
      if (hdferr /= 0) call fatal_error(error, where // "attribute " // name // " of " // trim(obj) // &
        " is not an integer")
    end subroutine get_int_att

    subroutine get_real_atts(fid, obj, name, where, value, error)
      integer(hid_t), intent(in) :: fid
      character(len=*), intent(in) :: obj, name, where
      real(dp), allocatable, intent(out) :: value(:)
      type(error_type), allocatable, intent(inout) :: error
      integer(hsize_t) :: dims(1)
      integer(size_t) :: tsize
      integer :: tclass, hdferr, rank
      logical :: exists
      allocate(value(0))
      call h5aexists_by_name_f(fid, obj, name, exists, hdferr)
      if (hdferr /= 0 .or. .not. exists) then
        call fatal_error(error, where // "attribute " // name // " of " // trim(obj) // " is missing")
        return
      end if
      call h5ltget_attribute_ndims_f(fid, obj, name, rank, hdferr)
      dims = 1
      if (rank > 0) call h5ltget_attribute_info_f(fid, obj, name, dims, tclass, tsize, hdferr)
      if (hdferr /= 0 .or. rank > 1) then
        call fatal_error(error, where // "attribute " // name // " of " // trim(obj) // " is not a list of numbers")
        return
      end if
      deallocate(value)
      allocate(value(dims(1)))
      call h5ltget_attribute_double_f(fid, obj, name, value, hdferr)
      if (hdferr /= 0) call fatal_error(error, where // "attribute " // name // " of " // trim(obj) // &
        " is not a number")
    end subroutine get_real_atts

    subroutine dataset_size(fid, name, where, n, error)
      integer(hid_t), intent(in) :: fid
      character(len=*), intent(in) :: name, where
      integer, intent(out) :: n
      type(error_type), allocatable, intent(inout) :: error
      integer(hsize_t) :: dims(1)
      integer(size_t) :: tsize
      integer :: tclass, hdferr, rank
      logical :: exists
      n = 0
      call h5lexists_f(fid, name, exists, hdferr)
      if (hdferr /= 0 .or. .not. exists) then
        call fatal_error(error, where // "variable " // name // " is missing")
        return
      end if
      call h5ltget_dataset_ndims_f(fid, name, rank, hdferr)
      if (hdferr /= 0 .or. rank /= 1) then
        call fatal_error(error, where // "variable " // name // " is not one-dimensional")
        return
      end if
      call h5ltget_dataset_info_f(fid, name, dims, tclass, tsize, hdferr)
      n = int(dims(1))
    end subroutine dataset_size
end module airlaunch_sweep_table
