!> Validation 1 (issue 3): axial wave.  A taut straight line (pre-strain eps0,
!> no gravity, no air, no damping) is held fixed at node N; at t = 0 node 0
!> starts moving away along the line at speed u (a sudden end motion).  In the
!> material coordinate the continuum obeys rho u_tt = EA u_ss, so the strain
!> front u/c travels the unstretched length L at c = sqrt(EA/rho) and reaches
!> the fixed end at t = L/c, where the reflection doubles it: the tension at
!> node N jumps from T0 by 2 rho c u.  We take the arrival as the first time
!> T_N - T0 reaches half the jump (the centre of the dispersive front of the
!> discrete chain) and require it within 2 % of L/c for N >= 100 (the issue's
!> tolerance; the front of the lumped chain spreads over O(N^(1/3)) segments, a
!> few per cent of L at N = 100, and its centre travels at c).
program test_line_wave
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type
  use airlaunch_strings, only: str
  use airlaunch_line
  use airlaunch_line_scene
  use testing
  implicit none
  real(dp), parameter :: length = 100.0_dp, ea = 1.0e5_dp, rho = 1.0_dp, eps0 = 0.01_dp, u = 1.0_dp
  real(dp) :: c, t_arrive

  c = sqrt(ea/rho)
  call section("axial wave, CVODE BDF band, L/c = " // str(length/c) // " s")
  t_arrive = arrival(100, "cvode")
  call check_close(t_arrive, length/c, "N = 100: arrival time [s]", rel=0.02_dp)
  t_arrive = arrival(200, "cvode")
  call check_close(t_arrive, length/c, "N = 200: arrival time [s]", rel=0.02_dp)
  call section("axial wave, paper marching scheme")
  t_arrive = arrival(100, "marching")
  call check_close(t_arrive, length/c, "N = 100: arrival time [s]", rel=0.02_dp)
  call finish()

contains

  !> Arrival time of the half-height front at node N.
  real(dp) function arrival(n, scheme) result(ta)
    integer, intent(in) :: n
    character(len=*), intent(in) :: scheme
    type(line_scene_config) :: cfg
    type(line_scene) :: scene
    type(line_model) :: model
    type(error_type), allocatable :: error
    real(dp) :: t0, jump, a, b
    integer :: i
    cfg%line = line_params(length=length, n_seg=n, ea=ea, mass_per_length=rho, gravity=.false., air=.false.)
    ! the end starts at t_start = 1 us, so the line is at rest at t = 0
    cfg%end_a = line_end(kind=end_prescribed, position=[0.0_dp, 0.0_dp, 0.0_dp], velocity=[-u, 0.0_dp, 0.0_dp], &
      t_start=1.0e-6_dp)
    cfg%end_b = line_end(kind=end_fixed, position=[length*(1 + eps0), 0.0_dp, 0.0_dp])
    cfg%integration%scheme = scheme
    cfg%integration%rtol = 1.0e-6_dp
    cfg%integration%atol = 1.0e-9_dp
    cfg%integration%max_order = 5   ! tight tolerance: the steps resolve the line's oscillations
    cfg%t_end = 1.25_dp*length/c
    cfg%output_interval = 1.0e-4_dp
    cfg%record_nodes = .false.
    if (scheme == "marching") then
      call model%init(cfg%line, error)
      cfg%integration%dt = 0.5_dp*model%stable_step()
    end if
    call scene%init(cfg, error)
    call check(.not. allocated(error), "init " // scheme // " N = " // str(n))
    if (allocated(error)) then
      print '(a)', error%message
      ta = -1
      return
    end if
    call scene%run(error)
    call check(.not. allocated(error), "run " // scheme // " N = " // str(n))
    t0 = ea*eps0
    jump = 2*rho*c*u
    ta = -1
    do i = 2, scene%n_out
      a = scene%end_tension(2, i-1) - t0
      b = scene%end_tension(2, i) - t0
      if (a < 0.5_dp*jump .and. b >= 0.5_dp*jump) then
        ta = scene%time(i-1) + (0.5_dp*jump - a)/(b - a)*(scene%time(i) - scene%time(i-1))
        exit
      end if
    end do
    print '(a, i0, a, es12.5, a, es12.5, a, i0, a, i0, a, f7.3, a)', "  N = ", n, ": T_N(end) - T0 = ", &
      scene%end_tension(2, scene%n_out) - t0, " N (2 rho c u = ", jump, "); steps ", scene%stats%steps, &
      ", force evaluations ", scene%stats%rhs_evals, ", wall ", scene%wall_time, " s"
    call scene%free()
  end function arrival
end program test_line_wave
