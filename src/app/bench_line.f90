!> Benchmark of the two line integrators (issue 3, "Performance"): for N = 20,
!> 60, 200 and each scheme, wall time per simulated second and the error of
!> the tip (node N) position against converged references (the largest
!> distance over 41 outputs, so that a lucky cancellation at one instant
!> cannot pass for accuracy), then the
!> cost of the default scheme at the paper scheme's error.  Ends with one line
!> `RESULT {json}`.  Run through `scripts/bench line`.
!>
!> Scenario ("paper line", documented in docs/line.md): the 60 m line of the
!> paper's scene trailing a parachute in the air stream of a carrier at
!> Mach 0.65, 10 km (air density fixed at the ISA 10 km value 0.41351 kg/m^3,
!> air velocity -194.7 m/s along x; the scene sits at y = 0 so that the
!> integrator's relative tolerance acts on line-sized coordinates).  EA = 1 MN,
!> 0.3 kg/m, c_d = 1000 N s (5 % damping of the line's first axial mode,
!> loss factor 0.1, typical of nylon), d = 25 mm, Cd_n = 1.2, Cd_t = 0.01, gravity on.
!> Node 0 (rocket nose) moves on a sinusoid (1 m vertical, 0.3 m lateral,
!> 0.5 Hz); node N carries a 10 kg point mass with a 10 m^2 drag area (canopy
!> with its apparent mass).  Starts straight, pre-stretched by the steady drag
!> (78 kN), at rest; 2 s simulated.
program bench_line
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type
  use airlaunch_strings, only: str
  use airlaunch_line
  use airlaunch_line_scene
  implicit none
  integer, parameter :: ns(3) = [20, 60, 200], n_ref = 400
  real(dp), parameter :: t_end = 2.0_dp, rho_air = 0.41351_dp, v_air = 194.7_dp
  real(dp), parameter :: rtols(9) = [1.0e-2_dp, 3.0e-3_dp, 1.0e-3_dp, 3.0e-4_dp, 1.0e-4_dp, 3.0e-5_dp, &
    1.0e-5_dp, 3.0e-6_dp, 1.0e-6_dp]
  real(dp), parameter :: rtol_default = 1.0e-5_dp
  integer, parameter :: n_rec = 41    ! tip recorded every t_end/40 = 0.05 s
  real(dp) :: tip_inf(3, n_rec), tip_n(3, n_rec), tip(3, n_rec)
  real(dp) :: wall, err_t, err_s, wall_m, err_m, err_ms, best_wall, best_err, best_rtol
  real(dp) :: wall_d, err_d, err_ds, speedup(3), dt_m, mm_wall, mm_rtol, speedup_mm(3)
  character(len=:), allocatable :: json, rows
  integer :: i, j
  integer(8) :: steps, steps_m, steps_d
  character(len=32) :: arg
  real(dp) :: c_d

  c_d = 1000.0_dp
  if (command_argument_count() >= 1) then
    call get_command_argument(1, arg)
    if (arg == "single") then
      call single()
      stop
    end if
    ! bench-line [C_D]: the same benchmark with another axial damping [N s]
    read(arg, *) c_d
  end if
  print '(a)', "bench line: 60 m line, EA 1 MN, c_d " // str(c_d) // " N s, parachute end, nose oscillating, " // &
    "2 s simulated"
  call run("cvode", n_ref, 1.0e-10_dp, 0.0_dp, tip_inf, wall, steps, 1, 5)
  print '(a, i0, a, 3f14.8, a, f8.2, a)', "converged reference: N = ", n_ref, ", cvode BDF5 rtol 1e-10: tip ", &
    tip_inf(:, n_rec), " m at t_end (", wall, " s)"
  print '(a)', "tip error = largest distance of the tip (node N) from the reference's over the 41 outputs (every 0.05 s)"
  print '(a)', ""
  print '(a)', "   N  scheme    setting           wall/sim-s [s]   steps    tip error [m]     tip error [m]"
  print '(a)', "                                                            vs same-N ref     vs converged"
  rows = ""
  do i = 1, size(ns)
    call run("cvode", ns(i), 1.0e-11_dp, 0.0_dp, tip_n, wall, steps, 1, 5)
    err_s = max_dist(tip_n, tip_inf)
    ! paper scheme at 0.9 of its stability limit
    dt_m = 0.9_dp*stable_dt(ns(i))
    call run("marching", ns(i), 0.0_dp, dt_m, tip, wall_m, steps_m, 3)
    err_m = max_dist(tip, tip_n)
    err_ms = max_dist(tip, tip_inf)
    ! default scheme at its default tolerance
    call run("cvode", ns(i), rtol_default, 0.0_dp, tip, wall_d, steps_d, 3)
    err_d = max_dist(tip, tip_n)
    err_ds = max_dist(tip, tip_inf)
    print '(i4, 2x, a, es9.2, 9x, es12.4, i10, 2es17.4)', ns(i), "marching  dt = ", dt_m, wall_m/t_end, steps_m, &
      err_m, err_ms
    print '(i4, 2x, a, es9.2, 9x, es12.4, i10, 2es17.4)', ns(i), "cvode     rtol = ", rtol_default, wall_d/t_end, &
      steps_d, err_d, err_ds
    ! the cheapest CVODE tolerance that reaches the paper scheme's error, and 1 mm
    best_wall = huge(1.0_dp); best_err = -1; best_rtol = -1
    mm_wall = huge(1.0_dp); mm_rtol = -1
    do j = 1, size(rtols)
      call run("cvode", ns(i), rtols(j), 0.0_dp, tip, wall, steps, 3)
      err_t = max_dist(tip, tip_n)
      print '(i4, 2x, a, es9.2, 9x, es12.4, i10, es17.4)', ns(i), "cvode     rtol = ", rtols(j), wall/t_end, steps, err_t
      if (err_t <= err_m .and. wall < best_wall) then
        best_wall = wall; best_err = err_t; best_rtol = rtols(j)
      end if
      if (err_t <= 1.0e-3_dp .and. wall < mm_wall) then
        mm_wall = wall; mm_rtol = rtols(j)
      end if
    end do
    speedup(i) = wall_m/best_wall
    speedup_mm(i) = wall_m/mm_wall
    print '(a, i0, a, es9.2, a, es9.2, a, es9.2, a, f8.1, a)', "  N = ", ns(i), ": paper scheme error ", err_m, &
      " m; cvode reaches it at rtol ", best_rtol, " (error ", best_err, " m): ", speedup(i), "x faster"
    print '(a, i0, a, es9.2, a, f8.1, a)', "  N = ", ns(i), ": at 1 mm (the paper scheme cannot go cheaper than " // &
      "its stability limit), cvode rtol ", mm_rtol, ": ", speedup_mm(i), "x faster"
    print '(a)', ""
    if (i > 1) rows = rows // ", "
    rows = rows // '{"N": ' // str(ns(i)) // &
      ', "marching": {"dt": ' // jnum(dt_m) // ', "wall_per_sim_s": ' // jnum(wall_m/t_end) // &
      ', "tip_error_time_m": ' // jnum(err_m) // ', "tip_error_total_m": ' // jnum(err_ms) // '}' // &
      ', "cvode": {"rtol": ' // jnum(rtol_default) // ', "wall_per_sim_s": ' // jnum(wall_d/t_end) // &
      ', "tip_error_time_m": ' // jnum(err_d) // ', "tip_error_total_m": ' // jnum(err_ds) // '}' // &
      ', "cvode_at_paper_error": {"rtol": ' // jnum(best_rtol) // ', "wall_per_sim_s": ' // &
      jnum(best_wall/t_end) // ', "tip_error_time_m": ' // jnum(best_err) // '}' // &
      ', "speedup_at_paper_error": ' // jnum(speedup(i)) // ', "speedup_at_1mm": ' // jnum(speedup_mm(i)) // &
      ', "discretization_error_m": ' // jnum(err_s) // '}'
  end do
  json = '{"bench": "line", "t_sim_s": ' // jnum(t_end) // ', "damping_Ns": ' // jnum(c_d) // &
    ', "reference_N": ' // str(n_ref) // &
    ', "rows": [' // rows // '], "min_speedup_at_paper_error": ' // jnum(minval(speedup)) // &
    ', "meets_10x": ' // merge("true ", "false", minval(speedup) >= 10.0_dp) // '}'
  print '(a)', "RESULT " // trim(json)

contains

  !> One run from the command line: bench-line single <scheme> <N> <rtol|dt> [max_order]
  !> (a diagnostic to study one setting; prints the work counters).
  subroutine single()
    type(line_scene_config) :: cfg
    type(line_scene) :: scene
    type(error_type), allocatable :: error
    character(len=16) :: a
    integer :: n, mo
    real(dp) :: x
    call get_command_argument(2, a)
    cfg%integration%scheme = a
    call get_command_argument(3, a)
    read(a, *) n
    call get_command_argument(4, a)
    read(a, *) x
    mo = 2
    if (command_argument_count() >= 5) then
      call get_command_argument(5, a)
      read(a, *) mo
    end if
    block
      type(line_scheme_options) :: opts
      opts = cfg%integration
      cfg = scenario(n)
      cfg%integration = opts
    end block
    cfg%integration%rtol = x
    cfg%integration%atol = x
    cfg%integration%dt = x
    cfg%integration%max_order = mo
    call scene%init(cfg, error)
    if (.not. allocated(error)) call scene%run(error)
    if (allocated(error)) then
      print '(a)', error%message
      return
    end if
    print '(a, 3f16.10)', "tip ", scene%tip(:, scene%n_out)
    print '(a, f10.4, a, i0, a, i0, a, i0, a, i0)', "wall ", scene%wall_time, " s; steps ", scene%stats%steps, &
      ", force evaluations ", scene%stats%rhs_evals, ", jacobians ", scene%stats%jac_evals, ", failures ", &
      scene%stats%failures
  end subroutine single

  !> Stable step of the marching scheme for N segments.
  real(dp) function stable_dt(n) result(h)
    integer, intent(in) :: n
    type(line_model) :: model
    type(error_type), allocatable :: error
    type(line_scene_config) :: cfg
    cfg = scenario(n)
    call model%init(cfg%line, error)
    h = model%stable_step()
  end function stable_dt

  !> The benchmark scenario with N segments.
  function scenario(n) result(cfg)
    integer, intent(in) :: n
    type(line_scene_config) :: cfg
    real(dp) :: eps0
    cfg%line = line_params(length=60.0_dp, n_seg=n, ea=1.0e6_dp, mass_per_length=0.3_dp, damping=c_d, &
      diameter=0.025_dp, cd_normal=1.2_dp, cd_tangential=0.01_dp, gravity=.true., air=.true., &
      wind=[-v_air, 0.0_dp, 0.0_dp], air_density=rho_air)
    eps0 = 0.5_dp*rho_air*10.0_dp*v_air**2/cfg%line%ea
    cfg%end_a = line_end(kind=end_prescribed, position=[0.0_dp, 0.0_dp, 0.0_dp], &
      amplitude=[0.0_dp, 1.0_dp, 0.3_dp], frequency=0.5_dp)
    cfg%end_b = line_end(kind=end_point_mass, mass=10.0_dp, drag_area=10.0_dp, &
      position=[-60.0_dp*(1 + eps0), 0.0_dp, 0.0_dp])
    cfg%t_end = t_end
    cfg%output_interval = t_end/(n_rec - 1)
    cfg%record_nodes = .false.
  end function scenario

  !> Run the scenario; tip position at t_end and the best wall time of `repeat` runs.
  subroutine run(scheme, n, rtol, dt, tip_out, wall_out, steps_out, repeat, max_order)
    character(len=*), intent(in) :: scheme
    integer, intent(in) :: n, repeat
    integer, intent(in), optional :: max_order
    real(dp), intent(in) :: rtol, dt
    real(dp), intent(out) :: tip_out(:, :), wall_out
    integer(8), intent(out) :: steps_out
    type(line_scene_config) :: cfg
    type(line_scene) :: scene
    type(error_type), allocatable :: error
    integer :: r
    cfg = scenario(n)
    cfg%integration%scheme = scheme
    if (scheme == "cvode") then
      cfg%integration%rtol = rtol
      cfg%integration%atol = rtol
      if (present(max_order)) cfg%integration%max_order = max_order
    else
      cfg%integration%dt = dt
    end if
    wall_out = huge(1.0_dp)
    do r = 1, repeat
      call scene%init(cfg, error)
      if (.not. allocated(error)) call scene%run(error)
      if (allocated(error)) then
        print '(a)', "bench line: " // error%message
        error stop 1
      end if
      wall_out = min(wall_out, scene%wall_time)
      tip_out = scene%tip(:, 1:scene%n_out)
      steps_out = scene%stats%steps
    end do
    call scene%free()
  end subroutine run

  !> Largest distance between two tip histories (3, n_rec) [m].
  pure real(dp) function max_dist(a, b) result(d)
    real(dp), intent(in) :: a(:, :), b(:, :)
    d = maxval(norm2(a - b, dim=1))
  end function max_dist

  !> A number as JSON text.
  function jnum(x) result(s)
    real(dp), intent(in) :: x
    character(len=:), allocatable :: s
    character(len=32) :: buf
    write(buf, '(es12.5)') x
    s = trim(adjustl(buf))
  end function jnum
end program bench_line
