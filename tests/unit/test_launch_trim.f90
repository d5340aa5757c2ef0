!> The paper scenario starts at rest: the Case 0 trim with the settled line.
!>
!> input/airlaunch_paper.nml is built as the program builds it
!> (read_scenario_config, setup_launch).  The settled line does not only pull
!> aft: its weight pulls the rocket's nose tie-down down (254 N, the test prints it;
!> the first segment hangs at ~-0.003 rad).  A trim fed with the aft pull alone
!> left that force and its ~1.6 kN m moment about the aircraft CG (the nose
!> 6.25 m ahead of it) unbalanced: the run started with a pitch acceleration of
!> about -2.0e-3 rad/s^2 (-0.11 deg/s^2) and a vertical one of about
!> 3.6e-3 m/s^2 (3.7e-4 g) at the aircraft CG instead of at rest (hand estimate
!> for the locked pair, 117 t and ~8.8e5 kg m^2 about its CG; docs/model.md).
!>
!> Reference: steady level flight, so every body's linear and angular
!> acceleration vanishes at t = 0.
!> Tolerances: the trim balances forces to 1e-10 of the total weight W and the
!> moment to 1e-10 W c; trim and settling are iterated until the line's force
!> at the tie-down changes by at most 1e-9 W; the line settles to 1e-9 of its
!> tension (~1e-4 N, below both).  So the unbalanced force is at most ~1.1e-9 W
!> (the locked pair accelerates by <= 1.1e-9 g; allowed 1e-8 g) and the
!> unbalanced moment at most 1.1e-9 W times the largest lever arm of the
!> tie-down and the tail, 10 m, over the aircraft's pitch inertia alone (a lower
!> bound of the pair's), ~1e-7 rad/s^2 (allowed: that bound).
program test_launch_trim
  use airlaunch_kinds, only: dp, g0
  use airlaunch_error, only: error_type
  use airlaunch_namelist, only: nml_file
  use airlaunch_scenario_config, only: scenario_config, read_scenario_config
  use airlaunch_launch_system, only: launch_system, rigid_size
  use airlaunch_launch_scene, only: launch_result, setup_launch
  use airlaunch_strings, only: str
  use testing
  implicit none
  type(nml_file) :: f
  type(scenario_config) :: cfg
  type(launch_system) :: sys
  type(launch_result) :: res
  type(error_type), allocatable :: error
  character(len=:), allocatable :: echo, path
  real(dp), allocatable :: y0(:), ydot(:)
  real(dp) :: weight, a_tol, w_tol
  integer :: status

  call section("the paper scenario, trimmed with its settled line")
  path = paper_input()
  call f%load(path, error)
  if (.not. allocated(error)) call read_scenario_config(f, cfg, echo, error)
  if (.not. allocated(error)) call setup_launch(cfg, sys, y0, res, error)
  call check(.not. allocated(error), "read " // path // " and set up the launch system")
  if (allocated(error)) then
    write(*, '(a)') error%message
    call finish()
  end if
  weight = (cfg%aircraft%mass + cfg%rocket%mass)*g0
  call check(res%trim_passes >= 2 .and. res%trim_line_force_change_n <= 1.0e-9_dp*weight, &
    "trim and settling agree (" // str(res%trim_passes) // " passes, last change " // &
    str(res%trim_line_force_change_n) // " N)")
  call check(sys%f(2, 0) < -100.0_dp, "the settled line pulls the tie-down down: " // str(sys%f(2, 0)) // " N")

  call section("t = 0: nothing accelerates")
  allocate(ydot(size(y0)))
  call sys%rhs(0.0_dp, y0, ydot, status)
  call check(status == 0, "rhs status")
  a_tol = 1.0e-8_dp*g0
  w_tol = 1.1e-9_dp*weight*10.0_dp/cfg%aircraft%inertia(3)
  call check_bodies_at_rest(ydot, a_tol, w_tol)
  ! the line's nodes too: settled to 1e-9 of the largest tension, over the lightest node
  call check(maxval(abs(ydot(rigid_size+1:))) <= 1.0e-9_dp*maxval(sys%tension)/minval(sys%line%node_mass), &
    "line nodes at rest (settled): max " // str(maxval(abs(ydot(rigid_size+1:)))) // " m/s^2")

  call section("fly the calibrated aircraft: the attitude moves between passes")
  ! trim_mode = 'fly' with the C_L0, C_m0 just calibrated: alpha is free, so
  ! each pass moves the tie-down and the line; the same equilibrium must come
  ! back (alpha 1.2174 deg, zero elevator: 1e-6 deg, the trim's 1e-10 W
  ! over the lift slope, with margin) and start at rest as above
  cfg%flight%trim_mode = "fly"
  cfg%aircraft%aero%cl0 = res%trim_cl0
  cfg%aircraft%aero%cm0 = res%trim_cm0
  deallocate(y0)
  call setup_launch(cfg, sys, y0, res, error)
  call check(.not. allocated(error), "set up in fly mode")
  if (allocated(error)) then
    write(*, '(a)') error%message
    call finish()
  end if
  call check(res%trim_line_force_change_n <= 1.0e-9_dp*weight, "trim and settling agree (" // &
    str(res%trim_passes) // " passes, last change " // str(res%trim_line_force_change_n) // " N)")
  call check_close(res%trim_alpha_deg, 1.2174_dp, "alpha [deg]", abs=1.0e-6_dp)
  call check_close(res%trim_elevator_deg, 0.0_dp, "elevator [deg]", abs=1.0e-6_dp)
  call sys%rhs(0.0_dp, y0, ydot, status)
  call check_bodies_at_rest(ydot, a_tol, w_tol)
  call finish()

contains

  !> The aircraft's and the rocket's linear and angular accelerations in
  !> ydot (13 states per body: r, v, q, w) are zero to a_tol and w_tol.
  subroutine check_bodies_at_rest(ydot, a_tol, w_tol)
    real(dp), intent(in) :: ydot(:), a_tol, w_tol
    integer :: k, i
    do k = 0, 1
      do i = 1, 3
        call check_close(ydot(13*k+3+i), 0.0_dp, trim(merge("aircraft", "rocket  ", k == 0)) // &
          " acceleration " // char(ichar("w") + i), abs=a_tol)
        call check_close(ydot(13*k+10+i), 0.0_dp, trim(merge("aircraft", "rocket  ", k == 0)) // &
          " angular acceleration " // char(ichar("w") + i), abs=w_tol)
      end do
    end do
  end subroutine check_bodies_at_rest
end program test_launch_trim
