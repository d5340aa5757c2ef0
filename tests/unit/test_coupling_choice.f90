!> The choice of the line coupling (airlaunch_coupling_choice) without solvers.
!>
!> 1. The indicator against hand-computed line states: a straight line of N
!>    equal segments stretched by eps and stretching uniformly at eps_dot
!>    (nodes x_k = k l0 (1 + eps) e, v_k = k l0 eps_dot e: every segment has
!>    strain eps and strain rate eps_dot exactly); the same line turning
!>    rigidly (v = w x x: no strain rate); a slack segment (strain < 0).
!>    Tolerances 1e-12 relative: a few flops on exact inputs.
!> 2. The hysteresis against a scripted indicator history: safe and busy for
!>    less than the dwell keeps the direct coupling, a full dwell switches,
!>    values between the two thresholds keep the rigidized coupling (no
!>    chatter), an unsafe value switches back at once and the dwell starts
!>    again; a safe but quiet line (few steps per outer step) stays direct, and
!>    a rigidized run whose line turns idle goes back after the dwell.
!> 3. The plan from the &line input (coupling_plan_of): per phase, single
!>    couplings, and a scene without a line is direct.
program test_coupling_choice
  use airlaunch_kinds, only: dp
  use airlaunch_scenario_config, only: scenario_config
  use airlaunch_coupling_choice, only: coupling_direct, coupling_rigidized, auto_settings, line_indicator, &
    line_indicator_of, coupling_plan, auto_switch, auto_hysteresis
  use airlaunch_launch_scene, only: coupling_plan_of
  use testing
  implicit none

  call section("indicator of hand-computed line states")
  call test_indicator()
  call section("hysteresis")
  call test_hysteresis()
  call section("plan from the input")
  call test_plan()
  call finish()

