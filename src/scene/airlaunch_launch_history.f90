!> What the air-launch scene records, shared by its two line couplings
!> (direct, and rigidized in the submodule airlaunch_launch_rigidized): the
!> milestones of a run, the sampled history of the output contract
!> (docs/output.md) and its netCDF writer.
module airlaunch_launch_history
  use airlaunch_kinds, only: dp, g0, rad2deg
  use airlaunch_error, only: error_type
  use airlaunch_rotation, only: dcm_to_euler, nose_elevation
  use airlaunch_cvode, only: cvode_stats
  use airlaunch_ncwrite, only: nc_writer
  use airlaunch_scenario_config, only: scenario_config
  use airlaunch_separation, only: separation_system, ground_at_cg, ground_at_nose, ground_at_tail
  use airlaunch_cut_joint, only: phase_free, phase_name
  use airlaunch_strings, only: str
  use airlaunch_launch_loads, only: launch_loads
  use airlaunch_clearance, only: clearance_geometry, clearance, segment_distance, set_fins
  use airlaunch_atmosphere, only: isa, air_state
  use airlaunch_gust, only: air_relative_velocity
  implicit none
  private
  public :: launch_result, launch_sample, launch_history, sample_launch, record_milestones, history_bytes
  public :: handle_launch_event, rocket_pitch_rate
  public :: write_milestones, event_or_minus, clearance_geometry_of, ground_body_name, ground_point_name

  !> Milestones of one run (also the summary row of a sweep case).
  type :: launch_result
    character(len=16) :: status = "completed"
    character(len=:), allocatable :: failure
    real(dp) :: trim_alpha_deg = 0.0_dp, trim_elevator_deg = 0.0_dp, trim_thrust_n = 0.0_dp
    real(dp) :: trim_cl0 = 0.0_dp, trim_cm0 = 0.0_dp   !< the aircraft's C_L0, C_m0 after the trim
    integer :: trim_passes = 1                    !< trim-and-settle passes (the line's force at the tie-down)
    real(dp) :: trim_line_force_change_n = 0.0_dp !< change of that force in the last pass [N]
    real(dp) :: release_time = -1.0_dp, edge_time = -1.0_dp, separation_time = -1.0_dp
    logical :: early_separation = .false.
    real(dp) :: edge_pull_time = -1.0_dp   !< bilateral edge: first time the edge had to pull [s]
    real(dp) :: pitch_at_separation_deg = 0.0_dp, pitch_rate_at_separation_deg_s = 0.0_dp
    real(dp) :: pitch_max_time = -1.0_dp, pitch_max_deg = 0.0_dp, nose_elevation_at_max_deg = 0.0_dp
    real(dp) :: min_clearance = huge(1.0_dp), peak_tension = 0.0_dp, peak_tension_time = -1.0_dp
    !> smallest distance from the aircraft's empennage point to the line [m]
    !> (huge: no line, or a run that failed before its first step)
    real(dp) :: min_line_clearance = huge(1.0_dp)
    !> smallest rocket-empennage clearance from the release on (every step of
    !> the integrators, refined between them) [m] and its time [s] (huge, -1:
    !> no step after the release)
    real(dp) :: min_exit_clearance = huge(1.0_dp), min_exit_clearance_time = -1.0_dp
    real(dp) :: max_aircraft_pitch_excursion_deg = 0.0_dp, max_load_factor_excursion = 0.0_dp
    real(dp) :: max_constraint_residual = 0.0_dp
    real(dp) :: line_break_time = -1.0_dp    !< the line first parted [s] (-1: it did not)
    integer :: line_break_segment = 0        !< there, at this segment (1: the rocket's tie-down; 0: whole)
    integer :: line_breaks = 0               !< segments parted in all
    integer, allocatable :: parted_segments(:)  !< which (ascending; unallocated: none)
    real(dp) :: max_quaternion_norm_error = 0.0_dp  !< largest | |q| - 1 | of the integrated quaternions
    !> the aircraft's CG or the rocket's lowest point reached &flight ground_altitude
    !> (the run ended there) [s] (-1: none)
    real(dp) :: ground_time = -1.0_dp
    integer :: ground_body = -1               !< which: 0 aircraft, 1 rocket (-1: none)
    !> where: airlaunch_separation's ground_at_cg, _nose or _tail (-1: none)
    integer :: ground_point = -1
    real(dp) :: ground_speed = 0.0_dp         !< that point's speed there, earth frame [m/s]
    real(dp) :: end_time = 0.0_dp
    logical :: has_line = .true.   !< false: no line (no peak tension; its attributes are left out)
    type(cvode_stats) :: stats
    !> Set when the trajectory file could not be written: the writer's message
    !> (kept even when the run failed too, whose error is the one returned)
    character(len=:), allocatable :: output_error
  end type launch_result

  !> The state of the rigid part at one instant, as the outputs see it.
  type :: launch_sample
    real(dp) :: aircraft_euler(3) = 0.0_dp   !< [rad]
    real(dp) :: rocket_euler(3) = 0.0_dp     !< [rad]
    real(dp) :: pitch_rate = 0.0_dp          !< rocket Euler pitch rate [rad/s]
    real(dp) :: load_factor = 1.0_dp         !< aircraft n along body y
    real(dp) :: clearance = 0.0_dp           !< rocket surface to the empennage point [m]
    real(dp) :: edge_clearance = 0.0_dp      !< rocket surface to the ramp edge after separation [m]
    real(dp) :: alpha = 0.0_dp               !< aircraft angle of attack [rad]
    real(dp) :: elevator = 0.0_dp            !< [rad]
    !> telemetry: what the bodies' inertial sensors and air-data systems would
    !> read (body axes x nose, y up, z right; docs/output.md)
    real(dp) :: aircraft_specific_force(3) = 0.0_dp  !< (a - g) in aircraft axes [m/s^2]
    real(dp) :: rocket_specific_force(3) = 0.0_dp    !< (a - g) at the rocket CG, rocket axes [m/s^2]
    real(dp) :: rocket_wdot(3) = 0.0_dp              !< rocket angular acceleration, rocket axes [rad/s^2]
    real(dp) :: aircraft_beta = 0.0_dp               !< [rad]
    real(dp) :: aircraft_mach = 0.0_dp, aircraft_qbar = 0.0_dp   !< [1], [Pa]
    real(dp) :: rocket_alpha = 0.0_dp, rocket_beta = 0.0_dp      !< at the rocket CG [rad]
    real(dp) :: rocket_mach = 0.0_dp, rocket_qbar = 0.0_dp       !< [1], [Pa]
  end type launch_sample

  !> The sampled history of the output contract.
  type :: launch_history
    integer :: nrec = 0
    logical :: has_line = .true.   !< false: no line and no parachute (their variables are left out)
    real(dp), allocatable :: time(:), phase(:), ac_pos(:, :), ac_eul(:, :), ac_alpha(:), ac_q(:), elev(:), &
      load_factor(:), rk_pos(:, :), rk_vel(:, :), rk_eul(:, :), rk_rate(:), rk_elev(:), pc_pos(:, :), &
      t_rocket(:), t_chute(:), nodes(:, :, :), cforce(:, :), normal(:), friction(:), lock(:), clearance(:), residual(:), &
      edge_clearance(:), ac_vel(:, :), ac_w(:, :), ac_sf(:, :), rk_w(:, :), rk_wdot(:, :), rk_sf(:, :), &
      ac_air(:, :), rk_air(:, :)
  contains
    procedure :: init => history_init
    procedure :: append => history_append
    procedure :: write_contract => history_write_contract
    procedure :: write_telemetry => history_write_telemetry
  end type launch_history

contains

  !> Room for nmax samples of a line with n segments (`has_line` false: no
  !> line, nothing of it is allocated); `stat` nonzero: the memory could not
  !> be had (the run is refused; what was allocated goes with the history).
  subroutine history_init(self, nmax, n, has_line, stat)
    class(launch_history), intent(inout) :: self
    integer, intent(in) :: nmax, n
    logical, intent(in) :: has_line
    integer, intent(out) :: stat
    self%nrec = 0
    self%has_line = has_line
    allocate(self%time(nmax), self%phase(nmax), self%ac_pos(3, nmax), self%ac_eul(3, nmax), self%ac_alpha(nmax), &
      self%ac_q(nmax), self%elev(nmax), self%load_factor(nmax), self%rk_pos(3, nmax), self%rk_vel(3, nmax), &
      self%rk_eul(3, nmax), self%rk_rate(nmax), self%rk_elev(nmax), self%cforce(6, nmax), self%normal(nmax), &
      self%friction(nmax), self%lock(nmax), self%clearance(nmax), self%residual(nmax), self%edge_clearance(nmax), &
      self%ac_vel(3, nmax), self%ac_w(3, nmax), self%ac_sf(3, nmax), self%rk_w(3, nmax), self%rk_wdot(3, nmax), &
      self%rk_sf(3, nmax), self%ac_air(nmax, 3), self%rk_air(nmax, 4), stat=stat)
    if (stat /= 0 .or. .not. self%has_line) return
    allocate(self%pc_pos(3, nmax), self%t_rocket(nmax), self%t_chute(nmax), self%nodes(3, 0:n, nmax), stat=stat)
  end subroutine history_init

  !> Memory of nmax samples [bytes] (history_init; 8-byte reals and integers
  !> alike, an upper bound).
  pure real(dp) function history_bytes(nmax, n, has_line) result(bytes)
    integer, intent(in) :: nmax, n
    logical, intent(in) :: has_line
    bytes = 8.0_dp*real(nmax, dp)*(60.0_dp + merge(5.0_dp + 3.0_dp*(n + 1), 0.0_dp, has_line))
  end function history_bytes

  !> The outputs of the rigid part of `sep` (evaluated at time t) and of the
  !> loads source `iloads`.
  function sample_launch(cfg, sep, iloads) result(s)
    type(scenario_config), intent(in) :: cfg
    type(separation_system), intent(in) :: sep
    integer, intent(in) :: iloads
    type(launch_sample) :: s
    real(dp) :: nose(3), aft(3), edge(3), v_air(3), speed
    type(air_state) :: air
    associate(b0 => sep%bodies(0), b1 => sep%bodies(1))
      s%aircraft_euler = dcm_to_euler(b0%c)
      s%rocket_euler = dcm_to_euler(b1%c)
      s%pitch_rate = rocket_pitch_rate(sep)
      ! load factor along the aircraft's y axis: specific force / g
      s%load_factor = dot_product(b0%c(:, 2), sep%a0 + [0.0_dp, g0, 0.0_dp])/g0
      ! what accelerometers at the CGs measure: the acceleration less gravity,
      ! in body axes (the chain's first generalized accelerations are the
      ! rocket's CG acceleration, earth frame, and its angular acceleration,
      ! rocket axes: airlaunch_kane_chain)
      s%aircraft_specific_force = matmul(transpose(b0%c), sep%a0 + [0.0_dp, g0, 0.0_dp])
      s%rocket_specific_force = matmul(transpose(b1%c), sep%udot(1:3) + [0.0_dp, g0, 0.0_dp])
      s%rocket_wdot = sep%udot(4:6)
      ! clearances of the rocket's surface (its axis segment less the radius)
      ! from the aircraft's empennage point and from the ramp edge
      nose = b1%point_position([cfg%rocket%aero%cg_from_nose, 0.0_dp, 0.0_dp])
      aft = b1%point_position([cfg%rocket%aero%cg_from_nose - cfg%rocket%aero%length, 0.0_dp, 0.0_dp])
      edge = b0%r + matmul(b0%c, [cfg%bay%ramp_edge_x, cfg%bay%floor_y, 0.0_dp])
      s%clearance = clearance(clearance_geometry_of(cfg), b0, b1)
      s%edge_clearance = segment_distance(edge, nose, aft) - cfg%rocket%aero%diameter/2
      if (sep%phase /= phase_free) s%edge_clearance = 0.0_dp
    end associate
    select type (src => sep%sources(iloads)%source)
    type is (launch_loads)
      s%alpha = src%aircraft_out%alpha
      s%elevator = src%aircraft_out%delta_e
      s%aircraft_beta = src%aircraft_out%beta
      associate(b0 => sep%bodies(0), b1 => sep%bodies(1))
        ! the air the aerodynamics read at the CGs (a gust's, lagged as the
        ! aircraft's lift reads it with &gust kussner)
        air = isa(b0%r(2))
        v_air = air_relative_velocity(src%gust, b0%r, b0%v, src%kussner_chord)
        speed = norm2(v_air)
        s%aircraft_mach = speed/air%sound_speed
        s%aircraft_qbar = 0.5_dp*air%density*speed**2
        air = isa(b1%r(2))
        v_air = matmul(transpose(b1%c), air_relative_velocity(src%gust, b1%r, b1%v))
        speed = norm2(v_air)
        s%rocket_mach = speed/air%sound_speed
        s%rocket_qbar = 0.5_dp*air%density*speed**2
        ! the aircraft's convention (airlaunch_aircraft_aero): alpha = atan2(-v_y, v_x), beta = asin(v_z/V)
        s%rocket_alpha = atan2(-v_air(2), v_air(1))
        if (speed > 0.0_dp) s%rocket_beta = asin(max(-1.0_dp, min(1.0_dp, v_air(3)/speed)))
      end associate
    end select
  end function sample_launch

  !> The tail (aircraft axes: the empennage point and the tailplane's half
  !> span) and the rocket's surface (rocket axes: its axis, radius and fins) of
  !> the clearance milestone.
  pure function clearance_geometry_of(cfg) result(geom)
    type(scenario_config), intent(in) :: cfg
    type(clearance_geometry) :: geom
    geom%point = [cfg%bay%tail_x, cfg%bay%tail_y, 0.0_dp]
    geom%half_span = cfg%bay%tail_half_span
    geom%nose = [cfg%rocket%aero%cg_from_nose, 0.0_dp, 0.0_dp]
    geom%aft = [cfg%rocket%aero%cg_from_nose - cfg%rocket%aero%length, 0.0_dp, 0.0_dp]
    geom%radius = cfg%rocket%aero%diameter/2
    call set_fins(geom, cfg%rocket%fin_count, cfg%rocket%aero%cg_from_nose - cfg%rocket%fin_root_le_from_nose, &
      cfg%rocket%fin_root_chord, cfg%rocket%fin_tip_chord, cfg%rocket%fin_sweep, cfg%rocket%fin_semi_span)
  end function clearance_geometry_of

  !> Euler pitch rate of the rocket (body 1 of `sep`) [rad/s], free of the
  !> singularity: theta' = sin(gamma) w_y + cos(gamma) w_z (Eqs. (49)-(50)).
  real(dp) function rocket_pitch_rate(sep) result(r)
    type(separation_system), intent(in) :: sep
    real(dp) :: e(3)
    e = dcm_to_euler(sep%bodies(1)%c)
    r = sin(e(3))*sep%bodies(1)%w(2) + cos(e(3))*sep%bodies(1)%w(3)
  end function rocket_pitch_rate

  !> An event at time t (state y of the separation system, bodies loaded):
  !> the first pitch maximum (root `pitch_root` < 0 in Case 3, while
  !> `find_pitch_max`), the phase change of the separation scene (`which_sep`),
  !> and the rocket's attitude at separation; a local minimum of the clearance
  !> in Case 3 (`clearance_root` rising, geometry `geom`) and the clearance at the
  !> separation update its milestone.  `changed`: the phase changed; `lower`:
  !> the minimum clearance fell (for &run stop_when_final).
  subroutine handle_launch_event(res, t, sep, y, which_sep, pitch_root, find_pitch_max, clearance_root, geom, &
      changed, lower, error)
    type(launch_result), intent(inout) :: res
    real(dp), intent(in) :: t, y(:)
    type(separation_system), intent(inout) :: sep
    integer, intent(in) :: which_sep(:), pitch_root, clearance_root
    logical, intent(inout) :: find_pitch_max
    type(clearance_geometry), intent(in) :: geom
    logical, intent(out) :: changed, lower
    type(error_type), allocatable, intent(inout) :: error
    real(dp) :: e(3)
    lower = .false.
    if (clearance_root > 0 .and. sep%phase == phase_free) call take_clearance()
    if (pitch_root < 0 .and. sep%phase == phase_free .and. find_pitch_max) then
      e = dcm_to_euler(sep%bodies(1)%c)
      res%pitch_max_time = t
      res%pitch_max_deg = e(2)*rad2deg
      res%nose_elevation_at_max_deg = nose_elevation(sep%bodies(1)%q)*rad2deg
      find_pitch_max = .false.
    end if
    call sep%handle_event(t, y, which_sep, changed, error)
    if (allocated(error)) then
      error%message = phase_name(sep%phase) // ", t = " // str(t) // " s: " // error%message
      return
    end if
    if (changed .and. sep%phase == phase_free .and. res%separation_time < 0.0_dp) then
      e = dcm_to_euler(sep%bodies(1)%c)
      res%pitch_at_separation_deg = e(2)*rad2deg
      res%pitch_rate_at_separation_deg_s = rocket_pitch_rate(sep)*rad2deg
      res%separation_time = t
      call take_clearance()
    end if
  contains
    subroutine take_clearance()
      real(dp) :: c
      c = clearance(geom, sep%bodies(0), sep%bodies(1))
      lower = c < res%min_clearance
      res%min_clearance = min(res%min_clearance, c)
    end subroutine take_clearance
  end subroutine handle_launch_event

  !> The milestones an output record takes (the same with and without the
  !> trajectory output, which computes more of the record): the rocket's
  !> clearance after separation (besides its events: at the run's end it may
  !> still be falling) and the cut joint's position residual before it (`sep`:
  !> bodies loaded and joint evaluated at the record's time).  The safety
  !> maxima (peak tension, line clearance, the aircraft's excursions) are the
  !> step trackers' alone (launch_coupled's take_maxima).  True if the
  !> clearance fell (for &run stop_when_final).
  logical function record_milestones(res, clearance_now, sep) result(changed)
    type(launch_result), intent(inout) :: res
    real(dp), intent(in) :: clearance_now   !< rocket surface to the empennage point [m]
    type(separation_system), intent(in) :: sep
    changed = .false.
    if (sep%phase == phase_free .and. clearance_now < res%min_clearance) then
      res%min_clearance = clearance_now
      changed = .true.
    end if
    if (sep%phase /= phase_free) res%max_constraint_residual = max(res%max_constraint_residual, &
      sep%js%res_position)
  end function record_milestones

  !> Append one sample: the rigid part from `sep` and `s`, the line's nodes,
  !> end tensions and the parachute's position from the caller (all three
  !> absent without a line).
  subroutine history_append(self, t, s, sep, nodes, tension, chute)
    class(launch_history), intent(inout) :: self
    real(dp), intent(in) :: t
    type(launch_sample), intent(in) :: s
    type(separation_system), intent(in) :: sep
    real(dp), intent(in), optional :: nodes(:, 0:), tension(:), chute(3)
    integer :: k
    self%nrec = self%nrec + 1
    k = self%nrec
    associate(b0 => sep%bodies(0), b1 => sep%bodies(1))
      self%time(k) = t
      self%phase(k) = sep%phase
      self%ac_pos(:, k) = b0%r
      self%ac_eul(:, k) = s%aircraft_euler*rad2deg
      self%ac_alpha(k) = s%alpha*rad2deg
      self%elev(k) = s%elevator*rad2deg
      self%ac_q(k) = b0%w(3)*rad2deg
      self%load_factor(k) = s%load_factor
      self%rk_pos(:, k) = b1%r
      self%rk_vel(:, k) = b1%v
      self%rk_eul(:, k) = s%rocket_euler*rad2deg
      self%rk_rate(k) = s%pitch_rate*rad2deg
      self%rk_elev(k) = nose_elevation(b1%q)*rad2deg
      self%ac_vel(:, k) = b0%v
      self%ac_w(:, k) = b0%w*rad2deg
      self%ac_sf(:, k) = s%aircraft_specific_force
      self%rk_w(:, k) = b1%w*rad2deg
      self%rk_wdot(:, k) = s%rocket_wdot*rad2deg
      self%rk_sf(:, k) = s%rocket_specific_force
      ! (time first: each column is written whole, without a temporary)
      self%ac_air(k, :) = [s%aircraft_beta*rad2deg, s%aircraft_mach, s%aircraft_qbar]
      self%rk_air(k, :) = [s%rocket_alpha*rad2deg, s%rocket_beta*rad2deg, s%rocket_mach, s%rocket_qbar]
    end associate
    if (self%has_line .and. present(nodes) .and. present(tension) .and. present(chute)) then
      self%pc_pos(:, k) = chute
      self%t_rocket(k) = tension(1)
      self%t_chute(k) = tension(size(tension))
      self%nodes(:, :, k) = nodes
    end if
    self%cforce(1:3, k) = sep%rh_force
    self%cforce(4:6, k) = sep%rh_moment
    self%normal(k) = sep%normal_force
    self%friction(k) = sep%friction_force
    self%lock(k) = sep%lock_force
    self%clearance(k) = s%clearance
    self%edge_clearance(k) = s%edge_clearance
    self%residual(k) = sep%js%res_position
  end subroutine history_append

  !> Dimensions and variables of the output contract (docs/output.md).
  subroutine history_write_contract(self, w, chute_text, line_text, werr)
    class(launch_history), intent(in) :: self
    type(nc_writer), intent(inout) :: w
    character(len=*), intent(in) :: chute_text   !< long name of parachute_position
    character(len=*), intent(in) :: line_text    !< qualifier of the line variables ("" or a note)
    type(error_type), allocatable, intent(inout) :: werr
    real(dp), allocatable :: node_index(:), part(:, :)
    integer :: j, nrec, n
    nrec = self%nrec
      call w%add_dim("time", self%time(1:nrec), "s", "time since the start (trimmed flight)", werr)
      call w%add_dim("xyz", [0.0_dp, 1.0_dp, 2.0_dp], "1", &
        "component: 0 = x forward, 1 = y up, 2 = z right (earth), or rocket axes 0 = x, 1 = y, 2 = z " // &
        "(constraint_moment)", werr)
      call w%add_dim("angle", [0.0_dp, 1.0_dp, 2.0_dp], "1", "Euler angle: 0 = yaw, 1 = pitch, 2 = roll", werr)
      if (self%has_line) then
        n = ubound(self%nodes, 2)
        node_index = [(real(j, dp), j = 0, n)]
        call w%add_dim("node", node_index, "1", "line node: 0 = rocket tie-down, N = parachute", werr)
      end if
      call w%add_var_1d("phase", ["time"], self%phase(1:nrec), "1", "phase: 0 locked, 1 rail extraction, " // &
        "2 rotation on the ramp edge, 3 free flight", werr)
      call w%add_var_2d("aircraft_position", ["xyz ", "time"], self%ac_pos(:, 1:nrec), "m", "aircraft CG, earth frame", werr)
      call w%add_var_2d("aircraft_euler_deg", ["angle", "time "], self%ac_eul(:, 1:nrec), "degree", &
        "aircraft yaw, pitch, roll", werr)
      call w%add_var_1d("aircraft_alpha_deg", ["time"], self%ac_alpha(1:nrec), "degree", "aircraft angle of attack", werr)
      call w%add_var_1d("aircraft_pitch_rate_deg_s", ["time"], self%ac_q(1:nrec), "degree s-1", &
        "aircraft body pitch rate", werr)
      call w%add_var_1d("elevator_deg", ["time"], self%elev(1:nrec), "degree", "elevator deflection", werr)
      call w%add_var_1d("aircraft_load_factor", ["time"], self%load_factor(1:nrec), "1", &
        "aircraft normal load factor (specific force along body y / g)", werr)
      call w%add_var_2d("rocket_position", ["xyz ", "time"], self%rk_pos(:, 1:nrec), "m", "rocket CG, earth frame", werr)
      call w%add_var_2d("rocket_velocity", ["xyz ", "time"], self%rk_vel(:, 1:nrec), "m s-1", &
        "rocket CG velocity, earth frame", werr)
      call w%add_var_2d("rocket_euler_deg", ["angle", "time "], self%rk_eul(:, 1:nrec), "degree", &
        "rocket yaw, pitch, roll (the paper's Euler convention; pitch in [-90, 90])", werr)
      call w%add_var_1d("rocket_pitch_rate_deg_s", ["time"], self%rk_rate(1:nrec), "degree s-1", &
        "rocket Euler pitch rate", werr)
      call w%add_var_1d("rocket_nose_elevation_deg", ["time"], self%rk_elev(1:nrec), "degree", &
        "rocket nose elevation, continuous through the vertical (0 level forward, 90 up, 180 level aft)", werr)
      if (self%has_line) then
        call w%add_var_2d("parachute_position", ["xyz ", "time"], self%pc_pos(:, 1:nrec), "m", chute_text, werr)
        call w%add_var_1d("line_tension_rocket_end_N", ["time"], self%t_rocket(1:nrec), "N", &
          "line tension at the rocket end" // line_text, werr)
        call w%add_var_1d("line_tension_parachute_end_N", ["time"], self%t_chute(1:nrec), "N", &
          "line tension at the parachute end" // line_text, werr)
        call w%add_var_3d("line_nodes", ["xyz ", "node", "time"], self%nodes(:, :, 1:nrec), "m", &
          "line node positions" // line_text // ", earth frame", werr)
      end if
      ! the wrench R_H as two variables of one unit each (one "N or N m"
      ! variable parses in no unit library: UDUNITS-2, pint, CF checkers)
      ! (through a contiguous copy: a row section of cforce would be packed into
      ! an array temporary for the writer, which the Checked build reports)
      part = self%cforce(1:3, 1:nrec)
      call w%add_var_2d("constraint_force", ["xyz ", "time"], part, "N", &
        "cut-joint constraint force of R_H on the rocket (CFA), earth frame", werr)
      part = self%cforce(4:6, 1:nrec)
      call w%add_var_2d("constraint_moment", ["xyz ", "time"], part, "N m", &
        "cut-joint constraint moment of R_H on the rocket about its CG (CFA), rocket axes (0 = x, 1 = y, 2 = z)", werr)
      call w%add_var_1d("edge_normal_force_N", ["time"], self%normal(1:nrec), "N", &
        "contact normal force of the rail / ramp edge on the rocket", werr)
      call w%add_var_1d("friction_force_N", ["time"], self%friction(1:nrec), "N", &
        "friction on the rocket along the exit direction (0 in Case 0: see lock_force_N)", werr)
      call w%add_var_1d("lock_force_N", ["time"], self%lock(1:nrec), "N", &
        "Case 0: force of the lock (tie-down) on the rocket along the exit direction (0 after release)", werr)
      call w%add_var_1d("clearance_m", ["time"], self%clearance(1:nrec), "m", &
        "distance from the rocket's surface (body cylinder and fins) to the aircraft's horizontal tail " // &
        "(&bay tail_x, tail_y, tail_half_span)", werr)
      call w%add_var_1d("edge_clearance_m", ["time"], self%edge_clearance(1:nrec), "m", &
        "distance from the rocket's surface to the ramp edge after separation (0 before)", werr)
      call w%add_var_1d("constraint_residual_m", ["time"], self%residual(1:nrec), "m", &
        "position residual of the cut-joint constraints", werr)
      call self%write_telemetry(w, werr)
  end subroutine history_write_contract

  !> What the bodies' inertial sensors and air-data systems would read
  !> (docs/output.md, "Telemetry"): velocities, body rates, specific forces,
  !> air data; vectors in body axes along the dimension `body_axis`.
  subroutine history_write_telemetry(self, w, werr)
    class(launch_history), intent(in) :: self
    type(nc_writer), intent(inout) :: w
    type(error_type), allocatable, intent(inout) :: werr
    integer :: nrec
    character(len=*), parameter :: rates = " (0 = x roll, 1 = y: positive nose left, 2 = z pitch: positive nose up)"
    nrec = self%nrec
    call w%add_dim("body_axis", [0.0_dp, 1.0_dp, 2.0_dp], "1", &
      "component in the body's own axes: 0 = x nose, 1 = y up, 2 = z right", werr)
    call w%add_var_2d("aircraft_velocity", ["xyz ", "time"], self%ac_vel(:, 1:nrec), "m s-1", &
      "aircraft CG velocity, earth frame", werr)
    call w%add_var_2d("aircraft_body_rates_deg_s", ["body_axis", "time     "], self%ac_w(:, 1:nrec), "degree s-1", &
      "aircraft angular velocity, aircraft axes" // rates, werr)
    call w%add_var_2d("aircraft_specific_force_m_s2", ["body_axis", "time     "], self%ac_sf(:, 1:nrec), "m s-2", &
      "aircraft specific force (CG acceleration less gravity: what an accelerometer at the CG reads), aircraft axes", &
      werr)
    call w%add_var_1d("aircraft_beta_deg", ["time"], self%ac_air(1:nrec, 1), "degree", &
      "aircraft sideslip asin(v_z/V) of the air-relative velocity at the CG, aircraft axes", werr)
    call w%add_var_1d("aircraft_mach", ["time"], self%ac_air(1:nrec, 2), "1", &
      "aircraft Mach number (air-relative speed at the CG)", werr)
    call w%add_var_1d("aircraft_dynamic_pressure_Pa", ["time"], self%ac_air(1:nrec, 3), "Pa", &
      "aircraft dynamic pressure (air-relative speed at the CG)", werr)
    call w%add_var_2d("rocket_body_rates_deg_s", ["body_axis", "time     "], self%rk_w(:, 1:nrec), "degree s-1", &
      "rocket angular velocity, rocket axes" // rates, werr)
    call w%add_var_2d("rocket_angular_acceleration_deg_s2", ["body_axis", "time     "], self%rk_wdot(:, 1:nrec), &
      "degree s-2", "rocket angular acceleration (derivative of rocket_body_rates_deg_s), rocket axes", werr)
    call w%add_var_2d("rocket_specific_force_m_s2", ["body_axis", "time     "], self%rk_sf(:, 1:nrec), "m s-2", &
      "rocket specific force (CG acceleration less gravity: what an accelerometer at the CG reads), rocket axes", werr)
    call w%add_var_1d("rocket_alpha_deg", ["time"], self%rk_air(1:nrec, 1), "degree", &
      "rocket angle of attack atan2(-v_y, v_x) of the air-relative velocity at its CG, rocket axes", werr)
    call w%add_var_1d("rocket_beta_deg", ["time"], self%rk_air(1:nrec, 2), "degree", &
      "rocket sideslip asin(v_z/V) of the air-relative velocity at its CG, rocket axes", werr)
    call w%add_var_1d("rocket_mach", ["time"], self%rk_air(1:nrec, 3), "1", &
      "rocket Mach number (air-relative speed at its CG)", werr)
    call w%add_var_1d("rocket_dynamic_pressure_Pa", ["time"], self%rk_air(1:nrec, 4), "Pa", &
      "rocket free-stream dynamic pressure at its CG (also while shielded in the bay)", werr)
  end subroutine history_write_telemetry

  !> The milestones as global attributes.
  subroutine write_milestones(w, res, error)
    use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
    type(nc_writer), intent(inout) :: w
    type(launch_result), intent(in) :: res
    type(error_type), allocatable, intent(inout) :: error
    real(dp) :: nan
    nan = ieee_value(1.0_dp, ieee_quiet_nan)
    call w%add_text_att("/", "status", trim(res%status), error)
    if (allocated(res%failure)) call w%add_text_att("/", "failure", res%failure, error)
    call w%add_real_att("/", "trim_alpha_deg", res%trim_alpha_deg, error)
    call w%add_real_att("/", "trim_elevator_deg", res%trim_elevator_deg, error)
    call w%add_real_att("/", "trim_thrust_N", res%trim_thrust_n, error)
    call w%add_real_att("/", "trim_cl0", res%trim_cl0, error)
    call w%add_real_att("/", "trim_cm0", res%trim_cm0, error)
    call w%add_real_att("/", "release_time_s", res%release_time, error)
    call w%add_real_att("/", "edge_time_s", res%edge_time, error)
    call w%add_real_att("/", "separation_time_s", res%separation_time, error)
    call w%add_text_att("/", "early_separation", merge("true ", "false", res%early_separation), error)
    call w%add_real_att("/", "edge_pull_time_s", res%edge_pull_time, error)
    ! the angles of an event that did not happen: NaN (a -1 deg pitch is a value)
    call w%add_real_att("/", "pitch_at_separation_deg", &
      merge(res%pitch_at_separation_deg, nan, res%separation_time >= 0.0_dp), error)
    call w%add_real_att("/", "pitch_rate_at_separation_deg_s", &
      merge(res%pitch_rate_at_separation_deg_s, nan, res%separation_time >= 0.0_dp), error)
    call w%add_real_att("/", "pitch_max_time_s", res%pitch_max_time, error)
    call w%add_real_att("/", "pitch_max_deg", merge(res%pitch_max_deg, nan, res%pitch_max_time >= 0.0_dp), error)
    call w%add_real_att("/", "nose_elevation_at_pitch_max_deg", &
      merge(res%nose_elevation_at_max_deg, nan, res%pitch_max_time >= 0.0_dp), error)
    call w%add_real_att("/", "min_clearance_m", merge(res%min_clearance, -1.0_dp, res%min_clearance < huge(1.0_dp)), error)
    call w%add_real_att("/", "min_exit_clearance_m", &
      merge(res%min_exit_clearance, -1.0_dp, res%min_exit_clearance < huge(1.0_dp)), error)
    call w%add_real_att("/", "min_exit_clearance_time_s", res%min_exit_clearance_time, error)
    call w%add_text_att("/", "line_enabled", trim(merge("true ", "false", res%has_line)), error)
    if (res%has_line) then
      call w%add_real_att("/", "min_line_clearance_m", &
        merge(res%min_line_clearance, -1.0_dp, res%min_line_clearance < huge(1.0_dp)), error)
      call w%add_real_att("/", "peak_line_tension_N", res%peak_tension, error)
      call w%add_real_att("/", "peak_line_tension_time_s", res%peak_tension_time, error)
      call w%add_real_att("/", "line_break_time_s", res%line_break_time, error)
      call w%add_int_att("/", "line_break_segment", [res%line_break_segment], error)
      call w%add_int_att("/", "line_breaks", [res%line_breaks], error)
      if (allocated(res%parted_segments)) call w%add_int_att("/", "line_parted_segments", res%parted_segments, error)
    end if
    call w%add_real_att("/", "max_aircraft_pitch_excursion_deg", res%max_aircraft_pitch_excursion_deg, error)
    call w%add_real_att("/", "max_load_factor_excursion", res%max_load_factor_excursion, error)
    call w%add_real_att("/", "max_constraint_residual_m", res%max_constraint_residual, error)
    call w%add_real_att("/", "max_quaternion_norm_error", res%max_quaternion_norm_error, error)
    call w%add_real_att("/", "ground_time_s", res%ground_time, error)
    call w%add_text_att("/", "ground_body", trim(ground_body_name(res%ground_body)), error)
    call w%add_text_att("/", "ground_point", trim(ground_point_name(res%ground_point)), error)
    ! (a speed is never negative: -1 marks "not reached", as min_clearance_m's)
    call w%add_real_att("/", "ground_speed_m_s", merge(res%ground_speed, -1.0_dp, res%ground_time >= 0.0_dp), error)
  end subroutine write_milestones

  !> "aircraft", "rocket" or "none" (ground_body -1).
  pure function ground_body_name(body) result(name)
    integer, intent(in) :: body
    character(len=8) :: name
    select case (body)
    case (0)
      name = "aircraft"
    case (1)
      name = "rocket"
    case default
      name = "none"
    end select
  end function ground_body_name

  !> "cg", "nose", "tail" or "none" (ground_point -1): the point of ground_body
  !> that reached the ground.
  pure function ground_point_name(point) result(name)
    integer, intent(in) :: point
    character(len=4) :: name
    select case (point)
    case (ground_at_cg)
      name = "cg"
    case (ground_at_nose)
      name = "nose"
    case (ground_at_tail)
      name = "tail"
    case default
      name = "none"
    end select
  end function ground_point_name

  pure real(dp) function event_or_minus(t) result(r)
    real(dp), intent(in) :: t
    r = t
    if (t < -1.0e300_dp) r = -1.0_dp
  end function event_or_minus

end module airlaunch_launch_history
