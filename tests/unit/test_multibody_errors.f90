!> Bad input and failures of the multibody scene (issue 4): each ends with an
!> error value whose message names the phase and the time.
!>   * contact point or tie-down point outside the rocket envelope
!>   * l10 <= l0 (rocket mounted nose aft), CG behind the ramp edge (l0 <= 0),
!>     ramp edge off the rail line
!>   * release time t0 < 0
!>   * singular Kane mass matrix (a massless, inertia-free line body), at the start
!>     and in the middle of an integration (through CVODE)
!>   * CFA system without solution: Coulomb friction beyond the Painleve limit on the
!>     ramp edge, mu > (J/m + x^2)/(h x) for a contact at x ahead of the CG, h below
!>     it, sliding forwards.
program test_multibody_errors
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type
  use airlaunch_rotation, only: quat_mul
  use airlaunch_cvode, only: cvode_solver, cvode_options
  use airlaunch_multibody
  use testing
  implicit none
  type(cut_joint_geometry) :: geo

  call section("inconsistent geometry and input")
  geo = base_geometry()
  geo%contact_point = [0.0_dp, -1.5_dp, 0.0_dp]
  call expect(run_start(geo, 0.0_dp, 1, .false., phase_preparation), "contact point", "outside the rocket")
  geo = base_geometry()
  call expect(run_start(geo, 0.0_dp, 2, .false., phase_preparation, tie_down=[12.0_dp, 0.0_dp, 0.0_dp]), &
    "tie-down point", "outside the rocket")
  call expect(run_start(geo, 0.0_dp, 1, .true., phase_extraction), "nose aft", "l10")
  call expect(run_start(geo, 0.0_dp, 1, .false., phase_extraction, l0=-2.0_dp), "CG behind the edge", "l0 = -2")
  geo = base_geometry()
  geo%edge_point = [-12.0_dp, -0.5_dp, 0.0_dp]
  call expect(run_start(geo, 0.0_dp, 1, .false., phase_extraction), "edge off the rail", "off the rail line")
  geo = base_geometry()
  call expect(run_start(geo, -1.0_dp, 1, .false., phase_preparation), "t0 < 0", "t0 = -1")

  call section("singular mass matrix")
  call expect(run_start(geo, 0.0_dp, 3, .false., phase_extraction, massless_line=.true.), &
    "massless line body at the start", "not positive definite")
  call singular_during_run()

  call section("CFA without solution (Painleve: friction too large on the ramp edge)")
  call painleve()
  call finish()

