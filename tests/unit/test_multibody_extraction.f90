!> Validations 3, 4 and 6 (first half) of issue 4: rail extraction.
!>
!> 3. Aircraft in prescribed motion (constant velocity, deck inclined by theta so
!>    that the rocket slides uphill), constant pull P along the rail at the rocket
!>    CG, gravity, Coulomb friction mu.  Locked (Case 0) until t0, then
!>      x(t) = 1/2 (P/m - g (sin theta + mu cos theta)) (t - t0)^2
!>    and the CFA normal force is m g cos theta, the friction -mu m g cos theta.
!>    Case 1 -> 2 when the CG has travelled l0: t = t0 + sqrt(2 l0 / a).
!> 4. Free aircraft and rocket in vacuum, an internal pull P between them along the
!>    rail line through both CGs: total momentum and angular momentum conserved, the
!>    relative acceleration along the rail equals the two-body value P (1/m0 + 1/m1).
!> Friction (Karnopp stick band): a pull below mu m g leaves the rocket stuck
!> (friction = -pull); a rocket sliding at v0 with no pull stops after v0/(mu g)
!> at v0^2/(2 mu g) and stays stuck (to v_stick/stick_rate = 1e-7 m: entering the
!> stick band at v_stick = 1e-4 m/s the slide rate decays at stick_rate = 1000 /s).
!> Tolerances: CVODE rtol 1e-11 (BDF integrates this quadratic motion almost
!> exactly); x(t) 1e-6 relative and events 1e-8 s (issue); forces 1e-6 relative;
!> momentum 1e-9 relative (issue).
program test_multibody_extraction
  use airlaunch_kinds, only: dp, g0, deg2rad
  use airlaunch_error, only: error_type
  use airlaunch_rotation, only: quat_from_euler
  use airlaunch_cvode, only: cvode_solver, cvode_options
  use airlaunch_multibody
  use testing
  implicit none

  call rail_with_prescribed_aircraft()
  call rail_between_free_bodies()
  call stick_and_slip()
  call finish()

