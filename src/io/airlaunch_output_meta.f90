!> Global attributes every airlaunch output file carries: the code version and
!> digest, the runtime numerical environment (airlaunch_runtime_env), the scene
!> and the fully resolved input (defaults included).
module airlaunch_output_meta
  use airlaunch_error, only: error_type
  use airlaunch_ncwrite, only: nc_writer
  use airlaunch_version, only: code_version, code_digest
  use airlaunch_runtime_env, only: query_runtime_env, write_runtime_env
  implicit none
  private
  public :: write_run_metadata, creation_time

contains

  !> Write the common global attributes.
  subroutine write_run_metadata(w, scene, title, echo, error)
    type(nc_writer), intent(inout) :: w                   !< open output
    character(len=*), intent(in) :: scene                 !< scene name
    character(len=*), intent(in) :: title                 !< one-line description
    character(len=*), intent(in) :: echo                  !< resolved namelist text
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    call w%add_text_att("/", "title", title, error)
    call w%add_text_att("/", "scene", scene, error)
    call w%add_text_att("/", "code_version", "airlaunch " // code_version, error)
    ! the build the numbers are the bits of (sources and build settings; the
    ! git description does not name the compiler flags nor an uncommitted edit)
    call w%add_text_att("/", "code_digest", code_digest, error)
    ! and what the build computed with on this machine (the BLAS kernel, libm's
    ! variants, the libraries' versions): read now, once per file
    call write_runtime_env(w, query_runtime_env(), error)
    call w%add_text_att("/", "created", creation_time(), error)
    call w%add_text_att("/", "input_namelist", echo, error)
    call w%add_text_att("/", "frames", "earth: x forward, y up, z right; body: x nose, y up, z right; " // &
      "Euler yaw about y, pitch about z, roll about x (Zheng & Zhang 2018, Eqs. (49)-(50))", error)
  end subroutine write_run_metadata

  !> The local time now as ISO 8601 with its offset from UTC
  !> (2026-11-29T22:08:39+01:00), so that files made at different sites
  !> compare; without the offset where the system gives none.
  function creation_time() result(stamp)
    character(len=:), allocatable :: stamp
    character(len=32) :: buf
    integer :: v(8)
    call date_and_time(values=v)
    write(buf, '(i4.4,"-",i2.2,"-",i2.2,"T",i2.2,":",i2.2,":",i2.2)') v(1), v(2), v(3), v(5), v(6), v(7)
    stamp = trim(buf)
    if (v(4) == -huge(v(4))) return
    write(buf, '(a1,i2.2,":",i2.2)') merge("+", "-", v(4) >= 0), abs(v(4))/60, mod(abs(v(4)), 60)
    stamp = stamp // trim(buf)
  end function creation_time
end module airlaunch_output_meta
