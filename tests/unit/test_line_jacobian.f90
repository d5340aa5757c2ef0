!> The line's analytic Jacobian against central differences of the forces it
!> differentiates, and end to end against CVODE's difference quotients.
!>
!> 1. line_model%force_jacobian (tension and dashpot of taut segments, slack
!>    segments, settling damping, drag with wind at a fixed density) against
!>    central differences of line_model%forces, block by block, on a line with
!>    taut and slack segments; every force is local, so the differences outside
!>    the three blocks of a node must vanish too.
!>    The same with two taut segments parted (line_model%part, the air-launch
!>    scene's break): they carry no tension, their nodes' other forces and
!>    every force away from them are unchanged bit for bit, the elastic energy
!>    loses exactly their 1/2 EA l0 eps^2, and the Jacobian still equals the
!>    central differences of the forces (it skips what the forces skip).
!> 2. line_system%jacobian (the band matrix CVODE receives: identity blocks,
!>    force blocks over the node masses, a point-mass end with drag, a fixed
!>    end left out of the state) against central differences of line_system%rhs,
!>    every entry of the band and zero outside it.
!>    The system also flags a right-hand side whose slack/taut pattern differs
!>    from the one the last Jacobian was formed at (and not one at that state).
!> 3. The cable pendulum of issue 7 with the analytic Jacobian and with CVODE's
!>    difference quotients: the same end-mass track (the Newton matrix changes
!>    the iteration, not the solution) with fewer force evaluations.
!>
!> Tolerances: central differences with step h have error O(h^2 f''') and
!> round-off O(eps |f|/h); h = 1e-6 m (or m/s) gives both far below 1e-8 of
!> the largest block entry, which is asserted (measured 1.3e-10; leaving out the
!> geometric-stiffness term or the drag's direction term gives 2e-2 and 1e-4).  The
!> states keep every segment's strain at least 1e-3 away from zero and every
!> taut segment's tension positive, so no difference crosses the tension-only
!> kink (where the Jacobian deliberately takes the taut side, line_model).
program test_line_jacobian
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type
  use airlaunch_strings, only: str
  use airlaunch_ode, only: band_view, node_blocks
  use airlaunch_line
  use airlaunch_line_cvode, only: line_system, line_band_upper, line_band_lower
  use testing
  implicit none
  integer, parameter :: n = 8
  real(dp), parameter :: h = 1.0e-6_dp

  call fixed_seed()   ! the same random states in every run
  call model_blocks()
  call parted_blocks()
  call system_band()
  call pendulum_same_track()
  call finish()

contains

  !> A line of n segments with drag, damping and settling damping, in a state with
  !> taut and slack segments (strain +2 %, -5 % alternating by pairs).
  subroutine test_line(model, x, v)
    type(line_model), intent(out) :: model
    real(dp), intent(out) :: x(3, 0:n), v(3, 0:n)
    type(error_type), allocatable :: error
    real(dp) :: r(3), dir(3), stretch
    integer :: k
    call model%init(line_params(length=real(n, dp), n_seg=n, ea=1.0e5_dp, mass_per_length=0.4_dp, &
      damping=200.0_dp, settling_damping=0.3_dp, diameter=0.05_dp, gravity=.true., air=.true., &
      air_density=0.9_dp, wind=[-50.0_dp, 5.0_dp, 10.0_dp]), error)
    call check(.not. allocated(error), "line model")
    x(:, 0) = [0.0_dp, 0.0_dp, 0.0_dp]
    do k = 1, n
      call random_number(r)
      dir = [1.0_dp, 0.4_dp*(r(1) - 0.5_dp), 0.4_dp*(r(2) - 0.5_dp)]
      dir = dir/sqrt(dot_product(dir, dir))
      stretch = merge(1.02_dp, 0.95_dp, mod((k - 1)/2, 2) == 0)
      x(:, k) = x(:, k-1) + stretch*model%l0*dir
    end do
    call random_number(v)
    v = 0.2_dp*(v - 0.5_dp)
  end subroutine test_line

  subroutine model_blocks()
    type(line_model) :: model
    real(dp) :: x(3, 0:n), v(3, 0:n)
    real(dp) :: ell, tk
    integer :: k, n_taut, n_slack
    call section("force blocks against central differences (taut and slack segments, drag, damping)")
    call test_line(model, x, v)
    n_taut = 0; n_slack = 0
    do k = 1, n
      ell = norm2(x(:, k) - x(:, k-1))
      tk = model%p%ea*(ell/model%l0 - 1.0_dp) + model%p%damping* &
        dot_product((x(:, k) - x(:, k-1))/ell, v(:, k) - v(:, k-1))/model%l0
      if (ell > model%l0) then
        n_taut = n_taut + 1
        call check(tk > 0.0_dp, "segment " // str(k) // " taut with positive tension (" // str(tk) // " N)")
      else
        n_slack = n_slack + 1
      end if
      call check(abs(ell/model%l0 - 1.0_dp) > 1.0e-3_dp, "segment " // str(k) // " away from the kink")
    end do
    call check(n_taut >= 3 .and. n_slack >= 3, "taut and slack segments: " // str(n_taut) // " / " // str(n_slack))
    call blocks_against_differences(model, x, v, "")
  end subroutine model_blocks

  !> The force blocks of `model` at (x, v) against central differences of its
  !> forces, every column (labels prefixed by `what`).
  subroutine blocks_against_differences(model, x, v, what)
    type(line_model), intent(in) :: model
    real(dp), intent(in) :: x(3, 0:n), v(3, 0:n)
    character(len=*), intent(in) :: what
    real(dp) :: dfdx(3, 3, -1:1, 0:n), dfdv(3, 3, -1:1, 0:n)
    real(dp) :: err_x, err_v, big_x, big_v, outside
    integer :: j, q
    call model%force_jacobian(x, v, dfdx, dfdv)
    err_x = 0.0_dp; err_v = 0.0_dp; outside = 0.0_dp
    big_x = maxval(abs(dfdx)); big_v = maxval(abs(dfdv))
    do j = 0, n
      do q = 1, 3
        call compare_column(model, x, v, .false., q, j, dfdx, err_x, outside)
        call compare_column(model, x, v, .true., q, j, dfdv, err_v, outside)
      end do
    end do
    print '(a, 2es10.2, a, 2es10.2)', "  largest entries df/dx, df/dv:", big_x, big_v, "; errors:", err_x, err_v
    call check(big_x > 1.0e4_dp .and. big_v > 10.0_dp, what // "blocks not trivially zero")
    call check_close(err_x, 0.0_dp, what // "df/dx blocks", abs=1.0e-8_dp*big_x)
    call check_close(err_v, 0.0_dp, what // "df/dv blocks", abs=1.0e-8_dp*big_v)
    call check_close(outside, 0.0_dp, what // "no coupling beyond the neighbours", abs=1.0e-8_dp*big_x)
  end subroutine blocks_against_differences

  subroutine parted_blocks()
    type(line_model) :: model, whole
    real(dp) :: x(3, 0:n), v(3, 0:n), f(3, 0:n), fw(3, 0:n), ten(n), tw(n)
    real(dp) :: eps, lost
    integer :: k, st, cut(2), j
    type(line_energy) :: e, ew
    call section("a parted line: two taut segments cut (line_model%part)")
    call test_line(model, x, v)
    whole = model
    cut = [1, 6]   ! taut by test_line's strain pattern (+2 % on segments 1, 2, 5, 6)
    lost = 0.0_dp
    do j = 1, 2
      k = cut(j)
      eps = norm2(x(:, k) - x(:, k-1))/model%l0 - 1.0_dp
      call check(eps > 1.0e-3_dp, "segment " // str(k) // " stretched before the cut (" // str(eps) // ")")
      lost = lost + 0.5_dp*model%p%ea*model%l0*eps**2
      call model%part(k)
    end do
    call model%part(cut(2))   ! a second cut of the same segment changes nothing
    call check(model%n_parted == 2, "two segments parted (" // str(model%n_parted) // ")")
    call model%forces(x, v, f, ten, st)
    call whole%forces(x, v, fw, tw, st)
    call check(all(ten(cut) == 0.0_dp) .and. all(tw(cut) > 0.0_dp), "the parted segments carry no tension")
    call check(all(pack(ten, [(all(k /= cut), k = 1, n)]) == pack(tw, [(all(k /= cut), k = 1, n)])), &
      "the other tensions unchanged, bit for bit")
    call check(all(f(:, 2:4) == fw(:, 2:4)) .and. all(f(:, 7:n) == fw(:, 7:n)), &
      "the forces on nodes away from the cuts unchanged, bit for bit")
    call check(any(f(:, 0) /= fw(:, 0)) .and. any(f(:, 6) /= fw(:, 6)), "the cut segments' nodes lose their pull")
    e = model%energy(x, v)
    ew = whole%energy(x, v)
    call check_close(ew%elastic - e%elastic, lost, "elastic energy less the parted segments' 1/2 EA l0 eps^2", &
      rel=1.0e-12_dp)
    call blocks_against_differences(model, x, v, "parted line: ")
  end subroutine parted_blocks

  !> Central difference of the forces along x(q, j) (or v(q, j)) against the
  !> blocks' column: largest difference into err, largest force change beyond
  !> the neighbours into outside.
  subroutine compare_column(model, x, v, along_v, q, j, blocks, err, outside)
    type(line_model), intent(in) :: model
    real(dp), intent(in) :: x(3, 0:n), v(3, 0:n)
    logical, intent(in) :: along_v
    integer, intent(in) :: q, j
    real(dp), intent(in) :: blocks(3, 3, -1:1, 0:n)
    real(dp), intent(inout) :: err, outside
    real(dp) :: xp(3, 0:n), vp(3, 0:n), fp(3, 0:n), fm(3, 0:n), tp(n), col(3, 0:n)
    integer :: i, st, sgn
    do sgn = 1, -1, -2
      xp = x; vp = v
      if (along_v) then
        vp(q, j) = v(q, j) + sgn*h
      else
        xp(q, j) = x(q, j) + sgn*h
      end if
      if (sgn == 1) then
        call model%forces(xp, vp, fp, tp, st)
      else
        call model%forces(xp, vp, fm, tp, st)
      end if
    end do
    col = (fp - fm)/(2.0_dp*h)
    do i = 0, n
      if (abs(i - j) <= 1) then
        err = max(err, maxval(abs(col(:, i) - blocks(:, q, j - i, i))))
      else
        outside = max(outside, maxval(abs(col(:, i))))
      end if
    end do
  end subroutine compare_column

  subroutine system_band()
    type(line_model) :: model
    type(line_system) :: sys
    type(band_view) :: jac
    type(error_type), allocatable :: error
    real(dp) :: x(3, 0:n), v(3, 0:n)
    real(dp), allocatable, target :: ab(:)
    real(dp), allocatable :: y(:), yp(:), fp(:), fm(:)
    real(dp) :: err, big, outside, entry
    integer :: ns, ldim, i, j, st
    call section("band Jacobian of the line system (fixed end, point mass with drag) against central differences")
    call test_line(model, x, v)
    call sys%setup(model, line_end(kind=end_fixed, position=x(:, 0)), &
      line_end(kind=end_point_mass, mass=5.0_dp, drag_area=0.8_dp, position=x(:, n)), error)
    call check(.not. allocated(error), "the lumped line system is built")
    ns = sys%n_state()
    call check(ns == 6*n, "states: the fixed end is not one (" // str(ns) // ")")
    allocate(y(ns), yp(ns), fp(ns), fm(ns))
    call sys%pack(x, v, y)
    ldim = line_band_upper + line_band_lower + 1
    allocate(ab(ldim*ns))
    ab = 0.0_dp
    jac%ab => ab
    jac%ldim = ldim
    jac%smu = line_band_upper
    call check(sys%has_jacobian(), "the line system has an analytic Jacobian")
    call sys%jacobian(0.0_dp, y, jac, st)
    call check(st == 0, "Jacobian evaluated")
    big = maxval(abs(ab))
    err = 0.0_dp; outside = 0.0_dp
    do j = 1, ns
      yp = y; yp(j) = y(j) + h
      call sys%rhs(0.0_dp, yp, fp, st)
      yp(j) = y(j) - h
      call sys%rhs(0.0_dp, yp, fm, st)
      do i = 1, ns
        if (i - j > line_band_lower .or. j - i > line_band_upper) then
          outside = max(outside, abs(fp(i) - fm(i))/(2.0_dp*h))
        else
          entry = ab((j - 1)*ldim + line_band_upper + i - j + 1)
          err = max(err, abs((fp(i) - fm(i))/(2.0_dp*h) - entry))
        end if
      end do
    end do
    print '(a, es10.2, a, es10.2)', "  largest entry ", big, ", largest difference ", err
    call check(big > 1.0e4_dp, "band not trivially zero")
    call check_close(err, 0.0_dp, "every band entry", abs=1.0e-8_dp*big)
    call check_close(outside, 0.0_dp, "nothing outside the band (mu = 8, ml = 11)", abs=1.0e-8_dp*big)

    ! The default scheme hands the Jacobian to the velocity-reduced solver as node
    ! blocks (d a / d x, d a / d v of the neighbours): they must be the band's
    ! velocity rows, entry for entry (the band was checked against differences above).
    call section("node blocks of the Jacobian: the band's velocity rows")
    block
      type(node_blocks) :: blk
      logical :: fresh
      integer :: k, d, p, q, row, col
      real(dp) :: diff, big_b
      allocate(blk%ax(3, 3, -1:1, n), blk%av(3, 3, -1:1, n))
      call sys%rhs(0.0_dp, y, fp, st)
      call sys%node_jacobian(0.0_dp, y, .false., blk, fresh, st)
      call check(st == 0 .and. fresh, "evaluated when the solver does not allow reuse")
      diff = 0.0_dp; big_b = 0.0_dp
      do k = 1, n                       ! state node k is line node k (node 0 is fixed)
        do d = -1, 1
          do q = 1, 3
            do p = 1, 3
              row = 6*(k - 1) + 3 + p
              col = 6*(k + d - 1) + q
              if (k + d < 1 .or. k + d > n) then
                diff = max(diff, abs(blk%ax(p, q, d, k)), abs(blk%av(p, q, d, k)))
                cycle
              end if
              diff = max(diff, abs(blk%ax(p, q, d, k) - ab((col - 1)*ldim + line_band_upper + row - col + 1)), &
                abs(blk%av(p, q, d, k) - ab((col + 2)*ldim + line_band_upper + row - col - 2)))
              big_b = max(big_b, abs(blk%ax(p, q, d, k)))
            end do
          end do
        end do
      end do
      call check(big_b > 1.0e3_dp, "blocks not trivially zero")
      call check(diff == 0.0_dp, "the same numbers as the band (and zero towards the fixed end)")

      ! Kept while CVODE allows it and every segment is as slack or taut as at the
      ! last evaluation; a segment that switched (the Jacobian changes discretely)
      ! or CVODE's refusal forces a new one.
      call section("node blocks kept or renewed by the slack/taut pattern")
      call sys%rhs(0.0_dp, y, fp, st)
      call sys%node_jacobian(0.0_dp, y, .true., blk, fresh, st)
      call check(.not. fresh, "same state, reuse allowed: kept")
      call sys%node_jacobian(0.0_dp, y, .false., blk, fresh, st)
      call check(fresh, "same state, reuse refused by CVODE: renewed")
      x(:, 1) = x(:, 0) + 0.9_dp*(x(:, 1) - x(:, 0))   ! segment 1 (strain +2 %) now 8 % short
      call sys%pack(x, v, yp)
      call sys%rhs(0.0_dp, yp, fp, st)
      call check(sys%tension(1) == 0.0_dp .and. sys%tension(2) > 0.0_dp, "segment 1 slack, segment 2 taut")
      call sys%node_jacobian(0.0_dp, yp, .true., blk, fresh, st)
      call check(fresh, "a taut segment gone slack: renewed although reuse is allowed")
      call sys%rhs(0.0_dp, yp, fp, st)
      call sys%node_jacobian(0.0_dp, yp, .true., blk, fresh, st)
      call check(.not. fresh, "and kept again at that pattern")
    end block
  end subroutine system_band

  subroutine pendulum_same_track()
    integer, parameter :: np = 20
    real(dp), parameter :: length = 60.0_dp
    type(line_model) :: model
    class(line_scheme), allocatable :: scheme
    type(line_scheme_options) :: opts
    type(line_scheme_stats) :: s(2)
    type(error_type), allocatable :: error
    real(dp) :: x(3, 0:np), v(3, 0:np), x0(3, 0:np), tip(3, 2)
    integer :: k, run
    call section("issue 7's pendulum (5 % damping): analytic Jacobian against difference quotients")
    call model%init(line_params(length=length, n_seg=np, ea=2.0e6_dp, mass_per_length=0.5_dp, &
      damping=8509.8_dp, gravity=.true.), error)
    do k = 0, np
      x0(:, k) = [length*k/np, 0.0_dp, 0.0_dp]
    end do
    do run = 1, 2
      opts%rtol = 1.0e-8_dp
      opts%atol = 1.0e-8_dp
      opts%analytic_jacobian = run == 1
      v = 0.0_dp
      call new_line_scheme(scheme, model, line_end(kind=end_fixed, position=x0(:, 0)), &
        line_end(kind=end_point_mass, mass=50.0_dp, position=x0(:, np)), x0, v, 0.0_dp, opts, error)
      if (.not. allocated(error)) call scheme%advance(3.0_dp, error)
      call check(.not. allocated(error), merge("analytic  ", "quotients ", run == 1) // " run to t = 3 s")
      if (allocated(error)) return
      call scheme%get_state(x, v)
      tip(:, run) = x(:, np)
      s(run) = scheme%stats()
      call scheme%free()
      deallocate(scheme)
    end do
    print '(a, 2(i8, a, i8, a))', "  steps / force evaluations: analytic ", s(1)%steps, " / ", s(1)%rhs_evals, &
      "; difference quotients ", s(2)%steps, " / ", s(2)%rhs_evals, ""
    ! both at rtol 1e-8: the end mass (60 m from the pivot) agrees to the tolerance's scale (6e-7 m)
    call check_close(norm2(tip(:, 1) - tip(:, 2)), 0.0_dp, "end mass at t = 3 s, analytic vs quotients [m]", &
      abs=1.0e-6_dp)
    call check(s(1)%rhs_evals < s(2)%rhs_evals, "fewer force evaluations with the analytic Jacobian")
  end subroutine pendulum_same_track
end program test_line_jacobian
