!> Validation 2 of issue 4: conservation laws of the whole rigid scene, a free
!> aircraft + the 3-body Kane chain (rocket, virtual rigid line, parachute) + the cut
!> joint in each phase (locked, frictionless rail, frictionless ramp edge, free),
!> from random consistent states with all bodies tumbling.
!>
!> Loads: an internal central pull between an aircraft point below the deck and the
!> rocket CG (it presses the rocket on the edge in Case 2; potential P |x_a - x_b|),
!> with gravity off, then on.
!>   gravity off: P and H (about the earth origin) conserved, |dP| <= 1e-9 sum|m v|,
!>                |dH| <= 1e-9 sum|h_i| (issue: 1e-9 relative);
!>   gravity on:  P - M g t and H - M (r_cm0 t + V_cm0 t^2/2) x g conserved (same tol);
!>   energy T + V conserved to the integrator tolerance: CVODE rtol = atol = 1e-11,
!>   checked at 1e-7 relative to the kinetic energy (the joint and the chain do no
!>   work; the Baumgarte terms act only on the integration drift).
program test_multibody_conservation
  use airlaunch_kinds, only: dp, g0
  use airlaunch_error, only: error_type
  use airlaunch_rotation, only: quat_from_euler
  use airlaunch_cvode, only: cvode_solver, cvode_options
  use airlaunch_multibody
  use testing
  implicit none
  call run(phase_preparation, .false.)
  call run(phase_extraction, .false.)
  call run(phase_rotation, .false.)
  call run(phase_free, .false.)
  call run(phase_preparation, .true.)
  call run(phase_extraction, .true.)
  call run(phase_rotation, .true.)
  call run(phase_free, .true.)
  call finish()

