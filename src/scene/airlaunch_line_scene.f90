!> Standalone line scene (issue 3, item 5): one flexible line with two ends
!> (fixed / prescribed / free / point mass), a straight or sagged initial shape,
!> gravity and air on or off, integrated by the default CVODE scheme or the
!> paper's marching scheme, with node positions, end tensions and forces,
!> energies and the equivalent-rigid-body parameters recorded in memory at a
!> fixed output cadence.
!>
!> If the integration fails (solver failure, non-finite state) `run` returns
!> the error, naming the time and the quantity, and the records up to the last
!> good output (`n_out` of them) stay valid.
!>
!> From a namelist (scene = 'line' in &run): `read_line_scene_config` reads
!> and validates the groups &line and &line_scene (docs/line.md lists every
!> variable), `run_line_scene` runs and writes the netCDF-4 output
!> (written so far, with status = "failed", if the run fails).
module airlaunch_line_scene
  use airlaunch_kinds, only: dp, rad2deg
  use airlaunch_error, only: error_type, fatal_error, add_output_error, run_status
  use airlaunch_strings, only: str, fixed
  use airlaunch_namelist
  use airlaunch_run_config, only: run_config, echo_buffer, refuse_records
  use airlaunch_ncwrite, only: nc_writer
  use airlaunch_output_meta, only: write_run_metadata
  use airlaunch_parachute, only: parachute
  use airlaunch_scenario_config, only: read_parachute, check_break, check_weak_link, refuse_reached_strength, &
    check_break_before_end
  use airlaunch_line
  implicit none
  private
  public :: line_scene_config, line_scene, read_line_scene_config, run_line_scene, line_result

  !> Inputs of the line scene (namelist groups &line and &line_scene).
  type :: line_scene_config
    type(line_params) :: line                       !< the line
    type(line_end) :: end_a                         !< end at node 0
    type(line_end) :: end_b                         !< end at node N
    type(line_scheme_options) :: integration        !< scheme and its settings
    character(len=16) :: initial_shape = "straight" !< "straight" or "sag"
    real(dp) :: initial_sag = 0.0_dp                !< "sag": midspan sag below the chord [m]
    real(dp) :: t_end = 1.0_dp                      !< simulated time [s]
    real(dp) :: output_interval = 0.01_dp           !< output cadence [s]
    logical :: record_nodes = .true.                !< keep all node positions
    logical :: record_tensions = .false.            !< keep all segment tensions
    !> the equivalent rigid body at every record (the output file's); false:
    !> only the last record's, the summary's (docs/performance.md, thirty-fourth session)
    logical :: record_rigid = .true.
    !> the line parts (docs/line.md, "A line that breaks"): segment j when its
    !> tension reaches its strength (breaking_strength, 0: never; the weak
    !> link's weak_link_strength at weak_link_segment, 0: none), and segment
    !> break_segment at break_time (-1: no scheduled cut)
    real(dp) :: breaking_strength = 0.0_dp          !< [N]
    real(dp) :: weak_link_strength = 0.0_dp         !< [N]
    integer :: weak_link_segment = 1                !< (the reader resolves it: n_seg by default)
    real(dp) :: break_time = -1.0_dp                !< [s]
    integer :: break_segment = 1
    !> the run ends where the lowest integrated node reaches the geometric
    !> altitude ground_altitude [m] (ground false: no ground)
    logical :: ground = .false.
    real(dp) :: ground_altitude = 0.0_dp
  end type line_scene_config

  !> Where the line scene's first and last segments are (messages).
  character(len=*), parameter :: scene_line_ends = "1 at end_a, n_seg at end_b"

  !> Largest initial end separation, as strain of the unstretched line: the
  !> model assumes small axial strain (assumption 3 of §2.1).
  real(dp), parameter :: max_initial_strain = 0.5_dp
  !> The recoil's window after the first break, in L/c: the unloading wave's
  !> round trip (the free end's snap-back is over by then; afterwards the pieces
  !> fall or are dragged, which is not the recoil).
  real(dp), parameter :: recoil_window = 2.0_dp
  !> Samples of the recoil over its window (every 0.05 L/c; the undamped
  !> chain's largest node speed comes within 0.1 L/c of the cut)
  integer, parameter :: recoil_samples = 40

  !> What a run of the line scene found (its milestones, for a sweep's
  !> summary row): times are -1 and tensions or speeds negative where not
  !> defined (no peak tracked, no break, no canopy, no record).
  type :: line_result
    real(dp) :: peak_tension = -1.0_dp         !< largest segment tension over every step [N]
    real(dp) :: peak_tension_time = -1.0_dp    !< its first time [s]
    integer :: peak_tension_segment = 0        !< the segment carrying it, 1..N (0: not tracked)
    real(dp) :: max_end_tension(2) = -1.0_dp   !< largest T_1 (end a) and T_N (end b) over the records [N]
    real(dp) :: line_break_time = -1.0_dp      !< the line first parted [s]
    integer :: line_break_segment = 0          !< there, this segment (0: whole)
    integer :: line_breaks = 0                 !< segments parted in all
    real(dp) :: deploy_speed = -1.0_dp         !< air speed at the canopy's deployment [m/s]
    real(dp) :: final_tip_speed = -1.0_dp      !< speed of node N (end b) at the last record [m/s]
    real(dp) :: ground_time = -1.0_dp          !< a node reached the ground; the run ended there [s]
    real(dp) :: ground_speed = -1.0_dp         !< that node's speed there [m/s]
    !> largest node speed change within 2 L/c of the first break (its samples and records) [m/s]
    real(dp) :: recoil_speed = -1.0_dp
    real(dp) :: end_time = 0.0_dp              !< time the integration reached [s]
    type(line_scheme_stats) :: stats           !< integrator work
    logical :: completed = .false.             !< reached t_end
    !> the output file could not be written (the message; unallocated: it was, or none asked for)
    character(len=:), allocatable :: output_error
  end type line_result

  !> One standalone line simulation and its records.
  type :: line_scene
    type(line_scene_config) :: cfg                   !< the inputs
    type(line_model) :: model                        !< the line
    class(line_scheme), allocatable :: scheme        !< the integrator
    integer :: n_out = 0                             !< records written
    real(dp), allocatable :: time(:)                 !< output times (n_out) [s]
    real(dp), allocatable :: nodes(:, :, :)          !< node positions (3, 0:N, n_out) [m]
    real(dp), allocatable :: tensions(:, :)          !< segment tensions (N, n_out) [N]
    real(dp), allocatable :: tip(:, :)               !< node N position (3, n_out) [m]
    real(dp), allocatable :: tip_velocity(:, :)      !< node N velocity (3, n_out) [m/s]
    real(dp), allocatable :: end_velocity(:, :, :)   !< node 0 / node N velocity (3, 2, n_out) [m/s]
    real(dp), allocatable :: end_tension(:, :)       !< T_1 and T_N (2, n_out) [N]
    real(dp), allocatable :: end_force(:, :, :)      !< force of the line on node 0 / node N (3, 2, n_out) [N]
    real(dp), allocatable :: energy(:, :)            !< kinetic, elastic, potential (3, n_out) [J]
    type(rigid_equivalent), allocatable :: rigid(:)  !< equivalent rigid body (n_out)
    !> without record_rigid: the latest record's state and piece, its rigid body taken at the run's end
    real(dp), allocatable :: x_rec(:, :), v_rec(:, :)
    integer :: first_rec = 0, last_rec = 0
    real(dp) :: wall_time = 0.0_dp                   !< wall-clock time of `run` [s]
    type(line_scheme_stats) :: stats                 !< integrator work
    logical :: completed = .false.                   !< reached t_end
    real(dp) :: t_reached = 0.0_dp                   !< time the integration reached (a failure's time) [s]
    real(dp) :: peak_tension = 0.0_dp                !< largest segment tension over every step [N]
    real(dp) :: peak_tension_time = -1.0_dp          !< its time [s]
    integer :: peak_tension_segment = 0              !< the segment carrying it, 1..N (0: none)
    logical :: ready = .false.                       !< init succeeded
    !> largest segment strain of the initial shape (negative: all slack)
    real(dp) :: initial_strain = 0.0_dp
    !> a canopy's deployment is ahead (its filling time not yet known)
    logical :: deploy_pending = .false.
    !> air speed relative to the canopy when it deployed [m/s] (-1: not yet, or no canopy)
    real(dp) :: deploy_speed = -1.0_dp
    real(dp) :: fill_end = -1.0_dp                   !< the canopy's filling ends [s] (-1: no filling ahead)
    real(dp), allocatable :: strength(:)             !< segment strengths [N] (unallocated: never parts)
    logical :: break_pending = .false.               !< the scheduled cut (break_time) is ahead
    real(dp) :: line_break_time = -1.0_dp            !< the line first parted [s] (-1: it did not)
    integer :: line_break_segment = 0                !< there, this segment (0: whole)
    integer :: line_breaks = 0                       !< segments parted in all
    !> the recoil after the first break: the largest speed change of a node since
    !> that instant, |v_k(t) - v_k(t_break)|, within 2 L/c of it (the unloading
    !> wave's round trip), over the records there and recoil_samples instants
    !> evenly over it (the integrator stops at each) [m/s]
    !> (-1: no break).  Bounded so, it does not grow with t_end as the pieces
    !> then fall or are dragged.
    real(dp) :: recoil_speed = -1.0_dp
    real(dp), allocatable :: v_break(:, :)           !< node velocities at the first break (3, 0:N) [m/s]
    real(dp) :: recoil_end = -1.0_dp                 !< the recoil's window closes [s] (-1: no break)
    real(dp) :: recoil_next = -1.0_dp                !< the window's next sample [s]
    logical :: recoil_open = .false.                 !< the window is open (its end not yet sampled)
    real(dp) :: ground_time = -1.0_dp                !< the lowest integrated node reached the ground [s] (-1: not)
    integer :: ground_node = -1                      !< which node, 0..N (-1: none)
    real(dp) :: ground_speed = -1.0_dp               !< its speed there [m/s] (-1: not reached)
    real(dp), allocatable, private :: x(:, :), v(:, :), f(:, :), tension(:)
  contains
    procedure :: init => scene_init
    procedure :: run => scene_run
    procedure :: free => scene_free
  end type line_scene

contains

  !> Check the inputs, build line, initial state and integrator.
  subroutine scene_init(self, cfg, error)
    class(line_scene), intent(inout) :: self               !< scene (re-initialised)
    type(line_scene_config), intent(in) :: cfg             !< inputs
    type(error_type), allocatable, intent(inout) :: error  !< set on bad input
    integer :: n, n_max, k, st
    real(dp) :: xa(3), xb(3), va(3), vb(3), sep, strain
    type(line_scheme_options) :: opts

    call self%free()
    self%cfg = cfg
    call self%model%init(cfg%line, error)
    if (allocated(error)) return
    ! a deploying canopy fills in t_f = n D0 / V, V the air speed relative to it
    ! when it deploys: at the start (deploy_time 0) from its initial velocity,
    ! later from the state there (deploy)
    call prepare_deployment(self, error)
    if (allocated(error)) return
    call self%cfg%end_a%check("end_a", error)
    if (allocated(error)) return
    call self%cfg%end_b%check("end_b", error)
    if (allocated(error)) return
    call check_scheme_options(cfg%integration, error)
    if (allocated(error)) return
    if (.not. (cfg%t_end > 0.0_dp)) then
      call fatal_error(error, "line_scene: t_end = " // str(cfg%t_end) // " s is not allowed: must be > 0")
      return
    end if
    if (.not. (cfg%output_interval > 0.0_dp)) then
      call fatal_error(error, "line_scene: output_interval = " // str(cfg%output_interval) // &
        " s is not allowed: must be > 0")
      return
    end if
    if (.not. (cfg%initial_sag >= 0.0_dp)) then
      call fatal_error(error, "line_scene: initial_sag = " // str(cfg%initial_sag) // &
        " m is not allowed: must be >= 0")
      return
    end if

    n = self%model%n
    call cfg%end_a%motion(0.0_dp, xa, va)
    call cfg%end_b%motion(0.0_dp, xb, vb)
    sep = norm2(xb - xa)
    if (sep <= 1.0e-9_dp*cfg%line%length) then
      call fatal_error(error, "line_scene: end_a and end_b are both at (" // str(xa(1)) // ", " // &
        str(xa(2)) // ", " // str(xa(3)) // ") m: a line of length " // str(cfg%line%length) // &
        " m cannot be laid between coincident ends; the end positions must differ")
      return
    end if
    strain = sep/cfg%line%length - 1.0_dp
    if (strain > max_initial_strain) then
      call fatal_error(error, "line_scene: the ends are " // str(sep) // " m apart, which stretches the " // &
        str(cfg%line%length) // " m line by " // str(100*strain) // " %: not allowed (at most " // &
        str(100*max_initial_strain) // " %; the model assumes small strain)")
      return
    end if

    allocate(self%x(3, 0:n), self%v(3, 0:n), self%f(3, 0:n), self%tension(n))
    if (.not. cfg%record_rigid) allocate(self%x_rec(3, 0:n), self%v_rec(3, 0:n))
    select case (trim(cfg%initial_shape))
    case ("straight")
      call straight_shape(n, xa, xb, self%x)
    case ("sag")
      call sagged_shape(n, xa, xb, cfg%initial_sag, self%x, error)
      if (allocated(error)) return
    case default
      call fatal_error(error, "line_scene: initial_shape = '" // trim(cfg%initial_shape) // &
        "' is not allowed: use 'straight' or 'sag'")
      return
    end select
    self%initial_strain = -1.0_dp
    do k = 1, n
      self%initial_strain = max(self%initial_strain, norm2(self%x(:, k) - self%x(:, k-1))/self%model%l0 - 1.0_dp)
    end do
    if (cfg%initial_shape == "sag" .and. self%initial_strain > max_initial_strain) then
      ! the parabola's length is set by chord and sag, not by L: the straight
      ! line's strain limit, on the segments actually built
      call fatal_error(error, "line_scene: initial_sag = " // str(cfg%initial_sag) // " m lays the " // &
        str(cfg%line%length) // " m line on a parabola " // str(parabola_length(sep, cfg%initial_sag)) // &
        " m long between ends " // str(sep) // " m apart, which stretches its segments by " // &
        str(100*self%initial_strain) // " %: not allowed (at most " // str(100*max_initial_strain) // &
        " %; the model assumes small strain; initial_sag = " // &
        str(parabola_sag_for_length(sep, cfg%line%length)) // " m gives the unstretched length)")
      return
    end if
    ! initial velocities: linear between the ends' initial velocities
    call straight_shape(n, va, vb, self%v)

    ! CVODE's first step sized for the run, not the first output (the steps do
    ! not depend on the output times) unless the caller chose otherwise
    opts = cfg%integration
    if (.not. (opts%t_final > 0.0_dp)) opts%t_final = cfg%t_end
    call new_line_scheme(self%scheme, self%model, self%cfg%end_a, self%cfg%end_b, self%x, self%v, 0.0_dp, &
      opts, error)
    if (allocated(error)) return
    call prepare_break(self, error)
    if (allocated(error)) return
    call prepare_ground(self, error)
    if (allocated(error)) return
    call set_next_stop(self, error)
    if (allocated(error)) return

    n_max = ceiling(cfg%t_end/cfg%output_interval - 1.0e-9_dp) + 1
    allocate(self%time(n_max), self%tip(3, n_max), self%tip_velocity(3, n_max), self%end_velocity(3, 2, n_max), &
      self%end_tension(2, n_max), self%end_force(3, 2, n_max), self%energy(3, n_max), self%rigid(n_max), stat=st)
    if (st == 0 .and. cfg%record_nodes) allocate(self%nodes(3, 0:n, n_max), stat=st)
    if (st == 0 .and. cfg%record_tensions) allocate(self%tensions(n, n_max), stat=st)
    if (st /= 0) then
      ! (a record: 24 reals, the equivalent rigid body, 3 per node, 1 per segment)
      call refuse_records(error, cfg%output_interval, n_max, real(n_max, dp)*(8.0_dp*24 + &
        storage_size(self%rigid)/8.0_dp + merge(24.0_dp*(n + 1), 0.0_dp, cfg%record_nodes) + &
        merge(8.0_dp*n, 0.0_dp, cfg%record_tensions)))
      return
    end if
    self%n_out = 0
    self%ready = .true.
  end subroutine scene_init

  !> A deploying canopy end's filling time: set at once when it deploys at the
  !> start, else pending (deploy sets it when the run gets there; until then
  !> the canopy is packed whatever its filling time: a placeholder).
  subroutine prepare_deployment(self, error)
    type(line_scene), intent(inout) :: self                !< scene (cfg set)
    type(error_type), allocatable, intent(inout) :: error  !< set on bad input
    type(line_end) :: en
    real(dp) :: x(3), v(3)
    self%deploy_pending = .false.
    self%deploy_speed = -1.0_dp
    en = canopy_end_of(self%cfg)
    if (.not. en%inflating()) return
    if (en%canopy%deploy_time > 0.0_dp) then
      self%deploy_pending = .true.
      en%canopy%fill_time = huge(1.0_dp)
      call put_end(self%cfg, en)
    else
      call en%motion(0.0_dp, x, v)
      call set_deployment(self, 0.0_dp, v, error)
    end if
  end subroutine prepare_deployment

  !> The canopy deploys at t with velocity v: its filling time from the air
  !> speed |wind - v| (an error naming the time if it is 0).
  subroutine set_deployment(self, t, v, error)
    type(line_scene), intent(inout) :: self                !< scene
    real(dp), intent(in) :: t, v(3)                        !< deployment time [s], the end's velocity [m/s]
    type(error_type), allocatable, intent(inout) :: error  !< set if there is no air speed
    type(line_end) :: en
    real(dp) :: speed
    speed = norm2(self%cfg%line%wind - v)
    if (.not. (speed > 0.0_dp)) then
      call fatal_error(error, "line_scene: the canopy at end_" // merge("a", "b", canopy_index(self%cfg) == 1) // &
        " deploys at t = " // str(t) // " s with no air speed relative to it (wind - velocity = 0 m/s): " // &
        "its filling time n D0 / V needs V > 0; deploy it later or into a stream")
      return
    end if
    self%deploy_speed = speed
    en = canopy_end_of(self%cfg)
    en%canopy%fill_time = en%fill_time(speed)
    call put_end(self%cfg, en)
  end subroutine set_deployment

  !> The canopy deploys now (the scheme is at its deployment time): its
  !> filling time from its air speed here; the scheme restarts.
  subroutine deploy(self, error)
    type(line_scene), intent(inout) :: self                !< scene (a deployment pending)
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    type(line_end) :: en
    integer :: which
    which = canopy_index(self%cfg)
    call self%scheme%get_state(self%x, self%v)
    call set_deployment(self, self%scheme%t, self%v(:, merge(0, self%model%n, which == 1)), error)
    if (allocated(error)) return
    en = canopy_end_of(self%cfg)
    call self%scheme%set_fill_time(which, en%canopy%fill_time, error)
    if (allocated(error)) return
    ! the filling's end: the entrained air's momentum force stops with a jump
    ! (set_next_stop stops the scheme there)
    if (self%scheme%t + en%canopy%fill_time < self%cfg%t_end) self%fill_end = self%scheme%t + en%canopy%fill_time
    self%deploy_pending = .false.
  end subroutine deploy

  !> An end whose motion is given, not integrated ('fixed' or 'prescribed').
  pure logical function is_kinematic(kind)
    character(len=*), intent(in) :: kind   !< &line_scene a_kind or b_kind
    is_kinematic = trim(kind) == "fixed" .or. trim(kind) == "prescribed"
  end function is_kinematic

  !> The line's strengths (a line that can break) into the scheme, which
  !> watches their margin; an initial shape whose tension already reaches a
  !> strength is an input error naming the variable that set it.  A scheduled
  !> cut is pending.
  subroutine prepare_break(self, error)
    type(line_scene), intent(inout) :: self                !< scene (scheme built)
    type(error_type), allocatable, intent(inout) :: error  !< set on bad input
    real(dp) :: margin
    integer :: k, st
    associate(c => self%cfg)
      self%break_pending = c%break_time > 0.0_dp
      if (.not. (c%breaking_strength > 0.0_dp .or. c%weak_link_strength > 0.0_dp)) return
      self%strength = segment_strengths(self%model%n, c%breaking_strength, c%weak_link_strength, &
        c%weak_link_segment)
      call self%model%tensions(self%x, self%v, self%tension, st)
      call weakest_segment(self%strength, self%tension, margin, k)
      if (margin <= 0.0_dp) then
        call refuse_reached_strength(c%breaking_strength, c%weak_link_strength, c%weak_link_segment, k, &
          self%tension(k), "the initial shape's tension", error)
        return
      end if
      call self%scheme%set_strength(self%strength, error)
    end associate
  end subroutine prepare_break

  !> The ground (a line scene with ground_altitude) into the scheme, which
  !> watches the lowest integrated node's height above it; a node that starts
  !> at or below it is an input error.
  subroutine prepare_ground(self, error)
    type(line_scene), intent(inout) :: self                !< scene (scheme built)
    type(error_type), allocatable, intent(inout) :: error  !< set on bad input
    integer :: k0, k1, k
    if (.not. self%cfg%ground) return
    call integrated_nodes(self, k0, k1)
    if (k1 < k0) then
      call fatal_error(error, "line_scene: ground_altitude = " // str(self%cfg%ground_altitude) // " m is not " // &
        "allowed on a line of n_seg = 1 between two kinematic ends: no node of it is integrated, so nothing " // &
        "can reach the ground")
      return
    end if
    k = k0 - 1 + minloc(self%x(2, k0:k1), 1)
    if (.not. self%x(2, k) > self%cfg%ground_altitude) then
      call fatal_error(error, "line_scene: ground_altitude = " // str(self%cfg%ground_altitude) // " m is not " // &
        "allowed: node " // str(k) // " starts at altitude " // str(self%x(2, k)) // " m, not above it")
      return
    end if
    call self%scheme%set_ground(self%cfg%ground_altitude, error)
  end subroutine prepare_ground

  !> The nodes the scheme integrates: k0..k1 (the kinematic ends' are given).
  pure subroutine integrated_nodes(self, k0, k1)
    type(line_scene), intent(in) :: self   !< scene
    integer, intent(out) :: k0, k1         !< first and last
    k0 = merge(1, 0, self%cfg%end_a%is_kinematic())
    k1 = self%model%n - merge(1, 0, self%cfg%end_b%is_kinematic())
  end subroutine integrated_nodes

  !> The scheme stopped where the lowest integrated node reached the ground.
  subroutine take_ground(self)
    type(line_scene), intent(inout) :: self   !< scene (the scheme at the event)
    integer :: k0, k1
    call self%scheme%get_state(self%x, self%v)
    call integrated_nodes(self, k0, k1)
    self%ground_node = k0 - 1 + minloc(self%x(2, k0:k1), 1)
    self%ground_time = self%scheme%t
    self%ground_speed = norm2(self%v(:, self%ground_node))
  end subroutine take_ground

  !> Stop the scheme at the next change of the system known in advance: the
  !> canopy's deployment, the end of its filling, the scheduled cut.
  subroutine set_next_stop(self, error)
    type(line_scene), intent(inout) :: self                !< scene
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    real(dp) :: t, next
    t = self%scheme%t
    next = huge(1.0_dp)
    if (self%deploy_pending) next = min(next, deployment_time(self%cfg))
    if (self%fill_end > t) next = min(next, self%fill_end)
    if (self%break_pending) next = min(next, self%cfg%break_time)
    if (self%recoil_open) next = min(next, self%recoil_next)
    if (next > t .and. next < huge(1.0_dp)) call self%scheme%set_stop_time(next, error)
  end subroutine set_next_stop

  !> Advance the scheme to t_target, handling on the way the canopy's
  !> deployment, a segment reaching its strength and the scheduled cut.
  subroutine advance_to(self, t_target, error)
    type(line_scene), intent(inout) :: self                !< scene
    real(dp), intent(in) :: t_target                       !< [s]
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    real(dp) :: t_next
    do while (self%scheme%t < t_target)
      t_next = t_target
      if (self%deploy_pending) t_next = min(t_next, deployment_time(self%cfg))
      ! (the scheme returns early at a stop time or where a strength or the
      ! ground is reached)
      call self%scheme%advance(t_next, error)
      if (allocated(error)) return
      if (self%scheme%ground_reached) then
        call take_ground(self)
        return
      end if
      if (self%scheme%strength_reached) then
        call part_at_strength(self, error)
      else if (self%break_pending .and. self%scheme%t >= self%cfg%break_time) then
        self%break_pending = .false.
        call self%model%part(self%cfg%break_segment)
        call take_parts(self, self%cfg%break_segment, error)
      end if
      if (allocated(error)) return
      if (self%deploy_pending .and. self%scheme%t >= deployment_time(self%cfg)) call deploy(self, error)
      if (self%recoil_open .and. self%scheme%t >= self%recoil_next) call sample_recoil(self)
      if (.not. allocated(error)) call set_next_stop(self, error)
      if (allocated(error)) return
    end do
  end subroutine advance_to

  !> A segment's tension reached its strength: the one with the smallest
  !> margin parts, and with it any other at its own strength
  !> (line_model%part_reached).
  subroutine part_at_strength(self, error)
    type(line_scene), intent(inout) :: self                !< scene (the scheme at the event)
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    integer :: first, st
    call self%scheme%get_state(self%x, self%v)
    call self%model%tensions(self%x, self%v, self%tension, st)
    call self%model%part_reached(self%strength, self%tension, first)
    call take_parts(self, first, error)
  end subroutine part_at_strength

  !> The scene's line has parted (first: the segment that parted first now):
  !> the scheme's line parts alike, and the break is recorded.
  subroutine take_parts(self, first, error)
    type(line_scene), intent(inout) :: self                !< scene
    integer, intent(in) :: first                           !< segment 1..N
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    integer :: j
    do j = 1, self%model%n
      if (self%model%parted(j)) call self%scheme%part(j, error)
      if (allocated(error)) return
    end do
    if (self%line_breaks == 0) then
      self%line_break_time = self%scheme%t
      self%line_break_segment = first
      ! (the state does not jump at a break: the velocities the recoil starts from)
      call self%scheme%get_state(self%x, self%v)
      self%v_break = self%v
      self%recoil_speed = 0.0_dp
      self%recoil_end = self%scheme%t + recoil_window*self%model%n*self%model%l0/self%model%wave_speed()
      self%recoil_next = self%scheme%t + (self%recoil_end - self%scheme%t)/recoil_samples
      self%recoil_open = .true.
    end if
    self%line_breaks = self%model%n_parted
  end subroutine take_parts

  !> One of the recoil window's samples (the scheme at recoil_next): the
  !> recoil with the scheme's velocities, and the next sample (none after the
  !> window's end).
  subroutine sample_recoil(self)
    type(line_scene), intent(inout) :: self   !< scene (the window open)
    call self%scheme%get_state(self%x, self%v)
    call take_recoil(self)
    self%recoil_next = self%recoil_next + (self%recoil_end - self%line_break_time)/recoil_samples
    ! (the last sample lands on the window's end up to rounding)
    self%recoil_open = self%recoil_next <= self%recoil_end*(1.0_dp + 1.0e-12_dp)
  end subroutine sample_recoil

  !> The recoil so far with the current velocities (self%v).
  subroutine take_recoil(self)
    type(line_scene), intent(inout) :: self   !< scene (after the first break)
    integer :: k
    do k = 0, self%model%n
      self%recoil_speed = max(self%recoil_speed, norm2(self%v(:, k) - self%v_break(:, k)))
    end do
  end subroutine take_recoil

  !> The canopy's deployment time [s].
  pure real(dp) function deployment_time(cfg) result(t)
    type(line_scene_config), intent(in) :: cfg   !< the scene (with a canopy end)
    type(line_end) :: en
    en = canopy_end_of(cfg)
    t = en%canopy%deploy_time
  end function deployment_time

  !> Which end carries the canopy (1 = a, 2 = b; 2 if none).
  pure integer function canopy_index(cfg) result(which)
    type(line_scene_config), intent(in) :: cfg   !< the scene
    which = merge(1, 2, cfg%end_a%canopy_end)
  end function canopy_index

  !> Store the canopy end `en` back into the scene's inputs.
  pure subroutine put_end(cfg, en)
    type(line_scene_config), intent(inout) :: cfg   !< the scene
    type(line_end), intent(in) :: en                !< its canopy end
    if (canopy_index(cfg) == 1) then
      cfg%end_a = en
    else
      cfg%end_b = en
    end if
  end subroutine put_end

  !> Integrate to t_end, recording at every output time (t = 0 included).
  subroutine scene_run(self, error)
    class(line_scene), intent(inout) :: self               !< scene (after init)
    type(error_type), allocatable, intent(inout) :: error  !< set on failure
    integer :: i, n_max
    integer(8) :: c0, c1, rate
    real(dp) :: t_out

    if (.not. self%ready) then
      call fatal_error(error, "line_scene: run called before a successful init")
      return
    end if
    call system_clock(c0, rate)
    self%completed = .false.
    n_max = size(self%time)
    call record(self, error)
    do i = 2, n_max
      if (allocated(error)) exit
      t_out = min((i - 1)*self%cfg%output_interval, self%cfg%t_end)
      call advance_to(self, t_out, error)
      if (allocated(error)) exit
      call record(self, error)
      if (self%ground_time >= 0.0_dp) exit   ! (the run ends at the ground)
    end do
    self%completed = .not. allocated(error)
    if (.not. self%cfg%record_rigid .and. self%n_out > 0) self%rigid(self%n_out) = &
      rigidize(self%model, self%x_rec, self%v_rec, self%first_rec, self%last_rec)
    self%t_reached = self%scheme%t
    self%peak_tension = self%scheme%peak_tension(self%peak_tension_time)
    self%peak_tension_segment = self%scheme%peak_segment
    self%stats = self%scheme%stats()
    call system_clock(c1)
    self%wall_time = real(c1 - c0, dp)/real(rate, dp)
  end subroutine scene_run

  !> Append one record at the scheme's current time; a non-finite state is an
  !> error naming the node and the time (and is not recorded).
  subroutine record(self, error)
    type(line_scene), intent(inout) :: self                !< scene
    type(error_type), allocatable, intent(inout) :: error  !< set on a non-finite state
    integer :: n, k, st, m, i, first, last
    real(dp) :: t, ek(2)
    type(line_energy) :: e
    type(line_end) :: en
    n = self%model%n
    t = self%scheme%t
    call self%scheme%get_state(self%x, self%v)
    do k = 0, n
      if (.not. all(abs(self%x(:, k)) <= huge(1.0_dp) .and. abs(self%v(:, k)) <= huge(1.0_dp))) then
        call fatal_error(error, "line_scene: the position or velocity of node " // str(k) // &
          " is not finite at t = " // str(t) // " s")
        return
      end if
    end do
    call self%model%forces(self%x, self%v, self%f, self%tension, st)
    ! the peak tension is never below a record (the schemes take it over their
    ! steps); a record's time depends on the output cadence: not a candidate
    ! for the peak's first time
    if (associated(self%scheme%peak)) then
      i = maxloc(self%tension, 1)
      call self%scheme%peak(1)%offer(t, self%tension(i), candidate=.false.)
      call self%scheme%note_peak_segment(self%tension(i), i)
    end if
    m = self%n_out + 1
    self%time(m) = t
    self%tip(:, m) = self%x(:, n)
    self%tip_velocity(:, m) = self%v(:, n)
    self%end_velocity(:, 1, m) = self%v(:, 0)
    self%end_velocity(:, 2, m) = self%v(:, n)
    if (self%recoil_open .and. t <= self%recoil_end) call take_recoil(self)
    self%end_tension(:, m) = [self%tension(1), self%tension(n)]
    self%end_force(:, 1, m) = self%f(:, 0)
    self%end_force(:, 2, m) = self%f(:, n)
    e = self%model%energy(self%x, self%v)
    do i = 1, 2
      en = self%cfg%end_b
      if (i == 1) en = self%cfg%end_a
      k = merge(0, n, i == 1)
      ek = en%energy(t, self%x(:, k), self%v(:, k), self%cfg%line%gravity, self%cfg%line%air, &
        self%cfg%line%air_density)
      e%kinetic = e%kinetic + ek(1)
      e%potential = e%potential + ek(2)
    end do
    self%energy(:, m) = [e%kinetic, e%elastic, e%potential]
    ! after a break, of the larger piece still holding an end (Eqs. (18)-(32)
    ! describe one connected line)
    call whole_piece(self%model, first, last)
    if (self%cfg%record_rigid) then
      self%rigid(m) = rigidize(self%model, self%x, self%v, first, last)
    else
      ! kept for the last record's rigid body (scene_run): the summary reads no
      ! other, and it was 7 % of the heavy airdrop's instructions at every record
      self%x_rec = self%x
      self%v_rec = self%v
      self%first_rec = first
      self%last_rec = last
    end if
    if (allocated(self%nodes)) self%nodes(:, :, m) = self%x
    if (allocated(self%tensions)) self%tensions(:, m) = self%tension
    self%n_out = m
  end subroutine record

  !> Release the integrator and the records.
  subroutine scene_free(self)
    class(line_scene), intent(inout) :: self   !< scene
    if (allocated(self%scheme)) then
      call self%scheme%free()
      deallocate(self%scheme)
    end if
    ! each on its own: an ALLOCATE of several that failed (stat) may have made some of them
    if (allocated(self%time)) deallocate(self%time)
    if (allocated(self%tip)) deallocate(self%tip)
    if (allocated(self%tip_velocity)) deallocate(self%tip_velocity)
    if (allocated(self%end_velocity)) deallocate(self%end_velocity)
    if (allocated(self%end_tension)) deallocate(self%end_tension)
    if (allocated(self%end_force)) deallocate(self%end_force)
    if (allocated(self%energy)) deallocate(self%energy)
    if (allocated(self%rigid)) deallocate(self%rigid)
    if (allocated(self%nodes)) deallocate(self%nodes)
    if (allocated(self%tensions)) deallocate(self%tensions)
    if (allocated(self%x)) deallocate(self%x, self%v, self%f, self%tension)
    if (allocated(self%x_rec)) deallocate(self%x_rec, self%v_rec)
    if (allocated(self%strength)) deallocate(self%strength)
    self%break_pending = .false.
    self%fill_end = -1.0_dp
    self%line_break_time = -1.0_dp
    self%line_break_segment = 0
    self%line_breaks = 0
    self%recoil_speed = -1.0_dp
    self%recoil_end = -1.0_dp
    self%recoil_next = -1.0_dp
    self%recoil_open = .false.
    self%ground_time = -1.0_dp
    self%ground_node = -1
    self%ground_speed = -1.0_dp
    if (allocated(self%v_break)) deallocate(self%v_break)
    self%n_out = 0
    self%completed = .false.
    self%ready = .false.
  end subroutine scene_free

  ! ---------------------------------------------------------------------
  ! Namelist input and netCDF output
  ! ---------------------------------------------------------------------

  !> Read and validate &line and &line_scene from `f`; the times, the output
  !> cadence and (if set in &run) the tolerances and the BDF order come from
  !> `run`.  `echo` receives the resolved groups.  The scene is built once to
  !> check the geometry, so every bad value is reported here (exit status 2)
  !> as one line naming the file, the group, the variable, its value and what
  !> is allowed.
  subroutine read_line_scene_config(f, run, cfg, echo, error)
    type(nml_file), intent(in) :: f                       !< scanned input
    type(run_config), intent(in) :: run                   !< &run settings
    type(line_scene_config), intent(out) :: cfg           !< resolved scene
    character(len=:), allocatable, intent(inout) :: echo  !< resolved input text
    type(error_type), allocatable, intent(inout) :: error !< set on bad input
    ! &line
    real(dp) :: length, ea, mass_per_length, damping, settling_damping, diameter, cd_normal, cd_tangential
    real(dp) :: wind(3), air_density, breaking_strength, break_time, weak_link_strength
    integer :: n_seg, break_segment, weak_link_segment
    logical :: gravity, air
    character(len=8) :: mass
    ! &line_scene
    character(len=16) :: a_kind, b_kind, initial_shape, scheme
    real(dp) :: a_position(3), a_velocity(3), a_amplitude(3), a_frequency, a_phase_deg, a_t_start, a_mass
    real(dp) :: a_drag_area, b_position(3), b_velocity(3), b_amplitude(3), b_frequency, b_phase_deg
    real(dp) :: b_t_start, b_mass, b_drag_area, initial_sag, dt, force_tol, ground_altitude
    integer :: max_iterations
    logical :: record_tensions, peak_tension, ground
    type(echo_buffer) :: line_buffer, scene_buffer
    namelist /line/ length, n_seg, ea, mass_per_length, damping, settling_damping, diameter, cd_normal, &
      cd_tangential, gravity, air, wind, air_density, mass, breaking_strength, break_time, break_segment, &
      weak_link_strength, weak_link_segment
    namelist /line_scene/ a_kind, a_position, a_velocity, a_amplitude, a_frequency, a_phase_deg, a_t_start, &
      a_mass, a_drag_area, b_kind, b_position, b_velocity, b_amplitude, b_frequency, b_phase_deg, b_t_start, &
      b_mass, b_drag_area, initial_shape, initial_sag, scheme, dt, force_tol, max_iterations, record_tensions, &
      peak_tension, ground, ground_altitude
    type(nml_var), parameter :: line_vars(19) = [nml_var("length", "real"), nml_var("n_seg", "integer"), &
      nml_var("ea", "real"), nml_var("mass_per_length", "real"), nml_var("damping", "real"), &
      nml_var("settling_damping", "real"), nml_var("diameter", "real"), nml_var("cd_normal", "real"), &
      nml_var("cd_tangential", "real"), nml_var("gravity", "logical"), nml_var("air", "logical"), &
      nml_var("wind", "real3"), nml_var("air_density", "real"), nml_var("mass", "string", length=8), &
      nml_var("breaking_strength", "real"), nml_var("break_time", "real"), nml_var("break_segment", "integer"), &
      nml_var("weak_link_strength", "real"), nml_var("weak_link_segment", "integer")]
    type(nml_var), parameter :: scene_vars(28) = [nml_var("a_kind", "string", 16), &
      nml_var("a_position", "real3"), nml_var("a_velocity", "real3"), &
      nml_var("a_amplitude", "real3"), nml_var("a_frequency", "real"), nml_var("a_phase_deg", "real"), &
      nml_var("a_t_start", "real"), nml_var("a_mass", "real"), nml_var("a_drag_area", "real"), &
      nml_var("b_kind", "string", 16), nml_var("b_position", "real3"), nml_var("b_velocity", "real3"), &
      nml_var("b_amplitude", "real3"), nml_var("b_frequency", "real"), nml_var("b_phase_deg", "real"), &
      nml_var("b_t_start", "real"), nml_var("b_mass", "real"), nml_var("b_drag_area", "real"), &
      nml_var("initial_shape", "string", 16), nml_var("initial_sag", "real"), nml_var("scheme", "string", 16), &
      nml_var("dt", "real"), nml_var("force_tol", "real"), nml_var("max_iterations", "integer"), &
      nml_var("record_tensions", "logical"), nml_var("peak_tension", "logical"), nml_var("ground", "logical"), &
      nml_var("ground_altitude", "real")]
    character(len=16), parameter :: kinds(5) = [character(len=16) :: "fixed", "prescribed", "free", &
      "point_mass", "canopy"]
    type(line_scene_config) :: d
    type(parachute) :: chute
    character(len=:), allocatable :: chute_echo
    integer :: unit, ios
    logical :: present
    character(len=256) :: msg

    ! defaults
    length = d%line%length; n_seg = d%line%n_seg; ea = d%line%ea; mass_per_length = d%line%mass_per_length
    damping = d%line%damping; settling_damping = d%line%settling_damping; diameter = d%line%diameter
    cd_normal = d%line%cd_normal; cd_tangential = d%line%cd_tangential; gravity = d%line%gravity
    air = d%line%air; wind = d%line%wind; air_density = d%line%air_density
    mass = d%line%mass
    breaking_strength = d%breaking_strength; break_time = d%break_time; break_segment = d%break_segment
    weak_link_strength = d%weak_link_strength; weak_link_segment = unset_int
    a_kind = "fixed"; a_position = [0.0_dp, 0.0_dp, 0.0_dp]; a_velocity = 0; a_amplitude = 0
    a_frequency = 0; a_phase_deg = 0; a_t_start = 0; a_mass = 0; a_drag_area = 0
    b_kind = "free"; b_position = [length, 0.0_dp, 0.0_dp]; b_velocity = 0; b_amplitude = 0
    b_frequency = 0; b_phase_deg = 0; b_t_start = 0; b_mass = 0; b_drag_area = 0
    initial_shape = d%initial_shape; initial_sag = d%initial_sag; scheme = d%integration%scheme
    dt = d%integration%dt; force_tol = d%integration%force_tol; max_iterations = d%integration%max_iterations
    record_tensions = .true.
    peak_tension = d%integration%peak_tension
    ground = d%ground
    ground_altitude = d%ground_altitude

    call f%check_group("line", line_vars, error)
    if (allocated(error)) return
    call f%check_group("line_scene", scene_vars, error)
    if (allocated(error)) return
    call f%position("line", unit, present, error)
    if (allocated(error)) return
    if (present) then
      read(unit, nml=line, iostat=ios, iomsg=msg)
      close(unit)
      if (ios /= 0) then
        call f%diagnose("line", line_vars, msg, error)
        return
      end if
    end if
    if (.not. f%is_set("line_scene", "b_position")) b_position = [length, 0.0_dp, 0.0_dp]
    call f%position("line_scene", unit, present, error)
    if (allocated(error)) return
    if (present) then
      read(unit, nml=line_scene, iostat=ios, iomsg=msg)
      close(unit)
      if (ios /= 0) then
        call f%diagnose("line_scene", scene_vars, msg, error)
        return
      end if
    end if

    call require_positive(f, "line", "length", length, "m", error)
    call require_int_range(f, "line", "n_seg", n_seg, 1, 100000, error)
    call require_positive(f, "line", "ea", ea, "N", error)
    call require_positive(f, "line", "mass_per_length", mass_per_length, "kg/m", error)
    call require_nonnegative(f, "line", "damping", damping, "N s", error)
    call require_nonnegative(f, "line", "settling_damping", settling_damping, "1/s", error)
    call require_nonnegative(f, "line", "diameter", diameter, "m", error)
    call require_nonnegative(f, "line", "cd_normal", cd_normal, "", error)
    call require_nonnegative(f, "line", "cd_tangential", cd_tangential, "", error)
    call require_nonnegative(f, "line", "air_density", air_density, "kg/m^3 (0: ISA)", error)
    call require_choice(f, "line_scene", "a_kind", a_kind, kinds, error)
    call require_choice(f, "line_scene", "b_kind", b_kind, kinds, error)
    call require_nonnegative(f, "line_scene", "a_frequency", a_frequency, "Hz", error)
    call require_nonnegative(f, "line_scene", "b_frequency", b_frequency, "Hz", error)
    call require_nonnegative(f, "line_scene", "a_drag_area", a_drag_area, "m^2", error)
    call require_nonnegative(f, "line_scene", "b_drag_area", b_drag_area, "m^2", error)
    if (trim(a_kind) == "point_mass") call require_positive(f, "line_scene", "a_mass", a_mass, "kg", error)
    if (trim(b_kind) == "point_mass") call require_positive(f, "line_scene", "b_mass", b_mass, "kg", error)
    if (.not. allocated(error)) call read_canopy(f, a_kind, b_kind, merge(a_mass, b_mass, trim(a_kind) == &
      "canopy"), merge(a_drag_area, b_drag_area, trim(a_kind) == "canopy"), air, run%t_end, chute, chute_echo, error)
    call require_choice(f, "line_scene", "initial_shape", initial_shape, &
      [character(len=16) :: "straight", "sag"], error)
    call require_nonnegative(f, "line_scene", "initial_sag", initial_sag, "m", error)
    call require_choice(f, "line_scene", "scheme", scheme, [character(len=16) :: "cvode", "marching"], error)
    call require_choice(f, "line", "mass", mass, [character(len=16) :: "lumped", "mixed"], error)
    if (allocated(error)) return

    cfg%line = line_params(length=length, n_seg=n_seg, ea=ea, mass_per_length=mass_per_length, &
      damping=damping, settling_damping=settling_damping, diameter=diameter, cd_normal=cd_normal, &
      cd_tangential=cd_tangential, gravity=gravity, air=air, wind=wind, air_density=air_density, mass=mass)
    cfg%end_a = line_end(kind=end_kind_code(a_kind), position=a_position, velocity=a_velocity, &
      amplitude=a_amplitude, frequency=a_frequency, phase_deg=a_phase_deg, t_start=a_t_start, mass=a_mass, &
      drag_area=a_drag_area)
    cfg%end_b = line_end(kind=end_kind_code(b_kind), position=b_position, velocity=b_velocity, &
      amplitude=b_amplitude, frequency=b_frequency, phase_deg=b_phase_deg, t_start=b_t_start, mass=b_mass, &
      drag_area=b_drag_area)
    if (trim(a_kind) == "canopy") cfg%end_a = canopy_end(cfg%end_a, chute)
    if (trim(b_kind) == "canopy") cfg%end_b = canopy_end(cfg%end_b, chute)
    cfg%initial_shape = initial_shape
    cfg%initial_sag = initial_sag
    cfg%breaking_strength = breaking_strength
    cfg%break_time = break_time
    cfg%break_segment = break_segment
    cfg%weak_link_strength = weak_link_strength
    cfg%weak_link_segment = weak_link_segment
    cfg%ground = ground
    cfg%ground_altitude = ground_altitude
    cfg%integration%scheme = scheme
    cfg%integration%dt = dt
    cfg%integration%force_tol = force_tol
    cfg%integration%max_iterations = max_iterations
    cfg%integration%peak_tension = peak_tension
    if (f%is_set("run", "rtol")) cfg%integration%rtol = run%rtol
    if (f%is_set("run", "atol")) cfg%integration%atol = run%atol
    if (f%is_set("run", "max_order")) cfg%integration%max_order = run%max_order
    cfg%integration%max_steps = run%max_steps
    cfg%integration%max_wall_time = run%max_wall_time
    cfg%t_end = run%t_end
    cfg%output_interval = run%output_dt
    cfg%record_nodes = run%trajectory
    cfg%record_tensions = record_tensions .and. run%trajectory
    cfg%record_rigid = run%trajectory
    call check_scene_combinations(f, run, cfg, a_kind, b_kind, error)
    if (allocated(error)) return
    weak_link_segment = cfg%weak_link_segment   ! (resolved there: the echo gives it)

    ! the geometry and the scheme's stability are checked by building the scene
    call probe_scene(cfg, error)
    if (allocated(error)) then
      if (index(error%message, "&line: ") == 1) then   ! (prepare_break: a strength)
        error%message = f%path // ": " // error%message
        return
      end if
      if (index(error%message, "line_scene: ") == 1) error%message = error%message(13:)
      error%message = f%path // ": &line_scene: " // error%message
      return
    end if

    do while (line_buffer%another_try())
      write(line_buffer%lines, nml=line, iostat=line_buffer%ios)
    end do
    call line_buffer%append_to(echo)
    do while (scene_buffer%another_try())
      write(scene_buffer%lines, nml=line_scene, iostat=scene_buffer%ios)
    end do
    call scene_buffer%append_to(echo)
    if (allocated(chute_echo)) echo = echo // chute_echo
  end subroutine read_line_scene_config

  !> The scene's choices that exclude each other (the paper's marching with the
  !> mixed mass, a line break, a ground or too many steps; a strength nothing
  !> watches; a ground altitude without a ground), checked on the resolved
  !> scene; each refusal names the variables, the values and what is allowed.
  !> An unset weak_link_segment becomes the last segment (check_weak_link).
  subroutine check_scene_combinations(f, run, cfg, a_kind, b_kind, error)
    type(nml_file), intent(in) :: f                       !< scanned input
    type(run_config), intent(in) :: run                   !< &run settings
    type(line_scene_config), intent(inout) :: cfg         !< resolved scene
    character(len=*), intent(in) :: a_kind, b_kind        !< &line_scene a_kind, b_kind
    type(error_type), allocatable, intent(inout) :: error !< set on bad input
    type(line_scene_config) :: d

    if (trim(cfg%integration%scheme) == "marching" .and. trim(cfg%line%mass) == "mixed") call fatal_error(error, &
      f%path // ": &line: mass = 'mixed' is not allowed with scheme = 'marching': the paper's " // &
      "explicit marching needs the lumped (diagonal) mass; use mass = 'lumped' (the default)")
    if (trim(cfg%integration%scheme) == "marching") then
      call require_positive(f, "line_scene", "dt", cfg%integration%dt, "s", error)
      call require_positive(f, "line_scene", "force_tol", cfg%integration%force_tol, "N", error)
      call require_int_range(f, "line_scene", "max_iterations", cfg%integration%max_iterations, 1, 1000, error)
    end if
    call check_break(f, "direct", cfg%line%n_seg, cfg%breaking_strength, cfg%break_time, cfg%break_segment, &
      scene_line_ends, error)
    call check_weak_link(f, "direct", cfg%line%n_seg, cfg%breaking_strength, cfg%weak_link_strength, &
      cfg%weak_link_segment, scene_line_ends, error)
    if (allocated(error)) return
    if ((cfg%breaking_strength > 0.0_dp .or. cfg%weak_link_strength > 0.0_dp .or. cfg%break_time > 0.0_dp) .and. &
        trim(cfg%integration%scheme) == "marching") then
      call fatal_error(error, f%path // ": &line: a line break (breaking_strength, weak_link_strength or " // &
        "break_time) is not allowed with scheme = 'marching' (the paper's explicit marching neither locates " // &
        "the break nor restarts on the parted line: use scheme = 'cvode', the default)")
      return
    end if
    call check_break_before_end(f, cfg%break_time, run%t_end, error)
    if (allocated(error)) return
    ! (the default value passes: the resolved input, run again, sets it)
    if (.not. cfg%ground .and. cfg%ground_altitude /= d%ground_altitude) then
      call fatal_error(error, f%path // ": &line_scene: ground_altitude = " // str(cfg%ground_altitude) // &
        " m is not allowed with ground = .false. (the default: the scene has no ground); set ground = .true.")
      return
    end if
    if (cfg%ground) then
      if (trim(cfg%integration%scheme) == "marching") then
        call fatal_error(error, f%path // ": &line_scene: ground_altitude = " // str(cfg%ground_altitude) // &
          " m is not allowed with scheme = 'marching' (the paper's explicit marching does not locate events: " // &
          "use scheme = 'cvode', the default)")
        return
      end if
    end if
    if ((cfg%breaking_strength > 0.0_dp .or. cfg%weak_link_strength > 0.0_dp) .and. cfg%line%n_seg == 1 .and. &
        is_kinematic(a_kind) .and. is_kinematic(b_kind)) then
      ! no node of the line is integrated: nothing would watch the strength
      call fatal_error(error, f%path // ": &line: " // trim(merge("breaking_strength ", "weak_link_strength", &
        cfg%breaking_strength > 0.0_dp)) // " = " // str(max(cfg%breaking_strength, cfg%weak_link_strength)) // &
        " N is not allowed on a line of n_seg = 1 between two kinematic ends (a_kind = '" // trim(a_kind) // &
        "', b_kind = '" // trim(b_kind) // "'): no node of it is integrated, so no event watches its " // &
        "tension; use n_seg >= 2 (break_time cuts it at a given time)")
      return
    end if

    if (trim(cfg%integration%scheme) == "marching" .and. run%max_steps > 0) then
      if (run%t_end/cfg%integration%dt > run%max_steps) then
        call fatal_error(error, f%path // ": &line_scene: dt = " // str(cfg%integration%dt) // &
          " s is not allowed with t_end = " // str(run%t_end) // " s (" // str(run%t_end/cfg%integration%dt) // " marching steps; &run max_steps = " // &
          str(run%max_steps) // ": raise dt or max_steps)")
        return
      end if
    end if
  end subroutine check_scene_combinations

  !> The canopy of a 'canopy' end: the group &parachute (the air-launch
  !> scene's, docs/input.md), allowed only with such an end.  Its mass and
  !> drag areas are the group's: the end's a_/b_mass and a_/b_drag_area must
  !> stay 0 (the default, which the resolved input echoes).
  subroutine read_canopy(f, a_kind, b_kind, point_mass, point_drag_area, air, t_end, chute, echo, error)
    type(nml_file), intent(in) :: f                        !< scanned input
    character(len=*), intent(in) :: a_kind, b_kind         !< the ends' kinds
    real(dp), intent(in) :: point_mass, point_drag_area    !< the canopy end's a_/b_mass, a_/b_drag_area
    logical, intent(in) :: air                             !< &line air
    real(dp), intent(in) :: t_end                          !< &run t_end [s]
    type(parachute), intent(out) :: chute                  !< the canopy
    character(len=:), allocatable, intent(inout) :: echo   !< the resolved &parachute
    type(error_type), allocatable, intent(inout) :: error  !< set on bad input
    character(len=1) :: e
    character(len=*), parameter :: where = "the canopy's mass and drag areas are &parachute mass, " // &
      "drag_area and packed_drag_area"
    if (trim(a_kind) /= "canopy" .and. trim(b_kind) /= "canopy") then
      if (f%has_group("parachute")) call fatal_error(error, f%path // ": &parachute: the group is not " // &
        "allowed without a canopy end (a_kind or b_kind = 'canopy'; a point_mass end takes a_/b_mass and " // &
        "a_/b_drag_area)")
      return
    end if
    if (trim(a_kind) == "canopy" .and. trim(b_kind) == "canopy") then
      call fatal_error(error, f%path // ": &line_scene: a_kind = 'canopy' is not allowed with b_kind = " // &
        "'canopy': one &parachute group describes one canopy; make one end a point_mass")
      return
    end if
    e = merge("a", "b", trim(a_kind) == "canopy")
    if (point_mass /= 0.0_dp) then
      call fatal_error(error, f%path // ": &line_scene: " // e // "_mass = " // str(point_mass) // " kg is not " // &
        "allowed with " // e // "_kind = 'canopy' (must be 0, the default): " // where)
      return
    end if
    if (point_drag_area /= 0.0_dp) then
      call fatal_error(error, f%path // ": &line_scene: " // e // "_drag_area = " // str(point_drag_area) // &
        " m^2 is not allowed with " // e // "_kind = 'canopy' (must be 0, the default): " // where)
      return
    end if
    if (.not. air) then
      call fatal_error(error, f%path // ": &line: air = .false. is not allowed with " // e // "_kind = " // &
        "'canopy' (a canopy's drag, filling and apparent mass come from the air): set air = .true. " // &
        "(the line scene's default is .false.), or use a point_mass end")
      return
    end if
    call read_parachute(f, chute, echo, error)
    if (allocated(error)) return
    if (chute%deploy_time >= t_end) call fatal_error(error, f%path // ": &parachute: deploy_time = " // &
      str(chute%deploy_time) // " s is not allowed: must be < &run t_end = " // str(t_end) // &
      " s (the canopy would never inflate; < 0: open from the start)")
  end subroutine read_canopy

  !> A point-mass end carrying the canopy `chute` (its mass the canopy's).
  pure function canopy_end(base, chute) result(en)
    type(line_end), intent(in) :: base     !< the end as read (kind, position, velocity)
    type(parachute), intent(in) :: chute   !< the canopy
    type(line_end) :: en
    en = base
    en%kind = end_point_mass
    en%mass = chute%mass
    en%drag_area = 0.0_dp
    en%canopy_end = .true.
    en%canopy = chute
  end function canopy_end

  !> Build the scene once to check what the single values cannot show (end
  !> geometry, stability of the marching step).  (A separate procedure: the
  !> reader's namelist group &line_scene hides the type name there.)
  subroutine probe_scene(cfg, error)
    type(line_scene_config), intent(in) :: cfg             !< scene
    type(error_type), allocatable, intent(inout) :: error  !< set on bad input
    type(line_scene) :: probe
    type(line_scene_config) :: small
    small = cfg
    small%t_end = min(cfg%t_end, cfg%output_interval)   ! no need for the full record arrays
    call probe%init(small, error)
    call probe%free()
  end subroutine probe_scene

  !> Run the scene and write its output file (if &run trajectory); `summary`
  !> receives the milestones for the program to print.  On a numerical
  !> failure the output so far is written with status = "failed".
  subroutine run_line_scene(run, cfg, echo, summary, error, result)
    type(run_config), intent(in) :: run                   !< &run settings
    type(line_scene_config), intent(in) :: cfg            !< the scene
    character(len=*), intent(in) :: echo                  !< resolved input
    character(len=:), allocatable, intent(out) :: summary !< milestones, one per line
    type(error_type), allocatable, intent(inout) :: error !< set on failure
    type(line_result), intent(out), optional :: result    !< the milestones as numbers (a sweep's row)
    type(line_scene) :: scene
    type(error_type), allocatable :: run_error
    integer :: m, i_max(2)
    character(len=1), parameter :: nl = new_line("a")

    call scene%init(cfg, error)
    if (allocated(error)) then
      call scene%free()   ! the integrator may be built (CVODE's C objects have no finaliser)
      return
    end if
    call scene%run(run_error)
    m = scene%n_out
    if (present(result)) result = result_of(scene)
    if (run%trajectory) call write_output(scene, run%output, echo, run_error, error)
    if (present(result) .and. allocated(error)) result%output_error = error%message
    i_max = maxloc(scene%end_tension(:, 1:m))
    summary = "line: " // str(cfg%line%length) // " m, " // str(cfg%line%n_seg) // " segments, scheme " // &
      trim(cfg%integration%scheme) // ", " // trim(cfg%line%mass) // " mass" // nl // &
      canopy_note(scene) // initial_note(scene) // nl // &
      end_note(scene) // str(int(scene%stats%steps)) // " steps, " // str(int(scene%stats%rhs_evals)) // &
      " force evaluations, " // scheme_work(cfg%integration%scheme, scene%stats) // "wall " // &
      str(scene%wall_time) // " s" // nl // &
      "largest end tension " // str(scene%end_tension(i_max(1), i_max(2))) // " N at end " // &
      merge("a", "b", i_max(1) == 1) // ", t = " // str(scene%time(i_max(2))) // " s (records); at the end (t = " // &
      str(scene%time(m)) // " s): a " // str(scene%end_tension(1, m)) // " N, b " // str(scene%end_tension(2, m)) // &
      " N" // peak_note(scene) // nl // break_note(scene) // ground_note(scene) // &
      "equivalent rigid body at the end" // piece_note(scene%rigid(m), scene%model%n) // ": d_rigid " // &
      str(scene%rigid(m)%d_rigid) // " m, m_rigid " // &
      str(scene%rigid(m)%m_rigid) // " kg" // m_rigid_note(scene%rigid(m)) // ", theta " // str(scene%rigid(m)%theta*rad2deg) // " deg, phi " // &
      str(scene%rigid(m)%phi*rad2deg) // " deg" // nl // energy_summary(scene)
    if (allocated(run_error)) then
      call add_output_error(run_error, error)
      call move_alloc(run_error, error)
    end if
    call scene%free()
  end subroutine run_line_scene

  !> The scene's milestones as numbers (line_result).
  function result_of(scene) result(r)
    type(line_scene), intent(in) :: scene  !< scene (after run)
    type(line_result) :: r
    integer :: m
    m = scene%n_out
    if (scene%peak_tension_time >= 0.0_dp) then
      r%peak_tension = scene%peak_tension
      r%peak_tension_time = scene%peak_tension_time
      r%peak_tension_segment = scene%peak_tension_segment
    end if
    if (m > 0) then
      r%max_end_tension = maxval(scene%end_tension(:, 1:m), dim=2)
      r%final_tip_speed = norm2(scene%tip_velocity(:, m))
    end if
    r%line_break_time = scene%line_break_time
    r%line_break_segment = scene%line_break_segment
    r%line_breaks = scene%line_breaks
    r%recoil_speed = scene%recoil_speed
    r%deploy_speed = scene%deploy_speed
    r%ground_time = scene%ground_time
    r%ground_speed = scene%ground_speed
    r%end_time = scene%t_reached
    r%stats = scene%stats
    r%completed = scene%completed
  end function result_of

  !> The summary's note on the peak tension over every step ('' without it:
  !> &line_scene peak_tension = .false.).
  function peak_note(scene) result(text)
    type(line_scene), intent(in) :: scene  !< scene (after run)
    character(len=:), allocatable :: text
    text = ""
    if (scene%peak_tension_time >= 0.0_dp) text = "; peak segment tension " // str(scene%peak_tension) // &
      " N in segment " // str(scene%peak_tension_segment) // ", first reached at t = " // &
      str(scene%peak_tension_time) // " s (over every step)"
  end function peak_note

  !> The summary's line on the line's break ('' for a line that cannot part).
  function break_note(scene) result(text)
    type(line_scene), intent(in) :: scene  !< scene (after run)
    character(len=:), allocatable :: text
    text = ""
    if (.not. (allocated(scene%strength) .or. scene%cfg%break_time > 0.0_dp)) return
    text = "line break: none" // new_line("a")
    if (scene%line_breaks > 0) text = "line break: segment " // str(scene%line_break_segment) // " parted at t = " // &
      str(scene%line_break_time) // " s, " // str(scene%line_breaks) // " segment(s) in all" // &
      cascade_note(scene%line_breaks) // "; recoil " // &
      str(scene%recoil_speed) // " m/s (the largest change of a node's velocity within 2 L/c of it)" // &
      new_line("a")
  end function break_note

  !> The summary's line on the ground ('' without one: no ground_altitude).
  function ground_note(scene) result(text)
    type(line_scene), intent(in) :: scene  !< scene (after run)
    character(len=:), allocatable :: text
    text = ""
    if (.not. scene%cfg%ground) return
    text = "ground (" // str(scene%cfg%ground_altitude) // " m): not reached" // new_line("a")
    if (scene%ground_time >= 0.0_dp) text = "ground (" // str(scene%cfg%ground_altitude) // " m): reached by node " // &
      str(scene%ground_node) // " at t = " // str(scene%ground_time) // " s, speed " // str(scene%ground_speed) // &
      " m/s (the run ends there)" // new_line("a")
  end function ground_note

  !> The summary's line on the initial shape: its largest segment strain and
  !> tension EA eps (the shape 'sag' has the parabola's length, not L's).
  function initial_note(scene) result(text)
    type(line_scene), intent(in) :: scene  !< scene (after init)
    character(len=:), allocatable :: text
    text = "initial shape " // trim(scene%cfg%initial_shape)
    if (scene%cfg%initial_shape == "sag") text = text // " (midspan sag " // str(scene%cfg%initial_sag) // " m)"
    text = text // ": largest segment strain " // str(100*scene%initial_strain) // " %"
    if (scene%initial_strain > 0.0_dp) then
      text = text // " (tension " // str(scene%cfg%line%ea*scene%initial_strain) // " N)"
    else
      text = text // " (slack)"
    end if
  end function initial_note

  !> "end of run at t = ... s (completed), " or, after a failure, the time the
  !> integration reached and the last record's.
  function end_note(scene) result(s)
    type(line_scene), intent(in) :: scene   !< the run
    character(len=:), allocatable :: s
    if (scene%completed) then
      s = "end of run at t = " // str(scene%time(scene%n_out)) // " s (completed), "
    else
      s = "end of run at t = " // str(scene%t_reached) // " s (failed; last record at t = " // &
        str(scene%time(scene%n_out)) // " s), "
    end if
  end function end_note

  !> Which piece of a parted line the equivalent rigid body describes
  !> (whole_piece); nothing for the whole line.
  function piece_note(q, n) result(s)
    type(rigid_equivalent), intent(in) :: q
    integer, intent(in) :: n                !< the line's segments
    character(len=:), allocatable :: s
    s = ""
    if (q%first_node == 0 .and. q%last_node == n) return
    s = " (of the piece at end " // merge("a", "b", q%first_node == 0) // ", nodes " // str(q%first_node) // &
      " to " // str(q%last_node) // ": the line has parted)"
  end function piece_note

  !> What the printed m_rigid is against the line's own mass: the line mass
  !> itself when the centre does not move (the guard), else their ratio, with a
  !> word when it is large: Eq. (31) divides by |V_rigid|^2, so a deforming
  !> line whose centre moves slowly against its nodes has a huge m_rigid
  !> (docs/line.md §3).
  function m_rigid_note(q) result(s)
    type(rigid_equivalent), intent(in) :: q
    character(len=:), allocatable :: s
    real(dp) :: ratio
    if (q%m_fallback) then
      s = " (the line mass: the centre does not move, |V_rigid| ~ 0)"
      return
    end if
    ratio = q%m_rigid/q%line_mass
    s = " (" // fixed(ratio, 3) // " x the line mass"
    if (ratio > 10.0_dp) s = s // "; Eq. (31) is ill-conditioned here: the centre moves slowly against the nodes"
    s = s // ")"
  end function m_rigid_note

  !> Write the records of `scene` as netCDF-4 (docs/line.md, "Output").
  subroutine write_output(scene, path, echo, run_error, error)
    type(line_scene), intent(in) :: scene                 !< the run
    character(len=*), intent(in) :: path, echo            !< output file, resolved input
    type(error_type), allocatable, intent(in) :: run_error  !< the run's failure, if any
    type(error_type), allocatable, intent(inout) :: error !< set if writing fails
    type(nc_writer) :: w
    integer :: m, n, i, k
    real(dp), allocatable :: r1(:), r3(:, :)
    type(line_end) :: chute_end
    m = scene%n_out
    n = scene%model%n
    call w%create(path, error)
    if (allocated(error)) return
    call w%add_dim("time", scene%time(1:m), "s", "time", error)
    call w%add_dim("node", [(real(k, dp), k = 0, n)], "1", "line node index, 0 = end a ... N = end b", error)
    call w%add_dim("segment", [(real(k, dp), k = 1, n)], "1", "line segment index k (nodes k-1, k)", error)
    call w%add_dim("xyz", [0.0_dp, 1.0_dp, 2.0_dp], "1", &
      "component: 0 = x forward, 1 = y up, 2 = z right (earth), or body axes 0 = x, 1 = y, 2 = z", error)
    call w%add_dim("end", [0.0_dp, 1.0_dp], "1", "line end: 0 = end a (node 0), 1 = end b (node N)", error)
    if (allocated(scene%nodes)) call w%add_var_3d("line_node_position", ["xyz    ", "node   ", "time   "], &
      scene%nodes(:, :, 1:m), "m", "line node positions (earth frame)", error)
    if (allocated(scene%tensions)) call w%add_var_2d("line_tension", ["segment", "time   "], &
      scene%tensions(:, 1:m), "N", "segment tensions T = max(0, EA eps + c_d epsdot), 0 when slack", error)
    call w%add_var_2d("line_end_tension", ["end ", "time"], scene%end_tension(:, 1:m), "N", &
      "tension of the end segments (segment 1 at end a, segment N at end b)", error)
    call w%add_var_3d("line_end_force", ["xyz ", "end ", "time"], scene%end_force(:, :, 1:m), "N", &
      "force of the line on its end nodes: end tension plus the end half-segment's weight and drag", error)
    call w%add_var_2d("line_tip_position", ["xyz ", "time"], scene%tip(:, 1:m), "m", &
      "position of node N (end b), earth frame", error)
    call w%add_var_2d("line_tip_velocity", ["xyz ", "time"], scene%tip_velocity(:, 1:m), "m s-1", &
      "velocity of node N (end b), earth frame", error)
    call w%add_var_3d("line_end_velocity", ["xyz ", "end ", "time"], scene%end_velocity(:, :, 1:m), "m s-1", &
      "velocity of the end nodes (node 0 at end a, node N at end b), earth frame", error)
    allocate(r1(m), r3(3, m))
    r1 = scene%energy(1, 1:m)
    call w%add_var_1d("line_energy_kinetic", ["time"], r1, "J", &
      "kinetic energy of the line and its point-mass ends", error)
    r1 = scene%energy(2, 1:m)
    call w%add_var_1d("line_energy_elastic", ["time"], r1, "J", &
      "elastic energy of the line, sum of 1/2 EA l0 eps^2 over taut segments", error)
    r1 = scene%energy(3, 1:m)
    call w%add_var_1d("line_energy_potential", ["time"], r1, "J", &
      "gravitational potential energy (zero level y = 0)", error)
    call w%add_int_var_1d("rigid_first_node", ["time"], [(scene%rigid(i)%first_node, i = 1, m)], "1", &
      "first node of the line the rigid_* variables describe: 0, or after a break the piece at end b's", error)
    call w%add_int_var_1d("rigid_last_node", ["time"], [(scene%rigid(i)%last_node, i = 1, m)], "1", &
      "last node of the line the rigid_* variables describe: N, or after a break the piece at end a's", error)
    r1 = [(scene%rigid(i)%d, i = 1, m)]
    call w%add_var_1d("rigid_d", ["time"], r1, "m", "deformed arc length d of the line, Eq. (18)", error)
    r1 = [(scene%rigid(i)%d_rigid, i = 1, m)]
    call w%add_var_1d("rigid_d_rigid", ["time"], r1, "m", "equivalent rigid length d_rigid, Eq. (20)", error)
    r1 = [(scene%rigid(i)%theta*rad2deg, i = 1, m)]
    call w%add_var_1d("rigid_theta_deg", ["time"], r1, "degree", "Euler angle theta_rigid, Eq. (24)", error)
    r1 = [(scene%rigid(i)%phi*rad2deg, i = 1, m)]
    call w%add_var_1d("rigid_phi_deg", ["time"], r1, "degree", "Euler angle phi_rigid, Eq. (24)", error)
    r1 = [(scene%rigid(i)%m_rigid, i = 1, m)]
    call w%add_var_1d("rigid_mass", ["time"], r1, "kg", &
      "equivalent mass m_rigid, Eq. (31) (translational kinetic-energy equivalence)", error)
    do i = 1, m
      r3(:, i) = scene%rigid(i)%j_rigid
    end do
    call w%add_var_2d("rigid_inertia", ["xyz ", "time"], r3, "kg m2", &
      "equivalent moments of inertia about the virtual body's axes, Eq. (32) (z, along the line: " // &
      "the geometric inertia about the chord)", error)
    do i = 1, m
      r3(:, i) = scene%rigid(i)%omega_body
    end do
    call w%add_var_2d("rigid_omega", ["xyz ", "time"], r3, "rad s-1", &
      "angular velocity omega_rigid in the virtual body's axes (z along the line), Eq. (27)", error)
    do i = 1, m
      r3(:, i) = scene%rigid(i)%v_rigid
    end do
    call w%add_var_2d("rigid_velocity", ["xyz ", "time"], r3, "m s-1", &
      "velocity V_rigid of the virtual body's centre (earth frame), Eq. (29)", error)
    do i = 1, m
      r3(:, i) = scene%rigid(i)%v_eps
    end do
    call w%add_var_2d("rigid_v_eps", ["xyz ", "time"], r3, "m s-1", &
      "deformation velocity V_eps (earth frame), Eq. (25)", error)
    call write_run_metadata(w, "line", "airlaunch: standalone flexible line", echo, error)
    call w%add_text_att("/", "scheme", trim(scene%cfg%integration%scheme), error)
    call w%add_text_att("/", "mass_matrix", trim(scene%cfg%line%mass), error)
    call w%add_real_att("/", "initial_strain", scene%initial_strain, error)
    call w%add_real_att("/", "wall_time_s", scene%wall_time, error)
    call w%add_int_att("/", "steps", [int(min(scene%stats%steps, int(huge(1), kind(scene%stats%steps))))], error)
    if (scene%peak_tension_time >= 0.0_dp) then
      call w%add_real_att("/", "peak_tension_N", scene%peak_tension, error)
      call w%add_real_att("/", "peak_tension_time_s", scene%peak_tension_time, error)
      call w%add_int_att("/", "peak_tension_segment", [scene%peak_tension_segment], error)
    end if
    call w%add_real_att("/", "line_break_time_s", scene%line_break_time, error)
    call w%add_int_att("/", "line_break_segment", [scene%line_break_segment], error)
    call w%add_int_att("/", "line_breaks", [scene%line_breaks], error)
    call w%add_real_att("/", "line_recoil_speed_m_s", scene%recoil_speed, error)
    if (scene%cfg%ground) then
      call w%add_real_att("/", "ground_time_s", scene%ground_time, error)
      call w%add_int_att("/", "ground_node", [scene%ground_node], error)
      call w%add_real_att("/", "ground_speed_m_s", scene%ground_speed, error)
    end if
    if (scene%line_breaks > 0) call w%add_int_att("/", "line_parted_segments", &
      pack([(k, k = 1, n)], scene%model%parted), error)
    call w%add_text_att("/", "status", run_status(run_error), error)
    if (allocated(run_error)) call w%add_text_att("/", "failure", run_error%message, error)
    if (is_passive(scene%cfg)) call w%add_real_att("/", "max_energy_rise_J", energy_rise(scene), error)
    chute_end = canopy_end_of(scene%cfg)
    if (chute_end%inflating() .and. scene%deploy_speed > 0.0_dp) then   ! (a failed run may stop before it)
      call w%add_real_att("/", "canopy_fill_time_s", chute_end%canopy%fill_time, error)
      call w%add_real_att("/", "canopy_deploy_air_speed_m_s", scene%deploy_speed, error)
    end if
    call w%finish(error)
  end subroutine write_output

  !> The deploying canopy's filling (a line of its own), or nothing.
  function canopy_note(scene) result(note)
    type(line_scene), intent(in) :: scene   !< the run
    character(len=:), allocatable :: note
    type(line_end) :: en
    note = ""
    en = canopy_end_of(scene%cfg)
    if (.not. en%inflating()) return
    if (scene%deploy_speed > 0.0_dp) then
      note = "canopy: deploys at t = " // str(en%canopy%deploy_time) // " s into " // str(scene%deploy_speed) // &
        " m/s of air speed, fills in t_f = n D0 / V = " // str(en%canopy%fill_time) // " s" // new_line("a")
    else
      note = "canopy: deploys at t = " // str(en%canopy%deploy_time) // " s (not reached)" // new_line("a")
    end if
  end function canopy_note

  !> The scene's canopy end (at most one), or end b if it has none.
  pure function canopy_end_of(cfg) result(en)
    type(line_scene_config), intent(in) :: cfg   !< the scene
    type(line_end) :: en
    en = cfg%end_b
    if (cfg%end_a%canopy_end) en = cfg%end_a
  end function canopy_end_of

  !> A line that nothing does work on: no end moved on a path (fixed, free and
  !> point-mass ends) and no wind (in still air, drag, the dashpot and the
  !> settling damping only dissipate).  Its total energy can only fall.
  pure logical function is_passive(cfg)
    type(line_scene_config), intent(in) :: cfg  !< the scene
    is_passive = all([cfg%end_a%kind, cfg%end_b%kind] /= end_prescribed) .and. &
      all([cfg%end_a%kind, cfg%end_b%kind] /= end_body) .and. &
      .not. (cfg%line%air .and. any(cfg%line%wind /= 0.0_dp))
  end function is_passive

  !> Largest rise of the total (kinetic + elastic + potential) energy above its
  !> initial value over the records [J]; the invariant of a passive line is
  !> that it stays at zero up to the integration error.
  pure real(dp) function energy_rise(scene)
    type(line_scene), intent(in) :: scene  !< the run
    integer :: m
    m = scene%n_out
    energy_rise = maxval(sum(scene%energy(:, 1:m), dim=1)) - sum(scene%energy(:, 1))
  end function energy_rise

  !> The summary's energy line: the passive line's invariant, or why there is none.
  function energy_summary(scene) result(text)
    type(line_scene), intent(in) :: scene  !< the run
    character(len=:), allocatable :: text
    real(dp) :: kmax, rise
    if (.not. is_passive(scene%cfg)) then
      text = "energy: not checked (a moving end or the wind does work on the line)"
      return
    end if
    kmax = maxval(scene%energy(1, 1:scene%n_out))
    rise = energy_rise(scene)
    text = "energy (passive line, may only fall): largest rise above the initial total " // str(rise) // " J"
    if (kmax > 0.0_dp) text = text // " (" // str(100.0_dp*rise/kmax) // &
      " % of the largest kinetic energy, " // str(kmax) // " J)"
  end function energy_summary
  !> The scheme's own work counters for the summary, each followed by ", ".
  function scheme_work(scheme, stats) result(text)
    character(len=*), intent(in) :: scheme       !< "cvode" or "marching"
    type(line_scheme_stats), intent(in) :: stats !< counters of the run
    character(len=:), allocatable :: text
    if (scheme == "marching") then
      text = str(int(stats%iterations)) // " far-end iterations, "
    else
      text = str(int(stats%jac_evals)) // " Jacobians, " // str(int(stats%failures)) // &
        " failed steps (error test or Newton), "
    end if
  end function scheme_work

end module airlaunch_line_scene
