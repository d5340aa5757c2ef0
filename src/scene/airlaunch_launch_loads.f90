!> Applied loads of the air-launch scene, as one force source of the
!> separation system (src/multibody): aircraft aerodynamics and thrust (with
!> the elevator hold), rocket aerodynamics with the bay shielding, and the
!> line's end force at the rocket's tie-down point (direct coupling: the line
!> nodes are integrated with the bodies, DESIGN §4 (b)).  Both bodies'
!> aerodynamics take the air-relative velocity v - w_gust(r) of the discrete
!> gust (airlaunch_gust) at their centre of mass and, with `penetration`, read
!> the gust's change along them too: the rocket at each strip, fin and nose
!> station, the aircraft at its empennage (docs/model.md "Gusts").
module airlaunch_launch_loads
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_atmosphere, only: isa, air_state
  use airlaunch_rotation, only: dcm_to_euler
  use airlaunch_aircraft_aero, only: aircraft_aero, aircraft_aero_eval, aircraft_aero_out
  use airlaunch_rocket_aero, only: rocket_aero, rocket_aero_eval
  use airlaunch_rigid_body, only: rigid_body
  use airlaunch_gust, only: gust_field, air_relative_velocity
  use airlaunch_force_source, only: force_source, add_point_force
  use airlaunch_cut_joint, only: phase_free
  implicit none
  private
  public :: launch_loads

  !> Loads on the aircraft (body 0) and the rocket (body 1).
  type, extends(force_source) :: launch_loads
    type(aircraft_aero) :: aircraft                 !< aircraft aerodynamics and thrust
    type(rocket_aero) :: rocket                     !< rocket aerodynamics
    real(dp) :: edge_point(3) = 0.0_dp              !< ramp edge, aircraft axes [m]
    real(dp) :: tie_down(3) = 0.0_dp                !< line attachment, rocket axes [m]
    logical :: aircraft_aero_on = .true.            !< false for a prescribed aircraft
    logical :: line_on = .true.                     !< false: the scene has no line
    type(gust_field) :: gust                        !< the &gust (inactive by default)
    logical :: penetration = .false.                !< the bodies read the gust along them, not at the CG only
    !> the aircraft's lift builds up in the gust over this chord (Küssner,
    !> airlaunch_gust); 0: at once (quasi-steady)
    real(dp) :: kussner_chord = 0.0_dp
    ! --- set by the scene before each evaluation
    integer :: phase = 0                            !< current Case
    real(dp) :: line_force(3) = 0.0_dp              !< line end force on the rocket, earth [N]
    ! --- outputs of the last evaluation
    type(aircraft_aero_out) :: aircraft_out
  contains
    procedure :: add_loads => launch_add_loads
    procedure :: rearmost_gust_point => launch_rearmost_gust_point
  end type launch_loads

contains

  subroutine launch_add_loads(self, t, bodies, force, moment, error)
    class(launch_loads), intent(inout) :: self
    real(dp), intent(in) :: t
    type(rigid_body), intent(in) :: bodies(0:)
    real(dp), intent(inout) :: force(:, 0:)
    real(dp), intent(inout) :: moment(:, 0:)
    type(error_type), allocatable, intent(inout) :: error
    type(air_state) :: air
    real(dp) :: e(3), f(3), m(3), x_shield, edge_e(3), v_air(3), v_body(3)
    associate(b0 => bodies(0), b1 => bodies(1))
      if (self%aircraft_aero_on) then
        air = isa(b0%r(2))
        if (.not. air%in_range) then
          call fatal_error(error, "aircraft altitude " // str(b0%r(2)) // " m is outside the atmosphere model")
          return
        end if
        e = dcm_to_euler(b0%c)
        v_air = air_relative_velocity(self%gust, b0%r, b0%v, self%kussner_chord)
        v_body = matmul(transpose(b0%c), v_air)
        if (self%penetration .and. self%gust%active) then
          ! the empennage's air, without the rotation's part (Cm_q, Cn_r hold it)
          v_air = air_relative_velocity(self%gust, b0%point_position(self%aircraft%tail_point), b0%v, &
            self%kussner_chord)
          self%aircraft_out = aircraft_aero_eval(self%aircraft, air%density, v_body, &
            b0%w, e(2), v_tail=matmul(transpose(b0%c), v_air))
        else
          self%aircraft_out = aircraft_aero_eval(self%aircraft, air%density, v_body, &
            b0%w, e(2))
        end if
        force(:, 0) = force(:, 0) + matmul(b0%c, self%aircraft_out%force)
        moment(:, 0) = moment(:, 0) + self%aircraft_out%moment
      end if
      air = isa(b1%r(2))
      if (.not. air%in_range) then
        call fatal_error(error, "rocket altitude " // str(b1%r(2)) // " m is outside the atmosphere model")
        return
      end if
      if (self%phase == phase_free) then
        x_shield = huge(1.0_dp)
      else
        ! the part of the rocket still ahead of the ramp edge is inside the bay
        edge_e = b0%r + matmul(b0%c, self%edge_point)
        x_shield = dot_product(b1%c(:, 1), edge_e - b1%r)
      end if
      v_air = air_relative_velocity(self%gust, b1%r, b1%v)
      v_body = matmul(transpose(b1%c), v_air)
      if (self%penetration) then
        call rocket_aero_eval(self%rocket, air%density, air%sound_speed, v_body, b1%w, x_shield, f, m, &
          gust=self%gust, r_cg=b1%r, c=b1%c)
      else
        call rocket_aero_eval(self%rocket, air%density, air%sound_speed, v_body, b1%w, x_shield, f, m)
      end if
      force(:, 1) = force(:, 1) + matmul(b1%c, f)
      moment(:, 1) = moment(:, 1) + m
      if (self%line_on) call add_point_force(b1, self%tie_down, self%line_force, force(:, 1), moment(:, 1))
    end associate
    if (.false.) x_shield = t
  end subroutine launch_add_loads

  !> The smallest earth x of the points at which the bodies read the gust
  !> [m]: their centres of mass and, penetrating, the aircraft's empennage and
  !> the rocket's nose and tail.
  pure real(dp) function launch_rearmost_gust_point(self, bodies) result(x_min)
    class(launch_loads), intent(in) :: self
    type(rigid_body), intent(in) :: bodies(0:)
    real(dp) :: p(3)
    x_min = min(bodies(0)%r(1), bodies(1)%r(1))
    if (.not. self%penetration) return
    p = bodies(0)%point_position(self%aircraft%tail_point)
    x_min = min(x_min, p(1))
    p = bodies(1)%point_position([self%rocket%cg_from_nose, 0.0_dp, 0.0_dp])
    x_min = min(x_min, p(1))
    p = bodies(1)%point_position([self%rocket%cg_from_nose - self%rocket%length, 0.0_dp, 0.0_dp])
    x_min = min(x_min, p(1))
  end function launch_rearmost_gust_point
end module airlaunch_launch_loads