contains

  character(len=11) function fmt(x)
    real(dp), intent(in) :: x
    write(fmt, '(es11.3)') x
  end function fmt

  subroutine run(phase, gravity)
    integer, intent(in) :: phase
    logical, intent(in) :: gravity
    type(separation_system), target :: sys
    type(cvode_solver) :: solver
    type(error_type), allocatable :: error
    type(rigid_body) :: aircraft, rocket
    type(cut_joint_geometry) :: geo
    type(cut_joint_options) :: opt
    type(pair_force_source) :: pull
    type(gravity_source) :: grav
    real(dp), allocatable :: y(:)
    real(dp), parameter :: tend = 0.7_dp, pull_n = 4.0e5_dp
    real(dp) :: p0(3), h0(3), e0, pscale, hscale, mtot, rcm0(3), vcm0(3), g(3), dp_(3), dh(3), de
    integer :: k
    g = [0.0_dp, -g0, 0.0_dp]
    if (.not. gravity) g = 0.0_dp
    call section(trim(phase_name(phase)) // merge(", gravity on ", ", gravity off", gravity))
    aircraft = new_rigid_body("aircraft", 89000.0_dp, diag3(540740.0_dp, 737480.0_dp, 117030.0_dp), error)
    rocket = new_rigid_body("rocket", 28000.0_dp, diag3(7870.0_dp, 545000.0_dp, 545000.0_dp), error)
    geo%rail_direction = [-1.0_dp, -0.05_dp, 0.0_dp]
    geo%floor_point = [3.0_dp, -1.2_dp, 0.0_dp]
    geo%edge_point = geo%floor_point + 14.0_dp*geo%rail_direction
    call sys%init(aircraft, rocket, [9.25_dp, 0.0_dp, 0.0_dp], 3, geo, opt, 5.0_dp, error)
    call sys%set_line_body(2, 20.0_dp, [6000.0_dp, 6000.0_dp, 0.0_dp], 30.0_dp, error)
    call sys%chain%set_link(3, "parachute", 40.0_dp, diag3(30.0_dp, 40.0_dp, 30.0_dp), &
      [0.0_dp, 0.0_dp, 4.0_dp], [0.0_dp, 0.0_dp, 0.0_dp], error)
    call check(.not. allocated(error), "scene built")
    if (allocated(error)) then
      print '(a)', error%message
      return
    end if
    sys%bodies(0)%r = [5.0_dp, -3.0_dp, 2.0_dp]
    call sys%bodies(0)%set_attitude(quat_from_euler([0.2_dp, 0.1_dp, -0.15_dp]))
    sys%bodies(0)%v = [3.0_dp, 1.0_dp, -2.0_dp]
    sys%bodies(0)%w = [0.05_dp, -0.04_dp, 0.08_dp]
    select case (phase)
    case (phase_preparation)
      call sys%joint%place_on_rail(sys%bodies(0), 6.0_dp, 0.0_dp, sys%bodies(1))
    case (phase_extraction)
      call sys%joint%place_on_rail(sys%bodies(0), 6.0_dp, 0.8_dp, sys%bodies(1))
    case (phase_rotation)
      call sys%joint%place_on_edge(sys%bodies(0), 2.0_dp, 0.1_dp, 0.5_dp, 0.2_dp, sys%bodies(1))
    case default
      call sys%joint%place_on_rail(sys%bodies(0), 6.0_dp, 0.8_dp, sys%bodies(1))
      sys%bodies(1)%w = sys%bodies(1)%w + [0.1_dp, 0.3_dp, -0.2_dp]
    end select
    call sys%bodies(2)%set_attitude(quat_from_euler([0.3_dp, 1.2_dp, 0.5_dp]))
    sys%bodies(2)%w = [0.4_dp, -0.3_dp, 0.2_dp]
    call sys%bodies(3)%set_attitude(quat_from_euler([-0.4_dp, 0.7_dp, 0.1_dp]))
    sys%bodies(3)%w = [1.0_dp, 0.5_dp, -0.7_dp]
    pull%body_a = 0
    pull%body_b = 1
    pull%magnitude = pull_n
    pull%central = .true.
    pull%point_a = [-10.0_dp, -30.0_dp, 0.0_dp]
    call sys%add_source(pull)
    if (gravity) then
      grav%g = g
      call sys%add_source(grav)
    end if
    allocate(y(sys%state_size()))
    call sys%pack_state(y)
    call sys%start(0.0_dp, y, phase, error)
    call check(.not. allocated(error) .and. sys%phase == phase, "consistent start, phase kept")
    if (allocated(error)) then
      print '(a)', error%message
      return
    end if
    if (phase == phase_rotation) call check(sys%normal_force > 0, "edge pushes: N = " // fmt(sys%normal_force) // " N")
    call sys%load_state(y)
    p0 = sys%linear_momentum()
    h0 = sys%angular_momentum()
    e0 = sys%kinetic_energy() + sys%potential_energy(g) + pull_n*distance(sys)
    pscale = 0.0_dp; hscale = 0.0_dp; mtot = 0.0_dp; rcm0 = 0.0_dp; vcm0 = 0.0_dp
    do k = 0, 3
      pscale = pscale + norm2(sys%bodies(k)%linear_momentum())
      hscale = hscale + norm2(sys%bodies(k)%angular_momentum())
      mtot = mtot + sys%bodies(k)%mass
      rcm0 = rcm0 + sys%bodies(k)%mass*sys%bodies(k)%r
      vcm0 = vcm0 + sys%bodies(k)%mass*sys%bodies(k)%v
    end do
    rcm0 = rcm0/mtot
    vcm0 = vcm0/mtot
    call solver%init(sys, 0.0_dp, y, cvode_options(rtol=1e-11_dp, atol=1e-11_dp), error)
    call sys%advance(solver, tend, error)
    call check(.not. allocated(error), "integration over 0.7 s")
    if (allocated(error)) then
      print '(a)', error%message
      return
    end if
    call check(sys%phase == phase, "still in the same phase (now " // trim(phase_name(sys%phase)) // ")")
    if (sys%phase /= phase) print '(a, f8.4, l2)', "  left at t = ", sys%event_time(3), sys%early_separation
    call sys%evaluate(solver%t, solver%y, error)
    dp_ = sys%linear_momentum() - p0 - mtot*g*tend
    dh = sys%angular_momentum() - h0 - mtot*cross(rcm0*tend + 0.5_dp*vcm0*tend**2, g)
    de = sys%kinetic_energy() + sys%potential_energy(g) + pull_n*distance(sys) - e0
    call check(norm2(dp_) <= 1e-9_dp*pscale, "linear momentum" // merge(" - M g t", "        ", gravity) // &
      ": |dP| / sum|m v| = " // fmt(norm2(dp_)/pscale))
    call check(norm2(dh) <= 1e-9_dp*hscale, "angular momentum" // merge(" (gravity torque removed)", &
      "                         ", gravity) // ": |dH| / sum|h| = " // fmt(norm2(dh)/hscale))
    call check(abs(de) <= 1e-7_dp*sys%kinetic_energy(), "energy T + V: |dE| / T = " // &
      fmt(abs(de)/sys%kinetic_energy()))
    call check(sys%js%res_position < 1e-7_dp .and. sys%js%res_velocity < 1e-7_dp, "joint residual " // &
      fmt(sys%js%res_position) // " m, " // fmt(sys%js%res_velocity) // " m/s, " // fmt(sys%js%res_angle) // " rad")
    call check(sys%chain%joint_residual(sys%bodies(1:)) < 1e-12_dp, "chain joints closed by construction")
    call solver%free()
  end subroutine run

  real(dp) function distance(sys)
    type(separation_system), intent(in) :: sys
    distance = norm2(sys%bodies(0)%point_position([-10.0_dp, -30.0_dp, 0.0_dp]) - sys%bodies(1)%r)
  end function distance
end program test_multibody_conservation
