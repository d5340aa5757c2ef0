!> Inputs of the air-launch scene (the paper's scenario, §5.2): namelist groups
!> &flight, &aircraft, &bay, &rocket, &parachute, &line, &gust (see docs/input.md).
!> Values the paper gives are the defaults; values it does not give are
!> documented choices in input/airlaunch_paper.nml.
module airlaunch_scenario_config
  use airlaunch_kinds, only: dp, deg2rad, rad2deg
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_namelist
  use airlaunch_run_config, only: echo_buffer
  use airlaunch_atmosphere, only: isa_max_altitude, isa_min_altitude
  use airlaunch_aircraft_aero, only: aircraft_aero
  use airlaunch_rocket_aero, only: rocket_aero, max_mach_points
  use airlaunch_parachute, only: parachute
  use airlaunch_line, only: marching_stable_step
  use airlaunch_trim, only: trim_alpha_min_deg, trim_alpha_max_deg
  implicit none
  private
  public :: scenario_config, flight_config, aircraft_config, bay_config, rocket_config, line_config, gust_config
  public :: read_scenario_config, scenario_groups, read_parachute, check_break, check_weak_link, &
    refuse_reached_strength, check_break_before_end

  !> Where the air-launch line's first and last segments are (messages).
  character(len=*), parameter :: launch_line_ends = "1 at the rocket's tie-down, n_seg at the parachute"

  !> Groups of the air-launch scene.
  character(len=16), parameter :: scenario_groups(8) = [character(len=16) :: "run", "flight", &
    "aircraft", "bay", "rocket", "parachute", "line", "gust"]

  !> Largest peak gust velocity &gust takes [m/s]: 4x the largest design gust
  !> of CS-25.341(a) in true air speed below 20 km (U_ref 13.41 m/s EAS, with
  !> F_g = 1 and H = 107 m, is 26 m/s TAS at 20 km).
  real(dp), parameter :: gust_speed_max = 100.0_dp

  !> Variables of &line (air-launch scene).
  type(nml_var), parameter :: line_vars(25) = [nml_var("enabled", "logical"), nml_var("length", "real"), &
    nml_var("n_seg", "integer"), nml_var("ea", "real"), nml_var("mass_per_length", "real"), &
    nml_var("damping", "real"), nml_var("diameter", "real"), nml_var("cd_normal", "real"), &
    nml_var("cd_tangential", "real"), nml_var("coupling", "string", 16), nml_var("outer_dt", "real"), &
    nml_var("inner_rtol", "real"), nml_var("far_end", "string", 16), nml_var("coupling_by_phase", "string", 16), &
    nml_var("auto_min_strain", "real"), nml_var("auto_max_strain_change", "real"), nml_var("auto_dwell", "real"), &
    nml_var("auto_min_steps", "real"), nml_var("inner_scheme", "string", 16), nml_var("inner_dt", "real"), &
    nml_var("breaking_strength", "real"), nml_var("break_time", "real"), nml_var("break_segment", "integer"), &
    nml_var("weak_link_strength", "real"), nml_var("weak_link_segment", "integer")]

  !> The couplings `&line coupling` may name (DESIGN §4 (a), (b)), and the two
  !> ways of choosing between them during a run.
  character(len=16), parameter :: single_couplings(2) = [character(len=16) :: "direct", "rigidized"]
  character(len=16), parameter :: coupling_modes(4) = [character(len=16) :: "direct", "rigidized", &
    "per_phase", "auto"]

  !> Most values read for one &rocket Mach table (a list's limit): more than
  !> max_mach_points is an input error naming the count, not a read failure.
  integer, parameter :: max_table_read = max_list_items

  !> Largest rail angle to the aircraft's body x axis, either way [deg]: a
  !> cargo floor, not a launcher; the trimmed deck (trim angle + rail angle)
  !> then stays well short of the vertical, where the joint's frame is undefined.
  real(dp), parameter :: rail_angle_max_deg = 45.0_dp

  !> The ground's margin to the atmosphere model's floor [m].
  real(dp), parameter :: ground_margin_below = 1000.0_dp

  !> Flight condition and trim.
  type :: flight_config
    real(dp) :: altitude = 10000.0_dp        !< [m] geometric
    real(dp) :: mach = 0.65_dp
    character(len=16) :: trim_mode = "calibrate"  !< "calibrate" (CL0, Cm0 from trim_alpha) or "fly"
    real(dp) :: trim_alpha = 1.2174_dp*deg2rad    !< [rad]
    !> [m] geometric: the run ends when the aircraft's CG or the rocket's lowest point reaches it
    real(dp) :: ground_altitude = 0.0_dp
  end type flight_config

  !> Carrier aircraft.
  type :: aircraft_config
    real(dp) :: mass = 89000.0_dp
    real(dp) :: inertia(3) = [540740.0_dp, 737480.0_dp, 117030.0_dp]  !< Ixx, Iyy, Izz [kg m^2]
    character(len=16) :: dynamics = "free"       !< "free" (Newton-Euler) or "prescribed" (trimmed level flight)
    character(len=16) :: control = "attitude_hold"  !< "stick_fixed" or "attitude_hold"
    type(aircraft_aero) :: aero
  end type aircraft_config

  !> Cargo bay geometry in the aircraft body frame (origin at the aircraft CG).
  type :: bay_config
    real(dp) :: ramp_edge_x = -12.0_dp   !< x of the ramp edge [m]
    real(dp) :: floor_y = -1.5_dp        !< y of the cargo floor / rail surface [m]
    real(dp) :: length = 24.5_dp         !< usable length ahead of the ramp edge [m]
    real(dp) :: width = 3.46_dp          !< [m]
    real(dp) :: height = 3.4_dp          !< [m]
    real(dp) :: friction = 0.005_dp      !< rail friction coefficient
    real(dp) :: release_time = 0.5_dp    !< t0 [s]: end of Case 0
    real(dp) :: l0 = 10.0_dp             !< rocket CG ahead of the ramp edge at release [m] (resolved)
    character(len=8) :: l0_from = "cg"   !< what &bay l0 places: "cg" (the CG) or "tail" (the rocket's tail)
    real(dp) :: l0_given = 10.0_dp       !< &bay l0 as given (the tail's distance with l0_from = "tail") [m]
    character(len=16) :: edge_contact = "one_sided"  !< Case 2 contact: "one_sided" or "bilateral"
    real(dp) :: tail_x = -24.0_dp        !< empennage point (horizontal tail), aircraft axes [m]
    real(dp) :: tail_y = 6.0_dp
    real(dp) :: tail_half_span = 0.0_dp  !< the horizontal tail's half span across z, for the clearance [m]
    !> the rail's angle to the aircraft's body x axis, nose up (the rocket lies
    !> on it nose up; the rail line passes through the ramp edge) [rad]
    real(dp) :: rail_angle = 0.0_dp
  end type bay_config

  !> Rocket (payload).
  type :: rocket_config
    real(dp) :: mass = 28000.0_dp
    real(dp) :: inertia(3) = [7870.0_dp, 545000.0_dp, 545000.0_dp]
    real(dp) :: tie_down_from_nose = 0.0_dp   !< line attachment, aft of the nose tip on the axis [m]
    integer :: fin_count = 0                  !< 0 (no fins), 3, or 4 (X configuration)
    real(dp) :: fin_semi_span = 0.0_dp        !< [m] from the body surface
    real(dp) :: fin_root_chord = 0.0_dp       !< [m]
    real(dp) :: fin_tip_chord = 0.0_dp        !< [m]
    real(dp) :: fin_sweep = 0.0_dp            !< leading-edge sweep distance, root to tip [m]
    real(dp) :: fin_root_le_from_nose = 0.0_dp  !< root leading edge [m]
    type(rocket_aero) :: aero
  end type rocket_config

  !> Flexible line (riser) between the rocket's tie-down and the parachute.
  !> `enabled` false: the scene has neither line nor parachute (a gravity drop,
  !> a rail release): the other components are then unused.
  type :: line_config
    real(dp) :: length = 60.0_dp
    integer :: n_seg = 60
    real(dp) :: ea = 1.0e6_dp               !< axial stiffness [N]
    real(dp) :: mass_per_length = 0.5_dp    !< [kg/m]
    real(dp) :: damping = 0.0_dp            !< axial damping coefficient [N s]
    real(dp) :: diameter = 0.025_dp         !< [m]
    real(dp) :: cd_normal = 1.2_dp
    real(dp) :: cd_tangential = 0.01_dp
    !> "direct" (nodes with the bodies), "rigidized" (§2.4), "per_phase"
    !> (coupling_by_phase) or "auto" (the auto_* indicator, docs/model.md)
    character(len=16) :: coupling = "direct"
    real(dp) :: outer_dt = 0.02_dp          !< rigidized: outer step of §2.4 Steps 3-6 [s]
    real(dp) :: inner_rtol = 0.0_dp         !< rigidized: line sub-step tolerance (0: &run rtol)
    character(len=16) :: far_end = "parachute"  !< rigidized: node N "parachute" (far-end force) or "chain"
    logical :: enabled = .true.             !< false: no line and no parachute
    !> per_phase: the coupling ("direct" or "rigidized") of Case 0, 1, 2, 3
    character(len=16) :: coupling_by_phase(0:3) = ""
    real(dp) :: auto_min_strain = 1.0e-3_dp       !< auto: taut when every segment's strain reaches this
    real(dp) :: auto_max_strain_change = 0.05_dp  !< auto: slow when the stretch changes less per outer step
    real(dp) :: auto_dwell = 0.1_dp               !< auto: wanted this long before a switch [s]
    real(dp) :: auto_min_steps = 8.0_dp           !< auto: busy when the line costs this many steps per outer step
    !> rigidized: the line's sub-steps by "cvode" (BDF) or "marching" (the paper's, §2.3)
    character(len=16) :: inner_scheme = "cvode"
    real(dp) :: inner_dt = 0.0_dp           !< rigidized, marching: sub-step [s] (0: 0.9 of its stability limit)
    !> the line breaks at the first segment whose tension reaches this [N] (0: never)
    real(dp) :: breaking_strength = 0.0_dp
    real(dp) :: break_time = -1.0_dp        !< the line is cut at break_segment at this time [s] (-1: never)
    integer :: break_segment = 1            !< the segment break_time cuts (1: at the rocket's tie-down)
    !> a weak link: segment weak_link_segment parts when its tension reaches
    !> this [N], below the line's strength (0: no weak link)
    real(dp) :: weak_link_strength = 0.0_dp
    !> the weak link's segment (read as unset_int: n_seg, at the parachute)
    integer :: weak_link_segment = unset_int
  end type line_config

  !> A discrete 1 - cosine gust (airlaunch_gust) the flight meets: its peak
  !> velocity across the flight path, its gradient distance H (the gust is 2H
  !> long) and the time the aircraft's CG, flying on at V0, reaches its front.
  type :: gust_config
    real(dp) :: vertical = 0.0_dp            !< peak upward gust velocity [m/s] (earth y)
    real(dp) :: lateral = 0.0_dp             !< peak lateral gust velocity [m/s] (earth z)
    real(dp) :: gradient_length = 107.0_dp   !< H [m] (CS-25.341: 9 ... 107 m)
    real(dp) :: hit_time = 1.0_dp            !< the aircraft's CG at the gust's front [s]
    !> each station of the bodies reads the gust where it is (the rocket's
    !> strips, fins and nose, the aircraft's empennage); false: at the CG
    logical :: penetration = .true.
    !> the aircraft's lift builds up over the chords it flies into the gust
    !> (Küssner's function, Jones' approximation); false: at once
    logical :: kussner = .false.
  end type gust_config

  !> Everything the air-launch scene reads.
  type :: scenario_config
    type(flight_config) :: flight
    type(aircraft_config) :: aircraft
    type(bay_config) :: bay
    type(rocket_config) :: rocket
    type(parachute) :: chute
    type(line_config) :: line
    type(gust_config) :: gust
  end type scenario_config

contains

  !> Read and validate all groups; `echo` receives the resolved input.
  subroutine read_scenario_config(f, cfg, echo, error, t_end)
    type(nml_file), intent(in) :: f
    type(scenario_config), intent(out) :: cfg
    character(len=:), allocatable, intent(inout) :: echo
    type(error_type), allocatable, intent(inout) :: error
    real(dp), intent(in), optional :: t_end   !< end of the run [s], for the schedule checks
    call f%check_groups(scenario_groups, error)
    if (.not. allocated(error)) call read_flight(f, cfg%flight, echo, error)
    if (.not. allocated(error)) call read_aircraft(f, cfg%aircraft, echo, error)
    if (.not. allocated(error)) call read_bay(f, cfg%bay, echo, error)
    if (.not. allocated(error)) call read_rocket(f, cfg%rocket, echo, error)
    ! &bay l0 from the rocket's tail: the CG's distance follows the rocket's CG
    if (cfg%bay%l0_from == "tail") cfg%bay%l0 = cfg%bay%l0_given + cfg%rocket%aero%length - &
      cfg%rocket%aero%cg_from_nose
    if (line_enabled_in(f)) then
      if (.not. allocated(error)) call read_parachute(f, cfg%chute, echo, error)
      if (.not. allocated(error)) call read_line(f, cfg%line, echo, error)
    else
      if (.not. allocated(error)) call read_no_line(f, cfg%line, echo, error)
    end if
    if (.not. allocated(error)) call read_gust(f, cfg%gust, echo, error)
    if (.not. allocated(error)) call check_geometry(f, cfg, error)
    if (allocated(error) .or. .not. present(t_end)) return
    if (cfg%line%enabled .and. cfg%chute%deploy_time >= t_end) then
      call fatal_error(error, f%path // ": &parachute: deploy_time = " // str(cfg%chute%deploy_time) // &
        " is not allowed (the parachute would never inflate: the run ends at t_end = " // str(t_end) // " s)")
    else if (cfg%bay%release_time >= t_end) then
      call fatal_error(error, f%path // ": &bay: release_time = " // str(cfg%bay%release_time) // &
        " is not allowed (the rocket would never be released: the run ends at t_end = " // str(t_end) // " s)")
    else if ((cfg%gust%vertical /= 0.0_dp .or. cfg%gust%lateral /= 0.0_dp) .and. cfg%gust%hit_time >= t_end) then
      call fatal_error(error, f%path // ": &gust: hit_time = " // str(cfg%gust%hit_time) // &
        " is not allowed (the aircraft would never meet the gust: the run ends at t_end = " // str(t_end) // " s)")
    else if (cfg%line%enabled) then
      call check_break_before_end(f, cfg%line%break_time, t_end, error)
    end if
  end subroutine read_scenario_config

  !> Read one group: check names, read, diagnose.  `present` false: defaults.
  subroutine open_group(f, group, vars, unit, present, error)
    type(nml_file), intent(in) :: f
    character(len=*), intent(in) :: group
    type(nml_var), intent(in) :: vars(:)
    integer, intent(out) :: unit
    logical, intent(out) :: present
    type(error_type), allocatable, intent(inout) :: error
    call f%check_group(group, vars, error)
    present = .false.
    unit = -1
    if (allocated(error)) return
    call f%position(group, unit, present, error)
    if (allocated(error)) return
  end subroutine open_group

  subroutine read_flight(f, c, echo, error)
    type(nml_file), intent(in) :: f
    type(flight_config), intent(inout) :: c
    character(len=:), allocatable, intent(inout) :: echo
    type(error_type), allocatable, intent(inout) :: error
    real(dp) :: altitude, mach, trim_alpha_deg, ground_altitude
    character(len=16) :: trim_mode
    integer :: u, ios
    logical :: present
    character(len=256) :: msg
    type(echo_buffer) :: buffer
    namelist /flight/ altitude, mach, trim_mode, trim_alpha_deg, ground_altitude
    type(nml_var), parameter :: vars(5) = [nml_var("altitude", "real"), nml_var("mach", "real"), &
      nml_var("trim_mode", "string", 16), nml_var("trim_alpha_deg", "real"), nml_var("ground_altitude", "real")]
    altitude = c%altitude; mach = c%mach; trim_mode = c%trim_mode; trim_alpha_deg = c%trim_alpha*rad2deg
    ground_altitude = c%ground_altitude
    call open_group(f, "flight", vars, u, present, error)
    if (allocated(error)) return
    if (present) then
      read(u, nml=flight, iostat=ios, iomsg=msg)
      close(u)
      if (ios /= 0) then
        call f%diagnose("flight", vars, msg, error)
        return
      end if
    end if
    call require_range(f, "flight", "altitude", altitude, 0.0_dp, 20000.0_dp, "m", error)
    call require_range(f, "flight", "mach", mach, 0.05_dp, 0.95_dp, "", error)
    call require_choice(f, "flight", "trim_mode", trim_mode, [character(len=16) :: "calibrate", "fly"], error)
    call require_range(f, "flight", "trim_alpha_deg", trim_alpha_deg, trim_alpha_min_deg, trim_alpha_max_deg, "deg", error)
    ! the ground: 1 km above the atmosphere model's floor (a last step's trial
    ! states may go below the ground before its event is located), and below
    ! the release (setup_launch checks that the aircraft's CG and the rocket's
    ! lowest point start above it)
    if (.not. allocated(error)) call require_range(f, "flight", "ground_altitude", ground_altitude, &
      isa_min_altitude + ground_margin_below, altitude, "m: at most &flight altitude", error)
    if (allocated(error)) return
    c = flight_config(altitude, mach, trim_mode, trim_alpha_deg*deg2rad, ground_altitude)
    do while (buffer%another_try())
      write(buffer%lines, nml=flight, iostat=buffer%ios)
    end do
    call buffer%append_to(echo)
    if (.false.) altitude = isa_max_altitude
  end subroutine read_flight

  subroutine read_aircraft(f, c, echo, error)
    type(nml_file), intent(in) :: f
    type(aircraft_config), intent(inout) :: c
    character(len=:), allocatable, intent(inout) :: echo
    type(error_type), allocatable, intent(inout) :: error
    real(dp) :: mass, ixx, iyy, izz, wing_area, span, chord, cl0, cl_alpha, cl_de, cd0, k_induced
    real(dp) :: cm0, cm_alpha, cm_q, cm_de, k_theta, k_q, delta_e_max_deg, cl_alpha_tail, cy_beta_fin
    real(dp) :: cy_beta, croll_beta, croll_p, croll_r, cn_beta, cn_p, cn_r
    character(len=16) :: dynamics, control
    integer :: u, ios
    logical :: present
    character(len=256) :: msg
    type(echo_buffer) :: buffer
    namelist /aircraft/ mass, ixx, iyy, izz, wing_area, span, chord, cl0, cl_alpha, cl_de, cd0, &
      k_induced, cm0, cm_alpha, cm_q, cm_de, dynamics, control, k_theta, k_q, delta_e_max_deg, &
      cl_alpha_tail, cy_beta_fin, cy_beta, croll_beta, croll_p, croll_r, cn_beta, cn_p, cn_r
    type(nml_var), parameter :: vars(30) = [nml_var("mass", "real"), nml_var("ixx", "real"), &
      nml_var("iyy", "real"), nml_var("izz", "real"), nml_var("wing_area", "real"), nml_var("span", "real"), &
      nml_var("chord", "real"), nml_var("cl0", "real"), nml_var("cl_alpha", "real"), nml_var("cl_de", "real"), &
      nml_var("cd0", "real"), nml_var("k_induced", "real"), nml_var("cm0", "real"), &
      nml_var("cm_alpha", "real"), nml_var("cm_q", "real"), nml_var("cm_de", "real"), &
      nml_var("dynamics", "string", 16), nml_var("control", "string", 16), nml_var("k_theta", "real"), &
      nml_var("k_q", "real"), nml_var("delta_e_max_deg", "real"), &
      nml_var("cl_alpha_tail", "real"), nml_var("cy_beta_fin", "real"), nml_var("cy_beta", "real"), &
      nml_var("croll_beta", "real"), nml_var("croll_p", "real"), nml_var("croll_r", "real"), &
      nml_var("cn_beta", "real"), nml_var("cn_p", "real"), nml_var("cn_r", "real")]
    associate(a => c%aero)
      mass = c%mass; ixx = c%inertia(1); iyy = c%inertia(2); izz = c%inertia(3)
      wing_area = a%wing_area; span = a%span; chord = a%chord; cl0 = a%cl0; cl_alpha = a%cl_alpha
      cl_de = a%cl_de; cd0 = a%cd0; k_induced = a%k_induced; cm0 = a%cm0; cm_alpha = a%cm_alpha
      cm_q = a%cm_q; cm_de = a%cm_de; dynamics = c%dynamics; control = c%control
      k_theta = a%k_theta; k_q = a%k_q; delta_e_max_deg = a%delta_e_max*rad2deg
      cl_alpha_tail = a%cl_alpha_tail; cy_beta_fin = a%cy_beta_fin
      cy_beta = a%cy_beta; croll_beta = a%croll_beta; croll_p = a%croll_p; croll_r = a%croll_r
      cn_beta = a%cn_beta; cn_p = a%cn_p; cn_r = a%cn_r
    end associate
    call open_group(f, "aircraft", vars, u, present, error)
    if (allocated(error)) return
    if (present) then
      read(u, nml=aircraft, iostat=ios, iomsg=msg)
      close(u)
      if (ios /= 0) then
        call f%diagnose("aircraft", vars, msg, error)
        return
      end if
    end if
    call require_positive(f, "aircraft", "mass", mass, "kg", error)
    call require_positive(f, "aircraft", "ixx", ixx, "kg m^2", error)
    call require_positive(f, "aircraft", "iyy", iyy, "kg m^2", error)
    call require_positive(f, "aircraft", "izz", izz, "kg m^2", error)
    call require_positive(f, "aircraft", "wing_area", wing_area, "m^2", error)
    call require_positive(f, "aircraft", "span", span, "m", error)
    call require_positive(f, "aircraft", "chord", chord, "m", error)
    call require_positive(f, "aircraft", "cl_alpha", cl_alpha, "1/rad", error)
    call require_nonnegative(f, "aircraft", "cd0", cd0, "", error)
    call require_nonnegative(f, "aircraft", "k_induced", k_induced, "", error)
    call require_range(f, "aircraft", "cm_alpha", cm_alpha, -50.0_dp, 0.0_dp, "1/rad (statically stable)", error)
    call require_range(f, "aircraft", "cm_q", cm_q, -200.0_dp, 0.0_dp, "1/rad", error)
    call require_range(f, "aircraft", "cm_de", cm_de, -10.0_dp, -1.0e-3_dp, "1/rad", error)
    call require_choice(f, "aircraft", "dynamics", dynamics, [character(len=16) :: "free", "prescribed"], error)
    call require_choice(f, "aircraft", "control", control, [character(len=16) :: "stick_fixed", "attitude_hold"], error)
    call require_nonnegative(f, "aircraft", "k_theta", k_theta, "rad/rad", error)
    call require_nonnegative(f, "aircraft", "k_q", k_q, "rad s/rad", error)
    call require_range(f, "aircraft", "delta_e_max_deg", delta_e_max_deg, 1.0_dp, 45.0_dp, "deg", error)
    ! the empennage's share of the lift and side-force slopes (gust penetration)
    call require_range(f, "aircraft", "cl_alpha_tail", cl_alpha_tail, 0.0_dp, cl_alpha, &
      "1/rad: the tail's share of cl_alpha", error)
    call require_range(f, "aircraft", "cy_beta_fin", cy_beta_fin, -10.0_dp, 0.0_dp, "1/rad", error)
    ! lateral-directional derivatives: the damping ones <= 0 (a rate that fed
    ! itself would be a model error), the others of either sign (C_l_beta > 0
    ! is anhedral, C_n_beta < 0 a directionally unstable airframe)
    call require_range(f, "aircraft", "cy_beta", cy_beta, -10.0_dp, 0.0_dp, "1/rad", error)
    call require_range(f, "aircraft", "croll_beta", croll_beta, -10.0_dp, 10.0_dp, "1/rad", error)
    call require_range(f, "aircraft", "croll_p", croll_p, -10.0_dp, 0.0_dp, "1/rad (roll damping)", error)
    call require_range(f, "aircraft", "croll_r", croll_r, -10.0_dp, 10.0_dp, "1/rad", error)
    call require_range(f, "aircraft", "cn_beta", cn_beta, -10.0_dp, 10.0_dp, "1/rad", error)
    call require_range(f, "aircraft", "cn_p", cn_p, -10.0_dp, 10.0_dp, "1/rad", error)
    call require_range(f, "aircraft", "cn_r", cn_r, -10.0_dp, 0.0_dp, "1/rad (yaw damping)", error)
    if (allocated(error)) return
    c%mass = mass; c%inertia = [ixx, iyy, izz]; c%dynamics = dynamics; c%control = control
    c%aero%wing_area = wing_area; c%aero%span = span; c%aero%chord = chord; c%aero%cl0 = cl0
    c%aero%cl_alpha = cl_alpha; c%aero%cl_de = cl_de; c%aero%cd0 = cd0; c%aero%k_induced = k_induced
    c%aero%cm0 = cm0; c%aero%cm_alpha = cm_alpha; c%aero%cm_q = cm_q; c%aero%cm_de = cm_de
    c%aero%k_theta = k_theta; c%aero%k_q = k_q; c%aero%delta_e_max = delta_e_max_deg*deg2rad
    c%aero%cl_alpha_tail = cl_alpha_tail; c%aero%cy_beta_fin = cy_beta_fin
    c%aero%cy_beta = cy_beta; c%aero%croll_beta = croll_beta; c%aero%croll_p = croll_p
    c%aero%croll_r = croll_r; c%aero%cn_beta = cn_beta; c%aero%cn_p = cn_p; c%aero%cn_r = cn_r
    c%aero%attitude_hold = control == "attitude_hold"
    do while (buffer%another_try())
      write(buffer%lines, nml=aircraft, iostat=buffer%ios)
    end do
    call buffer%append_to(echo)
  end subroutine read_aircraft

  subroutine read_bay(f, c, echo, error)
    type(nml_file), intent(in) :: f
    type(bay_config), intent(inout) :: c
    character(len=:), allocatable, intent(inout) :: echo
    type(error_type), allocatable, intent(inout) :: error
    real(dp) :: ramp_edge_x, floor_y, length, width, height, friction, release_time, l0, tail_x, tail_y
    real(dp) :: rail_angle_deg, tail_half_span
    character(len=16) :: edge_contact
    character(len=8) :: l0_from
    integer :: u, ios
    logical :: present
    character(len=256) :: msg
    type(echo_buffer) :: buffer
    namelist /bay/ ramp_edge_x, floor_y, length, width, height, friction, release_time, l0, l0_from, &
      edge_contact, tail_x, tail_y, tail_half_span, rail_angle_deg
    type(nml_var), parameter :: vars(14) = [nml_var("tail_x", "real"), nml_var("tail_y", "real"), &
      nml_var("tail_half_span", "real"), &
      nml_var("ramp_edge_x", "real"), nml_var("floor_y", "real"), &
      nml_var("length", "real"), nml_var("width", "real"), nml_var("height", "real"), &
      nml_var("friction", "real"), nml_var("release_time", "real"), nml_var("l0", "real"), &
      nml_var("l0_from", "string", 8), nml_var("edge_contact", "string", 16), nml_var("rail_angle_deg", "real")]
    ramp_edge_x = c%ramp_edge_x; floor_y = c%floor_y; length = c%length; width = c%width
    height = c%height; friction = c%friction; release_time = c%release_time; l0 = c%l0_given
    l0_from = c%l0_from
    edge_contact = c%edge_contact; tail_x = c%tail_x; tail_y = c%tail_y
    tail_half_span = c%tail_half_span
    rail_angle_deg = c%rail_angle*rad2deg
    call open_group(f, "bay", vars, u, present, error)
    if (allocated(error)) return
    if (present) then
      read(u, nml=bay, iostat=ios, iomsg=msg)
      close(u)
      if (ios /= 0) then
        call f%diagnose("bay", vars, msg, error)
        return
      end if
    end if
    call require_positive(f, "bay", "length", length, "m", error)
    call require_positive(f, "bay", "width", width, "m", error)
    call require_positive(f, "bay", "height", height, "m", error)
    call require_range(f, "bay", "friction", friction, 0.0_dp, 1.0_dp, "", error)
    call require_nonnegative(f, "bay", "release_time", release_time, "s", error)
    call require_range(f, "bay", "tail_half_span", tail_half_span, 0.0_dp, 100.0_dp, "m", error)
    call require_positive(f, "bay", "l0", l0, "m", error)
    call require_choice(f, "bay", "l0_from", l0_from, [character(len=8) :: "cg", "tail"], error)
    call require_choice(f, "bay", "edge_contact", edge_contact, [character(len=16) :: "one_sided", "bilateral"], error)
    call require_range(f, "bay", "rail_angle_deg", rail_angle_deg, -rail_angle_max_deg, rail_angle_max_deg, &
      "deg (positive nose up)", error)
    if (allocated(error)) return
    c = bay_config(ramp_edge_x=ramp_edge_x, floor_y=floor_y, length=length, width=width, height=height, &
      friction=friction, release_time=release_time, l0=l0, l0_from=l0_from, l0_given=l0, &
      edge_contact=edge_contact, tail_x=tail_x, tail_y=tail_y, &
      tail_half_span=tail_half_span, rail_angle=rail_angle_deg*deg2rad)
    do while (buffer%another_try())
      write(buffer%lines, nml=bay, iostat=buffer%ios)
    end do
    call buffer%append_to(echo)
  end subroutine read_bay

  subroutine read_rocket(f, c, echo, error)
    type(nml_file), intent(in) :: f
    type(rocket_config), intent(inout) :: c
    character(len=:), allocatable, intent(inout) :: echo
    type(error_type), allocatable, intent(inout) :: error
    real(dp) :: mass, ixx, iyy, izz, length, diameter, cg_from_nose, tie_down_from_nose
    real(dp) :: cp_pot_from_nose, c_axial, c_dn, eta
    real(dp) :: fin_semi_span, fin_root_chord, fin_tip_chord, fin_sweep, fin_root_le_from_nose
    ! the optional Mach tables, read into arrays longer than a table may be
    ! (unset_real past the values given) so that too many points are named
    ! in one line, not a runtime read error
    real(dp), allocatable :: c_dn_mach(:), c_dn_table(:), c_axial_mach(:), c_axial_table(:)
    integer :: n_strips, fin_count, u, ios, n_dn, n_axial
    logical :: present
    character(len=256) :: msg
    character(len=:), allocatable :: group_text
    type(echo_buffer) :: buffer
    namelist /rocket/ mass, ixx, iyy, izz, length, diameter, cg_from_nose, tie_down_from_nose, &
      cp_pot_from_nose, c_axial, c_dn, eta, n_strips, fin_count, fin_semi_span, fin_root_chord, &
      fin_tip_chord, fin_sweep, fin_root_le_from_nose, c_dn_mach, c_dn_table, c_axial_mach, c_axial_table
    type(nml_var), parameter :: vars(23) = [nml_var("mass", "real"), nml_var("ixx", "real"), &
      nml_var("iyy", "real"), nml_var("izz", "real"), nml_var("length", "real"), &
      nml_var("diameter", "real"), nml_var("cg_from_nose", "real"), nml_var("tie_down_from_nose", "real"), &
      nml_var("cp_pot_from_nose", "real"), nml_var("c_axial", "real"), nml_var("c_dn", "real"), &
      nml_var("eta", "real"), nml_var("n_strips", "integer"), nml_var("fin_count", "integer"), &
      nml_var("fin_semi_span", "real"), nml_var("fin_root_chord", "real"), nml_var("fin_tip_chord", "real"), &
      nml_var("fin_sweep", "real"), nml_var("fin_root_le_from_nose", "real"), nml_var("c_dn_mach", "real_array", max_mach_points), &
      nml_var("c_dn_table", "real_array", max_mach_points), nml_var("c_axial_mach", "real_array", max_mach_points), &
      nml_var("c_axial_table", "real_array", max_mach_points)]
    allocate(c_dn_mach(max_table_read), c_dn_table(max_table_read), c_axial_mach(max_table_read), &
      c_axial_table(max_table_read), source=unset_real)
    associate(a => c%aero)
      mass = c%mass; ixx = c%inertia(1); iyy = c%inertia(2); izz = c%inertia(3)
      length = a%length; diameter = a%diameter; cg_from_nose = a%cg_from_nose
      tie_down_from_nose = c%tie_down_from_nose; cp_pot_from_nose = a%cp_pot_from_nose
      c_axial = a%c_axial; c_dn = a%c_dn; eta = a%eta; n_strips = a%n_strips
      c_dn_mach(:a%n_c_dn) = a%c_dn_mach(:a%n_c_dn); c_dn_table(:a%n_c_dn) = a%c_dn_table(:a%n_c_dn)
      c_axial_mach(:a%n_c_axial) = a%c_axial_mach(:a%n_c_axial)
      c_axial_table(:a%n_c_axial) = a%c_axial_table(:a%n_c_axial)
    end associate
    fin_count = c%fin_count; fin_semi_span = c%fin_semi_span; fin_root_chord = c%fin_root_chord
    fin_tip_chord = c%fin_tip_chord; fin_sweep = c%fin_sweep; fin_root_le_from_nose = c%fin_root_le_from_nose
    call open_group(f, "rocket", vars, u, present, error)
    if (allocated(error)) return
    if (present) then
      read(u, nml=rocket, iostat=ios, iomsg=msg)
      close(u)
      if (ios /= 0) then
        call f%diagnose("rocket", vars, msg, error)
        return
      end if
    end if
    call require_positive(f, "rocket", "mass", mass, "kg", error)
    call require_positive(f, "rocket", "ixx", ixx, "kg m^2", error)
    call require_positive(f, "rocket", "iyy", iyy, "kg m^2", error)
    call require_positive(f, "rocket", "izz", izz, "kg m^2", error)
    call require_positive(f, "rocket", "length", length, "m", error)
    call require_positive(f, "rocket", "diameter", diameter, "m", error)
    call require_range(f, "rocket", "cg_from_nose", cg_from_nose, 0.0_dp, length, "m (inside the rocket)", error)
    ! the separation's event (the nose passes the ramp edge after the CG did)
    ! needs the nose ahead of the CG: at 0 the set-up failed with exit 3
    if (.not. allocated(error) .and. cg_from_nose == 0.0_dp) call fatal_error(error, f%path // &
      ": &rocket: cg_from_nose = 0.0 is not allowed (must be > 0 m: the nose must lie ahead of the CG)")
    call require_range(f, "rocket", "tie_down_from_nose", tie_down_from_nose, 0.0_dp, length, &
      "m (inside the rocket)", error)
    call require_range(f, "rocket", "cp_pot_from_nose", cp_pot_from_nose, 0.0_dp, length, "m", error)
    call require_nonnegative(f, "rocket", "c_axial", c_axial, "", error)
    call require_nonnegative(f, "rocket", "c_dn", c_dn, "", error)
    call check_mach_table(f, "c_dn_mach", "c_dn_table", "cross-flow Mach numbers", c_dn_mach, c_dn_table, n_dn, error)
    call check_mach_table(f, "c_axial_mach", "c_axial_table", "free-stream Mach numbers", c_axial_mach, &
      c_axial_table, n_axial, error)
    call require_range(f, "rocket", "eta", eta, 0.0_dp, 1.0_dp, "", error)
    call require_int_range(f, "rocket", "n_strips", n_strips, 1, 1000, error)
    if (.not. allocated(error) .and. fin_count /= 0 .and. fin_count /= 3 .and. fin_count /= 4) &
      call fatal_error(error, f%path // ": &rocket: fin_count = " // str(fin_count) // &
        " is not allowed (0 = no fins, 3, or 4 in X configuration)")
    if (fin_count > 0) then
      ! both default to 0: a finned rocket must give them
      call require_positive(f, "rocket", "fin_semi_span", fin_semi_span, "m; required with fin_count = " // &
        str(fin_count), error)
      call require_positive(f, "rocket", "fin_root_chord", fin_root_chord, "m; required with fin_count = " // &
        str(fin_count), error)
      call require_nonnegative(f, "rocket", "fin_tip_chord", fin_tip_chord, "m", error)
      call require_nonnegative(f, "rocket", "fin_sweep", fin_sweep, "m", error)
      call require_range(f, "rocket", "fin_root_le_from_nose", fin_root_le_from_nose, 0.0_dp, &
        length - fin_root_chord, "m (the root chord must end at or ahead of the tail)", error)
    end if
    if (allocated(error)) return
    c%mass = mass; c%inertia = [ixx, iyy, izz]; c%tie_down_from_nose = tie_down_from_nose
    c%fin_count = fin_count; c%fin_semi_span = fin_semi_span; c%fin_root_chord = fin_root_chord
    c%fin_tip_chord = fin_tip_chord; c%fin_sweep = fin_sweep; c%fin_root_le_from_nose = fin_root_le_from_nose
    c%aero = rocket_aero(length=length, diameter=diameter, cg_from_nose=cg_from_nose, &
      cp_pot_from_nose=cp_pot_from_nose, c_axial=c_axial, c_dn=c_dn, eta=eta, n_strips=n_strips)
    c%aero%n_c_dn = n_dn
    c%aero%c_dn_mach(:n_dn) = c_dn_mach(:n_dn); c%aero%c_dn_table(:n_dn) = c_dn_table(:n_dn)
    c%aero%n_c_axial = n_axial
    c%aero%c_axial_mach(:n_axial) = c_axial_mach(:n_axial)
    c%aero%c_axial_table(:n_axial) = c_axial_table(:n_axial)
    if (fin_count > 0) call barrowman_fins(c)
    call write_group()
    group_text = ""
    call buffer%append_to(group_text)
    ! the tables given, and only those: the group's echo without them is the
    ! one before the tables existed (the paper's resolved input is unchanged)
    if (n_dn > 0) call insert_before_end(group_text, table_echo("C_DN_MACH", c_dn_mach(:n_dn)) // &
      table_echo("C_DN_TABLE", c_dn_table(:n_dn)))
    if (n_axial > 0) call insert_before_end(group_text, table_echo("C_AXIAL_MACH", c_axial_mach(:n_axial)) // &
      table_echo("C_AXIAL_TABLE", c_axial_table(:n_axial)))
    if (.not. allocated(echo)) echo = ""
    echo = echo // group_text
  contains
    !> The resolved group without the tables (a namelist writes whole arrays:
    !> the read's long ones would be echoed with their unset tails).  Its
    !> namelist is the read's less the four tables: a variable added to one
    !> goes into both (the resolved input must hold every value read).
    subroutine write_group()
      namelist /rocket/ mass, ixx, iyy, izz, length, diameter, cg_from_nose, tie_down_from_nose, &
        cp_pot_from_nose, c_axial, c_dn, eta, n_strips, fin_count, fin_semi_span, fin_root_chord, &
        fin_tip_chord, fin_sweep, fin_root_le_from_nose
      do while (buffer%another_try())
        write(buffer%lines, nml=rocket, iostat=buffer%ios)
      end do
    end subroutine write_group
  end subroutine read_rocket

  !> A Mach table (Mach points `xname`, values `yname`) as read: both or
  !> neither given, the same number of values without gaps, at most
  !> max_mach_points, Mach points >= 0 and strictly increasing, values >= 0.
  !> `n` receives its points (0: not given).
  subroutine check_mach_table(f, xname, yname, what, xs, ys, n, error)
    type(nml_file), intent(in) :: f
    character(len=*), intent(in) :: xname, yname, what   !< the two variables; what the points are
    real(dp), intent(in) :: xs(:), ys(:)                  !< as read (unset_real past the values)
    integer, intent(out) :: n                             !< points of the table
    type(error_type), allocatable, intent(inout) :: error
    integer :: nx, ny, i
    character(len=:), allocatable :: head
    n = 0
    if (allocated(error)) return
    head = f%path // ": &rocket: "
    nx = given(xs); ny = given(ys)
    do i = 1, nx
      if (xs(i) == unset_real) then
        call fatal_error(error, head // xname // "(" // str(i) // ") is not set, but " // xname // "(" // &
          str(nx) // ") is (give the points in order without gaps)")
        return
      end if
    end do
    do i = 1, ny
      if (ys(i) == unset_real) then
        call fatal_error(error, head // yname // "(" // str(i) // ") is not set, but " // yname // "(" // &
          str(ny) // ") is (give the values in order without gaps)")
        return
      end if
    end do
    if (nx > max_mach_points) then
      call fatal_error(error, head // xname // " = " // listed(xs(:nx)) // " is not allowed (" // str(nx) // &
        " points; at most " // str(max_mach_points) // ")")
    else if (ny > max_mach_points) then
      call fatal_error(error, head // yname // " = " // listed(ys(:ny)) // " is not allowed (" // str(ny) // &
        " values; at most " // str(max_mach_points) // ")")
    else if (ny == 0 .and. nx > 0) then
      call fatal_error(error, head // xname // " = " // listed(xs(:nx)) // " is not allowed without " // yname // &
        " (give " // yname // ", one value per point, or neither)")
    else if (nx == 0 .and. ny > 0) then
      call fatal_error(error, head // yname // " = " // listed(ys(:ny)) // " is not allowed without " // xname // &
        " (give " // xname // ", the " // what // " of the values, or neither)")
    else if (nx /= ny) then
      call fatal_error(error, head // yname // " = " // listed(ys(:ny)) // " is not allowed (" // str(ny) // &
        merge(" value ", " values", ny == 1) // " for the " // str(nx) // " points of " // xname // " = " // &
        listed(xs(:nx)) // ": one value per point)")
    end if
    if (allocated(error)) return
    do i = 1, nx
      if (.not. (xs(i) >= 0.0_dp)) then
        call fatal_error(error, head // xname // "(" // str(i) // ") = " // str(xs(i)) // &
          " is not allowed (must be >= 0: " // what // ")")
        return
      end if
    end do
    do i = 2, nx
      if (.not. (xs(i) > xs(i-1))) then
        call fatal_error(error, head // xname // " = " // listed(xs(:nx)) // " is not allowed (the " // what // &
          " must increase strictly: " // xname // "(" // str(i) // ") = " // str(xs(i)) // " <= " // xname // &
          "(" // str(i-1) // ") = " // str(xs(i-1)) // ")")
        return
      end if
    end do
    do i = 1, nx
      if (.not. (ys(i) >= 0.0_dp)) then
        call fatal_error(error, head // yname // "(" // str(i) // ") = " // str(ys(i)) // &
          " is not allowed (must be >= 0)")
        return
      end if
    end do
    n = nx
  contains
    !> The index of the last value given (0: none).
    pure integer function given(v)
      real(dp), intent(in) :: v(:)
      integer :: j
      given = 0
      do j = size(v), 1, -1
        if (v(j) /= unset_real) then
          given = j
          return
        end if
      end do
    end function given
  end subroutine check_mach_table

  !> Values as "a, b, c".
  pure function listed(v) result(s)
    real(dp), intent(in) :: v(:)
    character(len=:), allocatable :: s
    integer :: i
    s = ""
    do i = 1, size(v)
      if (i > 1) s = s // ", "
      s = s // str(v(i))
    end do
  end function listed

  !> An echo record ` NAME= a, b, c,` with 17 significant digits (the values
  !> read back bit for bit), ended by a newline.
  pure function table_echo(name, v) result(s)
    character(len=*), intent(in) :: name
    real(dp), intent(in) :: v(:)
    character(len=:), allocatable :: s
    character(len=32) :: b
    integer :: i
    s = " " // name // "="
    do i = 1, size(v)
      write(b, "(es24.16e3)") v(i)
      s = s // " " // trim(adjustl(b)) // ","
    end do
    s = s // new_line("a")
  end function table_echo

  !> Insert `lines` (whole lines) before the closing "/" of an echoed group.
  pure subroutine insert_before_end(text, lines)
    character(len=:), allocatable, intent(inout) :: text
    character(len=*), intent(in) :: lines
    integer :: k
    k = index(text, new_line("a") // " /", back=.true.)
    if (k == 0) k = index(text, new_line("a") // "/", back=.true.)
    text = text(:k) // lines // text(k+1:)
  end subroutine insert_before_end

  !> Fin normal-force slope and centre of pressure by Barrowman's equations
  !> (J. S. Barrowman, The practical calculation of the aerodynamic
  !> characteristics of slender finned vehicles, 1967): trapezoidal fins of
  !> semi-span s, root chord cr, tip chord ct, leading-edge sweep xr, on a body
  !> of radius R, with the fin-body interference factor 1 + R/(s + R):
  !>   CN_alpha = (1 + R/(s+R)) 4 N (s/d)^2 / (1 + sqrt(1 + (2 l_f/(cr + ct))^2)),
  !>   l_f = sqrt(s^2 + (xr + ct/2 - cr/2)^2),
  !>   x_cp = x_root_le + xr (cr + 2 ct)/(3 (cr + ct)) + (cr + ct - cr ct/(cr + ct))/6.
  !> At 90 deg the fins act as flat plates: C_N,90 = 1.28 A_proj/S_ref with the
  !> fin area projected normal to the cross-flow (4 fins in X: 2 sqrt(2) A; 3
  !> fins: 3 A 2/pi, the mean projection).
  subroutine barrowman_fins(c)
    type(rocket_config), intent(inout) :: c
    real(dp) :: r, s, cr, ct, xr, lf, area, s_ref, d
    d = c%aero%diameter
    r = d/2
    s = c%fin_semi_span; cr = c%fin_root_chord; ct = c%fin_tip_chord; xr = c%fin_sweep
    lf = sqrt(s**2 + (xr + ct/2 - cr/2)**2)
    c%aero%cn_alpha_fin = (1 + r/(s + r))*4*c%fin_count*(s/d)**2/(1 + sqrt(1 + (2*lf/(cr + ct))**2))
    c%aero%x_fin_from_nose = c%fin_root_le_from_nose + xr*(cr + 2*ct)/(3*(cr + ct)) + &
      (cr + ct - cr*ct/(cr + ct))/6
    c%aero%fin_root_le_from_nose = c%fin_root_le_from_nose
    c%aero%fin_root_chord = cr
    c%aero%fin_tip_chord = ct
    c%aero%fin_sweep = xr
    area = s*(cr + ct)/2
    s_ref = 4.0_dp*atan(1.0_dp)*d**2/4
    if (c%fin_count == 4) then
      c%aero%cn_fin_90 = 1.28_dp*2*sqrt(2.0_dp)*area/s_ref
    else
      c%aero%cn_fin_90 = 1.28_dp*3*area*2/(4.0_dp*atan(1.0_dp))/s_ref
    end if
  end subroutine barrowman_fins

  subroutine read_parachute(f, c, echo, error)
    type(nml_file), intent(in) :: f
    type(parachute), intent(inout) :: c
    character(len=:), allocatable, intent(inout) :: echo
    type(error_type), allocatable, intent(inout) :: error
    real(dp) :: mass, drag_area, cd0, deploy_time, fill_constant, inflation_exponent
    real(dp) :: packed_drag_area, added_mass_factor
    integer :: u, ios
    logical :: present
    character(len=256) :: msg
    character(len=:), allocatable :: given
    type(echo_buffer) :: buffer
    namelist /parachute/ mass, drag_area, cd0, deploy_time, fill_constant, inflation_exponent, &
      packed_drag_area, added_mass_factor
    type(nml_var), parameter :: vars(8) = [nml_var("mass", "real"), nml_var("drag_area", "real"), &
      nml_var("cd0", "real"), nml_var("deploy_time", "real"), nml_var("fill_constant", "real"), &
      nml_var("inflation_exponent", "real"), nml_var("packed_drag_area", "real"), &
      nml_var("added_mass_factor", "real")]
    mass = c%mass; drag_area = c%drag_area; cd0 = c%cd0; deploy_time = c%deploy_time
    fill_constant = c%fill_constant; inflation_exponent = c%inflation_exponent
    packed_drag_area = c%packed_drag_area; added_mass_factor = c%added_mass_factor
    call open_group(f, "parachute", vars, u, present, error)
    if (allocated(error)) return
    if (present) then
      read(u, nml=parachute, iostat=ios, iomsg=msg)
      close(u)
      if (ios /= 0) then
        call f%diagnose("parachute", vars, msg, error)
        return
      end if
    end if
    call require_positive(f, "parachute", "mass", mass, "kg", error)
    call require_positive(f, "parachute", "drag_area", drag_area, "m^2 (a parachute that never inflates cannot extract)", error)
    call require_range(f, "parachute", "cd0", cd0, 0.1_dp, 2.0_dp, "", error)
    call require_positive(f, "parachute", "fill_constant", fill_constant, "", error)
    ! j >= 1: below, the filling rate d/dt ((t - t_d)/t_f)^j is infinite at the
    ! deployment, and so is the apparent mass's momentum force (docs/model.md)
    call require_range(f, "parachute", "inflation_exponent", inflation_exponent, 1.0_dp, 8.0_dp, "", error)
    call require_nonnegative(f, "parachute", "packed_drag_area", packed_drag_area, "m^2", error)
    call require_nonnegative(f, "parachute", "added_mass_factor", added_mass_factor, "", error)
    if (allocated(error)) return
    ! the packed drag area is the canopy's before a deployment during the run:
    ! a canopy open from the start never uses it (nor its default, 0.05 m^2,
    ! which a drogue of a small payload does not exceed)
    if (deploy_time >= 0.0_dp .and. packed_drag_area >= drag_area) then
      given = ""
      if (.not. f%is_set("parachute", "packed_drag_area")) given = " (the default)"
      call fatal_error(error, f%path // ": &parachute: packed_drag_area = " // str(packed_drag_area) // given // &
        " is not allowed (must be < drag_area = " // str(drag_area) // " m^2): the canopy deploys at " // &
        "deploy_time = " // str(deploy_time) // " s, packed until then; give a smaller packed_drag_area")
      return
    end if
    c%mass = mass; c%drag_area = drag_area; c%cd0 = cd0; c%deploy_time = deploy_time
    c%fill_constant = fill_constant; c%inflation_exponent = inflation_exponent
    c%packed_drag_area = packed_drag_area; c%added_mass_factor = added_mass_factor
    do while (buffer%another_try())
      write(buffer%lines, nml=parachute, iostat=buffer%ios)
    end do
    call buffer%append_to(echo)
  end subroutine read_parachute

  !> &gust: a discrete 1 - cosine gust (airlaunch_gust); no gust with both
  !> peak velocities zero (the default).  The group is echoed in any case, so a
  !> sweep may vary its values over a base scenario without it.
  subroutine read_gust(f, c, echo, error)
    type(nml_file), intent(in) :: f
    type(gust_config), intent(inout) :: c
    character(len=:), allocatable, intent(inout) :: echo
    type(error_type), allocatable, intent(inout) :: error
    real(dp) :: vertical, lateral, gradient_length, hit_time
    logical :: penetration, kussner
    integer :: u, ios
    logical :: present
    character(len=256) :: msg
    type(echo_buffer) :: buffer
    namelist /gust/ vertical, lateral, gradient_length, hit_time, penetration, kussner
    type(nml_var), parameter :: vars(6) = [nml_var("vertical", "real"), nml_var("lateral", "real"), &
      nml_var("gradient_length", "real"), nml_var("hit_time", "real"), nml_var("penetration", "logical"), &
      nml_var("kussner", "logical")]
    vertical = c%vertical; lateral = c%lateral; gradient_length = c%gradient_length; hit_time = c%hit_time
    penetration = c%penetration; kussner = c%kussner
    call open_group(f, "gust", vars, u, present, error)
    if (allocated(error)) return
    if (present) then
      read(u, nml=gust, iostat=ios, iomsg=msg)
      close(u)
      if (ios /= 0) then
        call f%diagnose("gust", vars, msg, error)
        return
      end if
    end if
    call require_range(f, "gust", "vertical", vertical, -gust_speed_max, gust_speed_max, "m/s", error)
    call require_range(f, "gust", "lateral", lateral, -gust_speed_max, gust_speed_max, "m/s", error)
    ! below 1 m the gust is shorter than the strips and the chords at which
    ! the bodies read it
    call require_range(f, "gust", "gradient_length", gradient_length, 1.0_dp, 1.0e5_dp, "m", error)
    call require_nonnegative(f, "gust", "hit_time", hit_time, "s", error)
    if (allocated(error)) return
    c = gust_config(vertical, lateral, gradient_length, hit_time, penetration, kussner)
    do while (buffer%another_try())
      write(buffer%lines, nml=gust, iostat=buffer%ios)
    end do
    call buffer%append_to(echo)
  end subroutine read_gust

  subroutine read_line(f, c, echo, error)
    type(nml_file), intent(in) :: f
    type(line_config), intent(inout) :: c
    character(len=:), allocatable, intent(inout) :: echo
    type(error_type), allocatable, intent(inout) :: error
    real(dp) :: length, ea, mass_per_length, damping, diameter, cd_normal, cd_tangential
    real(dp) :: outer_dt, inner_rtol, auto_min_strain, auto_max_strain_change, auto_dwell, auto_min_steps
    real(dp) :: inner_dt, breaking_strength, break_time, weak_link_strength
    integer :: n_seg, u, ios, break_segment, weak_link_segment
    character(len=16) :: coupling, far_end, coupling_by_phase(4), inner_scheme
    logical :: present
    character(len=256) :: msg
    logical :: enabled
    namelist /line/ enabled, length, n_seg, ea, mass_per_length, damping, diameter, cd_normal, cd_tangential, &
      coupling, outer_dt, inner_rtol, far_end, coupling_by_phase, auto_min_strain, auto_max_strain_change, &
      auto_dwell, auto_min_steps, inner_scheme, inner_dt, breaking_strength, break_time, break_segment, &
      weak_link_strength, weak_link_segment
    enabled = .true.
    length = c%length; n_seg = c%n_seg; ea = c%ea; mass_per_length = c%mass_per_length
    damping = c%damping; diameter = c%diameter; cd_normal = c%cd_normal
    cd_tangential = c%cd_tangential; coupling = c%coupling
    outer_dt = c%outer_dt; inner_rtol = c%inner_rtol; far_end = c%far_end
    coupling_by_phase = c%coupling_by_phase
    auto_min_strain = c%auto_min_strain; auto_max_strain_change = c%auto_max_strain_change
    auto_dwell = c%auto_dwell; auto_min_steps = c%auto_min_steps
    inner_scheme = c%inner_scheme; inner_dt = c%inner_dt
    breaking_strength = c%breaking_strength; break_time = c%break_time; break_segment = c%break_segment
    weak_link_strength = c%weak_link_strength; weak_link_segment = c%weak_link_segment
    call open_group(f, "line", line_vars, u, present, error)
    if (allocated(error)) return
    if (present) then
      call check_list_length(f, "line", "coupling_by_phase", 4, "a coupling for each of Case 0, 1, 2, 3", error)
      if (allocated(error)) then
        close(u)
        return
      end if
      read(u, nml=line, iostat=ios, iomsg=msg)
      close(u)
      if (ios /= 0) then
        call f%diagnose("line", line_vars, msg, error)
        return
      end if
    end if
    call require_positive(f, "line", "length", length, "m", error)
    call require_int_range(f, "line", "n_seg", n_seg, 1, 1000, error)
    call require_positive(f, "line", "ea", ea, "N", error)
    call require_positive(f, "line", "mass_per_length", mass_per_length, "kg/m", error)
    call require_nonnegative(f, "line", "damping", damping, "N s", error)
    call require_positive(f, "line", "diameter", diameter, "m", error)
    call require_nonnegative(f, "line", "cd_normal", cd_normal, "", error)
    call require_nonnegative(f, "line", "cd_tangential", cd_tangential, "", error)
    call require_choice(f, "line", "coupling", coupling, coupling_modes, error)
    call require_range(f, "line", "outer_dt", outer_dt, 1.0e-5_dp, 0.1_dp, "s", error)
    call require_range(f, "line", "inner_rtol", inner_rtol, 0.0_dp, 1.0e-2_dp, "(0: &run rtol)", error)
    call require_choice(f, "line", "far_end", far_end, [character(len=16) :: "parachute", "chain"], error)
    call check_coupling_choice(f, coupling, coupling_by_phase, error)
    call check_inner_scheme(f, coupling, inner_scheme, inner_dt, error)
    if (.not. allocated(error) .and. inner_scheme == "marching") &
      call check_marching_step(f, inner_dt, ea, mass_per_length, length/n_seg, damping, error)
    call check_auto_settings(f, coupling, auto_min_strain, auto_max_strain_change, auto_dwell, auto_min_steps, &
      error)
    call check_break(f, coupling, n_seg, breaking_strength, break_time, break_segment, launch_line_ends, error)
    call check_weak_link(f, coupling, n_seg, breaking_strength, weak_link_strength, weak_link_segment, &
      launch_line_ends, error)
    if (.not. allocated(error) .and. coupling /= "direct" .and. far_end == "chain" .and. n_seg < 2) &
      call fatal_error(error, f%path // ": &line: n_seg = " // str(n_seg) // " is not allowed with " // &
        "far_end = 'chain' (both end nodes follow the chain: need n_seg >= 2)")
    if (allocated(error)) return
    c = line_config(length, n_seg, ea, mass_per_length, damping, diameter, cd_normal, cd_tangential, coupling, &
      outer_dt, inner_rtol, far_end, enabled)
    if (coupling == "per_phase") c%coupling_by_phase = coupling_by_phase
    c%auto_min_strain = auto_min_strain
    c%auto_max_strain_change = auto_max_strain_change
    c%auto_dwell = auto_dwell
    c%auto_min_steps = auto_min_steps
    c%inner_scheme = inner_scheme
    c%inner_dt = inner_dt
    c%breaking_strength = breaking_strength
    c%break_time = break_time
    c%break_segment = break_segment
    c%weak_link_strength = weak_link_strength
    c%weak_link_segment = weak_link_segment
    call echo_line(c, echo)
  end subroutine read_line

  !> The line's break (a strength, or a cut at a given time and segment): the
  !> direct coupling only - the rigidized line is one rod of the chain, which
  !> cannot part (and 'per_phase' and 'auto' may hand the line to it).
  !> `ends`: where segment 1 and segment n_seg are, for the messages.
  subroutine check_break(f, coupling, n_seg, breaking_strength, break_time, break_segment, ends, error)
    type(nml_file), intent(in) :: f
    character(len=*), intent(in) :: coupling
    integer, intent(in) :: n_seg, break_segment
    real(dp), intent(in) :: breaking_strength, break_time
    character(len=*), intent(in) :: ends
    type(error_type), allocatable, intent(inout) :: error
    call require_nonnegative(f, "line", "breaking_strength", breaking_strength, "N; 0: the line never breaks", &
      error)
    call require_set(f, "line", "break_time", break_time, "s", error)
    if (allocated(error)) return
    if (.not. (break_time > 0.0_dp .or. break_time == -1.0_dp)) then
      call fatal_error(error, f%path // ": &line: break_time = " // str(break_time) // " is not allowed " // &
        "(must be > 0 s, or -1 for no scheduled break)")
    else if (break_segment < 1 .or. break_segment > n_seg) then
      call fatal_error(error, f%path // ": &line: break_segment = " // str(break_segment) // " is not allowed " // &
        "(must be an integer in [1, n_seg = " // str(n_seg) // "]: " // ends // ")")
    else if (break_segment /= 1 .and. break_time == -1.0_dp) then
      call fatal_error(error, f%path // ": &line: break_segment = " // str(break_segment) // " is not allowed " // &
        "without break_time (it is the segment the scheduled break cuts: set break_time or remove it)")
    else if ((breaking_strength > 0.0_dp .or. break_time > 0.0_dp) .and. coupling /= "direct") then
      call refuse_break_coupling(f, "a line break (breaking_strength or break_time)", coupling, error)
    end if
  end subroutine check_break

  !> A way for the line to part (`what`) with a coupling other than the
  !> direct one: the rigidized line is one rod of the chain, which cannot part
  !> (and 'per_phase' and 'auto' may hand the line to it).
  subroutine refuse_break_coupling(f, what, coupling, error)
    type(nml_file), intent(in) :: f
    character(len=*), intent(in) :: what, coupling
    type(error_type), allocatable, intent(inout) :: error
    call fatal_error(error, f%path // ": &line: " // what // " is not allowed with coupling = '" // &
      trim(coupling) // "' (only the direct coupling's line can part: set coupling = 'direct')")
  end subroutine refuse_break_coupling

  !> A scheduled cut (&line break_time) at or after the run's end would
  !> never be made: an input error.
  subroutine check_break_before_end(f, break_time, t_end, error)
    type(nml_file), intent(in) :: f
    real(dp), intent(in) :: break_time, t_end
    type(error_type), allocatable, intent(inout) :: error
    if (break_time >= t_end) call fatal_error(error, f%path // ": &line: break_time = " // str(break_time) // &
      " is not allowed (the line would never be cut: the run ends at t_end = " // str(t_end) // " s)")
  end subroutine check_break_before_end

  !> The input error of a strength that segment k's tension at t = 0 already
  !> reaches (`held`: what holds that tension), naming the variable that set it.
  subroutine refuse_reached_strength(breaking_strength, weak_link_strength, weak_link_segment, k, tension, held, &
      error)
    real(dp), intent(in) :: breaking_strength, weak_link_strength, tension
    integer, intent(in) :: weak_link_segment, k
    character(len=*), intent(in) :: held
    type(error_type), allocatable, intent(inout) :: error
    character(len=:), allocatable :: what
    what = "breaking_strength = " // str(breaking_strength)
    if (weak_link_strength > 0.0_dp .and. k == weak_link_segment) &
      what = "weak_link_strength = " // str(weak_link_strength)
    call fatal_error(error, "&line: " // what // " N is not allowed: " // held // " is already " // str(tension) // &
      " N (segment " // str(k) // ") at t = 0 s (give a strength above it, or 0 for a line that never breaks)")
  end subroutine refuse_reached_strength

  !> The line's weak link: a segment (default n_seg, at the parachute) that
  !> parts at a strength below the line's. weak_link_segment is resolved here
  !> (unset: n_seg); given without a weak link it is refused, as break_segment
  !> is without break_time. The direct coupling only (refuse_break_coupling).
  subroutine check_weak_link(f, coupling, n_seg, breaking_strength, weak_link_strength, weak_link_segment, ends, &
      error)
    type(nml_file), intent(in) :: f
    character(len=*), intent(in) :: coupling
    integer, intent(in) :: n_seg
    real(dp), intent(in) :: breaking_strength, weak_link_strength
    integer, intent(inout) :: weak_link_segment
    character(len=*), intent(in) :: ends
    type(error_type), allocatable, intent(inout) :: error
    if (allocated(error)) return
    call require_nonnegative(f, "line", "weak_link_strength", weak_link_strength, "N; 0: no weak link", error)
    if (allocated(error)) return
    if (weak_link_segment == unset_int) weak_link_segment = n_seg
    if (weak_link_segment < 1 .or. weak_link_segment > n_seg) then
      call fatal_error(error, f%path // ": &line: weak_link_segment = " // str(weak_link_segment) // " is not " // &
        "allowed (must be an integer in [1, n_seg = " // str(n_seg) // "]: " // ends // ")")
    else if (weak_link_segment /= n_seg .and. weak_link_strength == 0.0_dp) then
      call fatal_error(error, f%path // ": &line: weak_link_segment = " // str(weak_link_segment) // " is not " // &
        "allowed without weak_link_strength (it is the weak link's segment: set weak_link_strength or remove it)")
    else if (weak_link_strength > 0.0_dp .and. breaking_strength > 0.0_dp .and. &
             weak_link_strength >= breaking_strength) then
      call fatal_error(error, f%path // ": &line: weak_link_strength = " // str(weak_link_strength) // " N is " // &
        "not allowed (must be below breaking_strength = " // str(breaking_strength) // " N: a weak link is " // &
        "the line's weakest segment)")
    else if (weak_link_strength > 0.0_dp .and. coupling /= "direct") then
      call refuse_break_coupling(f, "a weak link (weak_link_strength)", coupling, error)
    end if
  end subroutine check_weak_link

  !> The resolved &line group: the variables of the chosen coupling mode only
  !> (coupling_by_phase with 'per_phase', the auto_* thresholds with 'auto'),
  !> so that the echo reads back without a contradiction.
  subroutine echo_line(c, echo)
    type(line_config), intent(in) :: c
    character(len=:), allocatable, intent(inout) :: echo
    real(dp) :: length, ea, mass_per_length, damping, diameter, cd_normal, cd_tangential
    real(dp) :: outer_dt, inner_rtol, auto_min_strain, auto_max_strain_change, auto_dwell, auto_min_steps
    real(dp) :: inner_dt, breaking_strength, break_time, weak_link_strength
    integer :: n_seg, break_segment, weak_link_segment
    character(len=16) :: coupling, far_end, coupling_by_phase(4), inner_scheme
    logical :: enabled
    type(echo_buffer) :: buffer
    namelist /line/ enabled, length, n_seg, ea, mass_per_length, damping, diameter, cd_normal, cd_tangential, &
      coupling, outer_dt, inner_rtol, far_end, inner_scheme, inner_dt, breaking_strength, break_time, &
      break_segment, weak_link_strength, weak_link_segment
    enabled = c%enabled
    length = c%length; n_seg = c%n_seg; ea = c%ea; mass_per_length = c%mass_per_length
    damping = c%damping; diameter = c%diameter; cd_normal = c%cd_normal
    cd_tangential = c%cd_tangential; coupling = c%coupling
    outer_dt = c%outer_dt; inner_rtol = c%inner_rtol; far_end = c%far_end
    coupling_by_phase = c%coupling_by_phase
    auto_min_strain = c%auto_min_strain; auto_max_strain_change = c%auto_max_strain_change
    auto_dwell = c%auto_dwell; auto_min_steps = c%auto_min_steps
    inner_scheme = c%inner_scheme; inner_dt = c%inner_dt
    breaking_strength = c%breaking_strength; break_time = c%break_time; break_segment = c%break_segment
    weak_link_strength = c%weak_link_strength; weak_link_segment = c%weak_link_segment
    ! each mode's group is its own namelist /line/, so each is written by an
    ! internal procedure of its own (called, not passed: no trampoline)
    select case (coupling)
    case ("per_phase")
      call write_per_phase(buffer)
    case ("auto")
      call write_auto(buffer)
    case default
      do while (buffer%another_try())
        write(buffer%lines, nml=line, iostat=buffer%ios)
      end do
    end select
    call buffer%append_to(echo)
  contains
    subroutine write_per_phase(b)
      type(echo_buffer), intent(inout) :: b
      namelist /line/ enabled, length, n_seg, ea, mass_per_length, damping, diameter, cd_normal, cd_tangential, &
        coupling, outer_dt, inner_rtol, far_end, coupling_by_phase, breaking_strength, break_time, break_segment, &
        weak_link_strength, weak_link_segment
      do while (b%another_try())
        write(b%lines, nml=line, iostat=b%ios)
      end do
    end subroutine write_per_phase
    subroutine write_auto(b)
      type(echo_buffer), intent(inout) :: b
      namelist /line/ enabled, length, n_seg, ea, mass_per_length, damping, diameter, cd_normal, cd_tangential, &
        coupling, outer_dt, inner_rtol, far_end, auto_min_strain, auto_max_strain_change, auto_dwell, &
        auto_min_steps, breaking_strength, break_time, break_segment, weak_link_strength, weak_link_segment
      do while (b%another_try())
        write(b%lines, nml=line, iostat=b%ios)
      end do
    end subroutine write_auto
  end subroutine echo_line

  !> The paper's marching line (`inner_scheme = 'marching'`) sub-steps the
  !> rigidized coupling's line: it needs coupling = 'rigidized' (the direct
  !> coupling integrates the nodes with the bodies; the per-phase and automatic
  !> choices hand CVODE's line over), and inner_dt belongs to it.
  subroutine check_inner_scheme(f, coupling, inner_scheme, inner_dt, error)
    type(nml_file), intent(in) :: f
    character(len=*), intent(in) :: coupling, inner_scheme
    real(dp), intent(in) :: inner_dt
    type(error_type), allocatable, intent(inout) :: error
    if (allocated(error)) return
    call require_choice(f, "line", "inner_scheme", inner_scheme, [character(len=16) :: "cvode", "marching"], error)
    call require_range(f, "line", "inner_dt", inner_dt, 0.0_dp, 0.1_dp, "s (0: 0.9 of the marching " // &
      "scheme's stability limit)", error)
    if (allocated(error)) return
    if (inner_scheme == "marching" .and. coupling /= "rigidized") then
      call fatal_error(error, f%path // ": &line: inner_scheme = 'marching' is not allowed with coupling = '" // &
        trim(coupling) // "' (the paper's marching sub-steps the line of coupling = 'rigidized' only)")
    else if (inner_scheme /= "marching" .and. inner_dt > 0.0_dp) then
      call fatal_error(error, f%path // ": &line: inner_dt = " // str(inner_dt) // " s is not allowed with " // &
        "inner_scheme = '" // trim(inner_scheme) // "' (it is the marching line's sub-step: set inner_scheme " // &
        "= 'marching' or remove it)")
    end if
  end subroutine check_inner_scheme

  !> The marching line's sub-step within its stability limit (the line's
  !> highest axial mode, line_model%stable_step).
  subroutine check_marching_step(f, inner_dt, ea, mass_per_length, l0, damping, error)
    type(nml_file), intent(in) :: f
    real(dp), intent(in) :: inner_dt, ea, mass_per_length, l0, damping
    type(error_type), allocatable, intent(inout) :: error
    real(dp) :: limit
    limit = marching_stable_step(ea, mass_per_length, l0, damping, 0.0_dp)
    if (inner_dt > limit) call fatal_error(error, f%path // ": &line: inner_dt = " // str(inner_dt) // " s is " // &
      "not allowed: above the marching line's stability limit " // str(limit) // " s for these ea, " // &
      "mass_per_length, damping and length/n_seg (use inner_dt <= that, or 0 for 0.9 of it)")
  end subroutine check_marching_step

  !> `coupling_by_phase` belongs to coupling = 'per_phase' and names a single
  !> coupling for each of the four phases.
  subroutine check_coupling_choice(f, coupling, by_phase, error)
    type(nml_file), intent(in) :: f
    character(len=*), intent(in) :: coupling
    character(len=*), intent(in) :: by_phase(:)   !< Case 0..3
    type(error_type), allocatable, intent(inout) :: error
    integer :: k
    if (allocated(error)) return
    if (coupling /= "per_phase") then
      if (f%is_set("line", "coupling_by_phase")) call fatal_error(error, f%path // ": &line: coupling_by_phase " // &
        "is not allowed with coupling = '" // trim(coupling) // "' (it is read with coupling = 'per_phase' only: " // &
        "remove it, or set coupling = 'per_phase')")
      return
    end if
    if (.not. f%is_set("line", "coupling_by_phase")) then
      call fatal_error(error, f%path // ": &line: missing required value coupling_by_phase (with coupling = " // &
        "'per_phase': four couplings, direct or rigidized, for Case 0, 1, 2, 3)")
      return
    end if
    do k = 1, size(by_phase)
      call require_choice(f, "line", "coupling_by_phase (Case " // str(k - 1) // ")", by_phase(k), &
        single_couplings, error)
    end do
  end subroutine check_coupling_choice

  !> The auto_* thresholds belong to coupling = 'auto'.
  subroutine check_auto_settings(f, coupling, min_strain, max_strain_change, dwell, min_steps, error)
    type(nml_file), intent(in) :: f
    character(len=*), intent(in) :: coupling
    real(dp), intent(in) :: min_strain, max_strain_change, dwell, min_steps
    type(error_type), allocatable, intent(inout) :: error
    character(len=32), parameter :: names(4) = [character(len=32) :: "auto_min_strain", &
      "auto_max_strain_change", "auto_dwell", "auto_min_steps"]
    integer :: k
    if (allocated(error)) return
    if (coupling /= "auto") then
      do k = 1, size(names)
        if (f%is_set("line", trim(names(k)))) then
          call fatal_error(error, f%path // ": &line: " // trim(names(k)) // " is not allowed with coupling = '" // &
            trim(coupling) // "' (it is read with coupling = 'auto' only: remove it, or set coupling = 'auto')")
          return
        end if
      end do
      return
    end if
    call require_range(f, "line", "auto_min_strain", min_strain, 0.0_dp, 0.5_dp, "", error)
    call require_range(f, "line", "auto_max_strain_change", max_strain_change, 1.0e-6_dp, 10.0_dp, "", error)
    call require_range(f, "line", "auto_dwell", dwell, 0.0_dp, 1.0e3_dp, "s", error)
    call require_range(f, "line", "auto_min_steps", min_steps, 0.0_dp, 1.0e6_dp, "(0: the line's state alone)", error)
  end subroutine check_auto_settings

  !> A list variable must have `n` values (counted as written, `r*value`
  !> repeats included): fewer would leave the rest at their defaults, more
  !> would not read.
  subroutine check_list_length(f, group, name, n, what, error)
    type(nml_file), intent(in) :: f
    character(len=*), intent(in) :: group, name, what
    integer, intent(in) :: n
    type(error_type), allocatable, intent(inout) :: error
    integer :: i, m
    if (allocated(error) .or. .not. allocated(f%items)) return
    do i = 1, size(f%items)
      associate(it => f%items(i))
        if (it%group /= group .or. it%name /= name) cycle
        m = list_length(it%value)
        if (m /= n) then
          call fatal_error(error, f%where(it) // name // " = " // it%value // " is not allowed (" // str(m) // &
            merge(" value ", " values", m == 1) // "; it needs " // str(n) // ": " // what // ")")
          return
        end if
      end associate
    end do
  end subroutine check_list_length

  !> Number of values in a namelist list value: items separated by commas or
  !> blanks outside quotes, `r*value` counting r.
  pure integer function list_length(v) result(m)
    character(len=*), intent(in) :: v
    integer :: i, j, r, ios
    character :: quote
    logical :: in_item
    m = 0
    i = 1
    in_item = .false.
    do while (i <= len(v))
      select case (v(i:i))
      case (",", " ")
        in_item = .false.
      case ("'", '"')
        quote = v(i:i)
        j = index(v(i+1:), quote)
        if (j == 0) j = len(v) - i
        if (.not. in_item) m = m + 1
        in_item = .true.
        i = i + j
      case ("*")
        ! r*value: the repeat count was counted as one item, the value
        ! after the star belongs to it
        j = i - 1
        do while (j >= 1)
          if (verify(v(j:j), "0123456789") /= 0) exit
          j = j - 1
        end do
        read(v(j+1:i-1), *, iostat=ios) r
        if (ios == 0) m = m + r - 1
        in_item = .true.
      case default
        if (.not. in_item) m = m + 1
        in_item = .true.
      end select
      i = i + 1
    end do
  end function list_length

  !> The value of `&line enabled` as the file sets it (true if the file does
  !> not set it, or sets something that is not a logical: read_line reports that).
  logical function line_enabled_in(f) result(enabled)
    type(nml_file), intent(in) :: f
    integer :: i, ios
    logical :: value
    enabled = .true.
    if (.not. allocated(f%items)) return
    do i = 1, size(f%items)
      if (f%items(i)%group /= "line" .or. f%items(i)%name /= "enabled") cycle
      read(f%items(i)%value, *, iostat=ios) value
      if (ios == 0) enabled = value
    end do
  end function line_enabled_in

  !> `&line enabled = .false.`: the scene has no line and no parachute.  Any
  !> other &line variable and any &parachute group contradict that and are
  !> rejected; the echo is `&line enabled = F /` alone (so a sweep cannot vary
  !> what does not exist).
  subroutine read_no_line(f, c, echo, error)
    type(nml_file), intent(in) :: f
    type(line_config), intent(inout) :: c
    character(len=:), allocatable, intent(inout) :: echo
    type(error_type), allocatable, intent(inout) :: error
    logical :: enabled
    integer :: u, i
    logical :: present
    type(echo_buffer) :: buffer
    namelist /line/ enabled
    call open_group(f, "line", line_vars, u, present, error)
    if (allocated(error)) return
    if (present) close(u)
    if (allocated(f%items)) then
      do i = 1, size(f%items)
        associate(it => f%items(i))
          if (it%group == "line" .and. it%name /= "enabled") then
            call fatal_error(error, f%where(it) // it%name // " = " // it%value // " is not allowed with " // &
              "enabled = .false. (no line: remove " // it%name // ", or set enabled = .true.)")
            return
          else if (it%group == "parachute") then
            call fatal_error(error, f%where(it) // it%name // " = " // it%value // " is not allowed with " // &
              "&line enabled = .false. (no line, no parachute: remove the &parachute group, or enable the line)")
            return
          end if
        end associate
      end do
    end if
    if (f%has_group("parachute")) then
      call fatal_error(error, f%path // ": &parachute: the group is not allowed with &line enabled = .false. " // &
        "(no line, no parachute: remove the group, or enable the line)")
      return
    end if
    c = line_config(enabled=.false.)
    enabled = .false.
    do while (buffer%another_try())
      write(buffer%lines, nml=line, iostat=buffer%ios)
    end do
    call buffer%append_to(echo)
  end subroutine read_no_line

  !> Geometry that cannot work: rocket not fitting the bay, line shorter than
  !> the way out, tie-down or CG outside the rocket.
  subroutine check_geometry(f, cfg, error)
    type(nml_file), intent(in) :: f
    type(scenario_config), intent(in) :: cfg
    type(error_type), allocatable, intent(inout) :: error
    real(dp) :: nose_ahead, tail_ahead
    associate(b => cfg%bay, r => cfg%rocket%aero)
      nose_ahead = b%l0 + r%cg_from_nose          ! nose ahead of the ramp edge at release
      tail_ahead = b%l0 - (r%length - r%cg_from_nose)
      if (b%l0_from == "tail" .and. nose_ahead > b%length) then
        call fatal_error(error, f%path // ": &bay: l0 = " // str(b%l0_given) // " is not allowed with l0_from = " // &
          "'tail' (the rocket does not fit the bay: its nose, " // str(r%length) // " m ahead of its tail, " // &
          "would be " // str(nose_ahead) // " m ahead of the ramp edge, the bay is length = " // str(b%length) // &
          " m: need l0 <= " // str(b%length - r%length) // " m, or a longer bay)")
      else if (tail_ahead < 0.0_dp) then
        call fatal_error(error, f%path // ": &bay: l0 = " // str(b%l0) // " is not allowed (the rocket's tail, " // &
          str(r%length - r%cg_from_nose) // " m aft of its CG, would be outside the bay: need l0 >= " // &
          str(r%length - r%cg_from_nose) // " m)")
      else if (nose_ahead > b%length) then
        call fatal_error(error, f%path // ": &bay: l0 = " // str(b%l0) // " is not allowed (the rocket does not " // &
          "fit the bay: its nose, " // str(r%cg_from_nose) // " m ahead of its CG, would be " // str(nose_ahead) // &
          " m ahead of the ramp edge, the bay is length = " // str(b%length) // " m: need l0 <= " // &
          str(b%length - r%cg_from_nose) // " m, or a longer bay)")
      else if (r%diameter > min(b%width, b%height)) then
        call fatal_error(error, f%path // ": &rocket: diameter = " // str(r%diameter) // &
          " is not allowed (the bay is " // str(b%width) // " m wide and " // str(b%height) // " m high)")
      else if (cfg%rocket%fin_count == 4 .and. 2*(r%diameter/2 + cfg%rocket%fin_semi_span)/sqrt(2.0_dp) > &
          min(b%width, b%height)) then
        call fatal_error(error, f%path // ": &rocket: fin_semi_span = " // str(cfg%rocket%fin_semi_span) // &
          " is not allowed (fins in X span " // str(2*(r%diameter/2 + cfg%rocket%fin_semi_span)/sqrt(2.0_dp)) // &
          " m across, the bay is " // str(min(b%width, b%height)) // " m)")
      else if (cfg%rocket%fin_count == 3 .and. .not. three_fins_fit(r%diameter/2 + cfg%rocket%fin_semi_span, &
          b%width, b%height)) then
        call fatal_error(error, f%path // ": &rocket: fin_semi_span = " // str(cfg%rocket%fin_semi_span) // &
          " is not allowed (3 fins at 120 deg, their tips " // str(r%diameter/2 + cfg%rocket%fin_semi_span) // &
          " m from the axis, fit the bay, " // str(b%width) // " m wide and " // str(b%height) // &
          " m high, in no roll orientation: need fin_semi_span <= " // &
          str(largest_three_fin_tip(b%width, b%height) - r%diameter/2) // " m)")
      else if (cfg%line%enabled .and. cfg%line%length <= nose_ahead - cfg%rocket%tie_down_from_nose) then
        call fatal_error(error, f%path // ": &line: length = " // str(cfg%line%length) // &
          " is not allowed (shorter than the " // str(nose_ahead - cfg%rocket%tie_down_from_nose) // &
          " m from the tie-down point to the ramp edge)")
      end if
    end associate
  end subroutine check_geometry

  !> Three fins at 120 deg with their tips at `rho` from the rocket's axis fit
  !> a bay `width` wide and `height` high in some roll orientation.  Their tips
  !> span an equilateral triangle whose width across a direction at d from
  !> one of its sides' normals is sqrt(3) rho cos(d), d in [0, 30] deg, and
  !> 90 deg further sqrt(3) rho cos(30 deg - d): they fit where both fit, i.e.
  !> where the angles d_w = acos(width/(sqrt(3) rho)), d_h (height) that the
  !> two need (0 when a side fits in any orientation) add up to at most 30 deg.
  !> (The body's diameter is checked apart.)
  pure logical function three_fins_fit(rho, width, height) result(fit)
    real(dp), intent(in) :: rho, width, height   !< [m]
    real(dp), parameter :: thirty_deg = 30.0_dp*deg2rad
    real(dp) :: full
    full = sqrt(3.0_dp)*rho
    fit = acos(min(1.0_dp, width/full)) + acos(min(1.0_dp, height/full)) <= thirty_deg
  end function three_fins_fit

  !> The largest tip radius of three fins that fit the bay (three_fins_fit),
  !> by bisection [m].
  pure real(dp) function largest_three_fin_tip(width, height) result(rho)
    real(dp), intent(in) :: width, height   !< [m]
    real(dp) :: lo, hi
    integer :: i
    lo = 0.0_dp
    hi = max(width, height)   ! 1.5 rho > either: no fit
    do i = 1, 100
      rho = 0.5_dp*(lo + hi)
      if (three_fins_fit(rho, width, height)) then
        lo = rho
      else
        hi = rho
      end if
    end do
    rho = lo
  end function largest_three_fin_tip
end module airlaunch_scenario_config