contains

  subroutine test_indicator()
    integer, parameter :: n = 6
    real(dp), parameter :: l0 = 4.0_dp, eps = 0.05_dp, eps_dot = -0.3_dp, h = 0.02_dp
    real(dp) :: x(3, 0:n), v(3, 0:n), e(3), w(3), c(3)
    type(auto_settings) :: s
    type(line_indicator) :: ind
    integer :: k
    s%interval = h
    s%min_strain = 1.0e-3_dp
    e = [-0.6_dp, 0.0_dp, 0.8_dp]
    c = [10.0_dp, 2.0_dp, -3.0_dp]
    do k = 0, n
      x(:, k) = c + k*l0*(1.0_dp + eps)*e
      v(:, k) = [200.0_dp, 1.0_dp, 0.0_dp] + k*l0*eps_dot*e
    end do
    ind = line_indicator_of(x, v, l0, s)
    call check_close(ind%min_strain, eps, "uniform stretch: min strain", rel=1.0e-12_dp)
    call check_close(ind%mean_strain, eps, "uniform stretch: mean strain", rel=1.0e-12_dp)
    call check_close(ind%max_strain_rate, abs(eps_dot), "uniform stretch: strain rate [1/s]", rel=1.0e-12_dp)
    call check_close(ind%strain_change, abs(eps_dot)*h/eps, "strain change per outer step = |eps_dot| H / eps", &
      rel=1.0e-12_dp)
    ! the same line turning rigidly about its first node: no strain rate
    w = [0.3_dp, -1.1_dp, 0.7_dp]
    do k = 0, n
      v(:, k) = [200.0_dp, 1.0_dp, 0.0_dp] + cross(w, x(:, k) - x(:, 0))
    end do
    ind = line_indicator_of(x, v, l0, s)
    call check_close(ind%max_strain_rate, 0.0_dp, "rigid rotation: strain rate", abs=1.0e-12_dp)
    call check_close(ind%strain_change, 0.0_dp, "rigid rotation: strain change", abs=1.0e-12_dp)
    ! a slack segment (shorter than l0): the smallest strain is negative, and
    ! the change is taken over the threshold when the mean strain is below it
    x(:, 3) = x(:, 2) + 0.9_dp*l0*e
    do k = 4, n
      x(:, k) = x(:, 3) + (k - 3)*l0*e
    end do
    v = 0.0_dp
    v(:, n) = 0.01_dp*e
    ind = line_indicator_of(x, v, l0, s)
    call check_close(ind%min_strain, -0.1_dp, "slack segment: min strain", rel=1.0e-12_dp)
    call check_close(ind%strain_change, 0.01_dp/l0*h/s%min_strain, &
      "mean strain below the threshold: change over the threshold", rel=1.0e-12_dp)
  end subroutine test_indicator

  subroutine test_hysteresis()
    type(auto_settings) :: s
    type(auto_switch) :: sw
    type(line_indicator) :: safe, between, unsafe_slack, unsafe_fast, quiet, calm
    integer :: k, switches, last
    real(dp) :: t
    s = auto_settings(min_strain=1.0e-3_dp, max_strain_change=0.05_dp, dwell=0.1_dp, interval=0.02_dp, &
      min_steps=8.0_dp)
    ! taut, slow and busy (the line costs 20 steps per outer step)
    safe = line_indicator(min_strain=0.05_dp, mean_strain=0.05_dp, strain_change=0.01_dp, steps=20.0_dp)
    ! between the thresholds: neither safe (change > 0.05) nor unsafe (< 0.1)
    between = line_indicator(min_strain=0.05_dp, mean_strain=0.05_dp, strain_change=0.07_dp, steps=20.0_dp)
    unsafe_slack = line_indicator(min_strain=0.4e-3_dp, mean_strain=0.05_dp, strain_change=0.0_dp, steps=20.0_dp)
    unsafe_fast = line_indicator(min_strain=0.05_dp, mean_strain=0.05_dp, strain_change=0.11_dp, steps=20.0_dp)
    ! taut and slow, but the line hardly costs steps: not busy (6 < 8), not idle (6 >= 4)
    calm = line_indicator(min_strain=0.05_dp, mean_strain=0.05_dp, strain_change=0.01_dp, steps=6.0_dp)
    ! ... and idle (3 < 8/2)
    quiet = line_indicator(min_strain=0.05_dp, mean_strain=0.05_dp, strain_change=0.01_dp, steps=3.0_dp)
    ! safe and busy from t = 0: direct until the dwell is over (checks at 0, 0.02, ...)
    do k = 0, 4
      call sw%decide(s, k*0.02_dp, safe)
    end do
    call check(sw%active == coupling_direct, "safe and busy for 0.08 s < dwell 0.1 s: still direct")
    call sw%decide(s, 0.1_dp, safe)
    call check(sw%active == coupling_rigidized, "safe and busy for the dwell: rigidized")
    call sw%decide(s, 0.12_dp, between)
    call check(sw%active == coupling_rigidized, "between the thresholds: stays rigidized")
    call sw%decide(s, 0.14_dp, unsafe_fast)
    call check(sw%active == coupling_direct, "change > " // "2 x threshold: direct at once")
    call sw%decide(s, 0.16_dp, between)
    call check(sw%active == coupling_direct, "between the thresholds: stays direct")
    call sw%decide(s, 0.18_dp, safe)
    call sw%decide(s, 0.2_dp, safe)
    call check(sw%active == coupling_direct, "the dwell starts again after a switch back")
    do k = 1, 4
      call sw%decide(s, 0.2_dp + k*0.02_dp, safe)
    end do
    call check(sw%active == coupling_rigidized, "safe and busy for the dwell again: rigidized")
    call sw%decide(s, 0.3_dp, unsafe_slack)
    call check(sw%active == coupling_direct, "min strain < threshold/" // "2: direct at once")
    call check(auto_hysteresis == 2.0_dp, "hysteresis factor 2")
    ! the cost condition
    sw = auto_switch()
    do k = 0, 50
      call sw%decide(s, k*0.02_dp, calm)
    end do
    call check(sw%active == coupling_direct, "safe but not busy (6 < 8 steps per outer step): stays direct")
    sw = auto_switch(active=coupling_rigidized)
    do k = 0, 50
      call sw%decide(s, k*0.02_dp, calm)
    end do
    call check(sw%active == coupling_rigidized, "rigidized, 6 steps (between 4 and 8): stays rigidized")
    do k = 0, 4
      call sw%decide(s, 1.02_dp + k*0.02_dp, quiet)
    end do
    call check(sw%active == coupling_rigidized, "idle (3 < 4 steps) for 0.08 s < dwell: stays rigidized")
    call sw%decide(s, 1.12_dp, quiet)
    call check(sw%active == coupling_direct, "idle for the dwell: direct (one system is cheaper)")
    s%min_steps = 0.0_dp
    sw = auto_switch()
    do k = 0, 5
      call sw%decide(s, k*0.02_dp, quiet)
    end do
    call check(sw%active == coupling_rigidized, "min_steps = 0: the line's state alone decides")
    s%min_steps = 8.0_dp
    ! an indicator hovering around the safe threshold: no chatter
    sw = auto_switch()
    switches = 0
    last = sw%active
    do k = 0, 500
      t = k*0.02_dp
      if (mod(k, 2) == 0) then
        call sw%decide(s, t, safe)
      else
        call sw%decide(s, t, between)
      end if
      if (sw%active /= last) switches = switches + 1
      last = sw%active
    end do
    call check(switches == 0, "indicator alternating safe / between for 10 s: no switch (the dwell is never full)")
    sw = auto_switch(active=coupling_rigidized)
    switches = 0
    last = sw%active
    do k = 0, 500
      if (mod(k, 2) == 0) then
        call sw%decide(s, k*0.02_dp, safe)
      else
        call sw%decide(s, k*0.02_dp, between)
      end if
      if (sw%active /= last) switches = switches + 1
      last = sw%active
    end do
    call check(switches == 0, "the same from the rigidized coupling: no switch (never beyond 2 x threshold)")
  end subroutine test_hysteresis

  subroutine test_plan()
    type(scenario_config) :: cfg
    type(coupling_plan) :: plan
    cfg%line%coupling = "per_phase"
    cfg%line%coupling_by_phase = [character(len=16) :: "rigidized", "direct", "direct", "rigidized"]
    cfg%line%outer_dt = 0.05_dp
    plan = coupling_plan_of(cfg)
    call check(all(plan%by_phase == [coupling_rigidized, coupling_direct, coupling_direct, coupling_rigidized]), &
      "per_phase: one coupling per Case 0..3")
    call check(plan%initial() == coupling_rigidized, "per_phase starts with Case 0's coupling")
    call check(plan%uses_rigidized() .and. plan%mixed(), "per_phase with a rigidized phase: mixed, uses the chain")
    call check_close(plan%auto%interval, 0.05_dp, "check cadence = outer_dt", rel=1.0e-15_dp)
    cfg%line%coupling = "rigidized"
    plan = coupling_plan_of(cfg)
    call check(all(plan%by_phase == coupling_rigidized) .and. .not. plan%mixed(), "rigidized: every phase, not mixed")
    cfg%line%coupling = "auto"
    plan = coupling_plan_of(cfg)
    call check(plan%initial() == coupling_direct .and. plan%uses_rigidized() .and. plan%mixed(), &
      "auto starts direct and may use the chain")
    cfg%line%enabled = .false.
    plan = coupling_plan_of(cfg)
    call check(plan%mode == "direct" .and. all(plan%by_phase == coupling_direct) .and. .not. plan%uses_rigidized(), &
      "no line: direct")
  end subroutine test_plan

  pure function cross(a, b) result(c)
    real(dp), intent(in) :: a(3), b(3)
    real(dp) :: c(3)
    c = [a(2)*b(3) - a(3)*b(2), a(3)*b(1) - a(1)*b(3), a(1)*b(2) - a(2)*b(1)]
  end function cross
end program test_coupling_choice
