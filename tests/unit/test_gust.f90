!> The discrete 1 - cosine gust (airlaunch_gust) against its definition, and
!> its use by the line's drag and the canopy's drag against the same loads
!> computed with the gust's velocity as a uniform wind (line_params%wind, the
!> canopy velocity minus the air's): the two paths are independent code.
program test_gust
  use airlaunch_kinds, only: dp, pi
  use airlaunch_error, only: error_type
  use airlaunch_gust
  use airlaunch_line_model, only: line_model, line_params
  use airlaunch_parachute, only: parachute, canopy_node_acceleration, canopy_node_jacobian
  use testing
  implicit none
  type(gust_field) :: g
  real(dp), parameter :: u(3) = [0.0_dp, 12.0_dp, -5.0_dp], h = 30.0_dp, x0 = 100.0_dp
  real(dp) :: s, w(3), wm(3), wp(3), slope, d
  integer :: k

  call section("shape: zero outside [x_front, x_front + 2H], U at x_front + H")
  g = make_gust(u, h, x0)
  call check(g%active, "a gust with a nonzero peak is active")
  call check(all(gust_velocity(g, [x0 - 1.0e-9_dp, 0.0_dp, 0.0_dp]) == 0.0_dp), "zero before the front")
  call check(all(gust_velocity(g, [x0 + 2*h + 1.0e-9_dp, 0.0_dp, 0.0_dp]) == 0.0_dp), "zero behind the gust")
  w = gust_velocity(g, [x0 + h, -7.0_dp, 3.0_dp])
  call check_close(norm2(w - u), 0.0_dp, "the peak U at x_front + H (any y, z)", abs=1.0e-14_dp*norm2(u))
  ! (U/2)(1 - cos(pi s/H)) at s = H/3: (U/2)(1 - 1/2) = U/4
  w = gust_velocity(g, [x0 + h/3, 0.0_dp, 0.0_dp])
  call check_close(norm2(w - u/4), 0.0_dp, "U/4 at s = H/3", abs=1.0e-14_dp*norm2(u))
  block
    type(gust_field) :: calm
    calm = make_gust([0.0_dp, 0.0_dp, 0.0_dp], h, x0)
    call check(all(gust_velocity(calm, [x0 + h, 0.0_dp, 0.0_dp]) == 0.0_dp) .and. .not. calm%active, &
      "zero peak: inactive, zero everywhere")
  end block

  call section("smoothness: w and dw/dx continuous at both edges (C^1)")
  ! just inside an edge w = U (pi s/H)^2/4 + O(s^4): the value at s = 1e-3 H
  ! is 2.5e-6 |U|, and the one-sided slope w(s)/s is pi^2 s/(4 H^2) |U| -> 0
  do k = 0, 1
    d = 1.0e-3_dp*h
    s = merge(d, 2*h - d, k == 0)
    w = gust_velocity(g, [x0 + s, 0.0_dp, 0.0_dp])
    call check_close(norm2(w), norm2(u)*pi**2*1.0e-6_dp/4, "w at 1e-3 H inside edge " // merge("front", "back ", k == 0), &
      rel=1.0e-5_dp)
  end do
  ! the largest slope pi |U| / (2H) at s = H/2, by a central difference (h^2 error ~ 1e-10)
  wm = gust_velocity(g, [x0 + h/2 - 1.0e-3_dp, 0.0_dp, 0.0_dp])
  wp = gust_velocity(g, [x0 + h/2 + 1.0e-3_dp, 0.0_dp, 0.0_dp])
  slope = norm2(wp - wm)/2.0e-3_dp
  call check_close(slope, pi*norm2(u)/(2*h), "largest slope pi |U| / (2H) at s = H/2", rel=1.0e-8_dp)

  call section("the line's drag in the gust = with the gust's velocity as its wind")
  block
    type(line_model) :: a, b
    type(error_type), allocatable :: error
    real(dp) :: x(3, 0:4), v(3, 0:4), fa(3, 0:4), fb(3, 0:4), ta(4), tb(4)
    integer :: sa, sb
    ! a line across the flight path at x = x_front + H (every segment midpoint
    ! at the gust's peak), stretched, moving, in the ISA air at 3 km
    do k = 0, 4
      x(:, k) = [x0 + h, 3000.0_dp - 2.5_dp*k, 0.3_dp*k]
      v(:, k) = [150.0_dp + k, -2.0_dp*k, 1.0_dp]
    end do
    call a%init(line_params(length=9.0_dp, n_seg=4, ea=1.0e5_dp, mass_per_length=0.3_dp, air=.true.), error)
    call b%init(line_params(length=9.0_dp, n_seg=4, ea=1.0e5_dp, mass_per_length=0.3_dp, air=.true., wind=u), error)
    call check(.not. allocated(error), "the lines initialise")
    a%gust = g
    call a%forces(x, v, fa, ta, sa)
    call b%forces(x, v, fb, tb, sb)
    ! the same operations on the same numbers: the wind of one is the other's
    ! gust (to its last bit, U - (U/2)(1 - cos pi) = 0)
    call check_close(maxval(abs(fa - fb)), 0.0_dp, "node forces (gust vs uniform wind U)", &
      abs=1.0e-12_dp*maxval(abs(fb)))
    block
      real(dp) :: jxa(3, 3, -1:1, 0:4), jva(3, 3, -1:1, 0:4), jxb(3, 3, -1:1, 0:4), jvb(3, 3, -1:1, 0:4)
      call a%force_jacobian(x, v, jxa, jva)
      call b%force_jacobian(x, v, jxb, jvb)
      call check_close(maxval(abs(jva - jvb)), 0.0_dp, "velocity Jacobian (gust vs uniform wind U)", &
        abs=1.0e-12_dp*maxval(abs(jvb)))
      call check_close(maxval(abs(jxa - jxb)), 0.0_dp, "position Jacobian (the gust's gradient left out at its peak)", &
        abs=1.0e-12_dp*maxval(abs(jxb)))
    end block
    ! and the gust made a difference: without it the drag is another
    a%gust = gust_field()
    call a%forces(x, v, fa, ta, sa)
    call check(maxval(abs(fa - fb)) > 1.0e-3_dp*maxval(abs(fb)), "without the gust the forces differ")
  end block

  call section("the canopy's drag in the gust = its velocity relative to the air")
  block
    type(parachute) :: p, q
    real(dp) :: xc(3), vc(3), fl(3), acc_a(3), acc_b(3), drag_a(3), drag_b(3), ma, mb, ja(3, 3), jb(3, 3)
    logical :: ok_a, ok_b
    p%deploy_time = 0.5_dp; p%fill_time = 1.0_dp   ! mid-filling: the apparent mass's momentum term on
    q = p
    p%gust = g
    xc = [x0 + h, 3000.0_dp, 0.0_dp]
    vc = [140.0_dp, 3.0_dp, -2.0_dp]
    fl = [-5000.0_dp, 200.0_dp, 10.0_dp]
    call canopy_node_acceleration(p, 1.0_dp, xc, vc, 0.2_dp, fl, .true., .true., acc_a, drag_a, ok_a)
    call canopy_node_acceleration(q, 1.0_dp, xc, vc - u, 0.2_dp, fl, .true., .true., acc_b, drag_b, ok_b)
    call check(ok_a .and. ok_b, "the canopy is inside the atmosphere model")
    call check_close(norm2(drag_a - drag_b), 0.0_dp, "drag and momentum force from v - U", abs=1.0e-14_dp*norm2(drag_b))
    call check_close(norm2(acc_a - acc_b), 0.0_dp, "acceleration", abs=1.0e-14_dp*norm2(acc_b))
    call canopy_node_jacobian(p, 1.0_dp, xc, vc, 0.2_dp, .true., ma, ja, ok_a)
    call canopy_node_jacobian(q, 1.0_dp, xc, vc - u, 0.2_dp, .true., mb, jb, ok_b)
    call check_close(maxval(abs(ja - jb)), 0.0_dp, "velocity Jacobian of the drag at v - U", abs=1.0e-14_dp*maxval(abs(jb)))
  end block

  call finish()
end program test_gust
