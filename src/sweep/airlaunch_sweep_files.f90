!> Small file-system helpers of the sweep: whole-file text, directories,
!> deletion, renaming (through the C library: no shell is started inside an
!> MPI process).
module airlaunch_sweep_files
  use, intrinsic :: iso_c_binding, only: c_int, c_char, c_null_char
  use airlaunch_error, only: error_type, fatal_error
  implicit none
  private
  public :: read_text_file, write_text_file, make_dir, file_exists, delete_file, rename_file

  interface
    integer(c_int) function c_mkdir(path, mode) bind(C, name="mkdir")
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: path(*)
      integer(c_int), value :: mode
    end function c_mkdir
    integer(c_int) function c_rename(old, new) bind(C, name="rename")
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: old(*), new(*)
    end function c_rename
  end interface

contains

  !> The whole file as one string (lines joined with new_line).
  subroutine read_text_file(path, text, error)
    character(len=*), intent(in) :: path                  !< file
    character(len=:), allocatable, intent(out) :: text    !< its content
    type(error_type), allocatable, intent(inout) :: error !< set if unreadable
    integer :: unit, ios, fsize
    text = ""
    if (.not. file_exists(path)) then
      call fatal_error(error, path // ": file does not exist")
      return
    end if
    open(newunit=unit, file=path, access="stream", form="unformatted", status="old", action="read", iostat=ios)
    if (ios /= 0) then
      call fatal_error(error, path // ": cannot open the file for reading")
      return
    end if
    inquire(unit=unit, size=fsize)
    if (fsize > 0) then
      deallocate(text)
      allocate(character(len=fsize) :: text)
      read(unit, iostat=ios) text
      if (ios /= 0) call fatal_error(error, path // ": cannot read the file")
    end if
    close(unit)
  end subroutine read_text_file

  !> Write `text` to `path` (replacing it).
  subroutine write_text_file(path, text, error)
    character(len=*), intent(in) :: path                  !< file
    character(len=*), intent(in) :: text                  !< content
    type(error_type), allocatable, intent(inout) :: error !< set if not writable
    integer :: unit, ios
    open(newunit=unit, file=path, access="stream", form="unformatted", status="replace", action="write", &
      iostat=ios)
    if (ios /= 0) then
      call fatal_error(error, path // ": cannot write the file (directory missing or not writable?)")
      return
    end if
    write(unit, iostat=ios) text
    if (ios /= 0) call fatal_error(error, path // ": cannot write the file (disk full?)")
    close(unit)
  end subroutine write_text_file

  !> Create a directory and its parents (like mkdir -p).
  subroutine make_dir(path, error)
    character(len=*), intent(in) :: path                  !< directory
    type(error_type), allocatable, intent(inout) :: error !< set if it cannot be made
    integer :: i, rc
    do i = 2, len(path) + 1
      if (i <= len(path)) then
        if (path(i:i) /= "/") cycle
      end if
      rc = c_mkdir(path(:i-1) // c_null_char, int(o'755', c_int))
    end do
    if (.not. dir_exists(path)) call fatal_error(error, path // ": cannot create the directory")
  end subroutine make_dir

  !> True if `path` exists (file or directory).
  logical function file_exists(path)
    character(len=*), intent(in) :: path
    inquire(file=path, exist=file_exists)
  end function file_exists

  !> True if `path` is a directory (gfortran's inquire sees directories too).
  logical function dir_exists(path)
    character(len=*), intent(in) :: path
    inquire(file=path // "/.", exist=dir_exists)
  end function dir_exists

  !> Delete a file if it exists.
  subroutine delete_file(path)
    character(len=*), intent(in) :: path   !< file
    integer :: unit, ios
    if (.not. file_exists(path)) return
    open(newunit=unit, file=path, status="old", iostat=ios)
    if (ios == 0) close(unit, status="delete")
  end subroutine delete_file

  !> Rename `old` to `new` (atomic on one file system).
  subroutine rename_file(old, new, error)
    character(len=*), intent(in) :: old, new              !< paths
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    if (c_rename(old // c_null_char, new // c_null_char) /= 0) &
      call fatal_error(error, new // ": cannot rename " // old // " to it")
  end subroutine rename_file
end module airlaunch_sweep_files