contains

  function base_geometry() result(g)
    type(cut_joint_geometry) :: g
    g%rail_direction = [-1.0_dp, 0.0_dp, 0.0_dp]
    g%floor_point = [3.0_dp, -1.0_dp, 0.0_dp]
    g%edge_point = [-12.0_dp, -1.0_dp, 0.0_dp]
    g%contact_point = [0.0_dp, -1.0_dp, 0.0_dp]
    g%nose_x = 9.25_dp
    g%rocket_length = 18.5_dp
    g%rocket_radius = 1.0_dp
  end function base_geometry

  !> Check that `msg` is an error naming a phase, a time and `what`.
  subroutine expect(msg, case_name, what)
    character(len=*), intent(in) :: msg, case_name, what
    call check(index(msg, "phase ") > 0 .and. index(msg, "t = ") > 0 .and. index(msg, what) > 0, &
      case_name // ": " // msg)
  end subroutine expect

  !> Build and start a scene; return the error message ("" if none).
  function run_start(g, t0, nchain, nose_aft, phase, tie_down, massless_line, l0) result(msg)
    type(cut_joint_geometry), intent(in) :: g
    real(dp), intent(in) :: t0
    integer, intent(in) :: nchain, phase
    logical, intent(in) :: nose_aft
    real(dp), intent(in), optional :: tie_down(3)
    logical, intent(in), optional :: massless_line
    real(dp), intent(in), optional :: l0
    character(len=:), allocatable :: msg
    type(separation_system) :: sys
    type(rigid_body) :: aircraft, rocket
    type(cut_joint_options) :: opt
    type(error_type), allocatable :: err
    real(dp), allocatable :: y(:)
    real(dp) :: td(3)
    msg = ""
    td = [9.25_dp, 0.0_dp, 0.0_dp]
    if (present(tie_down)) td = tie_down
    aircraft = new_rigid_body("aircraft", 89000.0_dp, diag3(540740.0_dp, 737480.0_dp, 117030.0_dp), err)
    rocket = new_rigid_body("rocket", 28000.0_dp, diag3(7870.0_dp, 545000.0_dp, 545000.0_dp), err)
    call sys%init(aircraft, rocket, td, nchain, g, opt, t0, err)
    if (nchain >= 2) call sys%set_line_body(2, 20.0_dp, [6000.0_dp, 6000.0_dp, 0.0_dp], 30.0_dp, err)
    if (nchain >= 3) call sys%chain%set_link(3, "parachute", 40.0_dp, diag3(30.0_dp, 40.0_dp, 30.0_dp), &
      [0.0_dp, 0.0_dp, 4.0_dp], [0.0_dp, 0.0_dp, 0.0_dp], err)
    if (present(massless_line)) then
      if (massless_line) call sys%chain%set_link(2, "line", 0.0_dp, diag3(0.0_dp, 0.0_dp, 0.0_dp), &
        [0.0_dp, 0.0_dp, 15.0_dp], [0.0_dp, 0.0_dp, -15.0_dp], err)
    end if
    if (allocated(err)) then
      msg = "(set-up) " // err%message
      return
    end if
    call sys%add_source(gravity_source())
    sys%bodies(0)%v = [190.0_dp, 0.0_dp, 0.0_dp]
    if (present(l0)) then
      call sys%joint%place_on_rail(sys%bodies(0), l0, 0.0_dp, sys%bodies(1))
    else
      call sys%joint%place_on_rail(sys%bodies(0), 6.0_dp, 0.0_dp, sys%bodies(1))
    end if
    if (nose_aft) call sys%bodies(1)%set_attitude(quat_mul(sys%bodies(1)%q, [0.0_dp, 0.0_dp, 1.0_dp, 0.0_dp]))
    allocate(y(sys%state_size()))
    call sys%pack_state(y)
    call sys%start(0.0_dp, y, phase, err)
    if (allocated(err)) msg = err%message
  end function run_start

  !> The lead's outer loop sets a vanishing line body between two steps: the next
  !> right-hand side fails and CVODE stops with the phase and time.
  subroutine singular_during_run()
    type(separation_system), target :: sys
    type(rigid_body) :: aircraft, rocket
    type(cut_joint_options) :: opt
    type(cvode_solver) :: solver
    type(error_type), allocatable :: err
    real(dp), allocatable :: y(:)
    aircraft = new_rigid_body("aircraft", 89000.0_dp, diag3(540740.0_dp, 737480.0_dp, 117030.0_dp), err)
    rocket = new_rigid_body("rocket", 28000.0_dp, diag3(7870.0_dp, 545000.0_dp, 545000.0_dp), err)
    call sys%init(aircraft, rocket, [9.25_dp, 0.0_dp, 0.0_dp], 3, base_geometry(), opt, 0.2_dp, err)
    call sys%set_line_body(2, 20.0_dp, [6000.0_dp, 6000.0_dp, 0.0_dp], 30.0_dp, err)
    call sys%chain%set_link(3, "parachute", 40.0_dp, diag3(30.0_dp, 40.0_dp, 30.0_dp), &
      [0.0_dp, 0.0_dp, 4.0_dp], [0.0_dp, 0.0_dp, 0.0_dp], err)
    call sys%add_source(gravity_source())
    call sys%joint%place_on_rail(sys%bodies(0), 6.0_dp, 0.0_dp, sys%bodies(1))
    allocate(y(sys%state_size()))
    call sys%pack_state(y)
    call sys%start(0.0_dp, y, phase_preparation, err)
    call solver%init(sys, 0.0_dp, y, cvode_options(rtol=1e-8_dp, atol=1e-8_dp), err)
    call sys%advance(solver, 0.5_dp, err)
    call check(.not. allocated(err) .and. sys%phase == phase_extraction, "first 0.5 s fine, released at 0.2 s")
    call sys%set_line_body(2, 0.0_dp, [0.0_dp, 0.0_dp, 0.0_dp], 30.0_dp, err)
    call sys%advance(solver, 1.0_dp, err)
    call check(allocated(err), "integration stops after the line body vanished")
    if (allocated(err)) call expect(err%message, "during the run", "Kane mass matrix")
    call solver%free()
  end subroutine singular_during_run

  subroutine painleve()
    type(separation_system) :: sys
    type(rigid_body) :: aircraft, rocket
    type(cut_joint_geometry) :: g
    type(cut_joint_options) :: opt
    type(error_type), allocatable :: err
    real(dp), allocatable :: y(:)
    real(dp), parameter :: m = 1000.0_dp, jz = 8333.0_dp, h = 0.5_dp, x = 4.0_dp
    real(dp) :: mu_crit
    mu_crit = (jz/m + x**2)/(h*x)
    print '(a, f8.3)', "  Painleve limit mu = ", mu_crit
    g%rail_direction = [-1.0_dp, 0.0_dp, 0.0_dp]
    g%floor_point = [5.0_dp, 0.0_dp, 0.0_dp]
    g%edge_point = [0.0_dp, 0.0_dp, 0.0_dp]
    g%contact_point = [0.0_dp, -h, 0.0_dp]
    g%nose_x = 5.0_dp
    g%rocket_length = 10.0_dp
    g%rocket_radius = h
    aircraft = new_rigid_body("ramp", 1.0e5_dp, diag3(1.0e5_dp, 1.0e5_dp, 1.0e5_dp), err)
    rocket = new_rigid_body("plank", m, diag3(50.0_dp, jz, jz), err)
    ! below the limit the sliding contact is solvable
    opt%mu_edge = 0.5_dp*mu_crit
    call sys%init(aircraft, rocket, [5.0_dp, 0.0_dp, 0.0_dp], 1, g, opt, 0.0_dp, err, aircraft_prescribed=.true.)
    call sys%add_source(gravity_source())
    call sys%joint%place_on_edge(sys%bodies(0), x, 0.0_dp, -1.0_dp, 0.0_dp, sys%bodies(1))
    allocate(y(sys%state_size()))
    call sys%pack_state(y)
    call sys%start(0.0_dp, y, phase_rotation, err)
    call check(.not. allocated(err) .and. sys%normal_force > 0, "mu = limit/2, sliding forwards: solvable, N = " // &
      trim(adjustl(num(sys%normal_force))) // " N, friction " // trim(adjustl(num(sys%friction_force))) // " N")
    if (allocated(err)) deallocate(err)
    ! above it there is no consistent contact force
    sys%joint%opt%mu_edge = 2.0_dp*mu_crit
    call sys%start(0.0_dp, y, phase_rotation, err)
    call check(allocated(err), "mu = 2 x limit: the CFA reports no solution")
    if (allocated(err)) call expect(err%message, "Painleve", "CFA")
  end subroutine painleve

  function num(v) result(s)
    real(dp), intent(in) :: v
    character(len=16) :: s
    write(s, '(es16.6)') v
  end function num
end program test_multibody_errors
