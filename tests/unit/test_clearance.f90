!> The clearance milestone's geometry (airlaunch_clearance): the rate of the
!> clearance against central differences of the clearance along a rigid motion
!> of both bodies (constant velocities and body rates, the attitude advanced
!> in closed form), with the rocket's nearest axis point inside the axis and at
!> either end; and a local minimum located as the rate's rising zero.
program test_clearance
  use airlaunch_kinds, only: dp
  use airlaunch_strings, only: str
  use airlaunch_rotation, only: quat_mul
  use airlaunch_rigid_body, only: rigid_body
  use airlaunch_clearance
  use testing
  implicit none
  type(clearance_geometry) :: geom, probe
  type(rigid_body) :: ac, rk
  real(dp) :: t, h, fd, worst, lo, hi, mid
  integer :: k, it, g
  real(dp), parameter :: times(5) = [0.0_dp, 0.4_dp, 1.1_dp, 1.9_dp, 2.6_dp]
  real(dp), parameter :: point_x(3) = [-24.0_dp, 60.0_dp, -90.0_dp]

  geom = clearance_geometry(point=[-24.0_dp, 6.0_dp, 0.5_dp], nose=[9.25_dp, 0.0_dp, 0.0_dp], &
    aft=[-9.25_dp, 0.0_dp, 0.0_dp], radius=0.8_dp)

  call section("the rate is the time derivative of the clearance")
  ! central differences with h = 1e-5 s of a smooth distance: error ~h^2 |c'''| and
  ! rounding ~1e-16 |c|/h ~ 1e-10: 1e-7 m/s bounds both
  ! (the empennage point beside the axis; far ahead of it: the nose is the
  ! nearest point; far behind: the aft end)
  h = 1.0e-5_dp
  do g = 1, 3
    probe = geom
    probe%point(1) = point_x(g)
    worst = 0.0_dp
    do k = 1, size(times)
      t = times(k)
      call move(t + h)
      fd = clearance(probe, ac, rk)
      call move(t - h)
      fd = (fd - clearance(probe, ac, rk))/(2*h)
      call move(t)
      worst = max(worst, abs(clearance_rate(probe, ac, rk) - fd))
    end do
    call check_close(worst, 0.0_dp, "largest |rate - central difference| over 5 instants, point x = " // &
      str(probe%point(1)) // " m [m/s]", abs=1e-7_dp)
  end do

  call section("the rising zero of the rate is the minimum of the clearance")
  ! bisection on the rate over [0, 3] s, then the clearance there against a
  ! fine scan (the minimum of a smooth function: the scan is above it by at
  ! most ~c'' dt^2/8)
  lo = 0.0_dp; hi = 3.0_dp
  call move(lo)
  call check(clearance_rate(geom, ac, rk) < 0.0_dp, "closing at t = 0")
  call move(hi)
  call check(clearance_rate(geom, ac, rk) > 0.0_dp, "opening at t = 3 s")
  do it = 1, 60
    mid = 0.5_dp*(lo + hi)
    call move(mid)
    if (clearance_rate(geom, ac, rk) < 0.0_dp) then
      lo = mid
    else
      hi = mid
    end if
  end do
  call move(lo)
  fd = clearance(geom, ac, rk)
  worst = huge(1.0_dp)
  do it = 0, 30000
    call move(3.0_dp*it/30000)
    worst = min(worst, clearance(geom, ac, rk))
  end do
  call check(fd <= worst + 1.0e-12_dp, "no scanned clearance below the located minimum")
  call check_close(worst - fd, 0.0_dp, "the scan's minimum just above it [m]", abs=1.0e-6_dp)
  call finish()

contains

  !> Both bodies at time t: the aircraft flying level with a pitch rate, the
  !> rocket passing 2-3 m beside the empennage point (closest near t = 2.5 s),
  !> pitching and rolling.
  subroutine move(t)
    real(dp), intent(in) :: t
    ac%v = [200.0_dp, 0.5_dp, 0.0_dp]
    ac%w = [0.0_dp, 0.0_dp, 0.02_dp]
    ac%r = [0.0_dp, 0.0_dp, 0.0_dp] + t*ac%v
    call ac%set_attitude(spin([1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp], ac%w, t))
    rk%v = [197.0_dp, 4.5_dp, 0.0_dp]
    rk%w = [0.1_dp, 0.05_dp, 0.35_dp]
    rk%r = [-20.0_dp, -4.0_dp, 3.0_dp] + t*rk%v
    call rk%set_attitude(spin([0.9914449_dp, 0.0_dp, 0.0_dp, 0.1305262_dp], rk%w, t))
  end subroutine move

  !> Attitude after time t at the constant body rate w: q0 (x) [cos(|w|t/2), sin(|w|t/2) w/|w|].
  pure function spin(q0, w, t) result(q)
    real(dp), intent(in) :: q0(4), w(3), t
    real(dp) :: q(4), a
    a = norm2(w)*t/2
    q = quat_mul(q0, [cos(a), sin(a)*w/norm2(w)])
  end function spin
end program test_clearance
