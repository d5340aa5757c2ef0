!> Validations 5 and 6 (second half) of issue 4: a rocket-like plank tipping over a
!> fixed ramp edge from rest under gravity (Case 2 with the no-slip edge, i.e. a
!> pure pivot; the one-degree-of-freedom motion makes energy give the rate).
!>
!> Contact point (d, -h) from the CG in body axes, pivot fixed: with I_P = J_z + m(d^2+h^2)
!>   theta_dot^2 = 2 m g (d sin(theta) + h (1 - cos(theta))) / I_P.
!> For h = 0 the edge normal force is N = m g cos(theta) J_z / I_P, zero at theta = 90 deg,
!> reached at T = sqrt(I_P / (2 m g d)) * int_0^{pi/2} sin^{-1/2} = sqrt(I_P/(2 m g d))
!> * sqrt(pi)/2 Gamma(1/4)/Gamma(3/4): the early-separation event must fire there.
!> Tolerances: rate 1e-7 relative (CVODE rtol 1e-11 over ~100 steps); event 1e-8 s (issue).
!> Also: an edge that must pull from the start - one-sided, the rocket is free at
!> t0; bilateral, it stays and edge_pull_time records t0 (exact: the start time).
program test_multibody_tipping
  use airlaunch_kinds, only: dp, g0, pi
  use airlaunch_error, only: error_type
  use airlaunch_rotation, only: nose_elevation
  use airlaunch_cvode, only: cvode_solver, cvode_options
  use airlaunch_multibody
  use testing
  implicit none
  real(dp), parameter :: m = 1000.0_dp, len = 10.0_dp, d = 2.0_dp

  call rate_against_energy(0.5_dp)
  call separation_at_ninety()
  call pulled_from_the_start()
  call finish()

