!> The line scene from a namelist (&run scene = 'line', &line, &line_scene):
!> a good file runs and writes its netCDF output (no temporary file left); bad
!> files give one line naming the file, the group, the variable, its value
!> and what is allowed.
program test_line_namelist
  use airlaunch_error, only: error_type
  use airlaunch_namelist, only: nml_file
  use airlaunch_run_config, only: run_config, read_run_config
  use airlaunch_line_scene, only: line_scene_config, read_line_scene_config, run_line_scene
  use testing
  implicit none
  character(len=*), parameter :: run_group = "&run scene = 'line', t_end = 0.2, output_dt = 0.01, " // &
    "output = 'test_line_namelist.nc' /"
  character(len=*), parameter :: line_group = "&line length = 2.0, n_seg = 8, ea = 1.0e5, " // &
    "mass_per_length = 0.01, damping = 50.0 /"
  character(len=*), parameter :: scene_group = "&line_scene b_kind = 'point_mass', b_mass = 1.0, " // &
    "b_position = 1.0, -1.7320508, 0.0 /"
  character(len=:), allocatable :: summary, echo
  type(error_type), allocatable :: error
  logical :: exists

  call section("a good file runs and writes its output")
  call write_file("test_line_ok.nml", [character(len=200) :: run_group, line_group, scene_group])
  call run_file("test_line_ok.nml", error, summary, echo)
  call check(.not. allocated(error), "runs without error")
  if (allocated(error)) print '(a)', error%message
  if (allocated(summary)) print '(a)', summary
  inquire(file="test_line_namelist.nc", exist=exists)
  call check(exists, "test_line_namelist.nc written")
  inquire(file="test_line_namelist.nc.part", exist=exists)
  call check(.not. exists, "no temporary file left")
  if (allocated(echo)) call check(index(echo, "B_KIND") > 0 .or. index(echo, "b_kind") > 0, &
    "the resolved &line_scene is echoed")

  call section("bad files")
  call expect("test_line_bad1.nml", [character(len=200) :: run_group, "&line eaa = 1.0e5 /", scene_group], &
    [character(len=19) :: "test_line_bad1.nml", "&line              ", "unknown variable   ", "eaa                "])
  call expect("test_line_bad2.nml", [character(len=200) :: run_group, "&line ea = -1.0 /", scene_group], &
    [character(len=19) :: "test_line_bad2.nml", "&line              ", "ea = -1.0          ", "must be > 0        "])
  call expect("test_line_bad3.nml", [character(len=200) :: run_group, "&line n_seg = 0 /", scene_group], &
    [character(len=19) :: "test_line_bad3.nml", "&line              ", "n_seg = 0          ", "integer in [1,     "])
  call expect("test_line_bad4.nml", [character(len=200) :: run_group, line_group, &
    "&line_scene b_kind = 'fixed', b_position = 0.0, 0.0, 0.0 /"], &
    [character(len=19) :: "test_line_bad4.nml", "&line_scene        ", "coincident ends    ", "end_a and end_b    "])
  call expect("test_line_bad5.nml", [character(len=200) :: run_group, line_group, &
    "&line_scene b_kind = 'rope' /"], &
    [character(len=19) :: "test_line_bad5.nml", "&line_scene        ", "b_kind = 'rope'    ", "point_mass         "])
  call expect("test_line_bad6.nml", [character(len=200) :: run_group, line_group, &
    "&line_scene scheme = 'marching', dt = 0.0 /"], &
    [character(len=19) :: "test_line_bad6.nml", "&line_scene        ", "dt = 0.0           ", "must be > 0        "])
  call expect("test_line_bad7.nml", [character(len=200) :: run_group, line_group, &
    "&line_scene scheme = 'marching', dt = 0.01 /"], &
    [character(len=19) :: "test_line_bad7.nml", "&line_scene        ", "dt = 0.01 s        ", "stability limit    "])

  call section("a file removed after it was loaded: an error, not the runtime's stop")
  ! nml_position reopens the file for each group; gfortran's OPEN without
  ! iostat ended the program with its own message (found by an audit,
  ! thirty-first session).  Reference: the file does not exist any more.
  block
    type(nml_file) :: f
    type(run_config) :: run
    integer :: unit, u
    logical :: present
    call write_file("test_line_gone.nml", [character(len=200) :: run_group, line_group, scene_group])
    call f%load("test_line_gone.nml", error)
    call check(.not. allocated(error), "the file loads")
    open(newunit=u, file="test_line_gone.nml", status="old")
    close(u, status="delete")
    call f%position("line", unit, present, error)
    call check(allocated(error) .and. .not. present, "reopening a removed file is an error")
    if (allocated(error)) call check(index(error%message, "test_line_gone.nml: could not be opened again") == 1, &
      "the error names the file: " // error%message)
    if (allocated(error)) deallocate(error)
    call read_run_config(f, run, echo, error)
    call check(allocated(error), "reading &run from the removed file is an error")
  end block
  call finish()

contains

  subroutine write_file(path, lines)
    character(len=*), intent(in) :: path
    character(len=*), intent(in) :: lines(:)
    integer :: u, i
    open(newunit=u, file=path, status="replace", action="write")
    do i = 1, size(lines)
      write(u, '(a)') trim(lines(i))
    end do
    close(u)
  end subroutine write_file

  subroutine run_file(path, err, summ, ech)
    character(len=*), intent(in) :: path
    type(error_type), allocatable, intent(inout) :: err
    character(len=:), allocatable, intent(out) :: summ, ech
    type(nml_file) :: f
    type(run_config) :: run
    type(line_scene_config) :: cfg
    call f%load(path, err)
    if (.not. allocated(err)) call f%check_groups([character(len=16) :: "run", "line", "line_scene"], err)
    if (.not. allocated(err)) call read_run_config(f, run, ech, err)
    if (.not. allocated(err)) call read_line_scene_config(f, run, cfg, ech, err)
    if (.not. allocated(err)) call run_line_scene(run, cfg, ech, summ, err)
  end subroutine run_file

  subroutine expect(path, lines, texts)
    character(len=*), intent(in) :: path
    character(len=*), intent(in) :: lines(:), texts(:)
    type(error_type), allocatable :: err
    character(len=:), allocatable :: summ, ech
    integer :: i
    logical :: all_found
    call write_file(path, lines)
    call run_file(path, err, summ, ech)
    call check(allocated(err), path // " is rejected")
    if (.not. allocated(err)) return
    all_found = .true.
    do i = 1, size(texts)
      if (index(err%message, trim(texts(i))) == 0) all_found = .false.
    end do
    call check(all_found .and. index(err%message, new_line("a")) == 0, "one line: " // err%message)
  end subroutine expect
end program test_line_namelist
