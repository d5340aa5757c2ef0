!> The paper's explicit marching scheme with the end-force iteration
!> (Zheng & Zhang 2018, §2.3, Eqs. (12)–(17), Steps 1–5), as a selectable
!> fixed-step integrator of the same lumped-mass line as the default scheme.
!>
!> What the paper does.  The state Y of every segment is advanced explicitly by
!> Eq. (15), Y(n) = M^-1 (F - K dY/ds) dt + Y(n-1) (forward Euler of Eq. (14)),
!> the velocities along the line follow from the segment-to-segment recursion
!> Eq. (12) started at the end whose motion is known, and the force F(N) that
!> this gives at the far end is compared with the far-end boundary condition
!> F_N (Eq. (16)); Steps 2–5 repeat until |e| = |F_N - F(N)| < e0.
!>
!> What we do and why.  Eq. (13) is garbled in the source, so the spatial
!> difference is re-derived from Eq. (12) and the compatibility Eq. (10) on the
!> lumped-mass discretization of airlaunch_line_model, whose nodal forces
!> already are the discrete M^-1 (F - K dY/ds) of Eq. (14) (tension differences
!> plus loads).  One step of size h from t to t+h:
!>  Step 1  boundary data at t+h: the near ("known") end's position from its
!>          motion; the far end's condition (free: F_N = 0; point mass M:
!>          F_N = M g + D(v) - M a; kinematic: the far node must land on its
!>          prescribed position, the force being the reaction).
!>  Step 2  Eq. (15): every node except the near kinematic one and the far one
!>          gets v^{n+1} = v^n + h f(x^n, v^n)/m (forces at the old level:
!>          explicit, tension-only, with the same loads as the default scheme).
!>  Step 3  Eq. (12), the recursion along the line from the near end: the
!>          segment vector is advanced by the relative velocity of its nodes
!>          (Eq. (10) integrated), dx_k^{n+1} = dx_k^n + h (v_k^{n+1} - v_{k-1}^{n+1}),
!>          k = near+1 .. far, carried as node displacements
!>          d_k = x_k^{n+1} - x_k^n = d_{k-1} + h (v_k^{n+1} - v_{k-1}^{n+1}),
!>          x_k^{n+1} = x_k^n + d_k (the same recursion; the displacements keep
!>          the rounding of large coordinates out of the far-end residual).  The
!>          near kinematic end enters with its discrete velocity
!>          (x_0^{n+1} - x_0^n)/h, so the march reproduces its path exactly.
!>          The far node is advanced with a trial end force F:
!>          v_N^{n+1} = v_N^n + h (f_N + F)/m_N, and the far end's condition gives
!>          the force F(N) it would exert for that motion.
!>  Step 4  e = F - F(N)  (Eq. (16)).
!>  Step 5  Newton on F with the analytic 3x3 Jacobian de/dF until
!>          |e| <= e0 (`force_tol`, or the round-off level of e if larger),
!>          warm-started from the previous step's force.  For kinematic and free
!>          far ends e is affine in F with de/dF = I, so one correction F - e is
!>          exact; for a point mass de/dF = (1 + M/m) I - (dP/dv) h/m (P its
!>          weight and drag; LAPACK solves the 3x3 system).  The residual is
!>          formed from the far node's displacement: a kinematic end gives
!>          e = (m/h^2)(d_N - (x_target - x_N^n)).  (Before, a finite-difference
!>          Jacobian whose trial step moved the far node by ~h^2 delta/m, 3e-13 m
!>          for the paper's line at dt = 3e-4 s, was singular once that fell
!>          below the rounding of the coordinates: a line at y = 10 km stopped
!>          at t = 0.)
!> Stripped of notation this is the semi-implicit (symplectic) Euler method on
!> the lumped-mass semi-discretization, with the far end coupled implicitly
!> through its force: first order in time and conditionally stable,
!> h <= (2/w)(sqrt(1+zeta^2) - zeta) with w = 2c/l0 (line_model%stable_step);
!> a larger step is refused.  Because the interior update is explicit, the far
!> residual is affine in F for free, kinematic and drag-free point-mass ends and
!> Newton converges in one correction; a point mass with quadratic drag takes a
!> few (quadratic convergence: the Jacobian is exact with a fixed air density).  Only the far node depends on F, so each iteration costs O(1), the
!> march O(N).  If the node-0 end is not kinematic but the node-N end is, the
!> march starts from node N.  A point mass at the near (non-kinematic) end is
!> lumped with its node.
module airlaunch_line_marching
  use airlaunch_kinds, only: dp, i8
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_interrupt, only: interrupt_signal, interrupted_error
  use airlaunch_strings, only: str
  use airlaunch_linalg, only: solve_general
  use airlaunch_line_model, only: line_model, marching_diverged, far_end_not_converged, outside_atmosphere_message
  use airlaunch_line_ends, only: line_end, end_point_mass
  use airlaunch_line_scheme, only: line_scheme, line_scheme_options, line_scheme_stats, check_fill_target
  implicit none
  private
  public :: line_marching, new_line_marching

  !> The paper's explicit marching scheme on one line.
  type, extends(line_scheme) :: line_marching
    type(line_model) :: model                 !< the line
    type(line_end) :: ends(2)                 !< end at node 0, end at node N
    real(dp) :: dt = 0.0_dp                   !< largest step [s]
    real(dp) :: force_tol = 0.0_dp            !< e0 [N]
    integer :: max_iter = 20                  !< Newton iterations per step
    integer :: near = 0                       !< node the march starts from
    integer :: far = 0                        !< node of the iterated end force
    integer :: dir = 1                        !< +1 (0 -> N) or -1 (N -> 0)
    real(dp), allocatable :: x(:, :), v(:, :)        !< state at the last step's end tn (3, 0:N)
    real(dp), allocatable :: xn(:, :), vn(:, :)      !< new level (3, 0:N)
    real(dp), allocatable :: xp(:, :), vp(:, :)      !< state at the last step's start tp (3, 0:N)
    real(dp) :: tn = 0.0_dp, tp = 0.0_dp      !< end and start of the last step [s]
    !> a step ends here (the owner's next sample of a body end, set_body_motion):
    !> the end's motion is known up to it only; huge = none
    real(dp) :: t_stop = huge(1.0_dp)
    real(dp), allocatable :: f(:, :), tension(:)     !< node forces, tensions
    real(dp), allocatable :: inv_mass(:)             !< 1/m (near point mass lumped)
    real(dp) :: far_force(3) = 0.0_dp         !< converged force of the far end on the far node [N]
    real(dp) :: t_new = 0.0_dp                !< the step's end t+h [s]
    real(dp) :: far_mass = 0.0_dp             !< point-mass far end: its mass at t+h, apparent mass included [kg]
    real(dp) :: v_prev(3) = 0.0_dp            !< march velocity of the node before the far one
    real(dp) :: d_prev(3) = 0.0_dp            !< march displacement x^(n+1) - x^n of that node [m]
    real(dp) :: x_target(3) = 0.0_dp          !< kinematic far end: position at t+h
    real(dp) :: d_target(3) = 0.0_dp          !< kinematic far end: its displacement over the step [m]
    integer(i8) :: n_steps = 0, n_iter = 0, n_forces = 0
  contains
    procedure :: advance => marching_advance
    procedure :: step => marching_step
    procedure :: get_state => marching_get_state
    procedure :: stats => marching_stats
    procedure :: set_body_motion => marching_set_body_motion
    procedure :: set_stop_time => marching_set_stop_time
    procedure :: set_fill_time => marching_set_fill_time
    procedure :: free => marching_free
  end type line_marching

contains

  !> Create the marching scheme from the initial node state x0, v0 at time t0.
  !> A step above the stability limit is an error.
  subroutine new_line_marching(scheme, model, end_a, end_b, x0, v0, t0, opts, error)
    type(line_marching), intent(inout) :: scheme            !< the scheme (re-initialised)
    type(line_model), intent(in) :: model                   !< the line
    type(line_end), intent(in) :: end_a, end_b              !< ends at node 0 and node N
    real(dp), intent(in) :: x0(:, 0:), v0(:, 0:)            !< initial node state
    real(dp), intent(in) :: t0                              !< initial time [s]
    type(line_scheme_options), intent(in) :: opts           !< dt, force_tol, max_iterations
    type(error_type), allocatable, intent(inout) :: error   !< set on bad input
    integer :: n
    real(dp) :: h_max
    n = model%n
    if (model%mass_coupling > 0.0_dp) then
      call fatal_error(error, "line: mass = '" // trim(model%p%mass) // "' is not allowed with scheme = " // &
        "'marching': the paper's explicit marching needs the lumped (diagonal) mass; use mass = 'lumped'")
      return
    end if
    h_max = model%stable_step()
    if (opts%dt > h_max) then
      call fatal_error(error, "line_scene: dt = " // str(opts%dt) // " s is not allowed for the marching " // &
        "scheme: above its stability limit " // str(h_max) // " s (2/w (sqrt(1+zeta^2) - zeta), w = 2c/l0, " // &
        "c = " // str(model%wave_speed()) // " m/s, l0 = " // str(model%l0) // " m); use dt <= that")
      return
    end if
    call scheme%free()
    scheme%model = model
    scheme%ends = [end_a, end_b]
    scheme%dt = opts%dt
    scheme%force_tol = opts%force_tol
    scheme%max_iter = opts%max_iterations
    scheme%t = t0
    if (.not. end_a%is_kinematic() .and. end_b%is_kinematic()) then
      scheme%near = n; scheme%far = 0; scheme%dir = -1
    else
      scheme%near = 0; scheme%far = n; scheme%dir = 1
    end if
    allocate(scheme%x(3, 0:n), scheme%v(3, 0:n), scheme%xn(3, 0:n), scheme%vn(3, 0:n), &
      scheme%xp(3, 0:n), scheme%vp(3, 0:n), scheme%f(3, 0:n), scheme%tension(n), scheme%inv_mass(0:n))
    scheme%x = x0
    scheme%v = v0
    scheme%xn = x0
    scheme%vn = v0
    scheme%xp = x0
    scheme%vp = v0
    scheme%tn = t0
    scheme%tp = t0
    scheme%inv_mass = 1.0_dp/model%node_mass
    associate (e => scheme%ends(near_end(scheme)))
      if (e%kind == end_point_mass) scheme%inv_mass(scheme%near) = &
        1.0_dp/(model%node_mass(scheme%near) + e%mass)
    end associate
    scheme%far_force = 0.0_dp
    if (opts%peak_tension) call scheme%start_peak(opts%rtol)
  end subroutine new_line_marching

  !> Index (1 or 2) of the end at the near node.
  pure integer function near_end(self)
    type(line_marching), intent(in) :: self
    near_end = merge(1, 2, self%near == 0)
  end function near_end

  !> Index (1 or 2) of the end at the far node.
  pure integer function far_end(self)
    type(line_marching), intent(in) :: self
    far_end = merge(2, 1, self%near == 0)
  end function far_end

  !> March to t_out: steps of dt while they end before it; the state at t_out
  !> (get_state) is then the last step's linear interpolant, so the steps do
  !> not depend on the output times.  A step is cut to end on the owner's
  !> next body-end sample (t_stop).
  subroutine marching_advance(self, t_out, error)
    class(line_marching), intent(inout) :: self            !< scheme
    real(dp), intent(in) :: t_out                          !< output time [s]
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    real(dp) :: eps, h
    if (t_out <= self%t) return
    eps = 1.0e-12_dp*max(1.0_dp, abs(t_out))
    do while (self%tn < t_out - eps)
      if (interrupt_signal() /= 0) then
        ! a caught SIGINT or SIGTERM: the run ends here, its output so far kept
        call interrupted_error(error, interrupt_signal(), self%tn)
        return
      end if
      h = self%dt
      if (self%t_stop > self%tn + eps) h = min(h, self%t_stop - self%tn)
      call self%step(h, error)
      if (allocated(error)) return
      if (abs(self%tn - self%t_stop) <= eps) self%tn = self%t_stop
    end do
    self%t = t_out
  end subroutine marching_advance

  !> One step of size h (Steps 1–5 of the paper, see the module header).
  subroutine marching_step(self, h, error)
    class(line_marching), intent(inout) :: self            !< scheme
    real(dp), intent(in) :: h                              !< step [s]
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    integer :: k, st, it, fe, ne, k_peak
    real(dp) :: t1, vm_near(3), v_exact(3), force(3), e(3), jac(3, 3), rhs(3, 1), e_floor
    real(dp) :: x_far(3), v_far(3), d_far(3), dummy(3)

    t1 = self%tn + h
    ne = near_end(self)
    fe = far_end(self)
    self%t_new = t1
    ! a canopy end's inertia at the step's start (near, explicit) and end (far,
    ! implicit in Eq. (16)): its mass with the apparent mass of the moment
    associate (en => self%ends(ne))
      if (en%canopy_end) self%inv_mass(self%near) = 1.0_dp/(self%model%node_mass(self%near) + en%mass + &
        en%apparent_mass(self%tn, self%x(:, self%near), self%model%p%air, self%model%p%air_density))
    end associate
    associate (en => self%ends(fe))
      self%far_mass = en%mass + en%apparent_mass(t1, self%x(:, self%far), self%model%p%air, &
        self%model%p%air_density)
    end associate
    ! forces at the old level (explicit right-hand side of Eq. (15))
    k = self%model%node_outside_atmosphere(self%x)
    if (k >= 0) then
      call fatal_error(error, "line (marching): at t = " // str(self%tn) // " s " // &
        outside_atmosphere_message(self%x, k))
      return
    end if
    call self%model%forces(self%x, self%v, self%f, self%tension, st)
    self%n_forces = self%n_forces + 1
    if (st /= 0) then
      call marching_diverged(self%tn, error)
      return
    end if
    ! the peak tension over the steps (the scheme's resolution: no interpolant)
    if (associated(self%peak)) then
      k_peak = maxloc(self%tension, 1)
      call self%peak(1)%offer(self%tn, self%tension(k_peak))
      call self%note_peak_segment(self%tension(k_peak), k_peak)
    end if
    if (self%ends(ne)%kind == end_point_mass) self%f(:, self%near) = self%f(:, self%near) + &
      point_load(self, ne, self%tn, self%x(:, self%near), self%v(:, self%near))

    ! Step 2, Eq. (15): explicit velocity update of all nodes but the far one
    do k = 0, self%model%n
      if (k == self%far) cycle
      if (k == self%near .and. self%ends(ne)%is_kinematic()) cycle
      self%vn(:, k) = self%v(:, k) + h*self%f(:, k)*self%inv_mass(k)
    end do

    ! Step 1/3: the known end, then the recursion (12) along the line
    if (self%ends(ne)%is_kinematic()) then
      call self%ends(ne)%motion(t1, self%xn(:, self%near), v_exact)
      vm_near = (self%xn(:, self%near) - self%x(:, self%near))/h
      self%vn(:, self%near) = v_exact
    else
      self%xn(:, self%near) = self%x(:, self%near) + h*self%vn(:, self%near)
      vm_near = self%vn(:, self%near)
    end if
    self%v_prev = vm_near
    ! the march carries displacements d_k = x_k^(n+1) - x_k^n (Eq. (12) with
    ! Eq. (10): d_k = d_(k-1) + h (v_k^(n+1) - v_(k-1)^(n+1))), not positions, so
    ! that the rounding of large coordinates (a line at 10 km) does not enter
    self%d_prev = self%xn(:, self%near) - self%x(:, self%near)
    k = self%near + self%dir
    do while (k /= self%far)
      self%d_prev = self%d_prev + h*(self%vn(:, k) - self%v_prev)
      self%xn(:, k) = self%x(:, k) + self%d_prev
      self%v_prev = self%vn(:, k)
      k = k + self%dir
    end do
    if (self%ends(fe)%is_kinematic()) then
      call self%ends(fe)%motion(t1, self%x_target, dummy)
      self%d_target = self%x_target - self%x(:, self%far)
    end if

    ! Steps 3-5: Newton on the far-end force, Eq. (16), with its analytic
    ! Jacobian (far_jacobian: exact; the identity for kinematic and free ends)
    force = self%far_force
    call far_residual(self, h, force, e, x_far, v_far, d_far)
    it = 0
    do
      e_floor = residual_floor(self, h, force, d_far, v_far)
      if (norm2(e) <= max(self%force_tol, e_floor)) exit
      if (it >= self%max_iter) then
        call far_end_not_converged(t1, norm2(e), self%force_tol, it, error)
        return
      end if
      rhs(:, 1) = -e
      if (self%ends(fe)%kind == end_point_mass) then
        jac = far_jacobian(self, h, x_far, v_far)
        call solve_general(jac, rhs, error, "line (marching): far-end force Jacobian", estimate_condition=.false.)
        if (allocated(error)) return
      end if
      force = force + rhs(:, 1)
      call far_residual(self, h, force, e, x_far, v_far, d_far)
      it = it + 1
    end do
    self%n_iter = self%n_iter + it
    self%far_force = force
    self%xn(:, self%far) = x_far
    self%vn(:, self%far) = v_far
    if (self%ends(fe)%is_kinematic()) then
      call self%ends(fe)%motion(t1, self%xn(:, self%far), self%vn(:, self%far))
    end if
    ! the new level becomes the state, the old one the step's start (xp, vp),
    ! and that storage the next new level: the buffers rotate, nothing is copied
    call rotate(self%xp, self%x, self%xn)
    call rotate(self%vp, self%v, self%vn)
    self%tp = self%tn
    self%tn = t1
    self%n_steps = self%n_steps + 1
  end subroutine marching_step

  !> previous <- current <- new <- previous (descriptors only: no data is copied).
  subroutine rotate(previous, current, new)
    real(dp), allocatable, intent(inout) :: previous(:, :), current(:, :), new(:, :)
    real(dp), allocatable :: spare(:, :)
    call move_alloc(previous, spare)
    call move_alloc(current, previous)
    call move_alloc(new, current)
    call move_alloc(spare, new)
  end subroutine rotate

  !> Far node advanced with the trial end force `force`, and the residual
  !> e = F - F(N) of Eq. (16) of its end condition, formed from the far node's
  !> displacement d_far = x_far - x^n (the positions' rounding stays out).
  subroutine far_residual(self, h, force, e, x_far, v_far, d_far)
    type(line_marching), intent(in) :: self   !< scheme (after the march)
    real(dp), intent(in) :: h                 !< step [s]
    real(dp), intent(in) :: force(3)          !< trial force F of the end on the far node [N]
    real(dp), intent(out) :: e(3)             !< residual [N]
    real(dp), intent(out) :: x_far(3), v_far(3)  !< far node at t+h
    real(dp), intent(out) :: d_far(3)         !< its displacement over the step [m]
    integer :: kf, fe
    kf = self%far
    fe = far_end(self)
    v_far = self%v(:, kf) + h*(self%f(:, kf) + force)*self%inv_mass(kf)
    d_far = self%d_prev + h*(v_far - self%v_prev)
    x_far = self%x(:, kf) + d_far
    associate (en => self%ends(fe))
      if (en%is_kinematic()) then
        ! F - F(N), F(N) = F + (x_target - x_far) m/h^2 the reaction that puts
        ! the far node on its prescribed position: affine in F, de/dF = I
        e = (d_far - self%d_target)/(h*h*self%inv_mass(kf))
      else if (en%kind == end_point_mass) then
        ! Newton's law of the end mass with the backward-difference acceleration
        e = force - point_load(self, fe, self%t_new, x_far, v_far) + self%far_mass*(v_far - self%v(:, kf))/h
      else
        e = force   ! free end: no force, de/dF = I
      end if
    end associate
  end subroutine far_residual

  !> de/dF of far_residual for a point-mass far end:
  !>   I + (M/m) I - (dP/dv) h/m - (dP/dx) h^2/m,
  !> m the far node's mass, P the end's weight and drag; dP/dv is the drag's
  !> derivative (line_end%external_load_dv); dP/dx (the ISA density's change
  !> with altitude over one step) is left out: exact with a fixed air_density,
  !> a relative error of ~1e-4 h |v| otherwise, which Newton absorbs.
  function far_jacobian(self, h, x_far, v_far) result(jac)
    type(line_marching), intent(in) :: self     !< scheme
    real(dp), intent(in) :: h                   !< step [s]
    real(dp), intent(in) :: x_far(3), v_far(3)  !< far node at t+h
    real(dp) :: jac(3, 3)
    integer :: fe, i
    real(dp) :: hm
    fe = far_end(self)
    hm = h*self%inv_mass(self%far)
    jac = -hm*self%ends(fe)%external_load_dv(self%t_new, x_far, v_far, self%model%p%air, self%model%p%wind, &
      self%model%p%air_density)
    do i = 1, 3
      jac(i, i) = jac(i, i) + 1.0_dp + self%far_mass*self%inv_mass(self%far)
    end do
  end function far_jacobian

  !> Round-off level of the far-end residual (64 eps times the size of the
  !> terms that cancel in it), so that e0 below it cannot stall the iteration.
  real(dp) function residual_floor(self, h, force, d_far, v_far) result(floor)
    type(line_marching), intent(in) :: self       !< scheme
    real(dp), intent(in) :: h                     !< step [s]
    real(dp), intent(in) :: force(3)              !< current force [N]
    real(dp), intent(in) :: d_far(3), v_far(3)    !< far node's displacement and velocity at t+h
    real(dp) :: m_far, size
    integer :: fe
    fe = far_end(self)
    m_far = 1.0_dp/self%inv_mass(self%far)
    size = norm2(force) + norm2(self%f(:, self%far))
    if (self%ends(fe)%is_kinematic()) then
      ! (m/h^2)(d_far - d_target): displacements cancel, and the velocities in d_far
      size = size + m_far*(norm2(self%d_target) + norm2(d_far))/h**2 + &
        m_far*(norm2(self%v(:, self%far)) + norm2(self%v_prev))/h
    else if (self%ends(fe)%kind == end_point_mass) then
      ! M (v_far - v)/h: velocities cancel
      size = size + (self%far_mass + m_far)*norm2(v_far)/h
    end if
    floor = 64*epsilon(1.0_dp)*size
  end function residual_floor

  !> Weight and drag of a point-mass end at time t.
  function point_load(self, which, t, x, v) result(f)
    type(line_marching), intent(in) :: self   !< scheme
    integer, intent(in) :: which              !< end index
    real(dp), intent(in) :: t                 !< time [s]
    real(dp), intent(in) :: x(3), v(3)        !< end position, velocity
    real(dp) :: f(3)
    f = self%ends(which)%external_load(t, x, v, self%model%p%gravity, self%model%p%air, &
      self%model%p%wind, self%model%p%air_density)
  end function point_load

  !> Node state at the current time self%t: the last step's end, or its linear
  !> interpolant inside it (kinematic ends on their own motion).
  subroutine marching_get_state(self, x, v)
    class(line_marching), intent(inout) :: self   !< scheme
    real(dp), intent(out) :: x(:, 0:), v(:, 0:)
    real(dp) :: s
    integer :: e, k
    if (self%t == self%tn .or. self%tn == self%tp) then
      x = self%x
      v = self%v
      return
    end if
    s = (self%t - self%tp)/(self%tn - self%tp)
    x = self%xp + s*(self%x - self%xp)
    v = self%vp + s*(self%v - self%vp)
    do e = 1, 2
      k = merge(0, self%model%n, e == 1)
      if (self%ends(e)%is_kinematic()) call self%ends(e)%motion(self%t, x(:, k), v(:, k))
    end do
  end subroutine marching_get_state

  !> Work counters.
  function marching_stats(self) result(s)
    class(line_marching), intent(in) :: self   !< scheme
    type(line_scheme_stats) :: s
    s%steps = self%n_steps
    s%rhs_evals = self%n_forces
    s%iterations = self%n_iter
  end function marching_stats

  !> Make end `which` a body end moved by the owner's samples.
  subroutine marching_set_body_motion(self, which, t1, x1, v1, t2, x2, v2, error)
    class(line_marching), intent(inout) :: self            !< scheme
    integer, intent(in) :: which                           !< 1 = node 0, 2 = node N
    real(dp), intent(in) :: t1, t2, x1(3), v1(3), x2(3), v2(3)
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    if (which < 1 .or. which > 2) then
      call fatal_error(error, "line: end index " // str(which) // " is not allowed: 1 (node 0) or 2 (node N)")
      return
    end if
    if (.not. self%ends(which)%is_kinematic()) then
      call fatal_error(error, "line: end " // str(which) // " is not kinematic: a body end must be " // &
        "declared kinematic (body) when the scheme is built")
      return
    end if
    call self%ends(which)%set_body_motion(t1, x1, v1, t2, x2, v2)
    self%t_stop = t2
  end subroutine marching_set_body_motion

  !> End a step on t_stop (the steps are dt, one shorter step lands on it).
  subroutine marching_set_stop_time(self, t_stop, error)
    class(line_marching), intent(inout) :: self            !< scheme
    real(dp), intent(in) :: t_stop                         !< stop time [s]
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    if (.not. (t_stop > self%tn)) then
      call fatal_error(error, "line (marching): stop time " // str(t_stop) // " s is not after t = " // &
        str(self%tn) // " s")
      return
    end if
    self%t_stop = t_stop
  end subroutine marching_set_stop_time

  !> The canopy at end `which` deploys now and fills in `fill_time` (its mass
  !> and drag are taken per step: nothing else to restart).
  subroutine marching_set_fill_time(self, which, fill_time, error)
    class(line_marching), intent(inout) :: self            !< scheme
    integer, intent(in) :: which                           !< 1 = node 0, 2 = node N
    real(dp), intent(in) :: fill_time                      !< filling time [s]
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    call check_fill_target(self%ends, which, fill_time, error)
    if (allocated(error)) return
    self%ends(which)%canopy%fill_time = fill_time
  end subroutine marching_set_fill_time

  !> Release the work arrays.
  subroutine marching_free(self)
    class(line_marching), intent(inout) :: self   !< scheme
    if (allocated(self%x)) deallocate(self%x, self%v, self%xn, self%vn, self%xp, self%vp, self%f, self%tension, &
      self%inv_mass)
    self%n_steps = 0; self%n_iter = 0; self%n_forces = 0
    call self%release_peak()
  end subroutine marching_free
end module airlaunch_line_marching
