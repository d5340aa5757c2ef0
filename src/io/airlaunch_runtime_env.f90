!> The runtime numerical environment of the process: what it computes with
!> beyond the build that `code_digest` names.  The same build can give other
!> bits on another machine, because its libraries choose their code by the
!> processor when they are loaded (OpenBLAS's kernel, glibc's libm variants,
!> libgfortran's MATMUL kernel: airlaunch_runtime_env.c); these values say
!> which were chosen, so two files that differ in the last bits can be told
!> apart by what ran them (docs/output.md, "Runtime numerical environment").
!>
!> Queried when asked (once per output file, at the start of a sweep's rank,
!> for --version), never during an integration: every value is the process's
!> and does not change while it runs.  A value that cannot be found is
!> "unknown" (another BLAS than OpenBLAS has no core name).
module airlaunch_runtime_env
  use, intrinsic :: iso_c_binding, only: c_char, c_int, c_null_char
  use mpi_f08, only: MPI_Get_library_version, MPI_MAX_LIBRARY_VERSION_STRING
  use hdf5, only: h5get_libversion_f
  use airlaunch_error, only: error_type
  use airlaunch_ncwrite, only: nc_writer
  use airlaunch_strings, only: str
  implicit none
  private
  public :: runtime_env, query_runtime_env, write_runtime_env, env_names

  !> Longest value kept (a longer one, e.g. a library's path, is cut).
  integer, parameter :: value_len = 1024

  !> The attribute names, in the order they are written; the last only for
  !> the MPI programs (airlaunch-sweep).
  character(len=16), parameter :: env_names(11) = [character(len=16) :: &
    "cpu_model", "cpu_features", "blas_library", "blas_core", "blas_config", "lapack_library", &
    "lapack_version", "libm", "sundials_version", "hdf5_version", "mpi_library"]

  !> The values of env_names, queried by query_runtime_env.
  type :: runtime_env
    character(len=value_len) :: values(size(env_names)) = "unknown"
    integer :: n = size(env_names) - 1   !< values held: without mpi_library unless asked for
  contains
    procedure :: value => env_value
    procedure :: line => env_line
    procedure :: report => env_report
  end type runtime_env

  interface
    !> Value `which` (1 ... 9, the order of env_names) of
    !> airlaunch_runtime_env.c into buf(1:len), NUL-ended.
    subroutine env_query(which, buf, len) bind(C, name="airlaunch_env_query")
      import :: c_char, c_int
      implicit none
      integer(c_int), value, intent(in) :: which
      character(kind=c_char), intent(out) :: buf(*)
      integer(c_int), value, intent(in) :: len
    end subroutine env_query
  end interface

contains

  !> The environment of this process now; with `with_mpi`, also the MPI
  !> library's version (MPI_Get_library_version, which may be called before
  !> MPI_Init).
  function query_runtime_env(with_mpi) result(env)
    logical, intent(in), optional :: with_mpi   !< add mpi_library (default: no)
    type(runtime_env) :: env
    integer :: k
    do k = 1, 9
      env%values(k) = from_c(k)
    end do
    env%values(10) = hdf5_version()
    if (present(with_mpi)) then
      if (with_mpi) then
        env%values(11) = mpi_library()
        env%n = size(env_names)
      end if
    end if
  end function query_runtime_env

  !> Value `which` of the C queries as Fortran text (blank-padded; "unknown"
  !> if empty).
  function from_c(which) result(text)
    integer, intent(in) :: which   !< 1 ... 9, the order of env_names
    character(len=value_len) :: text
    character(kind=c_char) :: buf(value_len + 1)
    integer :: i
    buf = c_null_char
    call env_query(int(which, c_int), buf, int(size(buf), c_int))
    text = ""
    do i = 1, value_len
      if (buf(i) == c_null_char) exit
      text(i:i) = buf(i)
    end do
    if (len_trim(text) == 0) text = "unknown"
  end function from_c

  !> The HDF5 library's own version (the library linked, static or shared).
  function hdf5_version() result(text)
    character(len=value_len) :: text
    integer :: major, minor, release, hdferr
    call h5get_libversion_f(major, minor, release, hdferr)
    text = "unknown"
    if (hdferr == 0) text = str(major) // "." // str(minor) // "." // str(release)
  end function hdf5_version

  !> The MPI library's version string, its first line.
  function mpi_library() result(text)
    character(len=value_len) :: text
    character(len=MPI_MAX_LIBRARY_VERSION_STRING) :: version
    integer :: n, ierror, cut
    version = ""
    call MPI_Get_library_version(version, n, ierror)
    text = "unknown"
    if (ierror /= 0) return
    n = max(0, min(n, len(version)))
    cut = scan(version(1:n), achar(10) // achar(13) // achar(0))
    if (cut > 0) n = cut - 1
    if (len_trim(version(1:n)) > 0) text = trim(version(1:n))
  end function mpi_library

  !> The value of attribute `name` ("unknown" for a name not held).
  function env_value(self, name) result(text)
    class(runtime_env), intent(in) :: self
    character(len=*), intent(in) :: name   !< one of env_names
    character(len=:), allocatable :: text
    integer :: k
    text = "unknown"
    do k = 1, self%n
      if (trim(env_names(k)) == name) text = trim(self%values(k))
    end do
  end function env_value

  !> One line, "name=value; name=value; ..." (a sweep's journal and summary).
  function env_line(self) result(text)
    class(runtime_env), intent(in) :: self
    character(len=:), allocatable :: text
    integer :: k
    text = ""
    do k = 1, self%n
      if (k > 1) text = text // "; "
      text = text // trim(env_names(k)) // "=" // trim(self%values(k))
    end do
  end function env_line

  !> Lines "  name = value" (--version), each ending with a new line.
  function env_report(self) result(text)
    class(runtime_env), intent(in) :: self
    character(len=:), allocatable :: text
    integer :: k
    text = ""
    do k = 1, self%n
      text = text // "  " // trim(env_names(k)) // " = " // trim(self%values(k)) // new_line("a")
    end do
  end function env_report

  !> The values as global attributes of `w`, one per name.
  subroutine write_runtime_env(w, env, error)
    type(nc_writer), intent(inout) :: w                   !< open output
    type(runtime_env), intent(in) :: env                  !< what to write
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    integer :: k
    do k = 1, env%n
      call w%add_text_att("/", trim(env_names(k)), trim(env%values(k)), error)
    end do
  end subroutine write_runtime_env
end module airlaunch_runtime_env
