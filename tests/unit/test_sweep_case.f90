!> How a sweep case is applied to the base scenario: the case's assignment is
!> inserted into its group (after a '/' inside a string or a comment too), the
!> base's own assignment of the variable is taken out (commented out when alone
!> on its lines, cut out of a shared line), so that the standard readers (which
!> reject a variable assigned twice) read the case's value; a group the base
!> lacks is appended; values round-trip bit for bit through their text; a
!> vector's elements are read from the resolved input as the runtime writes it.
program test_sweep_case
  use, intrinsic :: iso_fortran_env, only: int64
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type
  use airlaunch_namelist, only: nml_file, nml_assignment
  use airlaunch_run_config, only: run_config, read_run_config
  use airlaunch_sweep_case, only: inject_assignments, strike_assignments, value_text, echo_elements
  use airlaunch_sweep_files, only: write_text_file
  use testing
  implicit none
  character(len=1), parameter :: nl = new_line("a")
  character(len=:), allocatable :: base, text, echo
  character(len=40), allocatable :: items(:)
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
  text = inject_assignments(without(base, ["t_end"]), [character(len=8) :: "run", "run"], &
    [character(len=40) :: "t_end = 2.5", "atol = 3.0000000000000001E-009"])
  call write_text_file("sweep_case_test.nml", text, error)
  call f%load("sweep_case_test.nml", error)
  call check(.not. allocated(error), "the injected text scans as a namelist")
  call read_run_config(f, run, echo, error)
  call check(.not. allocated(error), "the run reader accepts it (t_end once)")
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
  text = without(base, ["t_end"])
  call check(text == "&RUN  &END" // nl, "t_end cut out of the line it shares with the group's ends")
  text = inject_assignments(text, [character(len=8) :: "run"], [character(len=40) :: "t_end = 7"])
  call write_text_file("sweep_case_test.nml", text, error)
  call f2%load("sweep_case_test.nml", error)
  call read_run_config(f2, run, echo, error)
  call check(.not. allocated(error) .and. run%t_end == 7.0_dp, "t_end = 7 inserted before &END")

  call section("the base's assignment taken out: alone on its lines, or sharing one")
  base = "&run" // nl // &
    "  scene = 'airlaunch', t_end = 15.0,  rtol = 1e-6  ! tolerances" // nl // &
    "  atol = 1e-8, 1e-9 ,   ! a list over" // nl // &
    "         1e-10      ! three lines" // nl // &
    "  output = 'a/b.nc' /" // nl
  text = without(base, ["t_end", "atol "])
  call check(index(text, "  scene = 'airlaunch',   rtol = 1e-6  ! tolerances" // nl) > 0, &
    "t_end and its comma cut from the shared line, the rest kept")
  call check(index(text, "! (set by the sweep below)   atol = 1e-8, 1e-9 ,   ! a list over" // nl // &
    "! (set by the sweep below)          1e-10      ! three lines" // nl) > 0, &
    "an assignment alone on its two lines commented out on both")
  call check(index(text, "  output = 'a/b.nc' /") > 0, "the next assignment untouched")
  text = inject_assignments(text, [character(len=8) :: "run", "run"], [character(len=40) :: "t_end = 3", "atol = 2e-9"])
  call write_text_file("sweep_case_test.nml", text, error)
  call f2%load("sweep_case_test.nml", error)
  call read_run_config(f2, run, echo, error)
  call check(.not. allocated(error), "the readers accept the case's text (each variable once)")
  call check(run%t_end == 3.0_dp .and. run%atol == 2.0e-9_dp .and. run%rtol == 1.0e-6_dp, &
    "the case's t_end and atol, the base's rtol")

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

  call section("a vector's elements from the resolved input (the values of the other elements of a varied one)")
  ! as gfortran's namelist write gives them: repeat counts, separators, a trailing comma
  ! (allocated first: gfortran's -Wuninitialized misreads the reallocation of
  ! a never-allocated array on assignment)
  allocate(items(0))
  items = echo_elements(" 3*0.0000000000000000       ,")
  call check(size(items) == 3, "3*x: three elements")
  call check(all(items == "0.0000000000000000"), "each the repeated value")
  items = echo_elements("  70.000000000000000     , 2*0.0000000000000000       ,")
  call check(size(items) == 3 .and. items(1) == "70.000000000000000" .and. items(3) == "0.0000000000000000", &
    "x, 2*y: x, y, y")
  items = echo_elements(" -20.000000000000000     ,  1500.0000000000000     ,  0.0000000000000000     ,")
  call check(size(items) == 3 .and. items(2) == "1500.0000000000000", "x, y, z: one element each")
  call finish()
contains

  !> `text` without its assignments of the &run variables `names`, located by
  !> scanning the text as the sweep does with its base scenario.
  function without(text, names) result(out)
    character(len=*), intent(in) :: text, names(:)
    character(len=:), allocatable :: out
    type(nml_file) :: g
    type(error_type), allocatable :: err
    logical, allocatable :: hit(:)
    integer :: k
    call write_text_file("sweep_case_base.nml", text, err)
    call g%load("sweep_case_base.nml", err)
    call check(.not. allocated(err), "the base text scans")
    allocate(hit(size(g%items)))
    do k = 1, size(g%items)
      hit(k) = any(names == g%items(k)%name)
    end do
    out = strike_assignments(text, pack(g%items, hit))
  end function without
end program test_sweep_case
