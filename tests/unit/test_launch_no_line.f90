!> The air-launch scene without a line (`&line enabled = .false.`).
!>
!> 1. setup_launch builds a system of the 26 rigid states and allocates none of
!>    the line's arrays (node positions, velocities, forces, tensions).
!> 2. Trimmed Case 0 with the aircraft held steady (dynamics = 'prescribed') on
!>    a deck pitched theta = 7 deg nose-up (level flight trimmed at 7 deg): no
!>    body accelerates; the locked joint carries the rocket's weight components,
!>    m g cos(theta) normal and m g sin(theta) along the rail.
!> 3. At the release (Case 1) the rocket's tail is still inside the bay, so
!>    nothing acts on it but gravity and the rail: the right-hand side gives the
!>    block on an inclined plane, a = g (sin(theta) - mu cos(theta)) down the
!>    rail, with N = m g cos(theta) and friction -mu N.
!> Tolerances: 1e-9 relative (one evaluation: the CFA's LAPACK solve and the
!> trim, converged to 1e-10 of the weight, are exact to round-off).
program test_launch_no_line
  use airlaunch_kinds, only: dp, g0, deg2rad
  use airlaunch_error, only: error_type
  use airlaunch_scenario_config, only: scenario_config
  use airlaunch_launch_system, only: launch_system, rigid_size
  use airlaunch_launch_scene, only: launch_result, setup_launch
  use airlaunch_cut_joint, only: phase_extraction
  use testing
  implicit none
  type(scenario_config) :: cfg
  type(launch_system) :: sys
  type(launch_result) :: res
  type(error_type), allocatable :: error
  real(dp), allocatable :: y0(:), ydot(:)
  real(dp), parameter :: theta = 7.0_dp*deg2rad, mu = 0.05_dp, m = 28000.0_dp
  real(dp) :: a, rail(3), weight
  integer :: status, i

  cfg%line%enabled = .false.
  cfg%aircraft%dynamics = "prescribed"
  cfg%flight%altitude = 6000.0_dp
  cfg%flight%mach = 0.4_dp
  cfg%flight%trim_alpha = theta
  cfg%bay%friction = mu
  cfg%rocket%mass = m
  weight = m*g0
  rail = [-cos(theta), -sin(theta), 0.0_dp]   ! aircraft -x in the earth frame

  call section("state and arrays")
  call setup_launch(cfg, sys, y0, res, error)
  call check(.not. allocated(error), "setup_launch without a line")
  if (allocated(error)) then
    write(*, '(a)') error%message
    call finish()
  end if
  call check(.not. sys%has_line, "the system knows it has no line")
  call check(size(y0) == rigid_size .and. rigid_size == 26, "26 rigid states, no node")
  call check(.not. (allocated(sys%x) .or. allocated(sys%v) .or. allocated(sys%f) .or. allocated(sys%tension)), &
    "no line array allocated")
  call check(sys%line%n == 0, "the line model is empty")
  call check_close(res%trim_alpha_deg, 7.0_dp, "trim alpha = deck angle [deg]", abs=1.0e-9_dp)

  call section("trimmed Case 0: nothing accelerates")
  allocate(ydot(size(y0)))
  call sys%rhs(0.0_dp, y0, ydot, status)
  call check(status == 0, "rhs status")
  do i = 1, 3
    call check_close(ydot(3+i), 0.0_dp, "aircraft acceleration " // char(ichar("w") + i), abs=1.0e-9_dp*g0)
    call check_close(ydot(16+i), 0.0_dp, "rocket acceleration " // char(ichar("w") + i), abs=1.0e-9_dp*g0)
  end do
  call check_close(sys%sep%normal_force, weight*cos(theta), "locked: normal force = m g cos(theta)", rel=1.0e-9_dp)
  call check_close(abs(sys%sep%lock_force), weight*sin(theta), "locked: the lock's rail force = m g sin(theta)", &
    rel=1.0e-9_dp)
  call check(sys%sep%friction_force == 0.0_dp, "locked: no sliding friction (the lock holds the rocket)")

  call section("release: a block on a plane inclined by theta")
  call sys%prepare(0.0_dp, y0, status)
  call sys%sep%start(0.0_dp, sys%yabs(1:rigid_size), phase_extraction, error)
  call check(.not. allocated(error), "start Case 1")
  call sys%rhs(0.0_dp, y0, ydot, status)
  call check(status == 0, "rhs status")
  a = g0*(sin(theta) - mu*cos(theta))
  call check_close(dot_product(ydot(17:19), rail), a, "acceleration down the rail = g (sin - mu cos)", &
    rel=1.0e-9_dp)
  call check_close(norm2(ydot(17:19) - a*rail), 0.0_dp, "no acceleration across the rail", abs=1.0e-9_dp*g0)
  call check_close(norm2(ydot(4:6)), 0.0_dp, "prescribed aircraft does not accelerate", abs=1.0e-12_dp)
  call check_close(sys%sep%normal_force, weight*cos(theta), "normal force = m g cos(theta)", rel=1.0e-9_dp)
  call check_close(sys%sep%friction_force, -mu*weight*cos(theta), "friction = -mu N", rel=1.0e-9_dp)
  call finish()
end program test_launch_no_line
