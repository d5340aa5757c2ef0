!> Parachute canopy as a point mass with drag and apparent (added) mass.
!>
!> Drag: F = -1/2 rho (Cd S)(t) |u| u, u = v - w_gust(x) the velocity relative to
!> the air (w_gust: the air-launch scene's discrete gust, zero without one).
!> Inflation (Knacke, Parachute Recovery Systems Design Manual, NWC TP 6575,
!> 1991, ch. 5): filling time t_f = n D0 / V at the deployment speed, with
!> the canopy fill constant n (about 8 for a solid flat circular canopy), and
!>   (Cd S)(t) = (Cd S)_0 + ((Cd S) - (Cd S)_0) ((t - t_d)/t_f)^j,  t_d <= t <= t_d + t_f,
!> j the inflation exponent (1 linear, 2 quadratic growth of the drag area).
!> Apparent mass of the enclosed and entrained air (Knacke ch. 6; Lingard):
!>   m_a = k_a rho (pi/6) D_p^3, D_p = 0.7 D0 (inflated projected diameter),
!> added to the canopy mass in translation (m + m_a) a = F; scaled with the
!> inflation like the drag area.
module airlaunch_parachute
  use airlaunch_kinds, only: dp, pi, g0
  use airlaunch_atmosphere, only: isa, air_state
  use airlaunch_gust, only: gust_field, air_relative_velocity
  implicit none
  private
  public :: parachute, parachute_drag_area, parachute_added_mass, parachute_nominal_diameter, &
    parachute_added_mass_rate, &
    canopy_node_acceleration, canopy_node_jacobian

  !> Canopy data.
  type :: parachute
    real(dp) :: mass = 1.798_dp          !< canopy + suspension-line mass [kg]
    real(dp) :: drag_area = 10.0_dp      !< Cd S fully open [m^2]
    real(dp) :: cd0 = 0.75_dp            !< drag coefficient on the nominal area S0 (flat circular)
    real(dp) :: deploy_time = -1.0_dp    !< start of inflation [s]; < 0: open from the start
    real(dp) :: fill_constant = 8.0_dp   !< n of t_f = n D0 / V
    real(dp) :: inflation_exponent = 2.0_dp !< j
    real(dp) :: packed_drag_area = 0.05_dp  !< Cd S of the packed/streaming canopy [m^2]
    real(dp) :: added_mass_factor = 1.0_dp  !< k_a
    real(dp) :: fill_time = 0.0_dp       !< t_f [s], set from the deployment speed
    !> the air-launch scene's discrete gust: canopy_node_acceleration and
    !> canopy_node_jacobian take the velocity relative to it (inactive by default)
    type(gust_field) :: gust
  end type parachute

contains

  !> Nominal diameter D0 = sqrt(4 S0 / pi), S0 = Cd S / Cd0.
  pure real(dp) function parachute_nominal_diameter(p) result(d0)
    type(parachute), intent(in) :: p
    d0 = sqrt(4*p%drag_area/(pi*p%cd0))
  end function parachute_nominal_diameter

  !> Fraction of the inflation reached at time t, in [0, 1].
  pure real(dp) function inflation(p, t) result(f)
    type(parachute), intent(in) :: p
    real(dp), intent(in) :: t
    if (p%deploy_time < 0.0_dp .or. p%fill_time <= 0.0_dp) then
      f = 1.0_dp
    else if (t <= p%deploy_time) then
      f = 0.0_dp
    else
      f = min(1.0_dp, (t - p%deploy_time)/p%fill_time)**p%inflation_exponent
    end if
  end function inflation

  !> Rate of the inflation fraction, d/dt ((t - t_d)/t_f)^j [1/s] (0 outside the filling).
  pure real(dp) function inflation_rate(p, t) result(r)
    type(parachute), intent(in) :: p
    real(dp), intent(in) :: t
    real(dp) :: tau
    r = 0.0_dp
    if (p%deploy_time < 0.0_dp .or. p%fill_time <= 0.0_dp .or. t <= p%deploy_time) return
    tau = (t - p%deploy_time)/p%fill_time
    if (tau <= 0.0_dp .or. tau >= 1.0_dp) return
    r = p%inflation_exponent*tau**(p%inflation_exponent - 1.0_dp)/p%fill_time
  end function inflation_rate

  !> Drag area at time t [m^2].
  pure real(dp) function parachute_drag_area(p, t) result(cds)
    type(parachute), intent(in) :: p
    real(dp), intent(in) :: t
    cds = p%packed_drag_area + (p%drag_area - p%packed_drag_area)*inflation(p, t)
  end function parachute_drag_area

  !> Apparent mass of the open canopy in air of density rho [kg]:
  !> k_a rho pi/6 D_p^3, D_p = 0.7 D0.
  pure real(dp) function open_added_mass(p, rho) result(ma)
    type(parachute), intent(in) :: p
    real(dp), intent(in) :: rho
    ma = p%added_mass_factor*rho*pi/6*(0.7_dp*parachute_nominal_diameter(p))**3
  end function open_added_mass

  !> Apparent mass at time t in air of density rho [kg].
  pure real(dp) function parachute_added_mass(p, rho, t) result(ma)
    type(parachute), intent(in) :: p
    real(dp), intent(in) :: rho, t
    ma = open_added_mass(p, rho)*inflation(p, t)
  end function parachute_added_mass

  !> Rate of the apparent mass while the canopy fills, dm_a/dt at time t in air
  !> of density rho [kg/s] (the density's change along the path left out).
  pure real(dp) function parachute_added_mass_rate(p, rho, t) result(rate)
    type(parachute), intent(in) :: p
    real(dp), intent(in) :: rho, t
    rate = open_added_mass(p, rho)*inflation_rate(p, t)
  end function parachute_added_mass_rate

  !> Acceleration of the line's last node, which carries the canopy (both line
  !> couplings, DESIGN §4): mass = the node's share of the line + canopy +
  !> apparent mass; loads = the line's force on the node, the canopy's drag in
  !> still air (if `with_drag`) and the canopy's weight (if `with_weight`).
  !> While the canopy fills, its apparent mass grows and the air it entrains
  !> must be brought to the canopy's velocity: d((m + m_a) v)/dt = F, i.e.
  !> (m + m_a) a = F - (dm_a/dt) v (with the drag: the air's momentum; Knacke,
  !> NWC TP 6575, ch. 5, apparent mass in the opening force) - `drag` holds
  !> both.
  !> `ok` is false if the node left the atmosphere model (then acc = 0).
  pure subroutine canopy_node_acceleration(p, t, x, v, node_mass, line_force, with_drag, with_weight, &
      acc, drag, ok)
    type(parachute), intent(in) :: p
    real(dp), intent(in) :: t                 !< time [s]
    real(dp), intent(in) :: x(3), v(3)        !< node position (y = altitude) [m], velocity [m/s]
    real(dp), intent(in) :: node_mass         !< the line's mass lumped at the node [kg]
    real(dp), intent(in) :: line_force(3)     !< the line's force on the node [N]
    logical, intent(in) :: with_drag, with_weight
    real(dp), intent(out) :: acc(3)           !< acceleration [m/s^2]
    real(dp), intent(out) :: drag(3)          !< canopy drag [N]
    logical, intent(out) :: ok
    type(air_state) :: air
    real(dp) :: w(3), u(3)
    acc = 0.0_dp
    drag = 0.0_dp
    air = isa(x(2))
    ok = air%in_range
    if (.not. ok) return
    u = air_relative_velocity(p%gust, x, v)
    if (with_drag) drag = -0.5_dp*air%density*parachute_drag_area(p, t)*norm2(u)*u - &
      parachute_added_mass_rate(p, air%density, t)*u
    w = 0.0_dp
    if (with_weight) w(2) = -g0*p%mass
    acc = (line_force + drag + w)/canopy_node_mass(p, t, air%density, node_mass)
  end subroutine canopy_node_acceleration

  !> What the Jacobian of canopy_node_acceleration needs at (t, x, v): the
  !> node's whole mass (its share of the line + canopy + apparent mass) and the
  !> velocity derivative of the canopy's drag, d/dv (-1/2 rho CdS |u| u) =
  !> -1/2 rho CdS (|u| I + u u^T/|u|), u = v - w_gust(x), and of the apparent
  !> mass's momentum term, -(dm_a/dt) I (zero without drag).  The altitude
  !> dependence of the density (in drag and apparent mass) and the gust's
  !> change along x are left out: an approximate Newton matrix, off by
  !> (d rho/dh)/rho ~ 1e-4 per metre.
  !> `ok` is false if the node left the atmosphere model.
  pure subroutine canopy_node_jacobian(p, t, x, v, node_mass, with_drag, mass, drag_dv, ok)
    type(parachute), intent(in) :: p
    real(dp), intent(in) :: t                 !< time [s]
    real(dp), intent(in) :: x(3), v(3)        !< node position (y = altitude) [m], velocity [m/s]
    real(dp), intent(in) :: node_mass         !< the line's mass lumped at the node [kg]
    logical, intent(in) :: with_drag
    real(dp), intent(out) :: mass             !< the node's whole mass [kg]
    real(dp), intent(out) :: drag_dv(3, 3)    !< d drag / d v [N s/m]
    logical, intent(out) :: ok
    type(air_state) :: air
    real(dp) :: speed, c, u(3)
    integer :: i, j
    drag_dv = 0.0_dp
    mass = 0.0_dp
    air = isa(x(2))
    ok = air%in_range
    if (.not. ok) return
    mass = canopy_node_mass(p, t, air%density, node_mass)
    if (.not. with_drag) return
    u = air_relative_velocity(p%gust, x, v)
    speed = norm2(u)
    if (speed > 0.0_dp) then
      c = -0.5_dp*air%density*parachute_drag_area(p, t)
      do j = 1, 3
        do i = 1, 3
          drag_dv(i, j) = c*u(i)*u(j)/speed
        end do
        drag_dv(j, j) = drag_dv(j, j) + c*speed
      end do
    end if
    do j = 1, 3   ! the apparent mass's momentum, - (dm_a/dt) v
      drag_dv(j, j) = drag_dv(j, j) - parachute_added_mass_rate(p, air%density, t)
    end do
  end subroutine canopy_node_jacobian

  !> The canopy node's whole mass: its share of the line, the canopy and the
  !> apparent mass at time t in air of density rho [kg].
  pure real(dp) function canopy_node_mass(p, t, rho, node_mass) result(m)
    type(parachute), intent(in) :: p
    real(dp), intent(in) :: t, rho, node_mass
    m = node_mass + p%mass + parachute_added_mass(p, rho, t)
  end function canopy_node_mass
end module airlaunch_parachute