contains

  character(len=14) function fmt(x)
    real(dp), intent(in) :: x
    write(fmt, '(es14.6)') x
  end function fmt

  !> A plank on the edge lifted by twice its weight (rocket axes, up): the
  !> edge must pull (N = -m g < 0 at the start).  One-sided, it is free at
  !> once (early separation at t0); bilateral, it stays on the edge and
  !> `edge_pull_time` records t0 (as the Case 1 -> 2 event does).
  subroutine pulled_from_the_start()
    type(separation_system), target :: sys
    type(error_type), allocatable :: error
    real(dp), allocatable :: y(:)
    integer :: bilateral
    call section("7. an edge that must pull from the start")
    do bilateral = 0, 1
      call make_scene(sys, 0.0_dp, y, error, lift=2.0_dp*m*g0, bilateral=bilateral == 1)
      call check(.not. allocated(error), "start on the edge")
      if (allocated(error)) return
      call check(sys%normal_force < 0.0_dp .or. sys%phase == phase_free, "the edge would have to pull")
      if (bilateral == 1) then
        call check(sys%phase == phase_rotation .and. sys%edge_pull_time == 0.0_dp, &
          "bilateral: stays in Case 2, edge_pull_time = t0 = 0")
      else
        call check(sys%phase == phase_free .and. sys%early_separation .and. sys%event_time(3) == 0.0_dp, &
          "one-sided: free at t0, early separation")
      end if
    end do
  end subroutine pulled_from_the_start

  subroutine make_scene(sys, h, y, error, lift, bilateral)
    type(separation_system), intent(inout) :: sys
    real(dp), intent(in) :: h
    real(dp), allocatable, intent(out) :: y(:)
    type(error_type), allocatable, intent(inout) :: error
    real(dp), intent(in), optional :: lift          !< upward force on the rocket [N]
    logical, intent(in), optional :: bilateral      !< the edge may pull
    type(rigid_body) :: aircraft, rocket
    type(cut_joint_geometry) :: geo
    type(constant_load_source) :: pull
    type(cut_joint_options) :: opt
    real(dp) :: j(3, 3)
    j = 0.0_dp
    j(1, 1) = 50.0_dp; j(2, 2) = m*len**2/12; j(3, 3) = m*len**2/12
    aircraft = new_rigid_body("ramp", 1.0e5_dp, 1.0e5_dp*j/m, error)
    rocket = new_rigid_body("plank", m, j, error)
    geo%rail_direction = [-1.0_dp, 0.0_dp, 0.0_dp]
    geo%floor_point = [5.0_dp, 0.0_dp, 0.0_dp]
    geo%edge_point = [0.0_dp, 0.0_dp, 0.0_dp]
    geo%contact_point = [0.0_dp, -h, 0.0_dp]
    geo%nose_x = 0.5_dp*len
    geo%rocket_length = len
    geo%rocket_radius = max(h, 0.1_dp)
    opt%edge_no_slip = .true.
    call sys%init(aircraft, rocket, [0.5_dp*len, 0.0_dp, 0.0_dp], 1, geo, opt, 0.0_dp, error, &
      aircraft_prescribed=.true.)
    if (allocated(error)) return
    call sys%joint%place_on_edge(sys%bodies(0), d, 0.0_dp, 0.0_dp, 0.0_dp, sys%bodies(1))
    call sys%add_source(gravity_source())
    if (present(lift)) then
      pull%body = 1
      pull%force = [0.0_dp, lift, 0.0_dp]
      call sys%add_source(pull)
    end if
    if (present(bilateral)) sys%edge_bilateral = bilateral
    allocate(y(sys%state_size()))
    call sys%pack_state(y)
    call sys%start(0.0_dp, y, phase_rotation, error)
  end subroutine make_scene

  subroutine rate_against_energy(h)
    real(dp), intent(in) :: h
    type(separation_system), target :: sys
    type(cvode_solver) :: solver
    type(error_type), allocatable :: error
    real(dp), allocatable :: y(:)
    real(dp) :: ip, th, rate, expect, worst
    integer :: i, nchk
    call section("5. tipping over a fixed edge from rest: pitch rate vs energy (h = 0.5 m, d = 2 m)")
    call make_scene(sys, h, y, error)
    call check(.not. allocated(error), "start on the edge (Case 2, no slip)")
    if (allocated(error)) then
      print '(a)', error%message
      return
    end if
    ip = sys%chain%link(1)%inertia(3, 3) + m*(d**2 + h**2)
    call solver%init(sys, 0.0_dp, y, cvode_options(rtol=1e-11_dp, atol=1e-11_dp), error)
    worst = 0.0_dp
    nchk = 0
    do i = 1, 30
      call sys%advance(solver, 0.05_dp*i, error)
      if (allocated(error)) exit
      if (sys%phase /= phase_rotation) exit
      call sys%load_state(solver%y)
      th = nose_elevation(sys%bodies(1)%q)
      rate = sys%bodies(1)%w(3)
      expect = sqrt(2*m*g0*(d*sin(th) + h*(1 - cos(th)))/ip)
      if (th > 0.1_dp) then
        worst = max(worst, abs(rate - expect)/expect)
        nchk = nchk + 1
        if (mod(i, 5) == 0) print '(a, f8.3, a, f12.8, a, f12.8, a)', "  theta = ", th/pi*180, " deg  rate ", &
          rate, " rad/s  energy ", expect, " rad/s"
      end if
    end do
    call check(.not. allocated(error), "integration")
    if (allocated(error)) print '(a)', error%message
    call check(nchk >= 5 .and. worst <= 1e-7_dp, "pitch rate = energy value at " // fmt(real(nchk, dp)) // &
      " angles: worst relative error " // fmt(worst) // " (tol 1e-7)")
    call solver%free()
  end subroutine rate_against_energy

  subroutine separation_at_ninety()
    type(separation_system), target :: sys
    type(cvode_solver) :: solver
    type(error_type), allocatable :: error
    real(dp), allocatable :: y(:)
    real(dp) :: ip, tsep
    call section("6. early separation when the edge normal force reaches zero (h = 0: at 90 deg)")
    call make_scene(sys, 0.0_dp, y, error)
    call check(.not. allocated(error), "start on the edge")
    if (allocated(error)) then
      print '(a)', error%message
      return
    end if
    ip = sys%chain%link(1)%inertia(3, 3) + m*d**2
    tsep = sqrt(ip/(2*m*g0*d))*sqrt(pi)/2*gamma(0.25_dp)/gamma(0.75_dp)
    call solver%init(sys, 0.0_dp, y, cvode_options(rtol=1e-12_dp, atol=1e-12_dp), error)
    call sys%advance(solver, tsep + 0.3_dp, error)
    call check(.not. allocated(error), "integration")
    if (allocated(error)) print '(a)', error%message
    call check(sys%phase == phase_free .and. sys%early_separation, "Case 3 by early separation")
    call check_close(sys%event_time(3), tsep, "separation time = analytic crossing", abs=1e-8_dp)
    print '(a, es10.3, a)', "  event time error ", sys%event_time(3) - tsep, " s"
    call solver%free()
  end subroutine separation_at_ninety
end program test_multibody_tipping
