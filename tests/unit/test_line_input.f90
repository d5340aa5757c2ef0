!> Bad input and numerical failure of the line (issue 3, "Bad input"): each
!> rejected value gives one line naming the variable, its value and what is
!> allowed; a solver failure names the time and keeps the records so far.
program test_line_input
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type
  use airlaunch_strings, only: str
  use airlaunch_line
  use airlaunch_line_scene
  use testing
  implicit none
  type(line_scene_config) :: good, cfg
  type(line_scene) :: scene
  type(line_model) :: model
  type(error_type), allocatable :: error

  good%line = line_params(length=10.0_dp, n_seg=10, ea=1.0e4_dp, mass_per_length=0.1_dp)
  good%end_a = line_end(kind=end_fixed, position=[0.0_dp, 0.0_dp, 0.0_dp])
  good%end_b = line_end(kind=end_free, position=[10.0_dp, 0.0_dp, 0.0_dp])
  good%t_end = 0.1_dp

  call section("line parameters")
  call expect_model(line_params(n_seg=0), "n_seg = 0")
  call expect_model(line_params(n_seg=-3), "n_seg = -3")
  call expect_model(line_params(ea=0.0_dp), "ea = 0.0")
  call expect_model(line_params(ea=-1.0e5_dp), "ea = -100000.0")
  call expect_model(line_params(mass_per_length=-0.2_dp), "mass_per_length = -0.2")
  call expect_model(line_params(length=0.0_dp), "length = 0.0")
  call expect_model(line_params(damping=-1.0_dp), "damping = -1.0")
  call model%init(line_params(n_seg=1000), error)
  call check(.not. allocated(error) .and. size(model%node_mass) == 1001, "n_seg = 1000 is accepted")

  call section("scene and ends")
  cfg = good
  cfg%end_b%position = cfg%end_a%position
  call expect_scene(cfg, "cannot be laid between coincident ends")
  cfg = good
  cfg%end_b%position = [20.0_dp, 0.0_dp, 0.0_dp]
  call expect_scene(cfg, "stretches the 10.0 m line by 100.0 %")
  cfg = good
  cfg%end_b = line_end(kind=end_point_mass, mass=0.0_dp, position=[10.0_dp, 0.0_dp, 0.0_dp])
  call expect_scene(cfg, "end_b: mass = 0.0 kg")
  block   ! non-finite values (the library's own check: namelists already refuse them)
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_positive_inf, ieee_negative_inf
    real(dp) :: inf
    inf = ieee_value(1.0_dp, ieee_positive_inf)
    cfg = good
    cfg%end_b = line_end(kind=end_point_mass, mass=inf, position=[10.0_dp, 0.0_dp, 0.0_dp])
    call expect_scene(cfg, "end_b: mass = Infinity kg")
    cfg = good
    cfg%end_a = line_end(kind=end_prescribed, amplitude=[0.0_dp, inf, 0.0_dp], frequency=1.0_dp)
    call expect_scene(cfg, "end_a: position, velocity, amplitude, phase_deg and t_start must be finite")
    cfg = good
    cfg%end_a%velocity(1) = ieee_value(1.0_dp, ieee_negative_inf)
    call expect_scene(cfg, "end_a: position, velocity, amplitude, phase_deg and t_start must be finite")
    cfg = good
    cfg%end_b%drag_area = inf
    call expect_scene(cfg, "end_b: drag_area = Infinity m^2")
  end block
  cfg = good
  cfg%t_end = 0.0_dp
  call expect_scene(cfg, "t_end = 0.0 s")
  cfg = good
  cfg%output_interval = -1.0_dp
  call expect_scene(cfg, "output_interval = -1.0 s")
  cfg = good
  cfg%initial_shape = "spiral"
  call expect_scene(cfg, "initial_shape = 'spiral'")

  call section("integration settings")
  cfg = good
  cfg%integration%rtol = 0.0_dp
  call expect_scene(cfg, "rtol = 0.0")
  cfg = good
  cfg%integration%atol = -1.0e-8_dp
  call expect_scene(cfg, "atol = -1.00000000E-08")
  cfg = good
  cfg%integration%scheme = "marching"
  cfg%integration%dt = 0.0_dp
  call expect_scene(cfg, "dt = 0.0 s")
  cfg = good
  cfg%integration%scheme = "marching"
  cfg%integration%dt = -1.0e-4_dp
  call expect_scene(cfg, "dt = -1.00000000E-04 s")
  cfg = good
  cfg%integration%scheme = "marching"
  cfg%integration%dt = 1.0_dp
  call expect_scene(cfg, "above its stability limit")
  cfg = good
  cfg%integration%scheme = "marching"
  cfg%integration%force_tol = 0.0_dp
  call expect_scene(cfg, "force_tol = 0.0 N")
  cfg = good
  cfg%integration%scheme = "rk4"
  call expect_scene(cfg, "scheme = 'rk4'")

  call section("a solver failure names the time and keeps the records")
  cfg = good
  cfg%integration%rtol = 1.0e-16_dp
  cfg%integration%atol = 1.0e-20_dp
  call scene%init(cfg, error)
  call check(.not. allocated(error), "init accepts tiny (positive) tolerances")
  call scene%run(error)
  call check(allocated(error), "run fails")
  if (allocated(error)) then
    print '(a)', "  message: " // error%message
    call check(index(error%message, "t = ") > 0 .and. index(error%message, "line (cvode)") > 0, &
      "the message names the scheme and the time")
  end if
  call check(.not. scene%completed .and. scene%n_out >= 1, "records so far kept: " // str(scene%n_out))
  call scene%free()
  call finish()

contains

  subroutine expect_model(p, text)
    type(line_params), intent(in) :: p
    character(len=*), intent(in) :: text
    type(line_model) :: m
    type(error_type), allocatable :: err
    call m%init(p, err)
    call check(allocated(err), "rejected: " // text)
    if (allocated(err)) call check(index(err%message, text) > 0 .and. index(err%message, "allowed") > 0, &
      "message: " // err%message)
  end subroutine expect_model

  subroutine expect_scene(c, text)
    type(line_scene_config), intent(in) :: c
    character(len=*), intent(in) :: text
    type(line_scene) :: s
    type(error_type), allocatable :: err
    call s%init(c, err)
    call check(allocated(err), "rejected: " // text)
    if (allocated(err)) call check(index(err%message, text) > 0, "message: " // err%message)
    call s%free()
  end subroutine expect_scene
end program test_line_input
