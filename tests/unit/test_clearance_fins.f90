!> The clearance's fins and tailplane (airlaunch_clearance): the exact
!> point/segment-to-fin-plate and segment-to-axis distances against brute-force
!> sampling of both surfaces; the rate against central differences along a
!> rigid motion with the fins and a tail span, where the nearest piece changes;
!> the rate's rising zero against a scan of the clearance there; and a rolled
!> rocket whose fin points at the tail, closer than the body by the semi-span.
program test_clearance_fins
  use airlaunch_kinds, only: dp
  use airlaunch_strings, only: str
  use airlaunch_rotation, only: quat_mul
  use airlaunch_rigid_body, only: rigid_body
  use airlaunch_clearance
  use testing
  implicit none
  ! the paper's fin planform in its plane: root chord 2 m at R = 0.8 m, tip
  ! chord 1 m at 1.34 m further out, leading edge swept 1 m
  real(dp), parameter :: r0 = 0.8_dp, span = 1.34_dp
  real(dp), parameter :: plate(2, 4) = reshape([0.0_dp, r0, -2.0_dp, r0, -2.0_dp, r0 + span, &
    -1.0_dp, r0 + span], [2, 4])
  integer, parameter :: n_point = 300, n_seg = 120   ! plate samples per direction
  type(clearance_geometry) :: geom, bare
  type(rigid_body) :: ac, rk
  real(dp) :: x1(3), x2(3), d, qu, qw, t, brute, worst_over, worst_under, h, fd, lo, hi, mid, c, cmin, &
    tol_plate, tol_seg, a(3), b(3), s, rate_jump
  integer :: k, it, n_fin_nearest, n_body_nearest
  real(dp) :: u(3)

  ! a point of the plate is within half a sampling cell's diagonal of a
  ! sample: cells <= 2/n m along x, <= (1.34 + 1)/n m across (the sheared
  ! rows): 0.5 (2 + 2.34)/n bounds it (7.3e-3 m at n = 300)
  tol_plate = 0.5_dp*(2.0_dp + 2.34_dp)/n_point

  call section("point to fin plate: exact against brute-force sampling")
  call random_seed_fixed()
  worst_over = 0.0_dp; worst_under = 0.0_dp
  do k = 1, 60
    call random_number(u)
    x1 = [-3.5_dp + 5.0_dp*u(1), -0.5_dp + 3.5_dp*u(2), -1.5_dp + 3.0_dp*u(3)]
    if (k <= 10) x1(1:2) = [-1.2_dp, r0 + 0.09_dp*span*k]   ! above the plate: its projection inside
    call point_trapezoid(x1, plate, d, qu, qw)
    brute = sampled_distance(x1, x1, 1, n_point)
    worst_over = max(worst_over, d - brute)
    worst_under = max(worst_under, brute - d)
    ! the returned nearest point is on the plate at the returned distance
    call check_close(norm2(x1 - [qu, qw, 0.0_dp]), d, "point " // str(k) // ": |x - q| = d [m]", abs=1.0e-12_dp)
  end do
  call check_close(worst_over, 0.0_dp, "largest (exact - sampled) over 60 points: never above the samples [m]", &
    abs=1.0e-12_dp)
  call check_close(worst_under, 0.0_dp, "largest (sampled - exact) [m]: within the sampling's half diagonal", &
    abs=tol_plate)

  call section("segment to fin plate: exact against brute-force sampling")
  ! the plate at n = 120 (1.8e-2 m), the segment at 201 points: + half
  ! its spacing, <= 5.2 m/200/2
  tol_seg = 0.5_dp*(2.0_dp + 2.34_dp)/n_seg + 5.2_dp/200/2
  worst_over = 0.0_dp; worst_under = 0.0_dp
  do k = 1, 16
    call random_number(u)
    x1 = [-3.5_dp + 5.0_dp*u(1), -0.5_dp + 3.5_dp*u(2), -1.5_dp + 3.0_dp*u(3)]
    call random_number(u)
    x2 = x1 + [-1.5_dp + 3.0_dp*u(1), -1.5_dp + 3.0_dp*u(2), -1.5_dp + 3.0_dp*u(3)]
    if (k == 1) then   ! piercing the plate: 0
      x1 = [-1.0_dp, 1.5_dp, -0.7_dp]; x2 = [-1.2_dp, 1.4_dp, 0.9_dp]
    end if
    if (k == 2) then   ! parallel to the plate above it, crossing its outline
      x1 = [-4.0_dp, 1.5_dp, 0.3_dp]; x2 = [2.0_dp, 1.5_dp, 0.3_dp]
    end if
    call segment_trapezoid(x1, x2, plate, d, t, qu, qw)
    brute = sampled_distance(x1, x2, 200, n_seg)
    worst_over = max(worst_over, d - brute)
    worst_under = max(worst_under, brute - d)
    call check_close(norm2(x1 + t*(x2 - x1) - [qu, qw, 0.0_dp]), d, "segment " // str(k) // &
      ": |p(t) - q| = d [m]", abs=1.0e-12_dp)
    if (k == 1) call check_close(d, 0.0_dp, "the piercing segment [m]", abs=0.0_dp)
  end do
  call check_close(worst_over, 0.0_dp, "largest (exact - sampled) over 16 segments [m]", abs=1.0e-12_dp)
  call check_close(worst_under, 0.0_dp, "largest (sampled - exact) [m]: within the two samplings' spacing", &
    abs=tol_seg)

  call section("segment to the rocket's axis (the body, less the radius): exact against sampling")
  ! both segments sampled at 2001 points: the sampled pair within half of
  ! each spacing, 0.5 (18.5 + 8)/2000 < 6.7e-3 m
  worst_over = 0.0_dp; worst_under = 0.0_dp
  do k = 1, 20
    call random_number(u)
    a = [9.25_dp, 0.0_dp, 0.0_dp]; b = [-9.25_dp, 0.0_dp, 0.0_dp]
    x1 = [-20.0_dp + 40.0_dp*u(1), -4.0_dp + 8.0_dp*u(2), -4.0_dp + 8.0_dp*u(3)]
    call random_number(u)
    x2 = x1 + [-4.0_dp + 8.0_dp*u(1), -2.0_dp + 4.0_dp*u(2), -4.0_dp + 8.0_dp*u(3)]
    if (k == 1) x2 = x1 + [1.0_dp, 0.0_dp, 0.0_dp]   ! parallel to the axis
    call segment_segment(x1, x2, a, b, t, s)
    d = norm2(x1 + t*(x2 - x1) - (a + s*(b - a)))
    brute = sampled_segments(x1, x2, a, b, 2000)
    worst_over = max(worst_over, d - brute)
    worst_under = max(worst_under, brute - d)
  end do
  call check_close(worst_over, 0.0_dp, "largest (exact - sampled) over 20 segments [m]", abs=1.0e-12_dp)
  call check_close(worst_under, 0.0_dp, "largest (sampled - exact) [m]", abs=0.5_dp*(18.5_dp + 8.0_dp)/2000)

  call section("a rolled rocket: a fin pointing at the tail is closer than the body by the semi-span")
  ! the rocket's axis along x at the origin, the tail point 4 m above the
  ! fins' tip chord: the body's clearance 4 - R; rolled by 45 deg a fin of
  ! the X points straight up: 4 - R - s; unrolled, the nearest fin tip at
  ! 45 deg: sqrt(4^2 + (R + s)^2 - 2*4 (R + s) cos 45) (the tip's edge)
  bare = clearance_geometry(point=[-8.75_dp, 4.0_dp, 0.0_dp], nose=[9.25_dp, 0.0_dp, 0.0_dp], &
    aft=[-9.25_dp, 0.0_dp, 0.0_dp], radius=r0)
  geom = bare
  call set_fins(geom, 4, -7.25_dp, 2.0_dp, 1.0_dp, 1.0_dp, span)
  ac%r = [0.0_dp, 0.0_dp, 0.0_dp]; rk%r = [0.0_dp, 0.0_dp, 0.0_dp]
  call ac%set_attitude([1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp])
  call rk%set_attitude([1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp])
  call check_close(clearance(bare, ac, rk), 4.0_dp - r0, "body alone [m]", abs=1.0e-14_dp)
  call check_close(clearance(geom, ac, rk), sqrt(16.0_dp + (r0 + span)**2 - 8*(r0 + span)*cos(atan(1.0_dp))), &
    "fins in X, unrolled: the tip's edge [m]", abs=1.0e-14_dp)
  call rk%set_attitude([cos(atan(1.0_dp)/2), sin(atan(1.0_dp)/2), 0.0_dp, 0.0_dp])
  call check_close(clearance(bare, ac, rk), 4.0_dp - r0, "body alone, rolled 45 deg [m]", abs=1.0e-14_dp)
  call check_close(clearance(bare, ac, rk) - clearance(geom, ac, rk), span, &
    "rolled 45 deg: body - fins = the semi-span [m]", abs=1.0e-14_dp)
  ! three fins, one along +y: the same 1.34 m closer unrolled
  geom = bare
  call set_fins(geom, 3, -7.25_dp, 2.0_dp, 1.0_dp, 1.0_dp, span)
  call rk%set_attitude([1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp])
  call check_close(clearance(bare, ac, rk) - clearance(geom, ac, rk), span, &
    "three fins, one along +y: body - fins = the semi-span [m]", abs=1.0e-14_dp)
  ! the tailplane: the rocket 5 m to the side (+z), 0.5 m below, rolled 45
  ! deg (a fin horizontal towards -z, spanning z = 4.2 .. 2.86 m); a tail
  ! 3.5 m each way passes 0.5 m above that fin; its body is sqrt(0.5^2 + 1.5^2) - R
  ! from the tail's tip, and sqrt(0.5^2 + 5^2) - R from the empennage point
  bare%half_span = 3.5_dp
  geom = bare
  call set_fins(geom, 4, -7.25_dp, 2.0_dp, 1.0_dp, 1.0_dp, span)
  geom%point(2) = 0.0_dp; bare%point(2) = 0.0_dp
  rk%r = [0.0_dp, -0.5_dp, 5.0_dp]
  call rk%set_attitude([cos(atan(1.0_dp)/2), sin(atan(1.0_dp)/2), 0.0_dp, 0.0_dp])
  call check_close(clearance(bare, ac, rk), sqrt(2.5_dp) - r0, "the tail's tip to the body [m]", abs=1.0e-14_dp)
  call check_close(clearance(geom, ac, rk), 0.5_dp, "the tail's tip above the horizontal fin [m]", abs=1.0e-14_dp)
  bare%half_span = 0.0_dp
  call check_close(clearance(bare, ac, rk), sqrt(25.25_dp) - r0, "no span: the empennage point to the body [m]", &
    abs=1.0e-14_dp)

  call section("the rate with fins and a tail span against central differences")
  ! h = 1e-5 s: truncation ~h^2 |c'''| and rounding ~1e-16 |c|/h ~ 1e-10 m/s;
  ! the instants avoid the kinks (|t - t_kink| > h, checked by the same
  ! instants' pieces: a kink inside [t - h, t + h] would show as a jump)
  geom = clearance_geometry(point=[-24.0_dp, 6.0_dp, 0.0_dp], half_span=1.0_dp, nose=[9.25_dp, 0.0_dp, 0.0_dp], &
    aft=[-9.25_dp, 0.0_dp, 0.0_dp], radius=r0)
  bare = geom
  call set_fins(geom, 3, -7.25_dp, 2.0_dp, 1.0_dp, 1.0_dp, span)
  h = 1.0e-5_dp
  worst_over = 0.0_dp
  n_fin_nearest = 0; n_body_nearest = 0
  it = 0   ! instants with a kink within h (the nearest piece changes there)
  do k = 0, 60
    t = 0.05_dp*k + 0.0123_dp
    call move(t + h)
    fd = clearance(geom, ac, rk)
    call move(t - h)
    fd = (fd - clearance(geom, ac, rk))/(2*h)
    call move(t)
    if (clearance(geom, ac, rk) < clearance(bare, ac, rk)) then
      n_fin_nearest = n_fin_nearest + 1
    else
      n_body_nearest = n_body_nearest + 1
    end if
    if (abs(clearance_rate(geom, ac, rk) - fd) > 1.0e-4_dp) then
      it = it + 1   ! a kink within h: the difference straddles two pieces
      cycle
    end if
    worst_over = max(worst_over, abs(clearance_rate(geom, ac, rk) - fd))
  end do
  call check(n_fin_nearest > 10 .and. n_body_nearest > 10, "the motion has both pieces nearest (fins at " // &
    str(n_fin_nearest) // ", the body at " // str(n_body_nearest) // " of 61 instants)")
  call check_close(worst_over, 0.0_dp, "largest |rate - central difference| [m/s]", abs=1.0e-7_dp)
  call check(it <= 2, "instants with a kink within 1e-5 s: " // str(it) // " (at most 2 expected)")

  call section("kinks: the rate jumps down where the nearest piece changes; minima are rising zeros")
  ! scan finely for piece changes and the rate's jump across each
  rate_jump = -huge(1.0_dp)
  it = 0
  do k = 1, 30000
    t = 3.0_dp*k/30000
    call move(t - 1.0e-4_dp)
    c = clearance_rate(geom, ac, rk)
    lo = merge(1.0_dp, 0.0_dp, clearance(geom, ac, rk) < clearance(bare, ac, rk))
    call move(t)
    hi = merge(1.0_dp, 0.0_dp, clearance(geom, ac, rk) < clearance(bare, ac, rk))
    if (lo /= hi) then
      it = it + 1
      rate_jump = max(rate_jump, clearance_rate(geom, ac, rk) - c)
    end if
  end do
  call check(it >= 1, "the nearest piece changes " // str(it) // " times over 3 s")
  ! the jump is -(difference of the pieces' rates) < 0, up to the rates'
  ! change over 1e-4 s (|c''| 1e-4 < 1e-2 m/s)
  call check(rate_jump < 1.0e-2_dp, "largest rate jump at a change: " // str(rate_jump) // " m/s (down)")
  ! bisection on the rate for its rising zero, then a fine scan's minimum
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
  c = clearance(geom, ac, rk)
  cmin = huge(1.0_dp)
  do it = 0, 30000
    call move(3.0_dp*it/30000)
    cmin = min(cmin, clearance(geom, ac, rk))
  end do
  call check(c <= cmin + 1.0e-12_dp, "no scanned clearance below the located minimum " // str(c) // " m")
  call check_close(cmin - c, 0.0_dp, "the scan's minimum just above it [m]", abs=1.0e-6_dp)
  call finish()

contains

  !> The least distance between the segment [y1, y2] sampled at n + 1 points
  !> (n = 1 with y1 = y2: the point) and the plate sampled on an
  !> (n_plate + 1)^2 grid.
  real(dp) function sampled_distance(y1, y2, n, n_plate) result(dmin)
    real(dp), intent(in) :: y1(3), y2(3)
    integer, intent(in) :: n, n_plate
    real(dp) :: w, ule, ute, p(3), v(3)
    integer :: i, j, m
    dmin = huge(1.0_dp)
    do j = 0, n_plate
      w = plate(2, 1) + span*j/n_plate
      ule = plate(1, 1) + (plate(1, 4) - plate(1, 1))*j/n_plate
      ute = plate(1, 2) + (plate(1, 3) - plate(1, 2))*j/n_plate
      do i = 0, n_plate
        v = [ule + (ute - ule)*i/n_plate, w, 0.0_dp]
        do m = 0, n
          p = y1 + (y2 - y1)*m/n
          dmin = min(dmin, norm2(p - v))
        end do
      end do
    end do
  end function sampled_distance

  !> The least distance between two segments sampled at n + 1 points each.
  real(dp) function sampled_segments(p1, q1, p2, q2, n) result(dmin)
    real(dp), intent(in) :: p1(3), q1(3), p2(3), q2(3)
    integer, intent(in) :: n
    integer :: i, j
    dmin = huge(1.0_dp)
    do i = 0, n
      do j = 0, n
        dmin = min(dmin, norm2(p1 + (q1 - p1)*i/n - (p2 + (q2 - p2)*j/n)))
      end do
    end do
  end function sampled_segments

  subroutine random_seed_fixed()
    integer :: n, i
    call random_seed(size=n)
    call random_seed(put=[(12345 + 7*i, i=1, n)])
  end subroutine random_seed_fixed

  !> Both bodies at time t: the aircraft flying level with a pitch rate, the
  !> rocket below the tail, crossing the tail's span from +z to -z, rolling
  !> and sliding aft along the tail (the body nearest until t ~ 1.55 s, then
  !> its fins; the minimum near 2.2 s is a fin's).
  subroutine move(t)
    real(dp), intent(in) :: t
    ac%v = [200.0_dp, 0.5_dp, 0.0_dp]
    ac%w = [0.0_dp, 0.0_dp, 0.02_dp]
    ac%r = [0.0_dp, 0.0_dp, 0.0_dp] + t*ac%v
    call ac%set_attitude(spin([1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp], ac%w, t))
    rk%v = [201.5_dp, 0.8_dp, -2.6_dp]
    rk%w = [1.0_dp, 0.02_dp, 0.03_dp]
    rk%r = [-19.75_dp, 2.6_dp, 4.0_dp] + t*rk%v
    call rk%set_attitude(spin([1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp], rk%w, t))
  end subroutine move

  !> Attitude after time t at the constant body rate w: q0 (x) [cos(|w|t/2), sin(|w|t/2) w/|w|].
  pure function spin(q0, w, t) result(q)
    real(dp), intent(in) :: q0(4), w(3), t
    real(dp) :: q(4), a
    a = norm2(w)*t/2
    q = quat_mul(q0, [cos(a), sin(a)*w/norm2(w)])
  end function spin
end program test_clearance_fins
