!> Small file-system helpers of the sweep: whole-file text, directories,
!> deletion, renaming (through the C library: no shell is started inside an
!> MPI process).  The sweep's own files (journal rows, fingerprint, case
!> namelists) are written with unbuffered POSIX calls (airlaunch_sweep_posix.c):
!> gfortran's buffered writes do not report a full disk, these do, at once.
module airlaunch_sweep_files
  use, intrinsic :: iso_c_binding, only: c_int, c_long, c_char, c_null_char
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_path, only: delete_file   ! (public here too: the sweep's file helpers in one place)
  implicit none
  private
  public :: read_text_file, write_text_file, replace_text_file, make_dir, file_exists, delete_file, rename_file
  public :: open_for_writing, write_bytes, write_line, close_file, remove_case_files, lock_file, make_temp_file

  !> Length of the C library's message buffer.
  integer, parameter :: msg_len = 256

  interface
    integer(c_int) function c_mkdir(path, mode) bind(C, name="mkdir")
      import :: c_int, c_char
      implicit none
      character(kind=c_char), intent(in) :: path(*)
      integer(c_int), value, intent(in) :: mode
    end function c_mkdir
    integer(c_int) function c_rename(old, new) bind(C, name="rename")
      import :: c_int, c_char
      implicit none
      character(kind=c_char), intent(in) :: old(*), new(*)
    end function c_rename
    integer(c_int) function c_file_open(path, append, msg, msglen) bind(C, name="airlaunch_file_open")
      import :: c_int, c_char
      implicit none
      character(kind=c_char), intent(in) :: path(*)
      integer(c_int), value, intent(in) :: append, msglen
      character(kind=c_char), intent(inout) :: msg(*)
    end function c_file_open
    integer(c_int) function c_file_write(fd, data, n, msg, msglen) bind(C, name="airlaunch_file_write")
      import :: c_int, c_long, c_char
      implicit none
      integer(c_int), value, intent(in) :: fd, msglen
      character(kind=c_char), intent(in) :: data(*)
      integer(c_long), value, intent(in) :: n
      character(kind=c_char), intent(inout) :: msg(*)
    end function c_file_write
    integer(c_int) function c_remove_case_files(dir) bind(C, name="airlaunch_remove_case_files")
      import :: c_int, c_char
      implicit none
      character(kind=c_char), intent(in) :: dir(*)
    end function c_remove_case_files
    integer(c_int) function c_lock_file(path, msg, msglen) bind(C, name="airlaunch_lock_file")
      import :: c_int, c_char
      implicit none
      character(kind=c_char), intent(in) :: path(*)
      character(kind=c_char), intent(inout) :: msg(*)
      integer(c_int), value, intent(in) :: msglen
    end function c_lock_file
    integer(c_int) function c_temp_file(templ, suffix_len, msg, msglen) bind(C, name="airlaunch_temp_file")
      import :: c_int, c_char
      implicit none
      character(kind=c_char), intent(inout) :: templ(*)
      integer(c_int), value, intent(in) :: suffix_len, msglen
      character(kind=c_char), intent(out) :: msg(*)
    end function c_temp_file
    integer(c_int) function c_file_close(fd, msg, msglen) bind(C, name="airlaunch_file_close")
      import :: c_int, c_char
      implicit none
      integer(c_int), value, intent(in) :: fd, msglen
      character(kind=c_char), intent(inout) :: msg(*)
    end function c_file_close
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

  !> Write `text` to `path` (replacing it).  Every byte is checked: a full
  !> disk or any other write error sets `error` ("PATH: cannot write the
  !> file (write: No space left on device)"); the file may then hold part of
  !> `text`.
  subroutine write_text_file(path, text, error)
    character(len=*), intent(in) :: path                  !< file
    character(len=*), intent(in) :: text                  !< content
    type(error_type), allocatable, intent(inout) :: error !< set if not written in full
    integer :: fd
    call open_for_writing(path, .false., fd, error)
    call write_bytes(fd, text, error)
    call close_file(fd, error)
    if (allocated(error)) error%message = path // ": cannot write the file (" // error%message // ")"
  end subroutine write_text_file

  !> Write `text` to `path` atomically: to `path`.part, renamed to `path`
  !> once written in full.  On failure `path` is untouched and no .part is
  !> left behind.
  subroutine replace_text_file(path, text, error)
    character(len=*), intent(in) :: path                  !< file
    character(len=*), intent(in) :: text                  !< content
    type(error_type), allocatable, intent(inout) :: error !< set if not written in full
    call write_text_file(path // ".part", text, error)
    if (.not. allocated(error)) call rename_file(path // ".part", path, error)
    if (allocated(error)) call delete_file(path // ".part")
  end subroutine replace_text_file

  !> Open `path` for unbuffered writing: appending to it (`append`) or
  !> replacing its content; created if missing.  `fd` is -1 on failure.
  subroutine open_for_writing(path, append, fd, error)
    character(len=*), intent(in) :: path                  !< file
    logical, intent(in) :: append                         !< append (O_APPEND) or truncate
    integer, intent(out) :: fd                            !< file descriptor
    type(error_type), allocatable, intent(inout) :: error !< set on failure: the C library's reason
    character(kind=c_char, len=msg_len) :: msg
    msg = c_null_char
    fd = int(c_file_open(path // c_null_char, merge(1_c_int, 0_c_int, append), msg, int(msg_len, c_int)))
    if (fd < 0) call fatal_error(error, c_message(msg))
  end subroutine open_for_writing

  !> Write all of `text` to `fd` (nothing if `error` is already set).
  subroutine write_bytes(fd, text, error)
    integer, intent(in) :: fd                             !< from open_for_writing
    character(len=*), intent(in) :: text                  !< bytes to write
    type(error_type), allocatable, intent(inout) :: error !< set if a byte is not written: the reason
    character(kind=c_char, len=msg_len) :: msg
    if (allocated(error) .or. fd < 0) return
    msg = c_null_char
    if (c_file_write(int(fd, c_int), text, int(len(text), c_long), msg, int(msg_len, c_int)) /= 0) &
      call fatal_error(error, c_message(msg))
  end subroutine write_bytes

  !> Write `text` and a new line to `fd` (`text` as it is with newline =
  !> .false.: it ends its own lines); the programs' printing by write(2), which
  !> reports what gfortran's buffered unit 6 drops (a full disk, a closed
  !> descriptor).
  subroutine write_line(fd, text, error, newline)
    integer, intent(in) :: fd                             !< 1: the standard output
    character(len=*), intent(in) :: text                  !< the line
    type(error_type), allocatable, intent(inout) :: error !< set if a byte is not written (kept: the first)
    logical, intent(in), optional :: newline              !< add the new line (default: yes)
    logical :: nl
    nl = .true.
    if (present(newline)) nl = newline
    if (nl) then
      call write_bytes(fd, text // new_line("a"), error)
    else
      call write_bytes(fd, text, error)
    end if
  end subroutine write_line

  !> A new empty file of a unique name in `dir`: prefix, six random
  !> characters, suffix (mkstemps; created exclusively, mode 0600).
  subroutine make_temp_file(dir, prefix, suffix, path, error)
    character(len=*), intent(in) :: dir                   !< an existing directory
    character(len=*), intent(in) :: prefix, suffix        !< around the random part
    character(len=:), allocatable, intent(out) :: path    !< the file made
    type(error_type), allocatable, intent(inout) :: error !< set if none can be made: the reason
    character(kind=c_char, len=msg_len) :: msg
    character(kind=c_char, len=:), allocatable :: templ
    templ = dir // "/" // prefix // "XXXXXX" // suffix // c_null_char
    msg = c_null_char
    if (c_temp_file(templ, int(len(suffix), c_int), msg, int(msg_len, c_int)) /= 0) then
      call fatal_error(error, dir // ": cannot make a scratch file (" // c_message(msg) // ")")
      return
    end if
    path = templ(:len(templ) - 1)
  end subroutine make_temp_file

  !> Close `fd`, checking the result; `error`, if already set, is kept.
  subroutine close_file(fd, error)
    integer, intent(inout) :: fd                          !< from open_for_writing; -1 after
    type(error_type), allocatable, intent(inout) :: error !< set if close fails: the reason
    character(kind=c_char, len=msg_len) :: msg
    if (fd < 0) return
    msg = c_null_char
    if (c_file_close(int(fd, c_int), msg, int(msg_len, c_int)) /= 0) then
      if (.not. allocated(error)) call fatal_error(error, c_message(msg))
    end if
    fd = -1
  end subroutine close_file

  !> Hold an exclusive lock on `path` (created if missing) until the process
  !> ends.  `held_elsewhere`: another process holds it (no error set then).
  subroutine lock_file(path, held_elsewhere, error)
    character(len=*), intent(in) :: path                  !< lock file
    logical, intent(out) :: held_elsewhere                !< another process has it
    type(error_type), allocatable, intent(inout) :: error !< set on another failure: the reason
    character(kind=c_char, len=msg_len) :: msg
    integer(c_int) :: fd
    msg = c_null_char
    fd = c_lock_file(path // c_null_char, msg, int(msg_len, c_int))
    held_elsewhere = fd == -2
    if (fd == -1) call fatal_error(error, path // ": cannot lock (" // c_message(msg) // ")")
  end subroutine lock_file

  !> The text of a NUL-terminated message buffer.
  function c_message(msg) result(s)
    character(len=*), intent(in) :: msg
    character(len=:), allocatable :: s
    integer :: n
    n = index(msg, c_null_char) - 1
    if (n < 0) n = len_trim(msg)
    s = msg(:n)
  end function c_message

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

  !> Remove every case_<digits>.nc and case_<digits>.nc.part file of `dir`
  !> (a missing directory has none).
  subroutine remove_case_files(dir, error)
    character(len=*), intent(in) :: dir                   !< directory
    type(error_type), allocatable, intent(inout) :: error !< set if one remains
    integer(c_int) :: rc
    rc = c_remove_case_files(dir // c_null_char)
    if (rc < 0) call fatal_error(error, dir // ": cannot read the directory to remove its case files")
    if (rc > 0) call fatal_error(error, dir // ": cannot remove " // str(int(rc)) // " case files")
  end subroutine remove_case_files

  !> Rename `old` to `new` (atomic on one file system).
  subroutine rename_file(old, new, error)
    character(len=*), intent(in) :: old, new              !< paths
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    if (c_rename(old // c_null_char, new // c_null_char) /= 0) &
      call fatal_error(error, new // ": cannot rename " // old // " to it")
  end subroutine rename_file
end module airlaunch_sweep_files