contains

  character(len=14) function fmt(x)
    real(dp), intent(in) :: x
    write(fmt, '(es14.6)') x
  end function fmt

  !> The paper's rocket on a joint whose rail runs along -x of the aircraft.
  subroutine make_scene(sys, prescribed, mu, t0, error)
    type(separation_system), intent(inout) :: sys
    logical, intent(in) :: prescribed
    real(dp), intent(in) :: mu, t0
    type(error_type), allocatable, intent(inout) :: error
    type(rigid_body) :: aircraft, rocket
    type(cut_joint_geometry) :: geo
    type(cut_joint_options) :: opt
    aircraft = new_rigid_body("aircraft", 89000.0_dp, diag3(540740.0_dp, 737480.0_dp, 117030.0_dp), error)
    rocket = new_rigid_body("rocket", 28000.0_dp, diag3(7870.0_dp, 545000.0_dp, 545000.0_dp), error)
    geo%rail_direction = [-1.0_dp, 0.0_dp, 0.0_dp]
    geo%floor_point = [3.0_dp, -1.0_dp, 0.0_dp]
    geo%edge_point = [-12.0_dp, -1.0_dp, 0.0_dp]
    geo%contact_point = [0.0_dp, -1.0_dp, 0.0_dp]
    geo%nose_x = 9.25_dp
    geo%rocket_length = 18.5_dp
    geo%rocket_radius = 1.0_dp
    opt%mu_rail = mu
    opt%mu_edge = mu
    call sys%init(aircraft, rocket, [9.25_dp, 0.0_dp, 0.0_dp], 1, geo, opt, t0, error, &
      aircraft_prescribed=prescribed)
  end subroutine make_scene

  subroutine rail_with_prescribed_aircraft()
    type(separation_system), target :: sys
    type(cvode_solver) :: solver
    type(error_type), allocatable :: error
    type(constant_load_source) :: pull
    real(dp), allocatable :: y(:)
    real(dp), parameter :: theta = 3.0_dp*deg2rad, mu = 0.005_dp, pull_n = 78000.0_dp
    real(dp), parameter :: t0 = 0.5_dp, l0 = 6.0_dp, m = 28000.0_dp
    real(dp) :: acc, s0, tout, x, t12, worst
    integer :: i
    call section("3. rail extraction, prescribed aircraft, deck " // "3 deg uphill, mu = 0.005, P = 78 kN")
    call make_scene(sys, .true., mu, t0, error)
    call check(.not. allocated(error), "scene built")
    ! aircraft pitched nose-down by theta, flying along its axis at 60 m/s
    sys%bodies(0)%r = [0.0_dp, 10000.0_dp, 0.0_dp]
    call sys%bodies(0)%set_attitude(quat_from_euler([0.0_dp, -theta, 0.0_dp]))
    sys%bodies(0)%v = 60.0_dp*sys%bodies(0)%c(:, 1)
    sys%bodies(0)%w = 0.0_dp
    call sys%joint%place_on_rail(sys%bodies(0), l0, 0.0_dp, sys%bodies(1))
    pull%body = 1
    pull%force = [-pull_n, 0.0_dp, 0.0_dp]       ! rocket axes: aft along its axis
    pull%body_axes_force = .true.
    call sys%add_source(pull)
    call sys%add_source(gravity_source())
    allocate(y(sys%state_size()))
    call sys%pack_state(y)
    call sys%start(0.0_dp, y, phase_preparation, error)
    call check(.not. allocated(error), "start in Case 0")
    if (allocated(error)) then
      print '(a)', error%message
      return
    end if
    call check_close(sys%joint%l0, l0, "l0 from the geometry", rel=1e-12_dp)
    call check_close(sys%joint%l10, l0 + 9.25_dp, "l10 = l0 + nose distance", rel=1e-12_dp)
    s0 = sys%js%slide
    call solver%init(sys, 0.0_dp, y, cvode_options(rtol=1e-11_dp, atol=1e-9_dp, max_step=0.05_dp), error)
    acc = pull_n/m - g0*(sin(theta) + mu*cos(theta))
    t12 = t0 + sqrt(2*l0/acc)
    print '(a, f12.8, a, f14.10, a)', "  analytic a = ", acc, " m/s^2, Case 1 -> 2 at ", t12, " s"
    worst = 0.0_dp
    do i = 1, 8
      tout = t0 + (t12 - t0)*i/8.5_dp
      call sys%advance(solver, tout, error)
      if (allocated(error)) exit
      call sys%evaluate(solver%t, solver%y, error)
      x = sys%js%slide - s0
      worst = max(worst, abs(x - 0.5_dp*acc*(tout - t0)**2)/(0.5_dp*acc*(tout - t0)**2))
      if (i == 4) then
        call check_close(sys%normal_force, m*g0*cos(theta), "CFA normal force = m g cos(theta)", rel=1e-6_dp)
        call check_close(sys%friction_force, -mu*m*g0*cos(theta), "friction = -mu m g cos(theta)", rel=1e-6_dp)
        call check(abs(sys%lambda(3)) < 1e-6_dp*m*g0, "lateral force ~ 0: " // fmt(sys%lambda(3)) // " N")
        call check(sys%js%res_position < 1e-8_dp .and. sys%js%res_angle < 1e-9_dp, "constraint residual " &
          // fmt(sys%js%res_position) // " m, " // fmt(sys%js%res_angle) // " rad")
      end if
    end do
    call check(.not. allocated(error), "integration through Case 0 and Case 1")
    if (allocated(error)) print '(a)', error%message
    call check_close(sys%event_time(1), t0, "release event at t0", abs=1e-8_dp)
    call check(worst <= 1e-6_dp, "x(t) = a (t - t0)^2 / 2 at 8 times in Case 1: worst relative error " &
      // fmt(worst) // " (tol 1e-6)")
    call sys%advance(solver, t12 + 0.2_dp, error)
    call check(.not. allocated(error), "integration into Case 2")
    if (allocated(error)) print '(a)', error%message
    call check(sys%phase == phase_rotation, "phase 2 after the CG passed the edge")
    call check_close(sys%event_time(2), t12, "Case 1 -> 2 event time", abs=1e-8_dp)
    print '(a, es10.3, a)', "  event time error ", sys%event_time(2) - t12, " s"
    call solver%free()
  end subroutine rail_with_prescribed_aircraft

  subroutine rail_between_free_bodies()
    type(separation_system), target :: sys
    type(cvode_solver) :: solver
    type(error_type), allocatable :: error
    type(pair_force_source) :: winch
    real(dp), allocatable :: y(:)
    real(dp), parameter :: pull_n = 50000.0_dp, m0 = 89000.0_dp, m1 = 28000.0_dp, sd0 = 0.3_dp
    real(dp) :: p0(3), h0(3), s0, tout, arel, x
    call section("4. rail extraction between a free aircraft and the rocket, vacuum, internal pull 50 kN")
    call make_scene(sys, .false., 0.005_dp, 0.0_dp, error)
    ! general attitude and motion, rail line through both CGs
    sys%bodies(0)%r = [100.0_dp, 9000.0_dp, -50.0_dp]
    call sys%bodies(0)%set_attitude(quat_from_euler([0.4_dp, 0.3_dp, -0.2_dp]))
    sys%bodies(0)%v = [190.0_dp, 5.0_dp, -3.0_dp]
    sys%bodies(0)%w = 0.0_dp
    sys%joint%geo%floor_point = [0.0_dp, -1.0_dp, 0.0_dp]
    sys%joint%geo%edge_point = [-12.0_dp, -1.0_dp, 0.0_dp]
    call sys%joint%place_on_rail(sys%bodies(0), 8.0_dp, sd0, sys%bodies(1))
    winch%body_a = 0
    winch%body_b = 1
    winch%magnitude = pull_n
    winch%direction = [-1.0_dp, 0.0_dp, 0.0_dp]
    call sys%add_source(winch)
    allocate(y(sys%state_size()))
    call sys%pack_state(y)
    call sys%start(0.0_dp, y, phase_extraction, error)
    call check(.not. allocated(error), "start in Case 1")
    if (allocated(error)) then
      print '(a)', error%message
      return
    end if
    p0 = sys%linear_momentum()
    h0 = sys%angular_momentum()
    s0 = sys%js%slide
    call solver%init(sys, 0.0_dp, y, cvode_options(rtol=1e-12_dp, atol=1e-10_dp), error)
    tout = 1.5_dp
    call sys%advance(solver, tout, error)
    call check(.not. allocated(error), "integration")
    call sys%evaluate(solver%t, solver%y, error)
    arel = pull_n*(1/m0 + 1/m1)
    x = sys%js%slide - s0
    call check(sys%phase == phase_extraction, "still in Case 1")
    call check_close(x, sd0*tout + 0.5_dp*arel*tout**2, "relative travel = v0 t + P (1/m0 + 1/m1) t^2 / 2", &
      rel=1e-8_dp)
    call check_close(sys%js%slide_rate, sd0 + arel*tout, "relative speed", rel=1e-8_dp)
    call check(norm2(sys%linear_momentum() - p0) <= 1e-9_dp*norm2(p0), "linear momentum conserved: |dP|/|P| = " &
      // fmt(norm2(sys%linear_momentum() - p0)/norm2(p0)))
    call check(norm2(sys%angular_momentum() - h0) <= 1e-9_dp*norm2(h0), "angular momentum conserved: |dH|/|H| = " &
      // fmt(norm2(sys%angular_momentum() - h0)/norm2(h0)))
    call solver%free()
  end subroutine rail_between_free_bodies
  subroutine stick_and_slip()
    type(separation_system), target :: sys
    type(cvode_solver) :: solver
    type(error_type), allocatable :: error
    type(constant_load_source) :: pull
    real(dp), allocatable :: y(:)
    real(dp), parameter :: mu = 0.3_dp, m = 28000.0_dp, v0 = 2.0_dp
    real(dp) :: s0, tstop
    call section("friction: stick below the breakaway force, slide to a stop and stick")
    call make_scene(sys, .true., mu, 0.0_dp, error)
    sys%bodies(0)%v = [150.0_dp, 0.0_dp, 0.0_dp]
    call sys%joint%place_on_rail(sys%bodies(0), 6.0_dp, 0.0_dp, sys%bodies(1))
    pull%body = 1
    pull%force = [-0.5_dp*mu*m*g0, 0.0_dp, 0.0_dp]
    pull%body_axes_force = .true.
    call sys%add_source(pull)
    call sys%add_source(gravity_source())
    allocate(y(sys%state_size()))
    call sys%pack_state(y)
    call sys%start(0.0_dp, y, phase_extraction, error)
    call check(sys%stick, "half the breakaway pull: the rocket sticks")
    call check_close(sys%friction_force, -0.5_dp*mu*m*g0, "static friction balances the pull", rel=1e-9_dp)
    s0 = sys%js%slide
    call solver%init(sys, 0.0_dp, y, cvode_options(rtol=1e-10_dp, atol=1e-10_dp), error)
    call sys%advance(solver, 2.0_dp, error)
    call sys%evaluate(solver%t, solver%y, error)
    call check(abs(sys%js%slide - s0) < 1e-8_dp, "no creep after 2 s: " // fmt(sys%js%slide - s0) // " m")
    call solver%free()
    ! sliding with no pull: decelerates at mu g and stops
    sys%sources(1)%source = constant_load_source(body=1)
    call sys%joint%place_on_rail(sys%bodies(0), 6.0_dp, v0, sys%bodies(1))
    call sys%pack_state(y)
    call sys%start(0.0_dp, y, phase_extraction, error)
    call check(.not. sys%stick, "sliding at 2 m/s")
    call check_close(sys%friction_force, -mu*m*g0, "kinetic friction -mu m g", rel=1e-9_dp)
    s0 = sys%js%slide
    tstop = v0/(mu*g0)
    call solver%init(sys, 0.0_dp, y, cvode_options(rtol=1e-12_dp, atol=1e-12_dp), error)
    call sys%advance(solver, 0.5_dp*tstop, error)
    call sys%evaluate(solver%t, solver%y, error)
    call check_close(sys%js%slide - s0, v0*solver%t - 0.5_dp*mu*g0*solver%t**2, "x(t) while sliding", rel=1e-8_dp)
    call sys%advance(solver, tstop + 1.0_dp, error)
    call check(.not. allocated(error), "integration through the stop")
    call sys%evaluate(solver%t, solver%y, error)
    call check(sys%stick, "stuck after the stop")
    call check_close(sys%js%slide - s0, v0**2/(2*mu*g0), "stopping distance v0^2/(2 mu g)", &
      abs=sys%joint%opt%stick_velocity/sys%joint%opt%stick_rate + 1e-8_dp)
    call check(abs(sys%js%slide_rate) < 1e-6_dp, "at rest: " // fmt(sys%js%slide_rate) // " m/s")
    call solver%free()
  end subroutine stick_and_slip
end program test_multibody_extraction
