!> The air-launch scene (the paper's scenario, §4-§5.2): build the system from
!> the inputs, trim it, integrate the four phases with event location, record
!> the output contract (docs/output.md) and the milestones.
module airlaunch_launch_scene
  use airlaunch_kinds, only: dp, pi, g0, rad2deg, deg2rad
  use airlaunch_error, only: error_type, fatal_error, add_output_error, run_status
  use airlaunch_strings, only: str
  use airlaunch_atmosphere, only: isa, air_state
  use airlaunch_gust, only: gust_field, make_gust
  use airlaunch_rotation, only: quat_from_euler
  use airlaunch_cvode, only: cvode_solver, cvode_options, cvode_stats, add_stats
  use airlaunch_interrupt, only: wall_clock
  use airlaunch_linalg, only: solve_banded
  use airlaunch_run_config, only: run_config, refuse_records
  use airlaunch_ncwrite, only: nc_writer
  use airlaunch_output_meta, only: write_run_metadata
  use airlaunch_scenario_config, only: scenario_config, line_config, refuse_reached_strength
  use airlaunch_trim, only: trim_problem, trim_result, trim_case0
  use airlaunch_rigid_body, only: rigid_body, new_rigid_body
  use airlaunch_force_source, only: gravity_source
  use airlaunch_cut_joint, only: cut_joint_geometry, cut_joint_options, phase_name, phase_free, &
    phase_preparation
  use airlaunch_line_model, only: line_params, segment_strengths
  use airlaunch_launch_loads, only: launch_loads
  use airlaunch_launch_system, only: launch_system, launch_nroots, rigid_size, launch_pitch_root, launch_clearance_root, &
    launch_gust_root, launch_break_root
  use airlaunch_launch_history, only: launch_result, launch_sample, launch_history, sample_launch, &
    record_milestones, write_milestones, event_or_minus, handle_launch_event, clearance_geometry_of, history_bytes
  use airlaunch_coupling_choice, only: coupling_plan, auto_settings, coupling_direct, coupling_rigidized, &
    coupling_index
  implicit none
  private
  public :: launch_result, run_launch, setup_launch, coupling_plan_of


  interface
    !> The scene with the line coupled as `plan` says: direct (b), rigidized
    !> (a), per phase or automatically (submodule airlaunch_launch_coupled).
    module subroutine run_coupled(run, cfg, plan, echo, res, error)
      implicit none
      type(run_config), intent(in) :: run
      type(scenario_config), intent(in) :: cfg
      type(coupling_plan), intent(in) :: plan
      character(len=*), intent(in) :: echo
      type(launch_result), intent(inout) :: res
      type(error_type), allocatable, intent(inout) :: error
    end subroutine run_coupled
  end interface

contains

  !> Build the system, trim it and fill its initial state y0 (relative
  !> variables, see airlaunch_launch_system).
  !>
  !> The trim needs the line's force on the tie-down point, which the settled
  !> line gives only once the trimmed attitude places it: the first pass trims
  !> with the steady pull along earth -x (canopy drag and skin friction), every
  !> further pass with the settled line's end force of the pass before (its
  !> weight pulls the tie-down down, ~250 N in the paper scenario), until the
  !> end force changes by at most 1e-9 of the total weight between passes (the
  !> order of the trim's own convergence, 1e-10, and of the line's settling,
  !> 1e-9 of its tension): the system then starts at rest to that tolerance.
  subroutine setup_launch(cfg, sys, y0, res, error)
    type(scenario_config), intent(in) :: cfg
    type(launch_system), intent(inout) :: sys
    real(dp), allocatable, intent(out) :: y0(:)
    type(launch_result), intent(inout) :: res
    type(error_type), allocatable, intent(inout) :: error
    type(launch_system) :: fresh
    type(air_state) :: air
    real(dp) :: v0, pull, f_tie(3), f_new(3), tol, y_low
    integer :: pass
    integer, parameter :: max_pass = 6

    air = isa(cfg%flight%altitude)
    v0 = cfg%flight%mach*air%sound_speed
    ! steady pull: the canopy's drag and the skin friction of the trailing line
    pull = 0.5_dp*air%density*v0**2*(cfg%chute%drag_area + cfg%line%cd_tangential*pi*cfg%line%diameter &
      *cfg%line%length)
    if (cfg%chute%deploy_time >= 0.0_dp) pull = 0.5_dp*air%density*v0**2*cfg%chute%packed_drag_area
    if (.not. cfg%line%enabled) pull = 0.0_dp
    f_tie = [-pull, 0.0_dp, 0.0_dp]
    tol = 1.0e-9_dp*(cfg%aircraft%mass + cfg%rocket%mass)*g0
    do pass = 1, max_pass
      sys = fresh   ! each pass builds the system afresh (also a system set up before)
      if (allocated(y0)) deallocate(y0)
      call build_trimmed(f_tie, error)
      if (allocated(error)) return
      if (.not. sys%has_line) exit
      f_new = sys%f(:, 0)
      res%trim_line_force_change_n = norm2(f_new - f_tie)
      res%trim_passes = pass
      if (norm2(f_new - f_tie) <= tol) exit
      if (pass == max_pass) then
        call fatal_error(error, "Case 0 trim (t = 0 s): the trim and the settled line's force on the " // &
          "tie-down point did not agree after " // str(max_pass) // " passes (last change " // &
          str(norm2(f_new - f_tie)) // " N, allowed " // str(tol) // " N)")
        return
      end if
      f_tie = f_new
    end do
    ! the aircraft's CG and the rocket's lowest point start above the ground
    ! (its event watches for a crossing only)
    call sys%sep%rocket_lowest_point(sys%sep%bodies(1)%r(2), sys%sep%bodies(1)%c(2, :), y_low)
    associate(y_air => sys%sep%bodies(0)%r(2))
      if (.not. min(y_air, y_low) > cfg%flight%ground_altitude) then
        call fatal_error(error, "&flight: ground_altitude = " // str(cfg%flight%ground_altitude) // &
          " m is not allowed: the rocket's lowest point starts at " // str(y_low) // " m and the aircraft's CG at " // &
          str(y_air) // " m, not both above it (the default 0 m is sea level; set ground_altitude lower, " // &
          "down to -1000 m)")
        res%status = "invalid_input"
        return
      end if
    end associate
    ! a strength the trimmed flight's steady tension already reaches: the line
    ! would part before the run starts (the event watches for a crossing only)
    if (allocated(sys%strength)) then   ! a line that can break
      call check_steady_tension(sys, cfg%line, error)
      if (allocated(error)) res%status = "invalid_input"
    end if
  contains
    !> One pass: the trim with the line's force f_line (earth frame) at the
    !> tie-down point, the bodies in the trimmed flight, the line settled.
    subroutine build_trimmed(f_line, error)
      real(dp), intent(in) :: f_line(3)
      type(error_type), allocatable, intent(inout) :: error
      type(trim_problem) :: tp
      type(trim_result) :: tr
      type(rigid_body) :: b0, b1
      type(cut_joint_geometry) :: geo
      type(cut_joint_options) :: jopt
      type(launch_loads) :: loads
      type(gust_field) :: gust
      type(line_params) :: lp
      real(dp) :: radius, r_rocket(3), r_tie(3), exit_dir(3), deck_normal(3), edge(3)
      integer :: n, i, status

      radius = cfg%rocket%aero%diameter/2
      sys%has_line = cfg%line%enabled
      if (sys%has_line) then
        ! the line: weight and drag on, ISA density along it
        lp = line_params(length=cfg%line%length, n_seg=cfg%line%n_seg, ea=cfg%line%ea, &
          mass_per_length=cfg%line%mass_per_length, damping=cfg%line%damping, diameter=cfg%line%diameter, &
          cd_normal=cfg%line%cd_normal, cd_tangential=cfg%line%cd_tangential, gravity=.true., air=.true.)
        call sys%line%init(lp, error)
        if (allocated(error)) return
        sys%chute = cfg%chute
        if (sys%chute%deploy_time >= 0.0_dp) sys%chute%fill_time = &
          sys%chute%fill_constant*sqrt(4*sys%chute%drag_area/(pi*sys%chute%cd0))/v0
      end if

      ! --- the rail (aircraft axes): through the ramp edge, at &bay rail_angle
      !     nose up to the body x axis; the rocket slides out along exit_dir
      !     (aft, and down for a nose-up rail), its skin on the rail
      call rail_geometry(cfg, exit_dir, deck_normal, edge)
      ! --- trim of the Case 0 system (aircraft + locked rocket + parachute pull)
      r_rocket = edge - cfg%bay%l0*exit_dir + radius*deck_normal
      r_tie = r_rocket - (cfg%rocket%aero%cg_from_nose - cfg%rocket%tie_down_from_nose)*exit_dir
      tp = trim_problem(aircraft_mass=cfg%aircraft%mass, rocket_mass=cfg%rocket%mass, r_rocket=r_rocket, &
        r_tie=r_tie, pull=-f_line(1), pull_y=f_line(2), density=air%density, speed=v0, &
        mode=cfg%flight%trim_mode, alpha_target=cfg%flight%trim_alpha)
      loads%aircraft = cfg%aircraft%aero
      call trim_case0(tp, loads%aircraft, tr, error)
      if (allocated(error)) then
        if (tr%infeasible) then
          ! an equilibrium the aircraft cannot fly: the scenario is impossible (bad input)
          res%status = "invalid_input"
          if (index(error%message, "trim: ") == 1) error%message = error%message(len("trim: ")+1:)
          error%message = "&flight: trim_mode = '" // trim(cfg%flight%trim_mode) // "' cannot trim the Case 0 " // &
            "flight at mach = " // str(cfg%flight%mach) // " (&aircraft cl0 = " // str(cfg%aircraft%aero%cl0) // &
            ", cm0 = " // str(cfg%aircraft%aero%cm0) // ", delta_e_max_deg = " // &
            str(cfg%aircraft%aero%delta_e_max*rad2deg) // "): " // error%message // &
            "; give cl0, cm0 that trim this flight or trim_mode = 'calibrate'"
          return
        end if
        error%message = "Case 0 trim (t = 0 s): " // error%message
        return
      end if
      res%trim_alpha_deg = tr%alpha*rad2deg
      res%trim_elevator_deg = tr%delta_e*rad2deg
      res%trim_thrust_n = tr%thrust
      res%trim_cl0 = tr%cl0
      res%trim_cm0 = tr%cm0

      ! --- bodies: aircraft in trimmed level flight, rocket locked on the rail
      b0 = new_rigid_body("aircraft", cfg%aircraft%mass, diag(cfg%aircraft%inertia), error)
      if (allocated(error)) return
      b0%r = [0.0_dp, cfg%flight%altitude, 0.0_dp]
      b0%v = [v0, 0.0_dp, 0.0_dp]
      call b0%set_attitude(quat_from_euler([0.0_dp, tr%alpha, 0.0_dp]))
      b1 = new_rigid_body("rocket", cfg%rocket%mass, diag(cfg%rocket%inertia), error)
      if (allocated(error)) return
      geo = cut_joint_geometry(rail_direction=exit_dir, floor_point=edge, edge_point=edge, &
        contact_point=[0.0_dp, -radius, 0.0_dp], nose_x=cfg%rocket%aero%cg_from_nose, &
        rocket_length=cfg%rocket%aero%length, rocket_radius=radius)
      jopt = cut_joint_options(mu_rail=cfg%bay%friction, mu_edge=cfg%bay%friction)
      sys%tie_down = [cfg%rocket%aero%cg_from_nose - cfg%rocket%tie_down_from_nose, 0.0_dp, 0.0_dp]
      sys%clr = clearance_geometry_of(cfg)
      call sys%sep%init(b0, b1, sys%tie_down, 1, geo, jopt, cfg%bay%release_time, error, &
        aircraft_prescribed=cfg%aircraft%dynamics == "prescribed")
      if (allocated(error)) return
      sys%sep%edge_bilateral = cfg%bay%edge_contact == "bilateral"
      sys%sep%ground_altitude = cfg%flight%ground_altitude
      call sys%sep%joint%place_on_rail(sys%sep%bodies(0), cfg%bay%l0, 0.0_dp, sys%sep%bodies(1))
      call sys%sep%add_source(gravity_source())
      loads%rocket = cfg%rocket%aero
      loads%edge_point = geo%edge_point
      loads%tie_down = sys%tie_down
      loads%aircraft_aero_on = cfg%aircraft%dynamics /= "prescribed"
      loads%line_on = sys%has_line
      ! the &gust, met by the aircraft's CG at hit_time if it flies on at V0
      ! (the trim and the line's settling are of the still-air flight: at
      ! t = 0 the gust is ahead of every point the scene reads it at)
      gust = make_gust([0.0_dp, cfg%gust%vertical, cfg%gust%lateral], cfg%gust%gradient_length, &
        b0%r(1) + v0*cfg%gust%hit_time)
      loads%gust = gust
      ! in still air nothing reads a gust: no stations to visit
      loads%penetration = cfg%gust%penetration .and. gust%active
      if (cfg%gust%kussner .and. gust%active) loads%kussner_chord = cfg%aircraft%aero%chord
      loads%aircraft%tail_point = [cfg%bay%tail_x, cfg%bay%tail_y, 0.0_dp]
      sys%gust_watch = gust%active
      sys%gust_back = gust%x_front + 2*gust%gradient
      if (gust%active) sys%gust_max_step = 0.25_dp*2*gust%gradient/v0
      if (sys%has_line) then
        sys%line%gust = gust
        sys%chute%gust = gust
        if (cfg%line%breaking_strength > 0.0_dp .or. cfg%line%weak_link_strength > 0.0_dp) &
          sys%strength = segment_strengths(cfg%line%n_seg, cfg%line%breaking_strength, &
            cfg%line%weak_link_strength, cfg%line%weak_link_segment)
        sys%break_time = cfg%line%break_time
        sys%break_segment = cfg%line%break_segment
      end if
      call sys%sep%add_source(loads)
      sys%iloads = size(sys%sep%sources)

      ! --- state: reference frame at V0, h0; the line trails straight aft from
      !     the tie-down point, stretched by the steady pull
      sys%v_ref = v0
      sys%h_ref = cfg%flight%altitude
      n = merge(sys%line%n, 0, sys%has_line)
      allocate(y0(rigid_size + 6*n), sys%yabs(rigid_size + 6*n), sys%ydabs(rigid_size + 6*n))
      allocate(sys%jac_y(rigid_size + 6*n), sys%jac_f0(rigid_size + 6*n), sys%jac_f1(rigid_size + 6*n), &
        sys%jac_inc(rigid_size + 6*n))
      call sys%sep%pack_state(y0(1:rigid_size))
      do i = 0, 1
        y0(13*i+1:13*i+3) = y0(13*i+1:13*i+3) - [0.0_dp, sys%h_ref, 0.0_dp]
        y0(13*i+4) = y0(13*i+4) - v0
      end do
      if (sys%has_line) then
        allocate(sys%x(3, 0:n), sys%v(3, 0:n), sys%f(3, 0:n), sys%tension(n))
        call place_line(sys, cfg, pull, air%density, v0, y0, error)
        if (allocated(error)) return
      end if
      call sys%prepare(0.0_dp, y0, status)
      call sys%sep%start(0.0_dp, sys%yabs(1:rigid_size), phase_preparation, error)
    end subroutine build_trimmed

    pure function diag(d) result(m)
      real(dp), intent(in) :: d(3)
      real(dp) :: m(3, 3)
      m = 0
      m(1, 1) = d(1); m(2, 2) = d(2); m(3, 3) = d(3)
    end function diag
  end subroutine setup_launch

  !> The rail in the aircraft's axes: the exit direction (aft along the rail,
  !> which &bay rail_angle_deg tilts nose up, so that it also descends), the
  !> deck's normal (up, normal to it in the plane of symmetry) and the ramp
  !> edge (ramp_edge_x, floor_y), which the rail line passes through.  The
  !> zero angle gives the paper's rail, -x at y = floor_y, to the bit.
  pure subroutine rail_geometry(cfg, exit_dir, deck_normal, edge)
    type(scenario_config), intent(in) :: cfg
    real(dp), intent(out) :: exit_dir(3), deck_normal(3), edge(3)
    real(dp) :: c, s
    c = cos(cfg%bay%rail_angle)
    s = sin(cfg%bay%rail_angle)
    exit_dir = [-c, -s, 0.0_dp]
    deck_normal = [-s, c, 0.0_dp]
    edge = [cfg%bay%ramp_edge_x, cfg%bay%floor_y, 0.0_dp]
  end subroutine rail_geometry

  !> A segment whose strength the trimmed flight's steady tension (sys%tension,
  !> the settled line's) already reaches would part before the run starts: an
  !> input error naming the variable that set that strength.
  subroutine check_steady_tension(sys, line, error)
    type(launch_system), intent(in) :: sys
    type(line_config), intent(in) :: line
    type(error_type), allocatable, intent(inout) :: error
    real(dp) :: margin
    integer :: k
    call sys%weakest_segment(margin, k)
    if (margin > 0.0_dp) return
    call refuse_reached_strength(line%breaking_strength, line%weak_link_strength, line%weak_link_segment, k, &
      sys%tension(k), "the trimmed flight's steady line tension", error)
  end subroutine check_steady_tension

  !> The line's nodes in y: trailing straight aft from the tie-down point,
  !> stretched by the steady pull, then settled to their static equilibrium.
  !> When Newton's method fails from that start (a weak pull, e.g. a packed
  !> canopy: the line then hangs metres below the straight line and Newton's
  !> first steps slacken segments), it restarts from the hanging shape
  !> (`hanging_line`).
  subroutine place_line(sys, cfg, pull, rho, v0, y0, error)
    type(launch_system), intent(inout) :: sys
    type(scenario_config), intent(in) :: cfg
    real(dp), intent(in) :: pull   !< steady pull of the parachute and line drag [N]
    real(dp), intent(in) :: rho    !< air density at the flight altitude [kg/m^3]
    real(dp), intent(in) :: v0     !< flight speed [m/s]
    real(dp), intent(inout) :: y0(:)
    type(error_type), allocatable, intent(inout) :: error
    real(dp) :: seg, dir(3), x0(3)
    integer :: n, k, i
    type(error_type), allocatable :: straight_error
    n = sys%line%n
    seg = sys%line%l0*(1.0_dp + pull/cfg%line%ea)
    dir = [-1.0_dp, 0.0_dp, 0.0_dp]
    x0 = sys%sep%bodies(1)%point_position(sys%tie_down) - [0.0_dp, sys%h_ref, 0.0_dp]
    do k = 1, n
      i = rigid_size + 6*(k - 1)
      y0(i+1:i+3) = x0 + k*seg*dir
      y0(i+4:i+6) = 0.0_dp
    end do
    call settle_line(sys, y0, straight_error)
    if (.not. allocated(straight_error)) return
    call hanging_line(sys, cfg%line%ea, rho, v0, x0, y0)
    call settle_line(sys, y0, error)
    if (allocated(error)) error%message = "Case 0 trim (t = 0 s): the towed line's equilibrium in the " // &
      "trimmed flight was not found from a straight nor from a hanging start: " // error%message // &
      " (the first: " // straight_error%message // ")"
  end subroutine place_line

  !> Node positions of the line in the steady flight, from the far end
  !> inwards: the force in segment k balances the loads on the nodes beyond it,
  !>   T_N t_N = D + W_N + A_N(t_N),  T_k t_k = T_(k+1) t_(k+1) + W_k + A_k(t_k),
  !> with D the canopy's drag (air from ahead at V0), W_k the weights (the
  !> canopy's at node N) and A_k the air load of segment k (cross-flow and
  !> skin friction as in the line model, lumped at node k), which depends on
  !> the segment's direction t_k = S_k/|S_k|: a fixed point, iterated; then
  !> x_k = x_(k-1) + l0 (1 + T_k/EA) t_k from the tie-down point x0.
  subroutine hanging_line(sys, ea, rho, v0, x0, y0)
    type(launch_system), intent(in) :: sys
    real(dp), intent(in) :: ea                 !< axial stiffness [N]
    real(dp), intent(in) :: rho                !< air density [kg/m^3]
    real(dp), intent(in) :: v0                 !< flight speed [m/s]
    real(dp), intent(in) :: x0(3)              !< tie-down point (reference frame) [m]
    real(dp), intent(inout) :: y0(:)
    real(dp) :: s(3, sys%line%n), beyond(3), w(3), x(3), t(3), u(3), ut(3), un(3), ell, cds
    integer :: n, k, i, fp
    n = sys%line%n
    u = [-v0, 0.0_dp, 0.0_dp]   ! air relative to the line
    cds = sys%chute%drag_area
    if (sys%chute%deploy_time >= 0.0_dp) cds = sys%chute%packed_drag_area
    beyond = 0.5_dp*rho*v0**2*cds*[-1.0_dp, 0.0_dp, 0.0_dp]
    t = [-1.0_dp, 0.0_dp, 0.0_dp]
    do k = n, 1, -1
      w = 0.0_dp
      if (sys%line%p%gravity) w(2) = -g0*sys%line%node_mass(k)
      if (k == n .and. sys%line%p%gravity) w(2) = w(2) - g0*sys%chute%mass
      ell = sys%line%l0
      do fp = 1, 50
        s(:, k) = beyond + w
        if (sys%line%p%air) then
          ut = dot_product(u, t)*t
          un = u - ut
          s(:, k) = s(:, k) + rho*ell*(0.5_dp*sys%line%p%cd_normal*sys%line%p%diameter*norm2(un)*un &
            + 0.5_dp*sys%line%p%cd_tangential*pi*sys%line%p%diameter*norm2(ut)*ut)
        end if
        if (norm2(s(:, k)) <= tiny(1.0_dp)) exit   ! no load beyond: keep the direction
        if (norm2(s(:, k)/norm2(s(:, k)) - t) < 1.0e-12_dp) exit
        t = 0.5_dp*(t + s(:, k)/norm2(s(:, k)))   ! relaxed: the cross-flow load turns with t
        t = t/norm2(t)
      end do
      if (norm2(s(:, k)) <= tiny(1.0_dp)) s(:, k) = t   ! a guess: 1 N along the last direction
      beyond = s(:, k)
    end do
    x = x0
    do k = 1, n
      ell = norm2(s(:, k))
      x = x + sys%line%l0*(1.0_dp + ell/ea)*s(:, k)/ell
      i = rigid_size + 6*(k - 1)
      y0(i+1:i+3) = x
      y0(i+4:i+6) = 0.0_dp
    end do
  end subroutine hanging_line

  !> Static equilibrium of the trailing line in the trimmed flight: every node
  !> moves with the aircraft at V0, node 0 is the tie-down point, and the node
  !> positions (1..N, node N the parachute) are found by Newton's method with a
  !> finite-difference block-tridiagonal Jacobian (3-colouring of the nodes,
  !> LAPACK band solve).  Starting in equilibrium removes the transient that a
  !> straight initial line would ring with (weight and drag sag it).
  subroutine settle_line(sys, y, error)
    type(launch_system), intent(inout) :: sys
    real(dp), intent(inout) :: y(:)
    type(error_type), allocatable, intent(inout) :: error
    integer :: n, m, it, color, k, c, i, j, row, col
    real(dp), allocatable :: r(:), r2(:), ab(:, :), du(:, :)
    real(dp) :: scale, h
    integer, parameter :: kl = 5, ku = 5
    n = sys%line%n
    m = 3*n
    allocate(r(m), r2(m), ab(2*kl + ku + 1, m), du(m, 1))
    h = 1.0e-5_dp
    call residual(y, r)
    ! forces are judged against the line's tension (round-off of EA eps sets the floor)
    scale = max(1.0_dp, maxval(abs(r)), maxval(sys%tension))
    do it = 1, 30
      if (maxval(abs(r)) <= 1.0e-9_dp*scale) exit
      ab = 0.0_dp
      do color = 0, 2
        do c = 1, 3
          do k = 1 + color, n, 3
            i = rigid_size + 6*(k - 1) + c
            y(i) = y(i) + h
          end do
          call residual(y, r2)
          do k = 1 + color, n, 3
            i = rigid_size + 6*(k - 1) + c
            y(i) = y(i) - h
            col = 3*(k - 1) + c
            do row = max(1, 3*(k - 2) + 1), min(m, 3*k + 3)
              ab(kl + ku + 1 + row - col, col) = (r2(row) - r(row))/h
            end do
          end do
        end do
      end do
      du(:, 1) = -r
      call solve_banded(ab, kl, ku, du, error, "static line equilibrium")
      if (allocated(error)) return
      do k = 1, n
        j = rigid_size + 6*(k - 1)
        y(j+1:j+3) = y(j+1:j+3) + du(3*k-2:3*k, 1)
      end do
      call residual(y, r)
    end do
    if (maxval(abs(r)) > 1.0e-6_dp*scale) call fatal_error(error, "the trailing line has no static " // &
      "equilibrium in the trimmed flight (residual " // str(maxval(abs(r))) // " N)")
  contains
    !> Node accelerations times masses in the steady flight (zero at equilibrium).
    subroutine residual(yy, res)
      real(dp), intent(in) :: yy(:)
      real(dp), intent(out) :: res(:)
      real(dp) :: ydot(size(yy))
      integer :: kk, status, ii
      call sys%prepare(0.0_dp, yy, status)
      ! nodes move with the aircraft: relative velocity zero
      call sys%rhs(0.0_dp, yy, ydot, status)
      do kk = 1, n
        ii = rigid_size + 6*(kk - 1)
        res(3*kk-2:3*kk) = ydot(ii+4:ii+6)*sys%line%node_mass(kk)
      end do
    end subroutine residual
  end subroutine settle_line

  !> Run the scene and write its output (unless run%trajectory is false),
  !> with the line coupling(s) of `&line coupling`.
  subroutine run_launch(run, cfg, echo, res, error)
    type(run_config), intent(in) :: run
    type(scenario_config), intent(in) :: cfg
    character(len=*), intent(in) :: echo
    type(launch_result), intent(out) :: res
    type(error_type), allocatable, intent(inout) :: error
    call run_coupled(run, cfg, coupling_plan_of(cfg), echo, res, error)
  end subroutine run_launch

  !> How the run chooses the line coupling, from `&line` (a scene without a
  !> line is direct: it has nothing to rigidize).
  pure function coupling_plan_of(cfg) result(plan)
    type(scenario_config), intent(in) :: cfg
    type(coupling_plan) :: plan
    integer :: k
    plan%mode = cfg%line%coupling
    plan%by_phase = coupling_direct
    select case (cfg%line%coupling)
    case ("rigidized")
      plan%by_phase = coupling_rigidized
    case ("per_phase")
      do k = 0, 3
        plan%by_phase(k) = coupling_index(cfg%line%coupling_by_phase(k))
      end do
    end select
    plan%auto = auto_settings(min_strain=cfg%line%auto_min_strain, max_strain_change=cfg%line%auto_max_strain_change, &
      dwell=cfg%line%auto_dwell, interval=cfg%line%outer_dt, min_steps=cfg%line%auto_min_steps)
    if (.not. cfg%line%enabled) then
      plan%mode = "direct"
      plan%by_phase = coupling_direct
    end if
  end function coupling_plan_of

end module airlaunch_launch_scene
