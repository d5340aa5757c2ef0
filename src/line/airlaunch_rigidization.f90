!> Equivalent rigidization of the flexible line, Zheng & Zhang (2018) §2.4,
!> Eqs. (18)–(32): the virtual rigid body that links the two attach points and
!> moves and carries kinetic energy like the line.
!>
!> Frames.  The paper's virtual body frame has its z axis along the line
!> through the front attach point; B_rigid (Eq. (23)) maps earth components to
!> body components, B_rigid = X(theta) Z(phi) (rotation phi about z, then theta
!> about the new x), so B_rigid^-1 = B_rigid^T and Eq. (22) reads
!> B^T [0 0 d_rigid]^T = r.  The inertial frame O_d x_d y_d z_d is our earth frame
!> (x forward, y up, z right).  Attach point 1 (back, V_1) is node 0, attach
!> point 2 (front, V_2) is node N; the axial vector points from node 0 to node N.
!> For the Kane chain, which uses body x along the body axis, `dcm_line` gives the
!> same body as body-to-earth matrix with x along r and y up in the vertical plane.
!>
!> Discrete forms on the lumped-mass line (segment k: unstretched l0, tangent
!> t_k, strain rate epsdot_k; node masses m_k):
!>  (18) d = sum ell_k, the deformed arc length (ds of Eq. (18) read as the
!>       deformed element ds1; the unstretched L is `length0`);
!>  (19) r = sum ell_k t_k = x_N - x_0 (B^-1 l_s = t, integrated over the deformed arc);
!>  (20) d_rigid = |r|;  (21) r_o = r d_rigid/(2 d) (= r/2 for a straight line);
!>  (24) theta = acos(r_z/|r|) (computed as atan2(|r_xy|, r_z): acos loses
!>       half the digits near 0 and pi), phi = atan2(r_x, -r_y): the exact inverse of
!>       (22)–(23); the printed phi = -acos(r_y/sqrt(r_x^2+r_y^2)) loses the sign
!>       of r_x and flips the cosine;
!>  (25) V_eps = sum epsdot_k l0 t_k (integral over the unstretched s, so that
!>       the axial rate of a straight line is exactly V_2 - V_1);
!>  (26)–(28) re-derived: V_2 - V_1 - V_eps = omega x r, so in body components
!>       dV_b = B dV gives omega_x = -dV_b,y/d_rigid, omega_y = dV_b,x/d_rigid
!>       (the printed (28) multiplies by the columns of B instead of its rows and
!>       swaps the x/y labels); omega_z = omega_y cos(theta)/sin(theta) (Eq. (27),
!>       the frame spin of the two-angle parameterization, Eq. (6)), set to 0
!>       when |sin theta| < 1e-9 (line along the earth z axis);
!>  (30) V_oeps = integral of epsdot t over the first half of the unstretched line;
!>  (29) V_rigid = V_1 + V_oeps + omega x r_o (the cross product in the order of
!>       a rigid velocity field; the centre is x_0 + r_o);
!>  (31) with the dimension fix (DESIGN §2): kinetic-energy equivalence needs
!>       |V_rigid|^2 in the denominator.  As printed the numerator is the whole
!>       kinetic energy, which Eq. (32) counts again for the rotation, so for a
!>       line rotating about an end it gives 4/3 of the line mass.  We therefore
!>       take the translational part: m_rigid = sum m_k |u_k|^2 / |V_rigid|^2 with
!>       u_k = v_k - omega_t x (x_k - x_c), omega_t = omega without the frame
!>       spin omega_z of (27) (the chord's rotation, the part of a rotation the
!>       end velocities (26)-(28) determine; omega_z = omega_y cot(theta) moves
!>       no mass and grows without bound as theta -> 0), which equals the line
!>       mass for any rigid motion whose rotation is across the chord, bent line
!>       or straight, and (31)-with-the-fix for a pure translation (a bent
!>       line's spin about its chord is not seen by (26)-(28) and counts as
!>       translation).  The printed form
!>       with the fix is kept as `m_rigid_eq31`.  If |V_rigid| is ~0 (below
!>       1e-9 of the largest node speed, or below 1 um/s) m_rigid falls back to
!>       the line mass.  Near that limit (31) is ill-conditioned by nature: a
!>       deforming line whose centre hardly moves has a huge m_rigid; an owner
!>       that feeds m_rigid to a rigid-body chain should bound it;
!>  (32) J_i = sum m_k d_ki^2 w_ki^2 / omega_i^2, d_ki the distance of node k from
!>       body axis i through the centre, w_k = r_k x (v_k - V_rigid)/|r_k|^2 the
!>       node's angular velocity about the centre (body components); a rate
!>       omega_i ~ 0 (below 1e-9 of the rate scale - the chord's rate or the
!>       nodes' largest speed relative to V_rigid over their largest distance
!>       from the centre - or below 1 urad/s) falls back to the geometric
!>       J_i = sum m_k d_ki^2 (the inertia of the mass distribution about that
!>       axis).  About the chord (z) the rate of (27) is the frame's spin, not
!>       a rotation of the mass, so J_z is always the geometric value (zero for
!>       a straight line).
module airlaunch_rigidization
  use airlaunch_kinds, only: dp
  use airlaunch_rotation, only: cross
  use airlaunch_line_model, only: line_model
  implicit none
  private
  public :: rigid_equivalent, rigidize, whole_piece

  !> The virtual rigid body of a line state (earth frame unless "body").
  type :: rigid_equivalent
    real(dp) :: d = 0.0_dp                 !< (18) deformed arc length [m]
    real(dp) :: length0 = 0.0_dp           !< unstretched length L [m]
    real(dp) :: r(3) = 0.0_dp              !< (19) axial vector node 0 -> node N [m]
    real(dp) :: d_rigid = 0.0_dp           !< (20) equivalent length [m]
    real(dp) :: r_o(3) = 0.0_dp            !< (21) centre offset from node 0 [m]
    real(dp) :: centre(3) = 0.0_dp         !< x_0 + r_o [m]
    real(dp) :: theta = 0.0_dp             !< (24) [rad]
    real(dp) :: phi = 0.0_dp               !< (24) [rad]
    real(dp) :: b(3, 3) = 0.0_dp           !< (23) B_rigid, earth -> body
    real(dp) :: dcm_line(3, 3) = 0.0_dp    !< body (x along r, y up) -> earth
    real(dp) :: v_eps(3) = 0.0_dp          !< (25) deformation velocity [m/s]
    real(dp) :: omega_body(3) = 0.0_dp     !< (27) angular velocity, body components [rad/s]
    real(dp) :: omega(3) = 0.0_dp          !< the same in earth components [rad/s]
    real(dp) :: v_o_eps(3) = 0.0_dp        !< (30) deformation velocity of the first half [m/s]
    real(dp) :: v_rigid(3) = 0.0_dp        !< (29) velocity of the centre [m/s]
    real(dp) :: m_rigid = 0.0_dp           !< (31) translational kinetic-energy mass [kg]
    real(dp) :: m_rigid_eq31 = 0.0_dp      !< (31) as printed, with |V_rigid|^2 [kg]
    real(dp) :: j_rigid(3) = 0.0_dp        !< (32) body-axis moments of inertia [kg m^2]
    real(dp) :: line_mass = 0.0_dp         !< sum of the node masses [kg]
    integer :: first_node = 0              !< the line (or piece of a parted line) is nodes first_node..last_node
    integer :: last_node = 0
    logical :: degenerate = .false.        !< the ends coincide: no axis
    logical :: m_fallback = .false.        !< |V_rigid| ~ 0: m_rigid = line mass
    logical :: j_fallback(3) = .false.     !< omega_i ~ 0 (always for i = 3, the chord): geometric J_i
    logical :: spin_fallback = .false.     !< sin(theta) ~ 0: omega_z = 0
  end type rigid_equivalent

  !> Relative size below which a rate counts as zero.
  real(dp), parameter :: rate_tol = 1.0e-9_dp
  !> Absolute floors: a centre speed below 1 um/s, an angular rate below
  !> 1 urad/s count as rest (a settled line keeps round-off motions of order
  !> 1e-9 m/s whose ratios in (31)-(32) mean nothing).
  real(dp), parameter :: speed_floor = 1.0e-6_dp, rate_floor = 1.0e-6_dp

