!> A body end's motion between the owner's two samples (airlaunch_line_ends,
!> cubic Hermite interpolation): a cubic trajectory sampled at t1 and t2 with
!> its exact positions and velocities is reproduced exactly - position,
!> velocity and acceleration - at every time of [t1, t2], the two sample times
!> included (the one-sided acceleration there, which the mixed mass matrix
!> takes from a kinematic end), and outside it the motion continues with the
!> end velocity.  Tolerance 1e-12 relative to the largest value (a cubic is in
!> the interpolant's space: only rounding remains).
!>
!> The paper's marching scheme with a body end (the paper's way of coupling,
!> line.md §5): it steps at its dt, but a step ends on the owner's sample t2
!> of the end's motion (beyond it the motion is not known): with dt = 3 ms and
!> samples 10 ms apart, 4 steps per outer step (3 ms, 3 ms, 3 ms, 1 ms), and
!> the end node exactly on the sample at t2.
program test_line_ends
  use airlaunch_kinds, only: dp
  use airlaunch_strings, only: str
  use airlaunch_error, only: error_type
  use airlaunch_line
  use testing
  implicit none
  real(dp), parameter :: t1 = 2.0_dp, t2 = 2.25_dp, tol = 1.0e-12_dp
  real(dp), parameter :: c0(3) = [1.0_dp, -4.0_dp, 0.5_dp], c1(3) = [30.0_dp, 2.0_dp, -1.0_dp]
  real(dp), parameter :: c2(3) = [-6.0_dp, 9.0_dp, 4.0_dp], c3(3) = [40.0_dp, -25.0_dp, 12.0_dp]
  type(line_end) :: e
  real(dp) :: x(3), v(3), a(3), t, scale(3), acc_at(3)
  integer :: i

  call section("cubic Hermite of a body end reproduces a cubic")
  call e%set_body_motion(t1, pos(t1), vel(t1), t2, pos(t2), vel(t2))
  call check(e%kind == end_body .and. e%is_kinematic(), "the end becomes a kinematic body end")
  scale = [maxval(abs(pos(t2))) + maxval(abs(pos(t1))), maxval(abs(vel(t1))) + maxval(abs(vel(t2))), &
    maxval(abs(acc(t1))) + maxval(abs(acc(t2)))]
  do i = 0, 8
    t = t1 + (t2 - t1)*i/8.0_dp
    call e%motion(t, x, v, a)
    acc_at = acc(t)
    call check(maxval(abs(x - pos(t))) <= tol*scale(1), "position at t = " // str(t) // " s")
    call check(maxval(abs(v - vel(t))) <= tol*scale(2), "velocity at t = " // str(t) // " s")
    call check(maxval(abs(a - acc(t))) <= tol*scale(3), "acceleration at t = " // str(t) // " s: " // &
      str(a(1)) // ", " // str(a(2)) // ", " // str(a(3)) // " against " // str(acc_at(1)) // ", " // &
      str(acc_at(2)) // ", " // str(acc_at(3)) // " m/s^2")
  end do

  call section("outside the samples: the end velocity, no acceleration")
  call e%motion(t2 + 0.1_dp, x, v, a)
  call check(maxval(abs(x - (pos(t2) + 0.1_dp*vel(t2)))) <= tol*scale(1) .and. &
    maxval(abs(v - vel(t2))) <= tol*scale(2) .and. all(a == 0.0_dp), "after t2: x2 + v2 (t - t2)")
  call e%motion(t1 - 0.1_dp, x, v, a)
  call check(maxval(abs(x - (pos(t1) - 0.1_dp*vel(t1)))) <= tol*scale(1) .and. &
    maxval(abs(v - vel(t1))) <= tol*scale(2) .and. all(a == 0.0_dp), "before t1: x1 + v1 (t - t1)")
  call section("the marching scheme ends a step on the owner's sample of a body end")
  call marching_stops_on_samples()

  call finish()

contains

  subroutine marching_stops_on_samples()
    integer, parameter :: n = 4
    type(line_model) :: model
    type(line_marching) :: m
    type(line_scheme_options) :: opts
    type(line_scheme_stats) :: st
    type(error_type), allocatable :: error
    real(dp) :: xs(3, 0:n), vs(3, 0:n)
    integer :: k
    call model%init(line_params(length=4.0_dp, n_seg=n, ea=1.0e4_dp, mass_per_length=0.5_dp, gravity=.false., &
      air=.false.), error)
    do k = 0, n
      xs(:, k) = [real(k, dp), 0.0_dp, 0.0_dp]
    end do
    vs = 0.0_dp
    opts%scheme = "marching"
    opts%dt = 3.0e-3_dp
    call check(opts%dt < model%stable_step(), "dt = 3 ms below the stability limit " // str(model%stable_step()))
    call new_line_marching(m, model, line_end(kind=end_body, position=xs(:, 0)), line_end(kind=end_free), xs, vs, &
      0.0_dp, opts, error)
    call check(.not. allocated(error), "scheme built")
    if (allocated(error)) return
    do k = 1, 2
      call m%set_body_motion(1, 0.01_dp*(k - 1), [0.01_dp*(k - 1), 0.0_dp, 0.0_dp], [1.0_dp, 0.0_dp, 0.0_dp], &
        0.01_dp*k, [0.01_dp*k, 0.0_dp, 0.0_dp], [1.0_dp, 0.0_dp, 0.0_dp], error)
      call m%advance(0.01_dp*k, error)
      call check(.not. allocated(error), "outer step " // str(k))
      if (allocated(error)) return
      call m%get_state(xs, vs)
      st = m%stats()
      call check(st%steps == 4*k, "outer step " // str(k) // ": " // str(int(st%steps)) // &
        " steps in all (3, 3, 3, 1 ms per outer step)")
      call check(m%tn == 0.01_dp*k, "the last step ends on the sample")
      call check_close(xs(1, 0), 0.01_dp*k, "the body end on its sample", abs=1.0e-15_dp)
    end do
    call m%free()
  end subroutine marching_stops_on_samples

  pure function pos(tt) result(r)
    real(dp), intent(in) :: tt
    real(dp) :: r(3), s
    s = tt - t1
    r = c0 + c1*s + c2*s**2 + c3*s**3
  end function pos

  pure function vel(tt) result(r)
    real(dp), intent(in) :: tt
    real(dp) :: r(3), s
    s = tt - t1
    r = c1 + 2*c2*s + 3*c3*s**2
  end function vel

  pure function acc(tt) result(r)
    real(dp), intent(in) :: tt
    real(dp) :: r(3), s
    s = tt - t1
    r = 2*c2 + 6*c3*s
  end function acc
end program test_line_ends
