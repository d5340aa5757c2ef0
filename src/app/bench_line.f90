!> Benchmark of the two line integrators (issue 3, "Performance"): for N = 20,
!> 60, 200 and each scheme, wall time per simulated second and the error of
!> the tip (node N) position against converged references - the largest
!> distance over 41 outputs, so that a lucky cancellation at one instant
!> cannot pass for accuracy - against the same-N semi-discretization
!> integrated to 1e-11 (time error) and against N = 400 (total error).  The
!> paper's marching scheme runs at 0.9 of its stability limit (its cheapest
!> setting), CVODE over a tolerance sweep.  Then the default scheme's cost
!>  A. at the same N, reaching the paper scheme's error;
!>  B. reaching the paper run's error against the converged answer, each
!>     scheme at its cheapest N and setting (equal accuracy of the physical
!>     answer; both schemes also run at further N);
!>  C. at the same N, reaching 1 mm;
!>  D. as B, each scheme's wall read off its work-precision front (all N and
!>     settings; log-log between neighbouring runs) at the paper run's error:
!>     B on a ladder jumps by a whole rung when a run misses by a hair, D does
!>     not (B stays the verdict).
!> Ends with one line `RESULT {json}` (a speed-up no run of the default scheme's ladder
!> reaches is reported as 0, its tolerance as 0).  Run through `scripts/bench line`
!> (optional arguments: axial damping c_d [N s] (1000), EA [N] (1e6), mass per
!> length [kg/m] (0.3), the default scheme's mass matrix: lumped (the default)
!> or mixed); `bench-line single SCHEME N RTOL|DT [MAX_ORDER [dq]]` runs one
!> setting and prints its work counters (AIRLAUNCH_LINE_MASS=lumped|mixed sets
!> the cvode run's mass matrix there, lumped by default).  The marching scheme always lumps the
!> mass (the paper's), so each scheme's same-N reference is its own
!> semi-discretization.
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
  use airlaunch_blas_threads, only: use_one_blas_thread
  implicit none
  integer, parameter :: ns(3) = [20, 60, 200], n_ref = 400
  !> further segment counts (comparison B: the cheapest run of each scheme, any N,
  !> reaching the paper run's accuracy)
  integer, parameter :: nx = 13
  integer, parameter :: ns_extra(nx) = [5, 6, 8, 10, 15, 25, 30, 40, 50, 80, 100, 120, 150]
  real(dp), parameter :: t_end = 2.0_dp, rho_air = 0.41351_dp, v_air = 194.7_dp
  integer, parameter :: n_rec = 41    ! tip recorded every t_end/40 = 0.05 s
  !> tolerance ladder of the default scheme: 1-2-5 per decade, so that the
  !> cheapest run reaching a given error is found to within a factor 2.5 in
  !> rtol (with 1-3 per decade, N = 10 at rtol 3e-4 missing the N = 20 paper
  !> error by 7 % after a change of Jacobian moved comparison B there from
  !> 11.7x to 9.0x: the next rung was 3x tighter)
  integer, parameter :: nr = 13
  real(dp), parameter :: rtols(nr) = [1.0e-2_dp, 5.0e-3_dp, 2.0e-3_dp, 1.0e-3_dp, 5.0e-4_dp, 2.0e-4_dp, &
    1.0e-4_dp, 5.0e-5_dp, 2.0e-5_dp, 1.0e-5_dp, 5.0e-6_dp, 2.0e-6_dp, 1.0e-6_dp]
  real(dp), parameter :: rtol_default = 1.0e-5_dp
  real(dp) :: tip_inf(3, n_rec), tip_n(3, n_rec), tip(3, n_rec), wall
  real(dp) :: err_s(3), dt_m(3), wall_m(3), err_m(3), err_ms(3)
  real(dp) :: wall_c(nr, 3), err_c(nr, 3), errt_c(nr, 3), wall_x(nr, nx), errt_x(nr, nx)
  real(dp) :: sp_same(3), sp_acc(3), sp_mm(3), best
  integer :: bj_same(3), bj_acc(3), bj_mm(3), bn_acc(3)
  real(dp) :: bw_acc(3), be_acc(3), pw_acc(3), pe_acc(3), wall_mx(nx), errt_mx(nx), dt_x
  integer :: pn_acc(3)
  real(dp) :: sp_int(3), cw_int(3), pw_int(3)
  integer(8) :: steps, steps_m(3), steps_c(nr, 3), steps_x(nr, nx)
  character(len=:), allocatable :: json, rows
  character(len=32) :: arg
  real(dp) :: c_d, ea, rho
  real(dp) :: tip_nl(3, n_rec), err_sl(3)
  character(len=8) :: cvode_mass   ! the default scheme's mass matrix
  integer :: i, j, k

  c_d = 1000.0_dp
  ea = 1.0e6_dp
  rho = 0.3_dp
  cvode_mass = "lumped"
  call use_one_blas_thread()   ! before any LAPACK call: small systems only
  if (command_argument_count() >= 1) then
    call get_command_argument(1, arg)
    if (arg == "single") then
      call single()
      stop 0, quiet=.true.
    end if
    ! bench-line [C_D [EA [RHO]]]: the same benchmark with another axial damping
    ! [N s], stiffness [N], mass per length [kg/m] (sensitivity runs)
    read(arg, *) c_d
    if (command_argument_count() >= 2) then
      call get_command_argument(2, arg)
      read(arg, *) ea
    end if
    if (command_argument_count() >= 3) then
      call get_command_argument(3, arg)
      read(arg, *) rho
    end if
    if (command_argument_count() >= 4) call get_command_argument(4, cvode_mass)
  end if
  print '(a)', "bench line: 60 m line, EA " // str(ea) // " N, " // str(rho) // " kg/m, c_d " // str(c_d) // &
    " N s, parachute end, nose oscillating, 2 s simulated; cvode with the " // trim(cvode_mass) // &
    " mass matrix, marching with the lumped one"
  call run("cvode", n_ref, 1.0e-10_dp, 0.0_dp, tip_inf, wall, steps, 1, 5)
  print '(a, i0, a, 3f14.8, a, f8.2, a)', "converged reference: N = ", n_ref, ", cvode BDF5 rtol 1e-10: tip ", &
    tip_inf(:, n_rec), " m at t_end (", wall, " s)"
  print '(a)', "tip error = largest distance of the tip (node N) from the reference's over the 41 outputs " // &
    "(every 0.05 s); wall = best of 3"
  print '(a)', ""
  print '(a)', "   N  scheme    setting           wall/sim-s [s]   steps    tip error [m]     tip error [m]"
  print '(a)', "                                                            vs same-N ref     vs converged"
  do i = 1, size(ns)
    ! same-N references: each scheme's semi-discretization integrated to 1e-11
    call run("cvode", ns(i), 1.0e-11_dp, 0.0_dp, tip_n, wall, steps, 1, 5)
    err_s(i) = max_dist(tip_n, tip_inf)
    tip_nl = tip_n
    if (cvode_mass /= "lumped") call run("cvode", ns(i), 1.0e-11_dp, 0.0_dp, tip_nl, wall, steps, 1, 5, "lumped")
    err_sl(i) = max_dist(tip_nl, tip_inf)
    ! paper scheme at 0.9 of its stability limit (its cheapest setting)
    dt_m(i) = 0.9_dp*stable_dt(ns(i))
    call run("marching", ns(i), 0.0_dp, dt_m(i), tip, wall_m(i), steps_m(i), 3)
    err_m(i) = max_dist(tip, tip_nl)
    err_ms(i) = max_dist(tip, tip_inf)
    print '(i4, 2x, a, es9.2, 9x, es12.4, i10, 2es17.4)', ns(i), "marching  dt = ", dt_m(i), wall_m(i)/t_end, &
      steps_m(i), err_m(i), err_ms(i)
    do j = 1, nr
      call run("cvode", ns(i), rtols(j), 0.0_dp, tip, wall_c(j, i), steps_c(j, i), 3)
      err_c(j, i) = max_dist(tip, tip_n)
      errt_c(j, i) = max_dist(tip, tip_inf)
      print '(i4, 2x, a, es9.2, a, es12.4, i10, 2es17.4)', ns(i), "cvode     rtol = ", rtols(j), &
        merge(" (default)", "          ", rtols(j) == rtol_default), wall_c(j, i)/t_end, steps_c(j, i), &
        err_c(j, i), errt_c(j, i)
    end do
    print '(a, i0, a, es10.3, a, a, es10.3, a)', "  discretization error of N = ", ns(i), ": ", err_s(i), &
      " m (cvode's " // trim(cvode_mass) // " mass), ", "lumped (marching's) ", err_sl(i), " m"
    print '(a)', ""
  end do

  print '(a)', "both schemes at further N (error against the converged reference only):"
  do i = 1, nx
    dt_x = 0.9_dp*stable_dt(ns_extra(i))
    call run("marching", ns_extra(i), 0.0_dp, dt_x, tip, wall_mx(i), steps, 3)
    errt_mx(i) = max_dist(tip, tip_inf)
    print '(i4, 2x, a, es9.2, 9x, es12.4, i10, 17x, es17.4)', ns_extra(i), "marching  dt = ", &
      dt_x, wall_mx(i)/t_end, steps, errt_mx(i)
    do j = 1, nr
      call run("cvode", ns_extra(i), rtols(j), 0.0_dp, tip, wall_x(j, i), steps_x(j, i), 3)
      errt_x(j, i) = max_dist(tip, tip_inf)
      print '(i4, 2x, a, es9.2, 10x, es12.4, i10, 17x, es17.4)', ns_extra(i), "cvode     rtol = ", rtols(j), &
        wall_x(j, i)/t_end, steps_x(j, i), errt_x(j, i)
    end do
  end do
  print '(a)', ""

  ! A. same N (same semi-discretization): the cheapest tolerance reaching the paper scheme's error
  ! B. equal accuracy of the physical answer: the paper run's error against the converged
  !    solution, reached by the cheapest default run of any N and tolerance
  ! C. 1 mm against the same-N reference
  print '(a)', "comparison                     paper run (N, wall/sim-s, error)      cvode run (N, rtol, " // &
    "wall/sim-s, error)      speedup"
  do i = 1, size(ns)
    best = huge(1.0_dp); bj_same(i) = 0
    do j = 1, nr
      if (err_c(j, i) <= err_m(i) .and. wall_c(j, i) < best) then
        best = wall_c(j, i); bj_same(i) = j
      end if
    end do
    sp_same(i) = merge(wall_m(i)/best, 0.0_dp, bj_same(i) > 0)   ! 0: no rung reaches it
    best = huge(1.0_dp); bj_acc(i) = 0; bn_acc(i) = 0
    do k = 1, size(ns)
      do j = 1, nr
        if (errt_c(j, k) <= err_ms(i) .and. wall_c(j, k) < best) then
          best = wall_c(j, k); bj_acc(i) = j; bn_acc(i) = ns(k); be_acc(i) = errt_c(j, k)
        end if
      end do
    end do
    do k = 1, nx
      do j = 1, nr
        if (errt_x(j, k) <= err_ms(i) .and. wall_x(j, k) < best) then
          best = wall_x(j, k); bj_acc(i) = j; bn_acc(i) = ns_extra(k); be_acc(i) = errt_x(j, k)
        end if
      end do
    end do
    bw_acc(i) = best
    ! the paper scheme's cheapest run reaching its own N_i run's accuracy (any N)
    pw_acc(i) = wall_m(i); pn_acc(i) = ns(i); pe_acc(i) = err_ms(i)
    do k = 1, size(ns)
      if (err_ms(k) <= err_ms(i) .and. wall_m(k) < pw_acc(i)) then
        pw_acc(i) = wall_m(k); pn_acc(i) = ns(k); pe_acc(i) = err_ms(k)
      end if
    end do
    do k = 1, nx
      if (errt_mx(k) <= err_ms(i) .and. wall_mx(k) < pw_acc(i)) then
        pw_acc(i) = wall_mx(k); pn_acc(i) = ns_extra(k); pe_acc(i) = errt_mx(k)
      end if
    end do
    sp_acc(i) = merge(pw_acc(i)/bw_acc(i), 0.0_dp, bj_acc(i) > 0)
    best = huge(1.0_dp); bj_mm(i) = 0
    do j = 1, nr
      if (err_c(j, i) <= 1.0e-3_dp .and. wall_c(j, i) < best) then
        best = wall_c(j, i); bj_mm(i) = j
      end if
    end do
    sp_mm(i) = merge(wall_m(i)/best, 0.0_dp, bj_mm(i) > 0)
    call compare("A same N, paper's error      ", i, i, bj_same(i), err_m(i), err_c(max(1, bj_same(i)), i), &
      sp_same(i))
    if (bj_acc(i) > 0) then
      print '(a, i5, es12.4, es11.3, 6x, i5, es10.2, es12.4, es11.3, f10.1, a)', "B equal accuracy, any N      ", &
        pn_acc(i), pw_acc(i)/t_end, pe_acc(i), bn_acc(i), rtols(bj_acc(i)), bw_acc(i)/t_end, be_acc(i), sp_acc(i), "x"
    else
      print '(a, i5, es12.4, es11.3, 6x, a)', "B equal accuracy, any N      ", pn_acc(i), pw_acc(i)/t_end, &
        pe_acc(i), "no cvode run of the ladder reaches it"
    end if
    call compare("C same N, 1 mm               ", i, i, bj_mm(i), err_m(i), err_c(max(1, bj_mm(i)), i), sp_mm(i))
    cw_int(i) = wall_at_error([reshape(wall_c, [nr*size(ns)]), reshape(wall_x, [nr*nx])], &
      [reshape(errt_c, [nr*size(ns)]), reshape(errt_x, [nr*nx])], err_ms(i))
    pw_int(i) = wall_at_error([wall_m, wall_mx], [err_ms, errt_mx], err_ms(i))
    sp_int(i) = merge(pw_int(i)/cw_int(i), 0.0_dp, cw_int(i) < huge(1.0_dp))
    if (cw_int(i) < huge(1.0_dp)) then
      print '(a, i5, es12.4, es11.3, 6x, a, es12.4, es11.3, f10.1, a)', "D as B, on each front        ", &
        ns(i), pw_int(i)/t_end, err_ms(i), "    front          ", cw_int(i)/t_end, err_ms(i), sp_int(i), "x"
    else
      print '(a, i5, es12.4, es11.3, 6x, a)', "D as B, on each front        ", ns(i), pw_int(i)/t_end, &
        err_ms(i), "the cvode front does not reach it"
    end if
  end do

  rows = ""
  do i = 1, size(ns)
    if (i > 1) rows = rows // ", "
    j = minloc(abs(rtols - rtol_default), 1)
    rows = rows // '{"N": ' // str(ns(i)) // &
      ', "marching": {"dt": ' // jnum(dt_m(i)) // ', "wall_per_sim_s": ' // jnum(wall_m(i)/t_end) // &
      ', "tip_error_time_m": ' // jnum(err_m(i)) // ', "tip_error_total_m": ' // jnum(err_ms(i)) // '}' // &
      ', "cvode": {"rtol": ' // jnum(rtol_default) // ', "wall_per_sim_s": ' // jnum(wall_c(j, i)/t_end) // &
      ', "tip_error_time_m": ' // jnum(err_c(j, i)) // ', "tip_error_total_m": ' // jnum(errt_c(j, i)) // '}' // &
      ', "speedup_same_N_at_paper_error": ' // jnum(sp_same(i)) // &
      ', "cvode_rtol_same_N": ' // jnum(rung_rtol(bj_same(i))) // &
      ', "speedup_equal_accuracy": ' // jnum(sp_acc(i)) // &
      ', "paper_N_equal_accuracy": ' // str(pn_acc(i)) // &
      ', "cvode_N_equal_accuracy": ' // str(bn_acc(i)) // &
      ', "cvode_rtol_equal_accuracy": ' // jnum(rung_rtol(bj_acc(i))) // &
      ', "speedup_same_N_at_1mm": ' // jnum(sp_mm(i)) // &
      ', "speedup_equal_accuracy_on_fronts": ' // jnum(sp_int(i)) // &
      ', "discretization_error_m": ' // jnum(err_s(i)) // &
      ', "discretization_error_lumped_m": ' // jnum(err_sl(i)) // '}'
  end do
  json = '{"bench": "line", "cvode_mass": "' // trim(cvode_mass) // '", "t_sim_s": ' // jnum(t_end) // &
    ', "damping_Ns": ' // jnum(c_d) // &
    ', "ea_N": ' // jnum(ea) // ', "mass_per_length_kg_m": ' // jnum(rho) // &
    ', "reference_N": ' // str(n_ref) // ', "rows": [' // rows // ']' // &
    ', "min_speedup_same_N_at_paper_error": ' // jnum(minval(sp_same)) // &
    ', "min_speedup_equal_accuracy": ' // jnum(minval(sp_acc)) // &
    ', "min_speedup_equal_accuracy_on_fronts": ' // jnum(minval(sp_int)) // &
    ', "meets_10x_same_N": ' // merge("true ", "false", minval(sp_same) >= 10.0_dp) // &
    ', "meets_10x_equal_accuracy": ' // merge("true ", "false", minval(sp_acc) >= 10.0_dp) // '}'
  print '(a)', ""
  print '(a)', "RESULT " // trim(json)

contains

  !> One line of the comparison table.
  subroutine compare(what, i, k, j, e_paper, e_cvode, speedup)
    character(len=*), intent(in) :: what
    integer, intent(in) :: i, k, j
    real(dp), intent(in) :: e_paper, e_cvode, speedup
    if (j < 1) then
      print '(a, i5, es12.4, es11.3, 6x, a)', what, ns(i), wall_m(i)/t_end, e_paper, &
        "no cvode run of the ladder reaches it"
      return
    end if
    print '(a, i5, es12.4, es11.3, 6x, i5, es10.2, es12.4, es11.3, f10.1, a)', what, ns(i), wall_m(i)/t_end, &
      e_paper, ns(k), rtols(j), wall_c(j, k)/t_end, e_cvode, speedup, "x"
  end subroutine compare

  !> Tolerance of rung j of the ladder; 0 for j = 0 (no rung reached the target).
  pure real(dp) function rung_rtol(j) result(r)
    integer, intent(in) :: j
    r = 0.0_dp
    if (j >= 1) r = rtols(j)
  end function rung_rtol

  !> One run from the command line: bench-line single <scheme> <N> <rtol|dt> [max_order [dq]]
  !> (dq: CVODE's difference-quotient Jacobian instead of the analytic one)
  !> (a diagnostic to study one setting; prints the work counters).
  subroutine single()
    type(line_scene_config) :: cfg
    type(line_scene) :: scene
    type(error_type), allocatable :: error
    character(len=16) :: a
    integer :: n, mo, i
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
      character(len=8) :: m
      integer :: st
      opts = cfg%integration
      call get_environment_variable("AIRLAUNCH_LINE_MASS", m, status=st)
      if (st /= 0) m = "lumped"
      cfg = scenario(n, merge(m, "lumped  ", opts%scheme == "cvode"))
      cfg%integration = opts
      cfg%integration%peak_tension = .false.
    end block
    cfg%integration%rtol = x
    cfg%integration%atol = x
    cfg%integration%dt = x
    cfg%integration%max_order = mo
    if (command_argument_count() >= 6) then
      call get_command_argument(6, a)
      cfg%integration%analytic_jacobian = a /= "dq"
    end if
    call scene%init(cfg, error)
    if (.not. allocated(error)) call scene%run(error)
    if (allocated(error)) then
      print '(a)', error%message
      return
    end if
    print '(a, 3f16.10)', "tip ", scene%tip(:, scene%n_out)
    do i = 1, scene%n_out   ! the whole tip track, to compare runs
      print '(a, 3es24.16)', "trk ", scene%tip(:, i)
    end do
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
    cfg = scenario(n, "lumped")
    call model%init(cfg%line, error)
    h = model%stable_step()
  end function stable_dt

  !> The benchmark scenario with N segments and the mass matrix `mass`.
  function scenario(n, mass) result(cfg)
    integer, intent(in) :: n
    character(len=*), intent(in) :: mass
    type(line_scene_config) :: cfg
    real(dp) :: eps0
    cfg%line = line_params(length=60.0_dp, n_seg=n, ea=ea, mass_per_length=rho, damping=c_d, &
      diameter=0.025_dp, cd_normal=1.2_dp, cd_tangential=0.01_dp, gravity=.true., air=.true., &
      wind=[-v_air, 0.0_dp, 0.0_dp], air_density=rho_air, mass=mass)
    eps0 = 0.5_dp*rho_air*10.0_dp*v_air**2/cfg%line%ea
    cfg%end_a = line_end(kind=end_prescribed, position=[0.0_dp, 0.0_dp, 0.0_dp], &
      amplitude=[0.0_dp, 1.0_dp, 0.3_dp], frequency=0.5_dp)
    cfg%end_b = line_end(kind=end_point_mass, mass=10.0_dp, drag_area=10.0_dp, &
      position=[-60.0_dp*(1 + eps0), 0.0_dp, 0.0_dp])
    cfg%t_end = t_end
    cfg%output_interval = t_end/(n_rec - 1)
    cfg%record_nodes = .false.
    cfg%integration%peak_tension = .false.   ! (an output, like the nodes: both schemes)
  end function scenario

  !> Run the scenario; tip position at t_end and the best wall time of `repeat` runs.
  !> cvode uses `mass` (default: the benchmark's cvode_mass), marching the lumped mass.
  subroutine run(scheme, n, rtol, dt, tip_out, wall_out, steps_out, repeat, max_order, mass)
    character(len=*), intent(in) :: scheme
    integer, intent(in) :: n, repeat
    integer, intent(in), optional :: max_order
    character(len=*), intent(in), optional :: mass
    real(dp), intent(in) :: rtol, dt
    real(dp), intent(out) :: tip_out(:, :), wall_out
    integer(8), intent(out) :: steps_out
    type(line_scene_config) :: cfg
    type(line_scene) :: scene
    type(error_type), allocatable :: error
    integer :: r
    if (scheme /= "cvode") then
      cfg = scenario(n, "lumped")
    else if (present(mass)) then
      cfg = scenario(n, mass)
    else
      cfg = scenario(n, cvode_mass)
    end if
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

  !> Wall time at which a scheme reaches the error `target`, read off its
  !> work-precision front: the runs (wall, error) no other beats in both, joined by
  !> straight lines in log-log.  A target above the cheapest run's error costs that
  !> run; below the most accurate run's error: huge (out of reach).  The Fortran twin
  !> of postproc/bench_workprecision.py's wall_at_error, which is tested; the Python
  !> one applied to this benchmark's printed table gives column D to the printed digits.
  pure real(dp) function wall_at_error(walls, errs, target) result(w)
    real(dp), intent(in) :: walls(:), errs(:), target
    real(dp) :: w1, e1, w2, e2
    logical :: front(size(walls))
    integer :: i, j, k
    do i = 1, size(walls)
      front(i) = .not. any((walls <= walls(i) .and. errs <= errs(i)) .and. &
        (walls < walls(i) .or. errs < errs(i)))
    end do
    w = huge(1.0_dp)
    if (.not. any(front)) return
    ! the cheapest front run; from it along the front towards smaller errors
    i = minloc(walls, 1, mask=front)
    if (target >= errs(i)) then
      w = walls(i)
      return
    end if
    do k = 1, count(front) - 1
      ! next front run: the cheapest one more accurate than run i
      j = minloc(walls, 1, mask=front .and. errs < errs(i))
      w1 = walls(i); e1 = errs(i); w2 = walls(j); e2 = errs(j)
      if (target >= e2) then
        w = w1*(w2/w1)**(log(target/e1)/log(e2/e1))
        return
      end if
      i = j
    end do
  end function wall_at_error

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
    if (x /= 0.0_dp .and. (abs(x) < 1.0e-99_dp .or. abs(x) >= 1.0e100_dp)) then
      write(buf, '(es14.5e3)') x   ! es12.5 drops the E of a three-digit exponent: not JSON
    else
      write(buf, '(es12.5)') x
    end if
    s = trim(adjustl(buf))
  end function jnum
end program bench_line
