!> CVODE (SUNDIALS 6) behind one type that owns the context, the memory, the
!> vectors, the matrix and the solvers (STYLE.md habit 7).  The system is any
!> extension of `ode_system`; it reaches the C callbacks through user_data, so
!> there is no module state and many solvers can run side by side.
!>
!> Error output of CVODE is routed to a handler that keeps the last message for
!> the error value instead of printing it (library code never prints).
module airlaunch_cvode
  use, intrinsic :: iso_c_binding
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_ode, only: ode_system, band_view, node_blocks, rhs_ok, rhs_fatal
  use airlaunch_interrupt, only: interrupt_signal, interrupted_error, wall_clock
  use fsundials_context_mod
  use fsundials_nvector_mod
  use fsundials_matrix_mod
  use fsundials_linearsolver_mod
  use fsundials_nonlinearsolver_mod
  use fnvector_serial_mod
  use fsunmatrix_dense_mod
  use fsunmatrix_band_mod
  use fsunlinsol_dense_mod
  use fsunlinsol_band_mod
  use fsunnonlinsol_fixedpoint_mod
  use fcvode_mod
  use airlaunch_lapack_band, only: new_lapack_band_solver, new_second_order_band_solver, second_order_band_ok, &
    new_position_reduced_solver, partners_ok, new_lapack_dense_solver, &
    band_data, use_node_blocks
  implicit none
  private
  public :: cvode_options, cvode_solver, cvode_stats, add_stats, step_polynomial, step_observer

  !> How to integrate.
  type :: cvode_options
    character(len=16) :: method = "bdf"          !< "bdf" (stiff) or "adams"
    !> "dense", "band" (both LAPACK), "second_order_band" (LAPACK on the velocity system of
    !> [x, v]-per-node states), "position_reduced_band" (LAPACK on the band system without
    !> the positions x' = v; airlaunch_lapack_band), "sundials_dense", "sundials_band"
    !> (SUNDIALS' own LU, for comparison) or "none" (fixed point)
    character(len=24) :: linear_solver = "dense"
    integer :: upper_bandwidth = 0               !< band solver: upper half-bandwidth
    integer :: lower_bandwidth = 0               !< band solver: lower half-bandwidth
    real(dp) :: rtol = 1.0e-6_dp                 !< relative tolerance
    real(dp) :: atol = 1.0e-8_dp                 !< scalar absolute tolerance
    real(dp), allocatable :: atol_vector(:)      !< per-component absolute tolerance
    real(dp) :: max_step = 0.0_dp                !< largest step [s]; 0 = unlimited
    real(dp) :: initial_step = 0.0_dp            !< first step [s]; 0 = CVODE's estimate
    !> end of the run [s]: CVODE's estimate of the first step after each (re)start
    !> looks as far as this instead of the first output time, so that the steps
    !> do not depend on the output times; <= the start time: the first output time
    real(dp) :: t_final = 0.0_dp
    integer :: max_order = 0                     !< 0 = CVODE's default (5 BDF, 12 Adams)
    !> steps allowed between two outputs; <= 0 = no limit (not CVODE's default 500)
    integer :: max_num_steps = 200000
    !> steps allowed over the solver's life, re-initialisations included (a run's
    !> budget: `&run max_steps`); 0 = no limit
    integer :: max_total_steps = 0
    !> the run's wall-time budget [s] (`&run max_wall_time`); 0 = no limit
    real(dp) :: max_wall_time = 0.0_dp
    !> wall_clock() at which that budget is spent, the same for every integrator
    !> of the run (its owner sets it at the run's start); 0: max_wall_time from init
    real(dp) :: wall_deadline = 0.0_dp
    logical :: stability_limit_detection = .false. !< BDF order reduction near the imaginary axis
    !> Newton's convergence test: the iteration stops when its estimated error is
    !> below this fraction of the error tolerance (CVodeSetNonlinConvCoef); 0 = CVODE's 0.1
    real(dp) :: newton_coefficient = 0.0_dp
    !> with a band solver, use the system's analytic Jacobian if it has one
    !> (`ode_system%has_jacobian`); otherwise CVODE's difference quotients
    logical :: analytic_jacobian = .true.
  end type cvode_options

  !> Counters of the integration.
  type :: cvode_stats
    integer(c_long) :: steps = 0, rhs_evals = 0, jac_evals = 0, lin_setups = 0
    integer(c_long) :: err_test_fails = 0, nonlin_iters = 0, nonlin_fails = 0, root_evals = 0
  end type cvode_stats

  !> CVODE's interpolant over one internal step, y(t) = sum_j c(:, j) (t - tn)^j
  !> (j = 0..order; CVodeGetDky's derivatives at the step's end tn over j!), so
  !> that it can be evaluated after the solver has moved on.  The one shown to
  !> a step_observer holds its value at tn only (`known` = 0): the observer
  !> reads the other coefficients off CVODE (`fill`) while it is shown the
  !> step (CVODE's next step overwrites them), if it needs them (each is a
  !> CVodeGetDky).
  type :: step_polynomial
    real(dp) :: tn = 0.0_dp                    !< the step's end [s]
    integer :: order = 0                       !< its degree
    real(dp), allocatable :: c(:, :)           !< (n, 0:max order) Taylor coefficients at tn
    !> c(:, 0:known) are set (known >= order: all); the others are CVODE's (`fill`)
    integer :: known = huge(1)
    type(c_ptr) :: mem = c_null_ptr                    !< the CVODE memory that has them
    type(N_Vector), pointer :: nv_work => null()       !< CVodeGetDky's output vector ...
    real(c_double), pointer :: work(:) => null()       !< ... and its data
  contains
    procedure :: eval => polynomial_eval
    procedure :: copy => polynomial_copy
    procedure :: fill => polynomial_fill
    procedure :: whole => polynomial_whole
  end type step_polynomial

  !> Sees the solution stretch by stretch: `advance` calls `observe` after
  !> every internal step CVODE has made final (and the rest of a step an event
  !> interrupted), in time order, whatever the output times.
  type, abstract :: step_observer
  contains
    procedure(observe_interface), deferred :: observe
  end type step_observer

  abstract interface
    !> The solution on [t_start, t_end] is `poly` (CVODE's: its value at tn;
    !> a copy reads the other coefficients off CVODE with fill(from=poly),
    !> during this call only).  `restart`: the first
    !> stretch since a (re)start (the state at t_start may differ from the
    !> end of the stretch before).  `last`: the stretch ends at an event or a
    !> stop time (the caller may change the state or the system there) or at
    !> the end of the run (cvode_options%t_final; the stretch is cut there).
    subroutine observe_interface(self, poly, t_start, t_end, restart, last)
      import :: step_observer, step_polynomial, dp
      implicit none
      class(step_observer), intent(inout) :: self
      type(step_polynomial), intent(in) :: poly
      real(dp), intent(in) :: t_start, t_end
      logical, intent(in) :: restart, last
    end subroutine observe_interface
  end interface

  !> What the C callbacks need; lives on the heap so its address is stable.
  type :: callback_data
    class(ode_system), pointer :: sys => null()
    integer :: nroots = 0
    integer(c_int), allocatable :: root_info(:)   !< (max(1, nroots)) CVodeGetRootInfo, sized by set_roots
    character(len=:), allocatable :: last_message
    !> the Jacobian as node blocks, shared with the velocity-reduced solver
    !> (second_order_band with a system that has node_jacobian)
    type(node_blocks), pointer :: blocks => null()
  end type callback_data

  !> A CVODE integrator bound to one system.
  type :: cvode_solver
    type(c_ptr) :: ctx = c_null_ptr
    type(c_ptr) :: mem = c_null_ptr
    type(N_Vector), pointer :: nv_y => null(), nv_atol => null()
    type(SUNMatrix), pointer :: mat => null()
    type(SUNLinearSolver), pointer :: ls => null()
    type(SUNNonlinearSolver), pointer :: nls => null()
    !> The state, shared with CVODE's N_Vector (heap, stable address).
    real(c_double), pointer :: y(:) => null()
    type(callback_data), pointer :: cb => null()
    real(dp) :: t = 0.0_dp   !< time of `y`
    !> counters before the last re-initialisation (CVODE restarts its own)
    type(cvode_stats) :: stats_before
    !> no step taken since the last (re)start: the next one is the first (and
    !> after a re-initialisation CVODE's linear-solver counters still hold the
    !> previous segment's: they restart at the next step)
    logical :: fresh = .false.
    !> the last CVODE return was an event inside a step: the rest of that step
    !> has not been searched for further events yet
    logical :: after_root = .false.
    !> an event CVODE located after the output time it was stepping towards, to
    !> be reported by the next `advance` (its time, state and CVodeGetRootInfo)
    logical :: root_pending = .false.
    real(dp) :: root_t = 0.0_dp
    !> the stop time CVODE holds (set_stop_time; CVODE clears it when it stops
    !> there); huge = none
    real(dp) :: stop_time = huge(1.0_dp)
    real(dp), allocatable :: root_y(:)
    integer(c_int), allocatable :: root_which(:)
    real(dp) :: t_final = 0.0_dp           !< cvode_options%t_final
    integer(c_long) :: max_total = 0       !< cvode_options%max_total_steps
    real(dp) :: max_wall = 0.0_dp          !< cvode_options%max_wall_time [s]
    real(dp) :: wall_deadline = 0.0_dp     !< wall_clock() when it is spent (0: no limit) [s]
    logical :: out_of_time = .false.       !< the last failure: the wall-time budget spent
    integer(c_long) :: max_interval = 0    !< cvode_options%max_num_steps
    ! --- the stretches shown to a step_observer
    type(step_polynomial) :: poly          !< the interpolant of the last step
    real(c_double), pointer :: work(:) => null()   !< CVodeGetDky's output (heap, shared with nv_work)
    type(N_Vector), pointer :: nv_work => null()
    real(dp) :: t_seen = 0.0_dp            !< end of the last stretch shown (or the (re)start time)
    logical :: seen_restart = .true.       !< no stretch shown since the last (re)start
  contains
    procedure :: init => solver_init
    procedure :: steps_taken => solver_steps_taken
    procedure :: advance => solver_advance
    procedure :: reinit => solver_reinit
    procedure :: set_roots => solver_set_roots
    procedure :: set_stop_time => solver_set_stop_time
    procedure :: set_max_step => solver_set_max_step
    procedure :: stats => solver_stats
    procedure :: free => solver_free
  end type cvode_solver

contains

  !> Create the integrator for `sys` from state y0 at time t0.  On failure
  !> everything allocated so far is released (the solver is as after `free`).
  subroutine solver_init(self, sys, t0, y0, opts, error)
    class(cvode_solver), intent(inout) :: self            !< solver (re-initialised)
    class(ode_system), target, intent(inout) :: sys       !< the system (must outlive the solver)
    real(dp), intent(in) :: t0                            !< initial time [s]
    real(dp), intent(in) :: y0(:)                         !< initial state
    type(cvode_options), intent(in) :: opts               !< method and tolerances
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    type(error_type), allocatable :: init_error
    call init_parts(self, sys, t0, y0, opts, init_error)
    if (allocated(init_error)) then
      call self%free()
      call move_alloc(init_error, error)
    end if
  end subroutine solver_init

  !> solver_init's work; returns at the first failure (solver_init frees).
  subroutine init_parts(self, sys, t0, y0, opts, error)
    class(cvode_solver), intent(inout) :: self            !< solver (re-initialised)
    class(ode_system), target, intent(inout) :: sys       !< the system (must outlive the solver)
    real(dp), intent(in) :: t0                            !< initial time [s]
    real(dp), intent(in) :: y0(:)                         !< initial state
    type(cvode_options), intent(in) :: opts               !< method and tolerances
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    integer(c_int) :: ierr, lmm
    integer(c_long) :: neq

    call self%free()
    neq = int(size(y0), c_long)
    if (neq < 1) then
      call fatal_error(error, "CVODE: the system has no state")
      return
    end if
    allocate(self%y(neq))
    allocate(self%root_y(neq))
    self%y = y0
    self%t = t0
    allocate(self%cb)
    self%cb%sys => sys

    ierr = FSUNContext_Create(c_null_ptr, self%ctx)
    if (ierr /= 0) then
      call fatal_error(error, "CVODE: cannot create the SUNDIALS context")
      return
    end if
    self%nv_y => FN_VMake_Serial(neq, self%y, self%ctx)
    allocate(self%work(neq))
    self%nv_work => FN_VMake_Serial(neq, self%work, self%ctx)
    ! the interpolant's degree is at most the method's largest order
    allocate(self%poly%c(neq, 0:merge(12, 5, opts%method == "adams")))
    self%poly%c = 0.0_dp
    select case (opts%method)
    case ("bdf")
      lmm = CV_BDF
    case ("adams")
      lmm = CV_ADAMS
    case default
      call fatal_error(error, "CVODE: unknown method '" // trim(opts%method) // "' (allowed: bdf, adams)")
      return
    end select
    self%mem = FCVodeCreate(lmm, self%ctx)
    if (.not. c_associated(self%mem)) then
      call fatal_error(error, "CVODE: FCVodeCreate failed")
      return
    end if
    ierr = FCVodeSetErrHandlerFn(self%mem, c_funloc(error_handler), c_loc(self%cb))
    if (failed(ierr, "cannot install the error handler", error)) return
    ierr = FCVodeInit(self%mem, c_funloc(rhs_callback), real(t0, c_double), self%nv_y)
    if (failed(ierr, "FCVodeInit failed", error)) return
    ierr = FCVodeSetUserData(self%mem, c_loc(self%cb))
    if (failed(ierr, "cannot set the user data", error)) return
    call set_tolerances(self, opts, neq, error)
    if (allocated(error)) return
    call attach_linear_solver(self, sys, opts, neq, error)
    if (allocated(error)) return
    call apply_options(self, sys, opts, lmm, error)
    if (allocated(error)) return
    call self%set_roots(sys%nroots(), error)
  end subroutine init_parts

  !> The relative and absolute tolerances (a scalar atol, or one per state).
  subroutine set_tolerances(self, opts, neq, error)
    class(cvode_solver), intent(inout) :: self            !< solver being initialised
    type(cvode_options), intent(in) :: opts               !< method and tolerances
    integer(c_long), intent(in) :: neq                    !< number of states
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    integer(c_int) :: ierr
    real(c_double), pointer :: atol(:)

    if (allocated(opts%atol_vector)) then
      if (size(opts%atol_vector) /= neq) then
        call fatal_error(error, "CVODE: atol_vector has " // str(size(opts%atol_vector)) // &
          " entries for " // str(int(neq)) // " states")
        return
      end if
      self%nv_atol => FN_VNew_Serial(neq, self%ctx)
      atol => FN_VGetArrayPointer(self%nv_atol)
      atol = opts%atol_vector
      ierr = FCVodeSVtolerances(self%mem, real(opts%rtol, c_double), self%nv_atol)
    else
      ierr = FCVodeSStolerances(self%mem, real(opts%rtol, c_double), real(opts%atol, c_double))
    end if
    if (ierr /= 0) then
      call fatal_error(error, "CVODE: tolerances rejected (rtol = " // str(opts%rtol) // ")")
      return
    end if

  end subroutine set_tolerances

  !> The Newton iteration's linear solver (or the fixed-point iteration, "none")
  !> and the system's analytic Jacobian or node blocks where it has them.
  subroutine attach_linear_solver(self, sys, opts, neq, error)
    class(cvode_solver), intent(inout) :: self            !< solver being initialised
    class(ode_system), intent(inout) :: sys               !< the system
    type(cvode_options), intent(in) :: opts               !< method and tolerances
    integer(c_long), intent(in) :: neq                    !< number of states
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    integer(c_int) :: ierr

    select case (opts%linear_solver)
    case ("dense")
      ! dense Newton matrix factored by LAPACK (airlaunch_lapack_band)
      self%mat => FSUNDenseMatrix(neq, neq, self%ctx)
      self%ls => new_lapack_dense_solver(self%mat, self%ctx)
      ierr = FCVodeSetLinearSolver(self%mem, self%ls, self%mat)
    case ("sundials_dense")
      ! SUNDIALS' own dense LU (kept for comparison)
      self%mat => FSUNDenseMatrix(neq, neq, self%ctx)
      self%ls => FSUNLinSol_Dense(self%nv_y, self%mat, self%ctx)
      ierr = FCVodeSetLinearSolver(self%mem, self%ls, self%mat)
    case ("band")
      ! band Newton matrix factored by LAPACK (airlaunch_lapack_band)
      self%mat => FSUNBandMatrix(neq, int(opts%upper_bandwidth, c_long), &
        int(opts%lower_bandwidth, c_long), self%ctx)
      self%ls => new_lapack_band_solver(self%mat, self%ctx)
      ierr = FCVodeSetLinearSolver(self%mem, self%ls, self%mat)
    case ("second_order_band")
      if (.not. second_order_band_ok(int(neq), opts%upper_bandwidth, opts%lower_bandwidth)) then
        call fatal_error(error, "CVODE: second_order_band needs 6 states per node and half-bandwidths " // &
          ">= 8 (upper) and >= 11 (lower); got " // str(int(neq)) // " states, " // &
          str(opts%upper_bandwidth) // "/" // str(opts%lower_bandwidth))
        return
      end if
      ! storage without the ml rows of LU fill-in: this solver factors its own
      ! reduced matrix, and CVODE zeroes and copies the whole storage at every
      ! setup (31 rows -> 20: -4 % instructions in a slack-heavy line run,
      ! docs/line.md section 7; same results)
      self%mat => FSUNBandMatrixStorage(neq, int(opts%upper_bandwidth, c_long), &
        int(opts%lower_bandwidth, c_long), int(opts%upper_bandwidth, c_long), self%ctx)
      self%ls => new_second_order_band_solver(self%mat, self%ctx)
      ierr = FCVodeSetLinearSolver(self%mem, self%ls, self%mat)
    case ("position_reduced_band")
      ! positions with x' = v eliminated from the band system (airlaunch_lapack_band);
      ! CVODE's matrix without the LU fill rows, as for second_order_band
      block
        integer, allocatable :: partner(:)
        allocate(partner(neq))
        call sys%velocity_partners(partner)
        if (.not. partners_ok(partner, opts%upper_bandwidth, opts%lower_bandwidth)) then
          call fatal_error(error, "CVODE: position_reduced_band needs positions whose velocities are states, " // &
            "not positions themselves, within the band (" // str(count(partner /= 0)) // " positions declared)")
          return
        end if
        self%mat => FSUNBandMatrixStorage(neq, int(opts%upper_bandwidth, c_long), &
          int(opts%lower_bandwidth, c_long), int(opts%upper_bandwidth, c_long), self%ctx)
        self%ls => new_position_reduced_solver(self%mat, self%ctx, partner)
      end block
      ierr = FCVodeSetLinearSolver(self%mem, self%ls, self%mat)
    case ("sundials_band")
      ! SUNDIALS' own band LU (kept for comparison in the benchmarks)
      self%mat => FSUNBandMatrix(neq, int(opts%upper_bandwidth, c_long), &
        int(opts%lower_bandwidth, c_long), self%ctx)
      self%ls => FSUNLinSol_Band(self%nv_y, self%mat, self%ctx)
      ierr = FCVodeSetLinearSolver(self%mem, self%ls, self%mat)
    case ("none")
      self%nls => FSUNNonlinSol_FixedPoint(self%nv_y, 0, self%ctx)
      ierr = FCVodeSetNonlinearSolver(self%mem, self%nls)
    case default
      call fatal_error(error, "CVODE: unknown linear solver '" // trim(opts%linear_solver) // &
        "' (allowed: dense, band, second_order_band, position_reduced_band, sundials_dense, sundials_band, none)")
      return
    end select
    if (ierr /= 0) then
      call fatal_error(error, "CVODE: cannot attach the " // trim(opts%linear_solver) // " solver")
      return
    end if
    if (opts%analytic_jacobian .and. opts%linear_solver == "second_order_band" .and. sys%has_node_jacobian()) then
      ! the Newton matrix straight from the system's node blocks: CVODE's linear-
      ! system hook replaces its band Jacobian (zeroed, filled, saved, copied back
      ! and scaled at every setup) and lets the system keep valid blocks
      allocate(self%cb%blocks)
      allocate(self%cb%blocks%ax(3, 3, -1:1, int(neq)/6), self%cb%blocks%av(3, 3, -1:1, int(neq)/6), &
        self%cb%blocks%mass(-1:1, int(neq)/6), source=0.0_dp)
      call use_node_blocks(self%ls, self%cb%blocks)
      ierr = FCVodeSetLinSysFn(self%mem, c_funloc(linsys_callback))
      if (failed(ierr, "cannot install the linear-system function", error)) return
    else if (opts%analytic_jacobian .and. sys%has_jacobian()) then
      select case (opts%linear_solver)
      case ("band", "second_order_band", "position_reduced_band", "sundials_band")
        ierr = FCVodeSetJacFn(self%mem, c_funloc(jac_callback))
        if (failed(ierr, "cannot install the analytic Jacobian", error)) return
      end select
    end if
  end subroutine attach_linear_solver

  !> Step limits, wall-time budget, order, Newton coefficient, projection and
  !> stability-limit detection from the options.
  subroutine apply_options(self, sys, opts, lmm, error)
    class(cvode_solver), intent(inout) :: self            !< solver being initialised
    class(ode_system), intent(in) :: sys                  !< the system
    type(cvode_options), intent(in) :: opts               !< method and tolerances
    integer(c_int), intent(in) :: lmm                     !< CV_BDF or CV_ADAMS
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    integer(c_int) :: ierr

    ! max_num_steps <= 0: no per-output limit.  CVODE itself reads 0 as its
    ! default of 500 and a negative value as no limit, so <= 0 goes in as -1.
    self%max_interval = max(0_c_long, int(opts%max_num_steps, c_long))
    self%max_total = int(max(0, opts%max_total_steps), c_long)
    self%max_wall = max(0.0_dp, opts%max_wall_time)
    self%wall_deadline = 0.0_dp
    if (self%max_wall > 0.0_dp) then
      self%wall_deadline = opts%wall_deadline
      if (.not. self%wall_deadline > 0.0_dp) self%wall_deadline = wall_clock() + self%max_wall
    end if
    self%out_of_time = .false.
    self%stats_before = cvode_stats()
    call forget_steps(self)
    self%stop_time = huge(1.0_dp)
    self%t_final = opts%t_final
    ierr = FCVodeSetMaxNumSteps(self%mem, merge(self%max_interval, -1_c_long, self%max_interval > 0))
    if (failed(ierr, "max_num_steps = " // str(opts%max_num_steps) // " rejected", error)) return
    if (opts%max_step > 0.0_dp) then
      ierr = FCVodeSetMaxStep(self%mem, real(opts%max_step, c_double))
      if (failed(ierr, "max_step = " // str(opts%max_step) // " s rejected", error)) return
    end if
    if (opts%initial_step > 0.0_dp) then
      ierr = FCVodeSetInitStep(self%mem, real(opts%initial_step, c_double))
      if (failed(ierr, "initial_step = " // str(opts%initial_step) // " s rejected", error)) return
    end if
    if (opts%max_order > 0) then
      ierr = FCVodeSetMaxOrd(self%mem, int(opts%max_order, c_int))
      if (failed(ierr, "max_order = " // str(opts%max_order) // " rejected (at most 5 for bdf, 12 for adams)", &
        error)) return
    end if
    if (opts%newton_coefficient > 0.0_dp) then
      ierr = FCVodeSetNonlinConvCoef(self%mem, real(opts%newton_coefficient, c_double))
      if (failed(ierr, "newton_coefficient = " // str(opts%newton_coefficient) // " rejected", error)) return
    end if
    ierr = FCVodeSetMaxHnilWarns(self%mem, -1_c_int)
    if (failed(ierr, "cannot silence the t + h = t warnings", error)) return
    if (sys%has_projection() .and. lmm == CV_BDF) then
      ierr = FCVodeSetProjFn(self%mem, c_funloc(proj_callback))
      if (failed(ierr, "cannot install the projection", error)) return
    end if
    if (opts%stability_limit_detection) then
      ierr = FCVodeSetStabLimDet(self%mem, 1_c_int)
      if (failed(ierr, "cannot switch on stability limit detection", error)) return
    end if
  end subroutine apply_options

  !> True (and `error` set to "CVODE: <what> (flag <ierr>)") if a SUNDIALS call
  !> returned a nonzero flag.
  logical function failed(ierr, what, error)
    integer(c_int), intent(in) :: ierr                    !< the call's flag
    character(len=*), intent(in) :: what                  !< what failed
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    failed = ierr /= 0
    if (failed) call fatal_error(error, "CVODE: " // what // " (flag " // str(int(ierr)) // ")")
  end function failed

  !> Change the number of event functions (0 switches root finding off).
  subroutine solver_set_roots(self, n, error)
    class(cvode_solver), intent(inout) :: self            !< solver
    integer, intent(in) :: n                              !< number of event functions
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    integer(c_int) :: ierr
    self%cb%nroots = n
    if (allocated(self%cb%root_info)) deallocate(self%cb%root_info)
    allocate(self%cb%root_info(max(1, n)))
    if (allocated(self%root_which)) deallocate(self%root_which)
    allocate(self%root_which(max(1, n)), source=0_c_int)
    self%root_pending = .false.
    if (n > 0) then
      ierr = FCVodeRootInit(self%mem, int(n, c_int), c_funloc(root_callback))
      if (ierr == 0) ierr = FCVodeSetNoInactiveRootWarn(self%mem)
    else
      ierr = FCVodeRootInit(self%mem, 0_c_int, c_null_funptr)
    end if
    if (ierr /= 0) call fatal_error(error, "CVODE: root finding set-up failed")
  end subroutine solver_set_roots

  !> Integrate towards tout.  On return self%t and self%y hold the reached
  !> state: tout, or the time of an event (then `event` is true and `which`
  !> holds +-1 for the functions that crossed, with the direction).
  subroutine solver_advance(self, tout, error, event, which, observer)
    class(cvode_solver), intent(inout) :: self            !< solver
    real(dp), intent(in) :: tout                          !< target time [s]
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    logical, intent(out), optional :: event               !< an event stopped the step
    integer, intent(out), optional :: which(:)            !< CVodeGetRootInfo
    !> shown every stretch of the solution the steps of this call make final
    class(step_observer), intent(inout), optional :: observer
    logical :: last
    integer(c_int) :: ierr
    real(c_double) :: tret(1), tn(1), target
    integer(c_long) :: first, limit, taken
    if (present(event)) event = .false.
    if (.not. c_associated(self%mem)) then
      call fatal_error(error, "CVODE: advance called on a solver that is not initialised")
      return
    end if
    ! a message CVODE kept from an earlier call belongs to no failure of this one
    if (allocated(self%cb%last_message)) deallocate(self%cb%last_message)
    ! CVODE steps one step per call (CV_ONE_STEP) and the state at tout is read
    ! off its interpolant: its steps, and the events it locates within them
    ! (each step searched whole), then do not depend on the output times (with
    ! CV_NORMAL the event search stops at tout and the next one resumes there,
    ! which moves the located times at round-off level, and the steps after them)
    if (self%root_pending) then
      if (self%root_t <= tout) then
        self%root_pending = .false.
        self%t = self%root_t
        self%y = self%root_y
        call report_event(self, self%root_which, event, which)
        return
      end if
    end if
    if (self%fresh .and. .not. (tout > self%t)) then
      ! no step since the (re)start: y is the state at self%t (CVODE cannot
      ! interpolate before its first step)
      if (tout < self%t) call fatal_error(error, "CVODE: output time " // str(tout) // &
        " s is behind the solver's t = " // str(self%t) // " s")
      return
    end if
    ierr = FCVodeGetCurrentTime(self%mem, tn)
    if (self%fresh) tn(1) = self%t
    first = self%steps_taken()
    ! steps this call may take: what is left of the budget, and no more than
    ! the per-output limit (max_interval = 0 is none)
    limit = huge(limit)
    if (self%max_interval > 0) limit = self%max_interval
    do while (tn(1) < tout .or. self%after_root)
      ! after an event CVODE first returns the rest of its step (no new step),
      ! unless the event was at the step's end (tn = the event's time, self%t)
      if (.not. self%after_root .or. .not. (tn(1) > self%t)) then
        if (interrupt_signal() /= 0) then
          ! a caught SIGINT or SIGTERM: the run ends here, its output so far kept
          self%t = tn(1)
          call interrupted_error(error, interrupt_signal(), self%t)
          return
        end if
        if (self%wall_deadline > 0.0_dp) then
          if (wall_clock() > self%wall_deadline) then
            self%t = tn(1)
            self%out_of_time = .true.
            call fatal_error(error, failure_message(self, CV_TOO_MUCH_WORK))
            return
          end if
        end if
        taken = self%steps_taken()
        if (taken - first >= limit .or. (self%max_total > 0 .and. taken >= self%max_total)) then
          self%t = tn(1)
          call fatal_error(error, failure_message(self, CV_TOO_MUCH_WORK))
          return
        end if
      end if
      target = tout
      if (self%fresh .and. self%t_final > tout) target = self%t_final
      if (self%fresh .and. target - self%t < 2.0_dp * epsilon(1.0_dp) * max(abs(self%t), abs(target))) then
        ! a (re)start within two rounding units of the target (an event or a
        ! stop time 1 ulp before t_end): CVODE refuses to start there
        ! (CV_TOO_CLOSE) and t cannot resolve a step; the state at tout is the
        ! restart's to round-off in time
        self%t = tout
        return
      end if
      ierr = FCVode(self%mem, target, self%nv_y, tret, CV_ONE_STEP)
      self%fresh = .false.
      self%after_root = ierr == CV_ROOT_RETURN
      if (ierr < 0) then
        self%t = tret(1)
        call fatal_error(error, failure_message(self, ierr))
        if (allocated(self%cb%last_message)) deallocate(self%cb%last_message)
        return
      end if
      if (present(observer)) then
        ! an event or a stop time ends the stretch: the caller may change the
        ! state or the system there
        last = ierr == CV_ROOT_RETURN .or. ierr == CV_TSTOP_RETURN .or. &
          (ierr == CV_SUCCESS .and. tret(1) == self%stop_time)
        call show_stretch(self, observer, tret(1), last)
      end if
      if (ierr == CV_ROOT_RETURN) then
        ierr = FCVodeGetRootInfo(self%mem, self%cb%root_info)
        if (tret(1) <= tout) then
          self%t = tret(1)
          call report_event(self, self%cb%root_info, event, which)
          return
        end if
        ! after tout: report tout first, the event at the next call
        self%root_pending = .true.
        self%root_t = tret(1)
        self%root_y = self%y
        self%root_which = self%cb%root_info
        self%after_root = .false.   ! (the rest of its step is searched when it is reported)
        exit
      end if
      if (ierr == CV_SUCCESS .and. tret(1) == self%stop_time) then
        ! the rest of a step that ended on the stop time, searched after an event
        ! in it: CVODE has not cleared the stop time (it would return it again,
        ! with no step, at the next call): cleared here, and handled as reached
        ierr = clear_stop_time(self)
        ierr = CV_TSTOP_RETURN
      end if
      if (ierr == CV_TSTOP_RETURN) then   ! (CVODE has cleared it)
        self%stop_time = huge(1.0_dp)
        ! at or after tout: the step ended there, tout is read off it below
        if (tret(1) >= tout) exit
        self%t = tret(1)    ! before tout: the caller's stop
        return
      end if
      tn = tret
    end do
    ierr = FCVodeGetDky(self%mem, real(tout, c_double), 0_c_int, self%nv_y)
    if (ierr /= 0) then
      call fatal_error(error, "CVODE: cannot interpolate at t = " // str(tout) // " s (flag " // &
        str(int(ierr)) // ")" // cvode_said(self))
      return
    end if
    self%t = tout
  end subroutine solver_advance

  !> Show `observer` the solution from the last stretch's end to t_end (cut
  !> at cvode_options%t_final) with the interpolant of CVODE's last step.
  subroutine show_stretch(self, observer, t_end, last)
    class(cvode_solver), intent(inout) :: self     !< solver
    class(step_observer), intent(inout) :: observer
    real(dp), intent(in) :: t_end                  !< where CVODE returned [s]
    logical, intent(in) :: last                    !< an event or a stop time ends the stretch
    real(c_double) :: tn(1)
    integer(c_int) :: q(1), ierr
    real(dp) :: tb
    logical :: ends
    tb = t_end
    ends = last
    if (self%t_final > 0.0_dp .and. tb >= self%t_final) then
      if (self%t_seen >= self%t_final) return   ! after the run's end
      tb = self%t_final
      ends = .true.
    end if
    if (tb <= self%t_seen .and. .not. (ends .or. self%seen_restart)) return
    ierr = FCVodeGetLastOrder(self%mem, q)
    ierr = FCVodeGetCurrentTime(self%mem, tn)
    if (t_end == tn(1)) then
      ! CVODE returned the step's end: y is its state (zn[0], as CVodeGetDky gives)
      self%poly%c(:, 0) = self%y
    else
      ierr = FCVodeGetDky(self%mem, tn(1), 0_c_int, self%nv_work)
      if (ierr /= 0) return   ! (no step taken: nothing to show)
      self%poly%c(:, 0) = self%work
    end if
    ! the higher coefficients when the observer asks (poly%fill): CVODE's
    ! order after a step is the step's (it changes it at the next step's
    ! start), so CVodeGetDky gives each of them
    self%poly%order = min(q(1), ubound(self%poly%c, 2))
    self%poly%known = 0
    self%poly%mem = self%mem
    self%poly%nv_work => self%nv_work
    self%poly%work => self%work
    self%poly%tn = tn(1)
    call observer%observe(self%poly, self%t_seen, max(tb, self%t_seen), self%seen_restart, ends)
    self%poly%mem = c_null_ptr   ! (CVODE moves on: what is not read now is gone)
    self%t_seen = max(tb, self%t_seen)
    self%seen_restart = .false.
  end subroutine show_stretch

  !> y = the polynomial at time t, dy its time derivative (no allocation: y
  !> and dy sized by the caller).
  pure subroutine polynomial_eval(self, t, y, dy)
    class(step_polynomial), intent(in) :: self  !< interpolant
    real(dp), intent(in) :: t                   !< time [s]
    real(dp), intent(out) :: y(:)               !< state there
    real(dp), intent(out), optional :: dy(:)    !< its derivative
    real(dp) :: s
    integer :: j
    if (t == self%tn) then
      ! at the step's end (where most samples are): the coefficients themselves
      ! (what the Horner scheme below gives there, without its passes)
      y = self%c(:, 0)
      if (present(dy)) then
        dy = 0.0_dp
        if (self%order >= 1) dy = self%c(:, 1)
      end if
      return
    end if
    s = t - self%tn
    y = self%c(:, self%order)
    if (present(dy)) dy = 0.0_dp
    do j = self%order - 1, 0, -1
      if (present(dy)) dy = dy*s + (j + 1)*self%c(:, j + 1)
      y = y*s + self%c(:, j)
    end do
  end subroutine polynomial_eval

  !> self = a copy of the coefficients `from` holds (storage allocated at the
  !> first copy only); the copy of CVODE's step reads the others with
  !> fill(from=...) while CVODE is at that step.
  subroutine polynomial_copy(self, from)
    class(step_polynomial), intent(inout) :: self  !< copy
    type(step_polynomial), intent(in) :: from      !< original
    integer :: k
    if (.not. allocated(self%c)) then
      allocate(self%c, mold=from%c)
    else if (any(shape(self%c) /= shape(from%c))) then
      deallocate(self%c)
      allocate(self%c, mold=from%c)
    end if
    self%tn = from%tn
    self%order = from%order
    self%known = from%known
    k = min(from%order, from%known)
    self%c(:, 0:k) = from%c(:, 0:k)
  end subroutine polynomial_copy

  !> The coefficients up to order `upto` (default: all), read off CVODE
  !> (CVodeGetDky's derivatives at tn over k!) while the step is its latest:
  !> `from`, the step a step_observer is shown (default: self), and self its
  !> copy; an order CVODE cannot give ends the polynomial below it.
  subroutine polynomial_fill(self, upto, from)
    class(step_polynomial), intent(inout) :: self           !< interpolant
    integer, intent(in), optional :: upto                   !< the highest order wanted
    type(step_polynomial), intent(in), optional :: from     !< CVODE's step (self a copy of it)
    integer :: k, last
    integer(c_int) :: ierr
    real(dp) :: fact
    type(c_ptr) :: mem
    type(N_Vector), pointer :: nv
    real(c_double), pointer :: work(:)
    last = self%order
    if (present(upto)) last = min(upto, self%order)
    if (self%known >= last) return
    if (present(from)) then
      if (from%tn /= self%tn) return   ! (not a copy of it)
      mem = from%mem
      nv => from%nv_work
      work => from%work
    else
      mem = self%mem
      nv => self%nv_work
      work => self%work
    end if
    if (.not. c_associated(mem)) return   ! (not CVODE's latest step: nothing to read)
    fact = 1.0_dp
    do k = 1, self%known
      fact = fact*k
    end do
    do k = self%known + 1, last
      ierr = FCVodeGetDky(mem, real(self%tn, c_double), int(k, c_int), nv)
      if (ierr /= 0) then
        self%order = k - 1
        exit
      end if
      fact = fact*k
      self%c(:, k) = work/fact
      self%known = k
    end do
  end subroutine polynomial_fill

  !> Whether every coefficient is set (the polynomial can be evaluated anywhere).
  pure logical function polynomial_whole(self) result(whole)
    class(step_polynomial), intent(in) :: self  !< interpolant
    whole = self%known >= self%order
  end function polynomial_whole

  !> An event at self%t: `event` and `which` from CVodeGetRootInfo's `info`;
  !> the rest of its step is searched at the next `advance`.
  subroutine report_event(self, info, event, which)
    class(cvode_solver), intent(inout) :: self     !< solver
    integer(c_int), intent(in) :: info(:)          !< CVodeGetRootInfo
    logical, intent(out), optional :: event        !< set
    integer, intent(out), optional :: which(:)     !< +-1 per function that crossed
    integer :: n
    self%after_root = .true.
    if (present(event)) event = .true.
    if (present(which)) then
      which = 0
      n = min(size(which), self%cb%nroots)
      which(1:n) = info(1:n)
    end if
  end subroutine report_event

  !> Restart from a changed state (after an event); tolerances, linear solver
  !> and event functions are kept.
  subroutine solver_reinit(self, t, y, error)
    class(cvode_solver), intent(inout) :: self            !< solver
    real(dp), intent(in) :: t                             !< time [s]
    real(dp), intent(in) :: y(:)                          !< new state
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    integer(c_int) :: ierr
    type(cvode_stats) :: so_far
    if (.not. c_associated(self%mem)) then
      call fatal_error(error, "CVODE: reinit called on a solver that is not initialised")
      return
    end if
    if (size(y) /= size(self%y)) then
      call fatal_error(error, "CVODE: reinit with " // str(size(y)) // " states for a solver of " // &
        str(size(self%y)))
      return
    end if
    if (allocated(self%cb%last_message)) deallocate(self%cb%last_message)
    so_far = self%stats()
    self%y = y
    self%t = t
    ierr = FCVodeReInit(self%mem, real(t, c_double), self%nv_y)
    if (ierr /= 0) then
      call fatal_error(error, "CVODE: re-initialisation failed at t = " // str(t) // " s" // cvode_said(self))
      return
    end if
    ! CVODE's counters restart: keep the run's totals
    self%stats_before = so_far
    call forget_steps(self)
    ! a stop time at or behind the restart (an event exactly at it) would be
    ! refused by CVODE's first step
    if (self%stop_time <= t) then
      if (clear_stop_time(self) /= 0) call fatal_error(error, "CVODE: cannot clear the stop time at t = " // &
        str(t) // " s" // cvode_said(self))
    end if
  end subroutine solver_reinit

  !> " [CVODE: <its last message>]" (and the message cleared), or "".
  function cvode_said(self) result(s)
    class(cvode_solver), intent(inout) :: self  !< solver
    character(len=:), allocatable :: s
    s = ""
    if (.not. associated(self%cb)) return
    if (.not. allocated(self%cb%last_message)) return
    s = " [CVODE: " // self%cb%last_message // "]"
    deallocate(self%cb%last_message)
  end function cvode_said

  !> Do not step past tstop (for discontinuities known in advance).  A stop
  !> time CVODE has already passed (behind its internal time) is an error.
  subroutine solver_set_stop_time(self, tstop, error)
    class(cvode_solver), intent(inout) :: self            !< solver
    real(dp), intent(in) :: tstop                         !< stop time [s]
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    integer(c_int) :: ierr
    if (.not. c_associated(self%mem)) then
      call fatal_error(error, "CVODE: set_stop_time called on a solver that is not initialised")
      return
    end if
    ierr = FCVodeSetStopTime(self%mem, real(tstop, c_double))
    if (ierr == 0) self%stop_time = tstop
    if (ierr /= 0) call fatal_error(error, "CVODE: stop time " // str(tstop) // " s rejected at t = " // &
      str(self%t) // " s (flag " // str(int(ierr)) // ")" // cvode_said(self))
  end subroutine solver_set_stop_time

  !> Change the largest step (0 = unlimited).
  subroutine solver_set_max_step(self, hmax, error)
    class(cvode_solver), intent(inout) :: self            !< solver
    real(dp), intent(in) :: hmax                          !< largest step [s]
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    integer(c_int) :: ierr
    if (.not. c_associated(self%mem)) then
      call fatal_error(error, "CVODE: set_max_step called on a solver that is not initialised")
      return
    end if
    ierr = FCVodeSetMaxStep(self%mem, real(hmax, c_double))
    if (ierr /= 0) call fatal_error(error, "CVODE: largest step " // str(hmax) // " s rejected (flag " // &
      str(int(ierr)) // ")" // cvode_said(self))
  end subroutine solver_set_max_step

  !> Steps taken since `init`, over every re-initialisation.
  integer(c_long) function solver_steps_taken(self) result(n)
    class(cvode_solver), intent(in) :: self  !< solver
    integer(c_int) :: ierr
    integer(c_long) :: nst(1)
    n = self%stats_before%steps
    if (.not. c_associated(self%mem)) return
    ierr = FCVodeGetNumSteps(self%mem, nst)
    if (ierr == 0) n = n + nst(1)
  end function solver_steps_taken

  !> Integration counters since `init`, over every re-initialisation (CVODE
  !> restarts its own at each; the totals are kept here).
  function solver_stats(self) result(s)
    class(cvode_solver), intent(in) :: self  !< solver
    type(cvode_stats) :: s
    integer(c_int) :: ierr
    integer(c_long) :: n(1)
    s = self%stats_before
    ! no step since the (re)start: CVODE's counters are zero (after a restart its linear-solver ones
    ! restart at the next step and still hold what stats_before has)
    if (.not. c_associated(self%mem) .or. self%fresh) return
    s = cvode_stats()
    ierr = FCVodeGetNumSteps(self%mem, n); s%steps = n(1)
    ierr = FCVodeGetNumRhsEvals(self%mem, n); s%rhs_evals = n(1)
    ierr = FCVodeGetNumLinSolvSetups(self%mem, n); s%lin_setups = n(1)
    ierr = FCVodeGetNumErrTestFails(self%mem, n); s%err_test_fails = n(1)
    ierr = FCVodeGetNumNonlinSolvIters(self%mem, n); s%nonlin_iters = n(1)
    ierr = FCVodeGetNumNonlinSolvConvFails(self%mem, n); s%nonlin_fails = n(1)
    ierr = FCVodeGetNumGEvals(self%mem, n); s%root_evals = n(1)
    if (associated(self%mat)) then
      ierr = FCVodeGetNumJacEvals(self%mem, n); s%jac_evals = n(1)
    end if
    call add_stats(s, self%stats_before)
  end function solver_stats

  !> Accumulate counters (a solver's restart at an event resets its own): total += part.
  pure subroutine add_stats(total, part)
    type(cvode_stats), intent(inout) :: total  !< running totals
    type(cvode_stats), intent(in) :: part      !< counters to add
    total%steps = total%steps + part%steps
    total%rhs_evals = total%rhs_evals + part%rhs_evals
    total%jac_evals = total%jac_evals + part%jac_evals
    total%lin_setups = total%lin_setups + part%lin_setups
    total%err_test_fails = total%err_test_fails + part%err_test_fails
    total%nonlin_iters = total%nonlin_iters + part%nonlin_iters
    total%nonlin_fails = total%nonlin_fails + part%nonlin_fails
    total%root_evals = total%root_evals + part%root_evals
  end subroutine add_stats

  !> Release every SUNDIALS object (safe to call twice).
  subroutine solver_free(self)
    class(cvode_solver), intent(inout) :: self  !< solver
    integer(c_int) :: ierr
    if (c_associated(self%mem)) call FCVodeFree(self%mem)
    self%mem = c_null_ptr
    if (associated(self%ls)) ierr = FSUNLinSolFree(self%ls)
    if (associated(self%nls)) ierr = FSUNNonlinSolFree(self%nls)
    if (associated(self%mat)) call FSUNMatDestroy(self%mat)
    if (associated(self%nv_y)) call FN_VDestroy(self%nv_y)
    if (associated(self%nv_atol)) call FN_VDestroy(self%nv_atol)
    if (associated(self%nv_work)) call FN_VDestroy(self%nv_work)
    nullify(self%ls, self%nls, self%mat, self%nv_y, self%nv_atol, self%nv_work, self%poly%nv_work, self%poly%work)
    self%poly%mem = c_null_ptr
    if (c_associated(self%ctx)) ierr = FSUNContext_Free(self%ctx)
    self%ctx = c_null_ptr
    if (associated(self%y)) deallocate(self%y)
    if (associated(self%work)) deallocate(self%work)
    if (allocated(self%poly%c)) deallocate(self%poly%c)
    if (associated(self%cb)) then
      if (associated(self%cb%blocks)) deallocate(self%cb%blocks)
      deallocate(self%cb)
    end if
    self%t = 0.0_dp
    self%stats_before = cvode_stats()
    call forget_steps(self)
    if (allocated(self%root_y)) deallocate(self%root_y)
    self%t_final = 0.0_dp
    self%stop_time = huge(1.0_dp)
    self%max_total = 0
    self%max_interval = 0
  end subroutine solver_free

  !> Take CVODE's stop time away (SUNDIALS 6.4 has no call to clear it: it is
  !> moved beyond any time, to 1e100 s; at huge(1.0) CVODE's test
  !> (t_n + h - t_stop) h overflowed, harmless without traps but a SIGFPE in
  !> the Checked build's programs); CVODE's flag.
  integer(c_int) function clear_stop_time(self) result(ierr)
    class(cvode_solver), intent(inout) :: self  !< solver
    ierr = FCVodeSetStopTime(self%mem, 1.0e100_dp)
    if (ierr == 0) self%stop_time = huge(1.0_dp)
  end function clear_stop_time

  !> A (re)start: no step taken, no event pending.
  subroutine forget_steps(self)
    class(cvode_solver), intent(inout) :: self  !< solver
    self%fresh = .true.
    self%after_root = .false.
    self%root_pending = .false.
    self%t_seen = self%t
    self%seen_restart = .true.
  end subroutine forget_steps

  !> One line that says when and why CVODE stopped.
  function failure_message(self, flag) result(msg)
    type(cvode_solver), intent(in) :: self
    integer(c_int), intent(in) :: flag
    character(len=:), allocatable :: msg
    character(len=:), allocatable :: why
    integer(c_long) :: taken
    select case (flag)
    case (CV_TOO_MUCH_WORK)
      taken = self%steps_taken()
      if (self%out_of_time) then
        why = "the wall-time budget is spent (" // str(self%max_wall) // " s since the run started; this " // &
          "integrator took " // str(int(taken)) // " steps, &run max_wall_time)"
      else if (self%max_total > 0 .and. taken >= self%max_total) then
        why = "the step budget is spent (" // str(int(self%max_total)) // " steps in total, &run max_steps)"
      else
        why = "too many steps between two outputs (" // str(int(self%max_interval)) // &
          ", CV_TOO_MUCH_WORK): the problem is stiffer or faster than expected"
      end if
    case (CV_TOO_MUCH_ACC)
      why = "tolerances too tight for double precision (CV_TOO_MUCH_ACC)"
    case (CV_ERR_FAILURE)
      why = "error test failed repeatedly or at the minimum step (CV_ERR_FAILURE)"
    case (CV_CONV_FAILURE)
      why = "nonlinear solver failed to converge repeatedly (CV_CONV_FAILURE)"
    case (CV_LSETUP_FAIL)
      ! a singular Newton matrix is recoverable (CVODE retries, then reports
      ! CV_CONV_FAILURE); this is a structure check or a fatal Jacobian
      why = "linear solver setup failed (unrecoverable, CV_LSETUP_FAIL" // linear_flag(self) // ")"
    case (CV_LSOLVE_FAIL)
      why = "linear solve failed (unrecoverable, CV_LSOLVE_FAIL" // linear_flag(self) // ")"
    case (CV_RHSFUNC_FAIL, CV_UNREC_RHSFUNC_ERR, CV_FIRST_RHSFUNC_ERR, CV_REPTD_RHSFUNC_ERR)
      why = "right-hand side failed"
    case (CV_RTFUNC_FAIL)
      why = "event function failed"
    case default
      why = "CVODE flag " // str(int(flag))
    end select
    msg = "integration failed at t = " // str(self%t) // " s: " // why
    select case (flag)
    case (CV_TOO_MUCH_WORK, CV_ERR_FAILURE, CV_CONV_FAILURE)
      msg = msg // "; " // error_culprit(self)
    end select
    if (allocated(self%cb%sys%failure)) then
      if (len(self%cb%sys%failure) > 0) msg = msg // ": " // self%cb%sys%failure
    end if
    if (allocated(self%cb%last_message)) msg = msg // " [CVODE: " // self%cb%last_message // "]"
  end function failure_message

  !> ", linear solver flag <n>" (CVodeGetLastLinFlag), or "" if unavailable.
  function linear_flag(self) result(s)
    type(cvode_solver), intent(in) :: self
    character(len=:), allocatable :: s
    integer(c_long) :: flag(1)
    integer(c_int) :: ierr
    s = ""
    if (.not. c_associated(self%mem)) return
    ierr = FCVodeGetLastLinFlag(self%mem, flag)
    if (ierr == 0) s = ", linear solver flag " // str(int(flag(1)))
  end function linear_flag

  !> The step size and the state with the largest weighted local error
  !> estimate of the last step: the quantity the integrator could not follow.
  function error_culprit(self) result(s)
    type(cvode_solver), intent(in) :: self
    character(len=:), allocatable :: s
    type(N_Vector), pointer :: nv_e, nv_w
    real(c_double), pointer :: e(:), w(:)
    real(c_double) :: h(1)
    integer(c_int) :: ierr
    integer :: i
    s = ""
    if (.not. c_associated(self%mem)) return
    ierr = FCVodeGetCurrentStep(self%mem, h)
    if (ierr == 0) s = "step size " // str(h(1)) // " s"
    nv_e => FN_VClone(self%nv_y)
    nv_w => FN_VClone(self%nv_y)
    if (associated(nv_e) .and. associated(nv_w)) then
      ierr = FCVodeGetEstLocalErrors(self%mem, nv_e)
      if (ierr == 0) ierr = FCVodeGetErrWeights(self%mem, nv_w)
      if (ierr == 0) then
        e => FN_VGetArrayPointer(nv_e)
        w => FN_VGetArrayPointer(nv_w)
        i = maxloc(abs(e*w), dim=1)
        if (abs(e(i)*w(i)) > 0.0_c_double) s = s // ", largest local error estimate in " // &
          self%cb%sys%state_name(i) // " (state " // str(i) // ")"
      end if
    end if
    if (associated(nv_e)) call FN_VDestroy(nv_e)
    if (associated(nv_w)) call FN_VDestroy(nv_w)
  end function error_culprit

  !> CVODE right-hand side callback.
  integer(c_int) function rhs_callback(t, nv_y, nv_ydot, user_data) result(ierr) bind(C)
    real(c_double), value, intent(in) :: t
    type(N_Vector), intent(inout) :: nv_y, nv_ydot
    type(c_ptr), value, intent(in) :: user_data
    type(callback_data), pointer :: cb
    real(c_double), pointer :: y(:), ydot(:)
    integer :: status
    call c_f_pointer(user_data, cb)
    y => FN_VGetArrayPointer(nv_y)
    ydot => FN_VGetArrayPointer(nv_ydot)
    call cb%sys%rhs(t, y, ydot, status)
    ierr = int(status, c_int)
  end function rhs_callback

  !> CVODE Jacobian callback (band matrices): the system's analytic df/dy into
  !> the band matrix, which CVODE has zeroed.
  integer(c_int) function jac_callback(t, nv_y, nv_fy, mat, user_data, tmp1, tmp2, tmp3) result(ierr) bind(C)
    real(c_double), value, intent(in) :: t
    type(N_Vector), intent(inout) :: nv_y, nv_fy, tmp1, tmp2, tmp3
    type(SUNMatrix), intent(inout) :: mat
    type(c_ptr), value, intent(in) :: user_data
    type(callback_data), pointer :: cb
    real(c_double), pointer :: y(:)
    type(band_view) :: jac
    integer :: status
    call c_f_pointer(user_data, cb)
    y => FN_VGetArrayPointer(nv_y)
    jac%ldim = int(FSUNBandMatrix_LDim(mat))
    jac%smu = int(FSUNBandMatrix_StoredUpperBandwidth(mat))
    jac%mu = int(FSUNBandMatrix_UpperBandwidth(mat))
    jac%ml = int(FSUNBandMatrix_LowerBandwidth(mat))
    jac%ab => band_data(mat, jac%ldim)
    call cb%sys%jacobian(t, y, jac, status)
    ierr = int(status, c_int)
    if (.false.) ierr = int(FN_VGetLength(nv_fy) + FN_VGetLength(tmp1) + FN_VGetLength(tmp2) + &
      FN_VGetLength(tmp3), c_int)
  end function jac_callback

  !> CVODE linear-system callback (second-order systems with node blocks): the
  !> system's Jacobian blocks at (t, y) - kept if CVODE allows (jok) and the
  !> system finds them valid - and gamma, for the velocity-reduced solver's setup,
  !> which follows; CVODE's band matrix `mat` is not used.
  integer(c_int) function linsys_callback(t, nv_y, nv_fy, mat, jok, jcur, gamma, user_data, tmp1, tmp2, tmp3) &
      result(ierr) bind(C)
    real(c_double), value, intent(in) :: t
    type(N_Vector), intent(inout) :: nv_y, nv_fy, tmp1, tmp2, tmp3
    type(SUNMatrix), intent(inout) :: mat
    integer(c_int), value, intent(in) :: jok
    integer(c_int), intent(inout) :: jcur
    real(c_double), value, intent(in) :: gamma
    type(c_ptr), value, intent(in) :: user_data
    type(callback_data), pointer :: cb
    real(c_double), pointer :: y(:)
    logical :: fresh
    integer :: status
    call c_f_pointer(user_data, cb)
    y => FN_VGetArrayPointer(nv_y)
    call cb%sys%node_jacobian(t, y, jok /= 0, cb%blocks, fresh, status)
    cb%blocks%gamma = gamma
    jcur = merge(1_c_int, 0_c_int, fresh)
    ierr = int(status, c_int)
    if (.false.) ierr = int(FN_VGetLength(nv_fy) + FN_VGetLength(tmp1) + FN_VGetLength(tmp2) + &
      FN_VGetLength(tmp3) + FSUNBandMatrix_Columns(mat), c_int)
  end function linsys_callback

  !> CVODE projection callback: corr = P(y) - y.
  integer(c_int) function proj_callback(t, nv_y, nv_corr, eps, err, user_data) result(ierr) bind(C)
    real(c_double), value, intent(in) :: t, eps
    type(N_Vector), intent(inout) :: nv_y, nv_corr
    type(c_ptr), value, intent(in) :: err, user_data
    type(callback_data), pointer :: cb
    real(c_double), pointer :: y(:), corr(:)
    integer :: status
    call c_f_pointer(user_data, cb)
    y => FN_VGetArrayPointer(nv_y)
    corr => FN_VGetArrayPointer(nv_corr)
    ! copies by N_Vector operations: an array assignment between two pointers
    ! that may alias would go through a heap temporary (once per step)
    call FN_VScale(1.0_c_double, nv_y, nv_corr)
    call cb%sys%project(t, corr, status)
    call FN_VLinearSum(1.0_c_double, nv_corr, -1.0_c_double, nv_y, nv_corr)
    ierr = 0
    if (status /= rhs_ok) ierr = -1
    if (.false.) ierr = int(merge(1, 0, c_associated(err) .and. eps > 0), c_int)
  end function proj_callback

  !> CVODE event-function callback.
  integer(c_int) function root_callback(t, nv_y, gout, user_data) result(ierr) bind(C)
    real(c_double), value, intent(in) :: t
    type(N_Vector), intent(inout) :: nv_y
    real(c_double), intent(inout) :: gout(*)
    type(c_ptr), value, intent(in) :: user_data
    type(callback_data), pointer :: cb
    real(c_double), pointer :: y(:)
    integer :: status
    call c_f_pointer(user_data, cb)
    y => FN_VGetArrayPointer(nv_y)
    call cb%sys%roots(t, y, gout(1:cb%nroots), status)
    ierr = 0
    if (status == rhs_fatal) ierr = -1
    if (status /= rhs_ok .and. status /= rhs_fatal) ierr = -1
  end function root_callback

  !> CVODE error handler: keep the message, print nothing.
  subroutine error_handler(code, module, function, msg, user_data) bind(C)
    integer(c_int), value, intent(in) :: code
    type(c_ptr), value, intent(in) :: module, function, msg, user_data
    type(callback_data), pointer :: cb
    character(kind=c_char), pointer :: chars(:)
    integer :: n
    if (.not. c_associated(user_data) .or. .not. c_associated(msg)) return
    if (code == 0 .and. c_associated(module) .and. c_associated(function)) continue
    call c_f_pointer(user_data, cb)
    call c_f_pointer(msg, chars, [1024])
    n = 0
    do while (n < 1024)
      if (chars(n+1) == c_null_char) exit
      n = n + 1
    end do
    if (allocated(cb%last_message)) deallocate(cb%last_message)
    allocate(character(len=n) :: cb%last_message)
    cb%last_message = transfer(chars(1:n), cb%last_message)
  end subroutine error_handler
end module airlaunch_cvode
