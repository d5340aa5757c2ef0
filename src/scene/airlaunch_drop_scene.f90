!> Demo scene "drop": a point-mass store released from a carrier in level
!> flight falls through the ISA atmosphere with quadratic drag,
!>   m dv/dt = -m g e_y - 1/2 rho(y) |v| v (Cd A),
!> until it has fallen `fall_height` (an event located by CVODE root finding).
!> It exercises the whole chain (namelist, atmosphere, SUNDIALS, events,
!> netCDF output) with a problem that has closed-form limits (no drag: a
!> parabola), and is a quick first look at a free-falling cargo.
module airlaunch_drop_scene
  use airlaunch_kinds, only: dp, g0
  use airlaunch_error, only: error_type, fatal_error, add_output_error, run_status
  use airlaunch_strings, only: str
  use airlaunch_atmosphere, only: isa, air_state, isa_min_altitude, isa_max_altitude
  use airlaunch_ode, only: ode_system, rhs_ok, rhs_recoverable
  use airlaunch_cvode, only: cvode_solver, cvode_options
  use airlaunch_namelist
  use airlaunch_run_config, only: run_config, echo_buffer, refuse_records
  use airlaunch_ncwrite, only: nc_writer
  use airlaunch_output_meta, only: write_run_metadata
  implicit none
  private
  public :: drop_config, drop_system, read_drop_config, run_drop

  !> Inputs of the drop scene (&store).
  type :: drop_config
    real(dp) :: mass = unset_real        !< store mass [kg] (required)
    real(dp) :: drag_area = 1.0_dp       !< Cd*A [m^2]
    real(dp) :: altitude = 10000.0_dp    !< release altitude [m]
    real(dp) :: mach = 0.65_dp           !< carrier Mach number at release
    real(dp) :: fall_height = 1000.0_dp  !< stop after falling this far [m]
  end type drop_config

  !> The ODE system: state [x, y, z, vx, vy, vz] in the earth frame.
  type, extends(ode_system) :: drop_system
    type(drop_config) :: cfg
    real(dp) :: y_stop = 0.0_dp
  contains
    procedure :: rhs => drop_rhs
    procedure :: nroots => drop_nroots
    procedure :: roots => drop_roots
    procedure :: state_name => drop_state_name
  end type drop_system

