!> Trim of the Case 0 system: the aircraft with the rocket locked in its bay
!> and the deployed parachute pulling on the rocket's tie-down point (the
!> line's force there: `pull` aft along earth -x and `pull_y` vertical), in
!> steady level flight at the given altitude and speed.
!>
!> Unknowns (Newton's method, finite-difference Jacobian, LAPACK solve):
!>   mode "fly":       angle of attack, elevator, thrust for given CL0, Cm0;
!>   mode "calibrate": CL0, Cm0, thrust for a given angle of attack with zero
!>                     elevator (used to honour the paper's trim angle of
!>                     attack, 1.2174 deg, which is data of the paper while the
!>                     aircraft's zero-alpha lift and moment are not).
!> Equations: sum of forces (earth x, y) and pitching moment about the
!> aircraft's CG vanish.  Pitch attitude = angle of attack (level flight).
!>
!> A converged trim must also be flyable ("fly" mode): the elevator within
!> +-delta_e_max and the angle of attack within [trim_alpha_min_deg,
!> trim_alpha_max_deg], the range the input accepts for the paper's trim angle
!> (&flight trim_alpha_deg): the lift is linear, without stall, so an
!> equilibrium at, say, 60 deg is an artefact of the model.  Otherwise the
!> result says `infeasible` and an error is returned.
module airlaunch_trim
  use airlaunch_kinds, only: dp, g0, deg2rad, rad2deg
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_linalg, only: solve_general
  use airlaunch_rotation, only: rot_z, cross
  use airlaunch_aircraft_aero, only: aircraft_aero, aircraft_aero_eval, aircraft_aero_out
  implicit none
  private
  public :: trim_problem, trim_result, trim_case0, trim_alpha_min_deg, trim_alpha_max_deg

  !> Angles of attack a trim may have [deg] (also the input range of trim_alpha_deg).
  real(dp), parameter :: trim_alpha_min_deg = -5.0_dp, trim_alpha_max_deg = 15.0_dp

  !> What the trim needs to know.
  type :: trim_problem
    real(dp) :: aircraft_mass = 0.0_dp   !< clean aircraft [kg]
    real(dp) :: rocket_mass = 0.0_dp     !< [kg]
    real(dp) :: r_rocket(3) = 0.0_dp     !< rocket CG from aircraft CG, aircraft body frame [m]
    real(dp) :: r_tie(3) = 0.0_dp        !< line tie-down point from aircraft CG, aircraft body frame [m]
    real(dp) :: pull = 0.0_dp            !< line pull at the tie-down, along earth -x [N]
    real(dp) :: pull_y = 0.0_dp          !< earth-y component of the line's force at the tie-down [N]
                                         !< (the settled line's weight pulls it down: < 0)
    real(dp) :: density = 0.0_dp         !< [kg/m^3]
    real(dp) :: speed = 0.0_dp           !< [m/s]
    character(len=16) :: mode = "fly"    !< "fly" or "calibrate"
    real(dp) :: alpha_target = 0.0_dp    !< for "calibrate" [rad]
  end type trim_problem

  !> The trimmed state.
  type :: trim_result
    real(dp) :: alpha = 0.0_dp      !< angle of attack = pitch attitude [rad]
    real(dp) :: delta_e = 0.0_dp    !< elevator [rad]
    real(dp) :: thrust = 0.0_dp     !< [N]
    real(dp) :: cl0 = 0.0_dp, cm0 = 0.0_dp
    real(dp) :: residual = 0.0_dp   !< max |equation| after convergence [N or N m]
    integer :: iterations = 0
    logical :: infeasible = .false. !< converged, but elevator or alpha beyond their limits
  end type trim_result

contains

  !> Solve the trim; `ac` is returned with cl0, cm0, thrust, delta_e_trim and
  !> theta_ref of the trimmed state.
  subroutine trim_case0(prob, ac, res, error)
    type(trim_problem), intent(in) :: prob
    type(aircraft_aero), intent(inout) :: ac
    type(trim_result), intent(out) :: res
    type(error_type), allocatable, intent(inout) :: error
    real(dp) :: x(3), r(3), r2(3), jac(3, 3), dx(3, 1), h(3), scale(3)
    integer :: it, k
    logical :: bad_elevator, bad_alpha
    character(len=:), allocatable :: beyond
    ! initial guess
    select case (prob%mode)
    case ("fly")
      x = [0.03_dp, 0.0_dp, prob%pull + 0.02_dp*0.5_dp*prob%density*prob%speed**2*ac%wing_area]
    case ("calibrate")
      x = [ac%cl0, ac%cm0, prob%pull + 0.02_dp*0.5_dp*prob%density*prob%speed**2*ac%wing_area]
    case default
      call fatal_error(error, "trim: unknown mode '" // trim(prob%mode) // "' (fly or calibrate)")
      return
    end select
    scale = [(prob%aircraft_mass + prob%rocket_mass)*g0, (prob%aircraft_mass + prob%rocket_mass)*g0, &
             (prob%aircraft_mass + prob%rocket_mass)*g0*ac%chord]
    h = [1.0e-6_dp, 1.0e-6_dp, 1.0_dp]
    do it = 1, 50
      r = equations(x)
      res%residual = maxval(abs(r))
      res%iterations = it - 1
      if (all(abs(r) <= 1.0e-10_dp*scale)) exit
      do k = 1, 3
        x(k) = x(k) + h(k)
        r2 = equations(x)
        x(k) = x(k) - h(k)
        jac(:, k) = (r2 - r)/h(k)
      end do
      dx(:, 1) = -r
      call solve_general(jac, dx, error, "trim Jacobian")
      if (allocated(error)) then
        error%message = "trim: no equilibrium found at Newton step " // str(it) // " (" // error%message // &
          ": alpha, elevator and thrust do not move the force and moment residuals); check masses, speed " // &
          "and aerodynamic data"
        return
      end if
      x = x + dx(:, 1)
    end do
    ! the residual of the x that is applied (after 50 steps x moved after r)
    r = equations(x)
    res%residual = maxval(abs(r))
    if (.not. all(abs(r) <= 1.0e-8_dp*scale)) then
      call fatal_error(error, "trim: no equilibrium found (residual " // str(maxval(abs(r)/scale)) // &
        " of the weight after 50 Newton steps); check masses, speed and aerodynamic data")
      return
    end if
    res%alpha = alpha_of(x)
    res%delta_e = merge(x(2), 0.0_dp, prob%mode == "fly")
    res%thrust = x(3)
    bad_elevator = abs(res%delta_e) > ac%delta_e_max
    bad_alpha = res%alpha < trim_alpha_min_deg*deg2rad .or. res%alpha > trim_alpha_max_deg*deg2rad
    if (bad_elevator .or. bad_alpha) then
      res%infeasible = .true.
      if (bad_elevator .and. bad_alpha) then
        beyond = "the elevator limit and the alpha range"
      else if (bad_elevator) then
        beyond = "the elevator limit"
      else
        beyond = "the alpha range"
      end if
      call fatal_error(error, "trim: the equilibrium needs elevator " // deg(res%delta_e) // &
        " deg at alpha " // deg(res%alpha) // " deg, beyond " // beyond // " (allowed: |elevator| <= " // &
        deg(ac%delta_e_max) // " deg, alpha in [" // str(trim_alpha_min_deg) // ", " // &
        str(trim_alpha_max_deg) // "] deg)")
      return
    end if
    call apply(x)
    res%delta_e = ac%delta_e_trim
    res%thrust = ac%thrust
    res%cl0 = ac%cl0
    res%cm0 = ac%cm0
    ac%theta_ref = res%alpha
  contains
    !> An angle [rad] as degrees to 0.01 deg.
    function deg(a) result(t)
      real(dp), intent(in) :: a
      character(len=:), allocatable :: t
      t = str(anint(a*rad2deg*100)/100)
    end function deg

    real(dp) function alpha_of(xx)
      real(dp), intent(in) :: xx(3)
      if (prob%mode == "fly") then
        alpha_of = xx(1)
      else
        alpha_of = prob%alpha_target
      end if
    end function alpha_of

    subroutine apply(xx)
      real(dp), intent(in) :: xx(3)
      if (prob%mode == "fly") then
        ac%delta_e_trim = xx(2)
      else
        ac%cl0 = xx(1)
        ac%cm0 = xx(2)
        ac%delta_e_trim = 0.0_dp
      end if
      ac%thrust = xx(3)
    end subroutine apply

    !> Residuals [Fx, Fy, Mz] of the combined body for unknowns xx.
    function equations(xx) result(eq)
      real(dp), intent(in) :: xx(3)
      real(dp) :: eq(3)
      type(aircraft_aero) :: a
      type(aircraft_aero_out) :: o
      real(dp) :: alpha, c(3, 3), v_b(3), f_e(3), pull_b(3), grav_b(3), m_b(3)
      a = ac
      a%attitude_hold = .false.
      if (prob%mode == "fly") then
        alpha = xx(1)
        a%delta_e_trim = xx(2)
      else
        alpha = prob%alpha_target
        a%cl0 = xx(1)
        a%cm0 = xx(2)
        a%delta_e_trim = 0.0_dp
      end if
      a%thrust = xx(3)
      c = rot_z(alpha)                         ! body -> earth at pitch = alpha
      v_b = matmul(transpose(c), [prob%speed, 0.0_dp, 0.0_dp])
      o = aircraft_aero_eval(a, prob%density, v_b, [0.0_dp, 0.0_dp, 0.0_dp], alpha)
      f_e = matmul(c, o%force) + [-prob%pull, prob%pull_y - (prob%aircraft_mass + prob%rocket_mass)*g0, 0.0_dp]
      pull_b = matmul(transpose(c), [-prob%pull, prob%pull_y, 0.0_dp])
      grav_b = matmul(transpose(c), [0.0_dp, -prob%rocket_mass*g0, 0.0_dp])
      m_b = o%moment + cross(prob%r_rocket, grav_b) + cross(prob%r_tie, pull_b)
      eq = [f_e(1), f_e(2), m_b(3)]
    end function equations
  end subroutine trim_case0
end module airlaunch_trim
