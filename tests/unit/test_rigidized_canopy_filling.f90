!> Coupling (a), 'rigidized': the load on B3 (the canopy) while it fills.
!>
!> A filling canopy's apparent mass m_a(t) grows, and the still air it entrains
!> must be brought to the canopy's velocity.  The momentum balance of canopy +
!> entrained air, d((m + m_a) v)/dt = F (Knacke, Parachute Recovery Systems
!> Design Manual, NWC TP 6575, ch. 5: apparent mass in the opening force), gives
!> on the canopy, besides its drag, the force -(dm_a/dt) v_rel: it always opposes
!> the air-relative velocity (the entrained air is a momentum sink, never a
!> thrust).  The reference below is written from the documented closed forms
!> alone, not from the code's output:
!>   drag area   CdS(t) = CdS_p + (CdS - CdS_p) tau^j,  tau = (t - t_d)/t_f,
!>   m_a,open    = k_a rho pi/6 (0.7 D0)^3,  D0 = sqrt(4 CdS/(pi Cd0)),
!>   dm_a/dt     = m_a,open j tau^(j-1)/t_f,
!>   F_3         = -1/2 rho CdS(t) |v| v - (dm_a/dt) v   (still air).
!> Tolerance 1e-12 relative: the same arithmetic in another order (rounding
!> only).  The direct coupling's canopy node has the same law (checked against
!> analytic oscillations in test_line_canopy); before this test nothing
!> exercised the rigidized coupling with a canopy that is still filling (the
!> paper scenario's parachute is open from the start), so the sign of the
!> entrained-air term on B3 was unchecked.
program test_rigidized_canopy_filling
  use airlaunch_kinds, only: dp, pi
  use airlaunch_error, only: error_type
  use airlaunch_atmosphere, only: isa, air_state
  use airlaunch_multibody
  use airlaunch_rigidized_coupling
  use testing
  implicit none

  type(rigidized_loads) :: rl
  type(rigid_body) :: b(0:3)
  type(error_type), allocatable :: error
  type(air_state) :: air
  real(dp) :: force(3, 0:3), moment(3, 0:3), v3(3), expect(3), entrained(3)
  real(dp) :: t, tau, cds, d0, ma_open, ma_rate, rho
  real(dp), parameter :: t_d = 0.2_dp, t_f = 1.6_dp, j = 2.0_dp

  call section("canopy (B3) of the rigidized coupling while it fills: drag + entrained-air momentum")
  rl%length = 40.0_dp
  rl%diameter = 0.025_dp
  rl%cd_normal = 1.2_dp
  rl%cd_tangential = 0.01_dp
  rl%gravity = .false.
  rl%air = .true.
  rl%drag_strips = 8
  rl%chute%drag_area = 10.0_dp
  rl%chute%cd0 = 0.75_dp
  rl%chute%packed_drag_area = 0.05_dp
  rl%chute%added_mass_factor = 1.0_dp
  rl%chute%deploy_time = t_d
  rl%chute%fill_time = t_f
  rl%chute%inflation_exponent = j
  rl%v_eps = 0.0_dp
  b(2)%r = [0.0_dp, 5000.0_dp, 0.0_dp]
  call b(2)%set_attitude(line_body_attitude([rl%length, 0.0_dp, 0.0_dp]))
  b(2)%v = 0.0_dp
  b(2)%w = 0.0_dp
  b(3)%r = [100.0_dp, 6000.0_dp, 0.0_dp]
  v3 = [-120.0_dp, 8.0_dp, 3.0_dp]
  b(3)%v = v3
  b(3)%w = 0.0_dp
  air = isa(b(3)%r(2))
  rho = air%density

  t = t_d + 0.5_dp*t_f
  force = 0.0_dp; moment = 0.0_dp
  call rl%add_loads(t, b, force, moment, error)
  call check(.not. allocated(error), "loads evaluated")

  tau = (t - t_d)/t_f
  cds = 0.05_dp + (10.0_dp - 0.05_dp)*tau**j
  d0 = sqrt(4*10.0_dp/(pi*0.75_dp))
  ma_open = rho*pi/6*(0.7_dp*d0)**3
  ma_rate = ma_open*j*tau**(j - 1.0_dp)/t_f
  entrained = -ma_rate*v3
  expect = -0.5_dp*rho*cds*norm2(v3)*v3 + entrained
  call check(norm2(force(:, 3) - expect) <= 1.0e-12_dp*norm2(expect), &
    "F_3 = -1/2 rho CdS(t) |v| v - (dm_a/dt) v")
  call check_close(force(1, 3), expect(1), "  F_3 along the flight [N]", rel=1.0e-12_dp)
  call check(norm2(entrained) > 1.0e-3_dp*norm2(expect), "  the entrained-air term is not negligible here")
  call check(dot_product(force(:, 3), v3) < 0.0_dp, "  the canopy load does negative work (no thrust)")

  ! fully open (t > t_d + t_f): no entrained-air term, only the drag
  t = t_d + 2.0_dp*t_f
  force = 0.0_dp; moment = 0.0_dp
  call rl%add_loads(t, b, force, moment, error)
  expect = -0.5_dp*rho*10.0_dp*norm2(v3)*v3
  call check(norm2(force(:, 3) - expect) <= 1.0e-12_dp*norm2(expect), "open canopy: F_3 = -1/2 rho CdS |v| v")
  call finish()
end program test_rigidized_canopy_filling
