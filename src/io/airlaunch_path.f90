!> What a path names, which Fortran's inquire cannot tell: a regular file, a
!> directory or something else (a device, FIFO, socket), and whether two
!> paths name one file (airlaunch_path_kind.c, POSIX stat); the free space of
!> its file system (statvfs); an exclusive lock on a file (fcntl), released
!> with the process; and this process's id (getpid), to name files of its own.
module airlaunch_path
  use, intrinsic :: iso_c_binding, only: c_int, c_char, c_null_char, c_double
  use airlaunch_kinds, only: dp
  implicit none
  private
  public :: path_kind, same_file, process_id, kind_missing, kind_regular, kind_directory, kind_other
  public :: free_bytes, file_size_limit, file_lock, lock_held_elsewhere, lock_unavailable, ignore_file_size_signal
  public :: delete_file, parent_directory, command_argument

  !> What a path names (airlaunch_path_kind.c).
  integer, parameter :: kind_missing = 0, kind_regular = 1, kind_directory = 2, kind_other = 3
  !> file_lock%acquire's outcomes other than success (airlaunch_lock_output).
  integer, parameter :: lock_held_elsewhere = -1, lock_unavailable = -2

  !> An exclusive lock on a lock file, held until `release` (or the process
  !> ends), which also removes the file.
  type :: file_lock
    character(len=:), allocatable :: path
    integer :: fd = -1
  contains
    procedure :: acquire => lock_acquire
    procedure :: release => lock_release
  end type file_lock

  interface
    integer(c_int) function c_path_kind(path) bind(c, name="airlaunch_path_kind")
      import :: c_int, c_char
      implicit none
      character(kind=c_char), intent(in) :: path(*)
    end function c_path_kind
    integer(c_int) function c_same_file(a, b) bind(c, name="airlaunch_same_file")
      import :: c_int, c_char
      implicit none
      character(kind=c_char), intent(in) :: a(*), b(*)
    end function c_same_file
    integer(c_int) function c_getpid() bind(c, name="getpid")   ! pid_t is an int on Linux
      import :: c_int
      implicit none
    end function c_getpid
    real(c_double) function c_free_bytes(path) bind(c, name="airlaunch_free_bytes")
      import :: c_double, c_char
      implicit none
      character(kind=c_char), intent(in) :: path(*)
    end function c_free_bytes
    integer(c_int) function c_lock_file(path) bind(c, name="airlaunch_lock_output")
      import :: c_int, c_char
      implicit none
      character(kind=c_char), intent(in) :: path(*)
    end function c_lock_file
    !> Past the file size limit a write fails (EFBIG) instead of killing the process (SIGXFSZ).
    real(c_double) function c_file_size_limit() bind(c, name="airlaunch_file_size_limit")
      import :: c_double
      implicit none
    end function c_file_size_limit
    subroutine ignore_file_size_signal() bind(c, name="airlaunch_ignore_file_size_signal")
      implicit none
    end subroutine ignore_file_size_signal
    subroutine c_release_lock(path, fd) bind(c, name="airlaunch_release_output_lock")
      import :: c_int, c_char
      implicit none
      character(kind=c_char), intent(in) :: path(*)
      integer(c_int), value, intent(in) :: fd
    end subroutine c_release_lock
  end interface

contains

  !> What `path` names (kind_missing, kind_regular, kind_directory, kind_other).
  integer function path_kind(path)
    character(len=*), intent(in) :: path   !< a file name
    path_kind = int(c_path_kind(c_string(path)))
  end function path_kind

  !> Both paths name the same existing file.
  logical function same_file(a, b)
    character(len=*), intent(in) :: a, b   !< file names
    same_file = c_same_file(c_string(a), c_string(b)) /= 0
  end function same_file

  !> This process's id (names a file of its own).
  integer function process_id()
    process_id = int(c_getpid())
  end function process_id

  !> Free bytes on the file system that holds `path` (an existing file or
  !> directory) for an unprivileged user; negative if it cannot be told.
  real(dp) function free_bytes(path)
    character(len=*), intent(in) :: path
    free_bytes = real(c_free_bytes(c_string(path)), dp)
  end function free_bytes

  !> The process's file size limit (ulimit -f) [bytes]; -1: none.
  real(dp) function file_size_limit()
    file_size_limit = real(c_file_size_limit(), dp)
  end function file_size_limit

  !> Lock the file `path` (made if missing): 0 when held, else
  !> lock_held_elsewhere (another process holds it) or lock_unavailable
  !> (no lock can be had there: the caller goes on without one).
  integer function lock_acquire(self, path) result(status)
    class(file_lock), intent(inout) :: self
    character(len=*), intent(in) :: path
    self%path = trim(path)
    self%fd = int(c_lock_file(c_string(path)))
    status = min(self%fd, 0)
  end function lock_acquire

  !> Remove the lock file and release the lock (nothing if none is held).
  subroutine lock_release(self)
    class(file_lock), intent(inout) :: self
    if (self%fd < 0) return
    call c_release_lock(c_string(self%path), int(self%fd, c_int))
    self%fd = -1
  end subroutine lock_release

  !> Remove the file `path` if it is there.
  subroutine delete_file(path)
    character(len=*), intent(in) :: path
    integer :: unit, ios
    open(newunit=unit, file=path, status="old", iostat=ios)
    if (ios == 0) close(unit, status="delete", iostat=ios)
  end subroutine delete_file

  !> The directory part of `path` ("." if it has none).
  pure function parent_directory(path) result(dir)
    character(len=*), intent(in) :: path
    character(len=:), allocatable :: dir
    integer :: k
    k = index(path, "/", back=.true.)
    if (k == 0) then
      dir = "."
    else if (k == 1) then
      dir = "/"
    else
      dir = path(1:k-1)
    end if
  end function parent_directory

  !> A NUL-terminated copy of `s` for C.
  pure function c_string(s) result(c)
    character(len=*), intent(in) :: s
    character(kind=c_char, len=:), allocatable :: c
    c = trim(s) // c_null_char
  end function c_string

  !> Command-line argument i, whole (any length, trailing blanks kept).
  function command_argument(i) result(a)
    integer, intent(in) :: i
    character(len=:), allocatable :: a
    integer :: n
    call get_command_argument(i, length=n)
    allocate(character(len=n) :: a)
    if (n > 0) call get_command_argument(i, a)
  end function command_argument
end module airlaunch_path
