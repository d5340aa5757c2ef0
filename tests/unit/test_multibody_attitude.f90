!> Validation 7 of issue 4: a body passing pitch 90 deg and beyond (the rocket's
!> firing attitude, where the Euler kinematics (49)-(50) is singular) integrates
!> without loss of accuracy with quaternions.
!>
!> The rocket in free flight (Case 3) with a pure pitch rate W about its principal
!> z axis under gravity: exact attitude q(t) = q0 (x) [cos(W t/2), 0, 0, sin(W t/2)],
!> CG on the parabola r0 + v0 t + g t^2/2.  Checked over 1.6 turns (through 90, 180,
!> 270 deg): attitude error angle 1e-8 rad, the continuous nose elevation W t, the
!> Euler pitch never above 90 deg, and the quaternion norm error |1 - |q|| < 1e-12
!> (issue).  The separation scene projects its quaternions onto unit norm after
!> every CVODE step (CVodeSetProjFn), so with the outputs taken at step ends
!> (CVODE stop times) the norm error is round-off at an ordinary tolerance
!> (rtol 1e-10, no drift term).  The second run keeps the earlier alternative,
!> the stiff drift term k (1 - |q|^2) q with k = 1e5 /s at rtol 1e-13.
program test_multibody_attitude
  use airlaunch_kinds, only: dp, g0, pi
  use airlaunch_error, only: error_type
  use airlaunch_rotation, only: quat_from_euler, quat_mul, quat_conj, nose_elevation, quat_to_euler
  use airlaunch_cvode, only: cvode_solver, cvode_options, cvode_stats
  use airlaunch_multibody
  use testing
  implicit none

  call spin_through_vertical(0.0_dp, 1.0e-10_dp)
  call spin_through_vertical(1.0e5_dp, 1.0e-13_dp)
  call finish()

contains

  character(len=11) function fmt(x)
    real(dp), intent(in) :: x
    write(fmt, '(es11.3)') x
  end function fmt

  subroutine spin_through_vertical(gain, rtol)
    real(dp), intent(in) :: gain, rtol
    type(separation_system), target :: sys
    type(cvode_solver) :: solver
    type(cvode_stats) :: st
    type(error_type), allocatable :: error
    type(rigid_body) :: aircraft, rocket
    type(cut_joint_geometry) :: geo
    type(cut_joint_options) :: opt
    real(dp), allocatable :: y(:)
    real(dp), parameter :: w = 1.3_dp
    real(dp) :: q0(4), qe(4), qerr(4), r0(3), v0(3), t, worst_att, worst_norm, worst_pos, max_pitch, worst_elev
    real(dp) :: qn, eul(3), worst_drift
    integer :: i
    character(len=8) :: tag
    write(tag, '(es8.1)') gain
    call section("7. pure pitch spin through 90, 180, 270 deg, projection on, drift gain k = " // tag // " /s, rtol " // fmt(rtol))
    aircraft = new_rigid_body("aircraft", 89000.0_dp, reshape([5.4e5_dp, 0.0_dp, 0.0_dp, 0.0_dp, 7.4e5_dp, &
      0.0_dp, 0.0_dp, 0.0_dp, 1.2e5_dp], [3, 3]), error)
    rocket = new_rigid_body("rocket", 28000.0_dp, reshape([7870.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, 545000.0_dp, &
      0.0_dp, 0.0_dp, 0.0_dp, 545000.0_dp], [3, 3]), error)
    call sys%init(aircraft, rocket, [9.25_dp, 0.0_dp, 0.0_dp], 1, geo, opt, 0.0_dp, error, &
      aircraft_prescribed=.true.)
    sys%quat_gain = gain
    call sys%add_source(gravity_source())
    r0 = [10.0_dp, 9000.0_dp, 1.0_dp]
    v0 = [180.0_dp, 0.0_dp, 0.0_dp]
    q0 = quat_from_euler([0.0_dp, 0.2_dp, 0.0_dp])
    sys%bodies(0)%r = [0.0_dp, 9010.0_dp, 0.0_dp]
    sys%bodies(1)%r = r0
    sys%bodies(1)%v = v0
    call sys%bodies(1)%set_attitude(q0)
    sys%bodies(1)%w = [0.0_dp, 0.0_dp, w]
    allocate(y(sys%state_size()))
    call sys%pack_state(y)
    call sys%start(0.0_dp, y, phase_free, error)
    call check(.not. allocated(error), "start in free flight")
    call solver%init(sys, 0.0_dp, y, cvode_options(rtol=rtol, atol=rtol), error)
    worst_att = 0.0_dp; worst_norm = 0.0_dp; worst_drift = 0.0_dp; worst_pos = 0.0_dp; max_pitch = -huge(1.0_dp); worst_elev = 0.0_dp
    do i = 1, 160
      t = 0.05_dp*i
      call solver%set_stop_time(t, error)
      if (allocated(error)) exit
      call sys%advance(solver, t, error)
      if (allocated(error)) exit
      qn = norm2(solver%y(20:23))
      worst_drift = max(worst_drift, sys%quat_drift)
      worst_norm = max(worst_norm, abs(1.0_dp - qn))
      qe = quat_mul(q0, [cos(w*t/2), 0.0_dp, 0.0_dp, sin(w*t/2)])
      qerr = quat_mul(quat_conj(qe), solver%y(20:23)/qn)
      worst_att = max(worst_att, 2*atan2(norm2(qerr(2:4)), abs(qerr(1))))
      worst_pos = max(worst_pos, norm2(solver%y(14:16) - (r0 + v0*t + 0.5_dp*[0.0_dp, -g0, 0.0_dp]*t**2)))
      call sys%load_state(solver%y)
      eul = quat_to_euler(sys%bodies(1)%q)
      max_pitch = max(max_pitch, eul(2))
      if (0.2_dp + w*t < 1.5_dp*pi) worst_elev = max(worst_elev, abs(nose_elevation(sys%bodies(1)%q) - (0.2_dp + w*t)))
    end do
    call check(.not. allocated(error), "integration over 8 s (" // fmt(w*8/pi*180) // " deg)")
    st = solver%stats()
    print '(a, i0, a, i0)', "  CVODE steps ", st%steps, ", rhs evaluations ", st%rhs_evals
    print '(a, es10.3, a, es10.3, a, es10.3, a)', "  attitude error ", worst_att, " rad, position error ", &
      worst_pos, " m, |1 - |q|| ", worst_norm, ""
    call check(worst_att < 1e-8_dp, "attitude error angle " // fmt(worst_att) // " rad (tol 1e-8)")
    call check(worst_elev < 1e-8_dp, "nose elevation follows 0.2 + W t through the vertical: " // fmt(worst_elev))
    call check(max_pitch <= pi/2 + 1e-12_dp .and. max_pitch > pi/2 - 0.05_dp, "Euler pitch peaks at " // &
      fmt(max_pitch*180/pi) // " deg, never above 90 (the contract variable folds back)")
    call check(worst_pos < 1e-6_dp, "CG on the ballistic parabola: " // fmt(worst_pos) // " m")
    call check(max(worst_norm, worst_drift) < 1e-12_dp, "quaternion norm error " // fmt(worst_norm) // &
      " (tol 1e-12)")
    call solver%free()
  end subroutine spin_through_vertical
end program test_multibody_attitude
