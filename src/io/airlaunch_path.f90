!> What a path names, which Fortran's inquire cannot tell: a regular file, a
!> directory or something else (a device, FIFO, socket), and whether two
!> paths name one file (airlaunch_path_kind.c, POSIX stat); and this
!> process's id (getpid), to name files of its own.
module airlaunch_path
  use, intrinsic :: iso_c_binding, only: c_int, c_char, c_null_char
  implicit none
  private
  public :: path_kind, same_file, process_id, kind_missing, kind_regular, kind_directory, kind_other

  !> What a path names (airlaunch_path_kind.c).
  integer, parameter :: kind_missing = 0, kind_regular = 1, kind_directory = 2, kind_other = 3

  interface
    integer(c_int) function c_path_kind(path) bind(c, name="airlaunch_path_kind")
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: path(*)
    end function c_path_kind
    integer(c_int) function c_same_file(a, b) bind(c, name="airlaunch_same_file")
      import :: c_int, c_char
      character(kind=c_char), intent(in) :: a(*), b(*)
    end function c_same_file
    integer(c_int) function c_getpid() bind(c, name="getpid")   ! pid_t is an int on Linux
      import :: c_int
    end function c_getpid
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

  !> A NUL-terminated copy of `s` for C.
  pure function c_string(s) result(c)
    character(len=*), intent(in) :: s
    character(kind=c_char, len=:), allocatable :: c
    c = trim(s) // c_null_char
  end function c_string
end module airlaunch_path