contains

  !> State i of [x, y, z, vx, vy, vz] as "store position y" etc.
  function drop_state_name(self, i) result(name)
    class(drop_system), intent(in) :: self  !< the system
    integer, intent(in) :: i                !< state index (1..6)
    character(len=:), allocatable :: name
    character(len=1), parameter :: xyz(3) = ["x", "y", "z"]
    name = "store " // merge("position ", "velocity ", i <= 3) // xyz(modulo(i - 1, 3) + 1)
    if (.false.) name = name // str(self%y_stop)
  end function drop_state_name

  !> Read and validate &store.
  subroutine read_drop_config(f, cfg, echo, error)
    type(nml_file), intent(in) :: f
    type(drop_config), intent(out) :: cfg
    character(len=:), allocatable, intent(inout) :: echo
    type(error_type), allocatable, intent(inout) :: error
    real(dp) :: mass, drag_area, altitude, mach, fall_height
    logical :: present
    integer :: unit, ios
    character(len=256) :: msg
    type(echo_buffer) :: buffer
    namelist /store/ mass, drag_area, altitude, mach, fall_height
    type(nml_var), parameter :: vars(5) = [nml_var("mass", "real"), nml_var("drag_area", "real"), &
      nml_var("altitude", "real"), nml_var("mach", "real"), nml_var("fall_height", "real")]

    mass = cfg%mass; drag_area = cfg%drag_area; altitude = cfg%altitude
    mach = cfg%mach; fall_height = cfg%fall_height
    call f%check_group("store", vars, error)
    if (allocated(error)) return
    call f%position("store", unit, present, error)
    if (allocated(error)) return
    if (.not. present) then
      call fatal_error(error, f%path // ": group &store is missing (the drop scene needs at least &store mass)")
      return
    end if
    read(unit, nml=store, iostat=ios, iomsg=msg)
    close(unit)
    if (ios /= 0) then
      call f%diagnose("store", vars, msg, error)
      return
    end if
    call require_positive(f, "store", "mass", mass, "kg", error)
    call require_nonnegative(f, "store", "drag_area", drag_area, "m^2", error)
    ! below the ISA model's top by 1 km: a release at the top itself leaves the
    ! model with the integrator's first trial state (y = 47000.0007 m)
    call require_range(f, "store", "altitude", altitude, 0.0_dp, isa_max_altitude - 1000.0_dp, "m", error)
    call require_range(f, "store", "mach", mach, 1.0e-3_dp, 5.0_dp, "", error)
    call require_positive(f, "store", "fall_height", fall_height, "m", error)
    if (allocated(error)) return
    if (altitude - fall_height < isa_min_altitude) then
      call fatal_error(error, f%path // ": &store: fall_height = " // str(fall_height) // &
        " is not allowed (must be <= altitude + " // str(-isa_min_altitude) // " m, the atmosphere's floor)")
      return
    end if
    cfg = drop_config(mass, drag_area, altitude, mach, fall_height)
    do while (buffer%another_try())
      write(buffer%lines, nml=store, iostat=buffer%ios)
    end do
    call buffer%append_to(echo)
  end subroutine read_drop_config

  subroutine drop_rhs(self, t, y, ydot, status)
    class(drop_system), intent(inout) :: self
    real(dp), intent(in) :: t
    real(dp), intent(in) :: y(:)
    real(dp), intent(out) :: ydot(:)
    integer, intent(out) :: status
    type(air_state) :: air
    real(dp) :: speed
    air = isa(y(2))
    if (.not. air%in_range) then
      ! the input keeps the fall (release altitude less fall_height, the event
      ! that ends the run) inside the model, and the store never climbs: a state
      ! outside is a trial step's overshoot past the event, retried shorter
      ! (fatal, it failed a fall ending within ~100 m of the model's floor)
      self%failure = "store altitude y = " // str(y(2)) // " m left the atmosphere model at t = " // str(t) // " s"
      status = rhs_recoverable
      ydot = 0
      return
    end if
    speed = norm2(y(4:6))
    ydot(1:3) = y(4:6)
    ydot(4:6) = -0.5_dp*air%density*speed*y(4:6)*self%cfg%drag_area/self%cfg%mass
    ydot(5) = ydot(5) - g0
    status = rhs_ok
  end subroutine drop_rhs

  integer function drop_nroots(self)
    class(drop_system), intent(in) :: self
    drop_nroots = 1
    if (self%y_stop > huge(1.0_dp)) drop_nroots = 1
  end function drop_nroots

  subroutine drop_roots(self, t, y, g, status)
    class(drop_system), intent(inout) :: self
    real(dp), intent(in) :: t
    real(dp), intent(in) :: y(:)
    real(dp), intent(out) :: g(:)
    integer, intent(out) :: status
    g(1) = y(2) - self%y_stop
    status = rhs_ok
    if (t < 0.0_dp) status = rhs_ok
  end subroutine drop_roots

  !> Run the scene and write its output file.  `summary` receives the
  !> milestones as text for the program to print.
  subroutine run_drop(run, cfg, echo, summary, error)
    type(run_config), intent(in) :: run
    type(drop_config), intent(in) :: cfg
    character(len=*), intent(in) :: echo
    character(len=:), allocatable, intent(out) :: summary
    type(error_type), allocatable, intent(inout) :: error
    type(drop_system), target :: sys
    type(cvode_solver) :: solver
    type(cvode_options) :: opts
    type(error_type), allocatable :: run_error
    real(dp), allocatable :: time(:), pos(:, :), vel(:, :), mach(:)
    real(dp) :: tout, v0, t_impact
    integer :: n, nmax, k, st
    logical :: event
    type(air_state) :: air

    sys%cfg = cfg
    sys%y_stop = cfg%altitude - cfg%fall_height
    air = isa(cfg%altitude)
    v0 = cfg%mach*air%sound_speed
    opts%rtol = run%rtol
    opts%atol = run%atol
    opts%max_total_steps = run%max_steps
    opts%max_wall_time = run%max_wall_time   ! (its one integrator: the budget runs from its start)
    opts%t_final = run%t_end   ! the steps do not depend on the output times
    opts%max_order = run%max_order   ! 0: CVODE's default (BDF up to 5)
    opts%atol_vector = [spread(run%atol*1.0e3_dp, 1, 3), spread(run%atol*1.0e2_dp, 1, 3)]
    call solver%init(sys, 0.0_dp, [0.0_dp, cfg%altitude, 0.0_dp, v0, 0.0_dp, 0.0_dp], opts, error)
    if (allocated(error)) return
    nmax = ceiling(run%t_end/run%output_dt) + 2
    allocate(time(nmax), pos(3, nmax), vel(3, nmax), mach(nmax), stat=st)
    if (st /= 0) then
      call solver%free()   ! CVODE's C objects have no finaliser
      call refuse_records(error, run%output_dt, nmax, 64.0_dp*nmax)
      return
    end if
    n = 0
    call record()
    t_impact = -1.0_dp
    do k = 1, nmax - 1
      tout = min(k*run%output_dt, run%t_end)
      call solver%advance(tout, run_error, event)
      if (allocated(run_error)) exit
      call record()
      if (event) then
        t_impact = solver%t
        exit
      end if
      if (tout >= run%t_end) exit
    end do
    call solver%free()
    if (run%trajectory) call write_output()   ! trajectory = .false.: no file (input.md)
    summary = "release: altitude " // str(cfg%altitude) // " m, speed " // str(v0) // " m/s" // new_line("a")
    if (allocated(run_error)) then
      if (run_error%output) then
        ! the run completed; its file could not be written (the writer's own message)
        call move_alloc(run_error, error)
      else
        ! (the message prefixed in place: its flags, e.g. the signal of an
        ! interrupted run, stay)
        run_error%message = "drop scene: " // run_error%message
        call move_alloc(run_error, error)
        ! the summary so far (output.md): the last record
        summary = summary // "last record at t = " // str(time(n)) // " s, altitude " // str(pos(2, n)) // " m"
        return
      end if
    end if
    if (t_impact >= 0.0_dp) then
      summary = summary // "fell " // str(cfg%fall_height) // " m at t = " // str(t_impact) // " s, " // &
        "forward travel " // str(pos(1, n)) // " m, speed " // str(norm2(vel(:, n))) // " m/s"
    else
      summary = summary // "end of run at t = " // str(time(n)) // " s, altitude " // str(pos(2, n)) // " m"
    end if
  contains
    subroutine record()
      type(air_state) :: a
      n = n + 1
      time(n) = solver%t
      pos(:, n) = solver%y(1:3)
      vel(:, n) = solver%y(4:6)
      a = isa(solver%y(2))
      mach(n) = norm2(solver%y(4:6))/a%sound_speed
    end subroutine record

    subroutine write_output()
      type(nc_writer) :: w
      type(error_type), allocatable :: werr
      call w%create(run%output, werr)
      if (.not. allocated(werr)) then
        call w%add_dim("time", time(1:n), "s", "time since release", werr)
        call w%add_dim("xyz", [0.0_dp, 1.0_dp, 2.0_dp], "1", &
          "earth-frame component: 0 = x forward, 1 = y up, 2 = z right", werr)
        call w%add_var_2d("store_position", ["xyz ", "time"], pos(:, 1:n), "m", "store position (earth frame)", werr)
        call w%add_var_2d("store_velocity", ["xyz ", "time"], vel(:, 1:n), "m s-1", "store velocity (earth frame)", werr)
        call w%add_var_1d("store_mach", ["time"], mach(1:n), "1", "store Mach number", werr)
        call write_run_metadata(w, "drop", "airlaunch demo: store drop with quadratic drag", echo, werr)
        call w%add_real_att("/", "fall_time_s", t_impact, werr)
        call w%add_text_att("/", "status", run_status(run_error), werr)
        if (allocated(run_error)) call w%add_text_att("/", "failure", run_error%message, werr)
      end if
      call w%finish(werr)
      call add_output_error(run_error, werr)
    end subroutine write_output
  end subroutine run_drop
end module airlaunch_drop_scene
