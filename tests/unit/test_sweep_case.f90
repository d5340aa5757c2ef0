!> How a sweep case is applied to the base scenario: the case's assignment is
!> inserted into its group (after a '/' inside a string or a comment too) and
!> wins over the base's value when the standard readers read the text; a group
!> the base lacks is appended; values round-trip bit for bit through their text.
program test_sweep_case
  use, intrinsic :: iso_fortran_env, only: int64
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type
  use airlaunch_namelist, only: nml_file
  use airlaunch_run_config, only: run_config, read_run_config
  use airlaunch_sweep_case, only: inject_assignments, value_text
  use airlaunch_sweep_files, only: write_text_file
  use testing
  implicit none
  character(len=1), parameter :: nl = new_line("a")
  character(len=:), allocatable :: base, text, echo
  type(nml_file) :: f, f2
  type(run_config) :: run
  type(error_type), allocatable :: error
  real(dp) :: x, y
  integer(int64) :: bits, state
  integer :: i, ios, n_bad

  call section("insertion into the group, after slashes in strings and comments")
  base = "! a scenario / with slashes" // nl // &
    "&run" // nl // &
    "  scene = 'airlaunch', output = 'out/dir/run.nc'  ! path a/b" // nl // &
    "  t_end = 15.0, rtol = 1e-6 /" // nl
  text = inject_assignments(base, [character(len=8) :: "run", "run"], &
    [character(len=40) :: "t_end = 2.5", "atol = 3.0000000000000001E-009"])
  call write_text_file("sweep_case_test.nml", text, error)
  call f%load("sweep_case_test.nml", error)
  call check(.not. allocated(error), "the injected text scans as a namelist")
  call read_run_config(f, run, echo, error)
  call check(.not. allocated(error), "the run reader accepts it")
  call check(run%t_end == 2.5_dp, "the case's t_end wins over the base's 15")
  call check(run%atol == 3.0e-9_dp, "an assignment the base lacks is added")
  call check(run%rtol == 1.0e-6_dp .and. trim(run%output) == "out/dir/run.nc", &
    "the base's other values (a string with '/') are kept")
  call check(index(text, "! a scenario / with slashes") == 1, "the text before the group is untouched")

  call section("a group the base lacks is appended")
  text = inject_assignments(base, [character(len=8) :: "bay"], [character(len=40) :: "release_time = 1.25"])
  call check(index(text, "&bay" // nl // "  release_time = 1.25" // nl // "/") > 0, "&bay ... / appended")
  call check(index(text, base) == 1, "the base text comes first, unchanged")

  call section("&end terminators and upper-case group names")
  base = "&RUN t_end = 15.0 &END" // nl
  text = inject_assignments(base, [character(len=8) :: "run"], [character(len=40) :: "t_end = 7"])
  call write_text_file("sweep_case_test.nml", text, error)
  call f2%load("sweep_case_test.nml", error)
  call read_run_config(f2, run, echo, error)
  call check(.not. allocated(error) .and. run%t_end == 7.0_dp, "t_end = 7 inserted before &END")

  call section("values read back bit for bit")
  n_bad = 0
  state = 88172645463325252_int64
  do i = 1, 20000
    ! xorshift64 bit patterns -> finite doubles of every magnitude
    state = ieor(state, ishft(state, 13))
    state = ieor(state, ishft(state, -7))
    state = ieor(state, ishft(state, 17))
    bits = iand(state, not(ishft(int(z'7FF', int64), 52)))   ! keep the exponent below 0x7FF
    bits = ior(bits, ishft(iand(ishft(state, -40), int(z'7FE', int64)), 52))
    x = transfer(bits, x)
    echo = value_text(x)
    read(echo, *, iostat=ios) y
    if (ios /= 0 .or. transfer(y, bits) /= transfer(x, bits)) n_bad = n_bad + 1
  end do
  call check(n_bad == 0, "20000 random doubles: all identical after value_text and a read")
  call check(value_text(60.0_dp) == "60" .and. value_text(-3.0_dp) == "-3", "integral values as integers")
  call check(value_text(0.65_dp) == "6.5000000000000002E-001", "0.65 with 17 significant digits")
  call finish()
end program test_sweep_case