contains

  !> The nodes first..last of the piece a parted line's equivalent rigid body
  !> describes: the whole line (0..N) while no segment has parted; after a
  !> break, the piece that still holds end a (nodes 0..j-1, j the parted segment
  !> nearest end a) or the one that holds end b (nodes j'..N, j' the parted
  !> segment nearest end b), whichever has more segments (end a's on a tie).
  !> Eqs. (18)-(32) describe one connected line; over two pieces flying apart
  !> they mean nothing (docs/line.md §3).
  pure subroutine whole_piece(model, first, last)
    type(line_model), intent(in) :: model   !< the line
    integer, intent(out) :: first, last     !< node indices
    integer :: j_a, j_b
    first = 0
    last = model%n
    if (model%n_parted == 0) return
    j_a = findloc(model%parted, .true., dim=1)
    j_b = findloc(model%parted, .true., dim=1, back=.true.)
    if (j_a - 1 >= model%n - j_b) then
      last = j_a - 1
    else
      first = j_b
    end if
  end subroutine whole_piece

  !> The equivalent rigid body of the line `model` in the state x(3,0:N),
  !> v(3,0:N) (earth frame): of the whole line, or with `first` and `last` of
  !> the piece between those nodes (whole_piece), as a line of its own.
  function rigidize(model, x, v, first, last) result(q)
    type(line_model), intent(in) :: model   !< the line
    real(dp), intent(in) :: x(:, 0:)        !< node positions [m]
    real(dp), intent(in) :: v(:, 0:)        !< node velocities [m/s]
    integer, intent(in), optional :: first, last  !< the piece's end nodes (default 0, N)
    type(rigid_equivalent) :: q
    integer :: k, n, i, n0
    real(dp) :: dx(3), ell, t(3), epsdot, w_half, rxy, dvb(3), dv(3), vmax, u(3), rk(3), rkb(3)
    real(dp) :: wk(3), wkb(3), ke, ke_t, jnum(3), jgeo(3), wmax, r2, s_lo, w_chord(3), dv_max, r_max, d2(3)

    n0 = 0
    n = model%n
    if (present(first)) n0 = first
    if (present(last)) n = last
    q%first_node = n0
    q%last_node = n
    q%length0 = model%p%length
    if (n - n0 < model%n) q%length0 = (n - n0)*model%l0   ! a piece
    q%line_mass = sum(model%node_mass(n0:n))
    ! (18), (19), (25), (30)
    do k = n0 + 1, n
      dx = x(:, k) - x(:, k-1)
      ell = norm2(dx)
      q%d = q%d + ell
      if (ell <= 1.0e-12_dp*model%l0) cycle
      t = dx/ell
      epsdot = dot_product(t, v(:, k) - v(:, k-1))/model%l0
      q%v_eps = q%v_eps + epsdot*model%l0*t
      s_lo = (k - 1 - n0)*model%l0
      w_half = min(1.0_dp, max(0.0_dp, (0.5_dp*q%length0 - s_lo)/model%l0))
      q%v_o_eps = q%v_o_eps + w_half*epsdot*model%l0*t
    end do
    q%r = x(:, n) - x(:, n0)
    q%d_rigid = norm2(q%r)                                   ! (20)
    q%degenerate = q%d_rigid <= 1.0e-12_dp*q%length0
    if (q%degenerate .or. q%d <= 0.0_dp) then
      q%r_o = 0.0_dp
    else
      q%r_o = q%r*q%d_rigid/(2.0_dp*q%d)                     ! (21)
    end if
    q%centre = x(:, n0) + q%r_o

    ! (22)-(24): Euler angles of the axis
    if (q%degenerate) then
      q%theta = 0.0_dp
      q%phi = 0.0_dp
    else
      rxy = hypot(q%r(1), q%r(2))
      q%theta = atan2(rxy, q%r(3))   ! = acos(r_z/|r|), without acos's loss of digits near 0 and pi
      q%phi = 0.0_dp
      if (rxy > 1.0e-12_dp*q%d_rigid) q%phi = atan2(q%r(1), -q%r(2))
    end if
    q%b = b_rigid(q%theta, q%phi)                            ! (23)
    q%dcm_line = line_frame(q%r, q%degenerate)

    ! (26)-(28): angular velocity from the end velocities
    q%spin_fallback = .false.
    if (.not. q%degenerate) then
      dv = v(:, n) - v(:, n0) - q%v_eps                      ! (28) Delta V
      dvb = matmul(q%b, dv)
      q%omega_body(1) = -dvb(2)/q%d_rigid
      q%omega_body(2) = dvb(1)/q%d_rigid
      if (abs(sin(q%theta)) >= rate_tol) then
        q%omega_body(3) = q%omega_body(2)*cos(q%theta)/sin(q%theta)   ! (27)
      else
        q%omega_body(3) = 0.0_dp
        q%spin_fallback = .true.
      end if
    end if
    q%omega = matmul(transpose(q%b), q%omega_body)

    ! (29)
    q%v_rigid = v(:, n0) + q%v_o_eps + cross(q%omega, q%r_o)

    ! (31) kinetic-energy equivalence; the rotation taken out is the chord's,
    ! omega without the frame spin omega_z of (27) (no motion of the mass)
    w_chord = matmul(transpose(q%b), [q%omega_body(1), q%omega_body(2), 0.0_dp])
    vmax = 0.0_dp
    ke = 0.0_dp
    ke_t = 0.0_dp
    do k = n0, n
      vmax = max(vmax, norm2(v(:, k)))
      ke = ke + model%node_mass(k)*dot_product(v(:, k), v(:, k))
      u = v(:, k) - cross(w_chord, x(:, k) - q%centre)
      ke_t = ke_t + model%node_mass(k)*dot_product(u, u)
    end do
    q%m_fallback = norm2(q%v_rigid) <= max(rate_tol*vmax, speed_floor)
    if (q%m_fallback) then
      q%m_rigid = q%line_mass
      q%m_rigid_eq31 = q%line_mass
    else
      q%m_rigid = ke_t/dot_product(q%v_rigid, q%v_rigid)
      q%m_rigid_eq31 = ke/dot_product(q%v_rigid, q%v_rigid)
    end if

    ! (32) moments of inertia about the body axes through the centre; the rate
    ! scale is the chord's rate or the nodes' largest speed relative to the
    ! centre over their largest distance from it (not a node's own rate, which
    ! a node next to the centre makes arbitrarily large)
    jnum = 0.0_dp
    jgeo = 0.0_dp
    dv_max = 0.0_dp
    r_max = 0.0_dp
    do k = n0, n
      rk = x(:, k) - q%centre
      r2 = dot_product(rk, rk)
      rkb = matmul(q%b, rk)
      ! squared distances from the body axes, as sums of squares (r2 - rkb(i)**2
      ! rounds to -1e-20 about the axis of a straight line)
      d2 = [rkb(2)**2 + rkb(3)**2, rkb(1)**2 + rkb(3)**2, rkb(1)**2 + rkb(2)**2]
      do i = 1, 3
        jgeo(i) = jgeo(i) + model%node_mass(k)*d2(i)
      end do
      r_max = max(r_max, sqrt(r2))
      dv_max = max(dv_max, norm2(v(:, k) - q%v_rigid))
      if (r2 <= (1.0e-12_dp*q%length0)**2) cycle
      wk = cross(rk, v(:, k) - q%v_rigid)/r2
      wkb = matmul(q%b, wk)
      do i = 1, 3
        jnum(i) = jnum(i) + model%node_mass(k)*d2(i)*wkb(i)**2
      end do
    end do
    wmax = norm2(q%omega_body(1:2))
    if (r_max > 0.0_dp) wmax = max(wmax, dv_max/r_max)
    do i = 1, 3
      ! about the chord (i = 3) the rate of (27) is the frame's spin, not a
      ! rotation of the mass: J_z is always the geometric value
      q%j_fallback(i) = i == 3 .or. abs(q%omega_body(i)) <= max(rate_tol*wmax, rate_floor)
      if (q%j_fallback(i)) then
        q%j_rigid(i) = jgeo(i)
      else
        q%j_rigid(i) = jnum(i)/q%omega_body(i)**2
      end if
    end do
  end function rigidize

  !> B_rigid of Eq. (23) (earth -> body).
  pure function b_rigid(theta, phi) result(b)
    real(dp), intent(in) :: theta, phi   !< Euler angles of Eq. (24) [rad]
    real(dp) :: b(3, 3)
    b(1, :) = [cos(phi), sin(phi), 0.0_dp]
    b(2, :) = [-sin(phi)*cos(theta), cos(phi)*cos(theta), sin(theta)]
    b(3, :) = [sin(phi)*sin(theta), -cos(phi)*sin(theta), cos(theta)]
  end function b_rigid

  !> Body-to-earth matrix of the line body in the project's convention: x along
  !> r, y up in the vertical plane through r (earth x when r is vertical), z = x × y.
  pure function line_frame(r, degenerate) result(c)
    real(dp), intent(in) :: r(3)         !< axial vector
    logical, intent(in) :: degenerate    !< no axis
    real(dp) :: c(3, 3), ex(3), ey(3), up(3)
    if (degenerate) then
      c = reshape([1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, 1.0_dp, 0.0_dp, 0.0_dp, 0.0_dp, 1.0_dp], [3, 3])
      return
    end if
    ex = r/norm2(r)
    up = [0.0_dp, 1.0_dp, 0.0_dp]
    if (abs(dot_product(ex, up)) > 1.0_dp - 1.0e-12_dp) up = [1.0_dp, 0.0_dp, 0.0_dp]
    ey = up - dot_product(up, ex)*ex
    ey = ey/norm2(ey)
    c(:, 1) = ex
    c(:, 2) = ey
    c(:, 3) = cross(ex, ey)
  end function line_frame

end module airlaunch_rigidization
