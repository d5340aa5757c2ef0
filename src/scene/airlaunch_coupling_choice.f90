!> Which of the two line couplings (DESIGN §4: (b) 'direct', (a) 'rigidized')
!> the air-launch scene integrates with, and when (`&line coupling`):
!>  * a single one for the whole run ('direct', 'rigidized');
!>  * one per phase ('per_phase', `coupling_by_phase` for Case 0..3): the scene
!>    switches at the phase changes (events, where CVODE restarts anyway);
!>  * automatically ('auto'): the rigidized coupling while it is both safe (an
!>    indicator of the flexible line's state says that a rigid rod frozen over
!>    an outer step represents it) and worth it (the line forces the direct
!>    coupling into short steps), the direct coupling otherwise.
!>
!> The indicator (`line_indicator_of`, docs/model.md "Choosing the coupling"):
!>  * taut: the smallest segment strain min eps_k.  The virtual body is rigid:
!>    it pushes where the line would go slack and transmits a snatch at once
!>    instead of through the line's elastic wave;
!>  * slow: the relative change of the line's stretch over one outer step H,
!>    max_k |eps_dot_k| H / max(mean eps, auto_min_strain): the virtual body's
!>    length, mass and deformation velocity are frozen over H;
!>  * busy: the steps per outer step of the integrator that carries the line
!>    (the caller measures it: the direct coupling's whole system, or the
!>    rigidized coupling's line sub-steps).  Both couplings integrate the same
!>    stiff line, and the rigidized one adds the chain's steps, so it only pays
!>    when the line forces many short steps on the direct coupling's whole
!>    system (the line sub-steps are cheaper than steps of the whole system).
!> Hysteresis (`auto_switch`): the rigidized coupling is taken when the line is
!> taut, slow and busy (min eps >= auto_min_strain, change <=
!> auto_max_strain_change, steps >= auto_min_steps) at every check for
!> `auto_dwell` seconds.  The direct coupling is taken back at the first check
!> with min eps < auto_min_strain/2 or a change > 2 auto_max_strain_change
!> (accuracy), or after `auto_dwell` seconds of fewer than auto_min_steps/2
!> line sub-steps per outer step (cost).  Between the thresholds the current
!> coupling stays, so an indicator hovering near a threshold does not chatter.
!>
!> Pure logic without solvers (unit-tested in tests/unit/test_coupling_choice.f90).
module airlaunch_coupling_choice
  use airlaunch_kinds, only: dp
  implicit none
  private
  public :: coupling_direct, coupling_rigidized, coupling_name, coupling_index
  public :: auto_settings, line_indicator, line_indicator_of, coupling_plan, auto_switch
  public :: auto_hysteresis

  !> The two couplings.
  integer, parameter :: coupling_direct = 0, coupling_rigidized = 1
  !> Factor between the thresholds for taking and for leaving the rigidized coupling.
  real(dp), parameter :: auto_hysteresis = 2.0_dp

  !> Thresholds of the automatic choice (`&line auto_*`).
  type :: auto_settings
    real(dp) :: min_strain = 1.0e-3_dp        !< taut: smallest segment strain to take the rigidized coupling
    real(dp) :: max_strain_change = 0.05_dp   !< slow: largest relative stretch change per outer step
    real(dp) :: dwell = 0.1_dp                !< the indicator must say safe this long first [s]
    real(dp) :: interval = 0.02_dp            !< check cadence and H of the strain change (outer_dt) [s]
    !> busy: the integrator that carries the line takes at least this many
    !> steps per outer step (0: the choice looks at the line's state only)
    real(dp) :: min_steps = 8.0_dp
  end type auto_settings

  !> The state of the flexible line as the automatic choice sees it.
  type :: line_indicator
    real(dp) :: min_strain = 0.0_dp      !< smallest segment strain
    real(dp) :: mean_strain = 0.0_dp     !< mean segment strain
    real(dp) :: max_strain_rate = 0.0_dp !< largest |d eps/dt| of a segment [1/s]
    real(dp) :: strain_change = 0.0_dp   !< max |eps_dot| H / max(mean eps, min_strain threshold)
    !> steps per outer step of the integrator that carries the line (the direct
    !> coupling's, or the rigidized coupling's line sub-steps) over the last
    !> check interval (set by the caller; not a property of the line state)
    real(dp) :: steps = 0.0_dp
  end type line_indicator

  !> How the couplings are chosen over a run.
  type :: coupling_plan
    character(len=16) :: mode = "direct"                  !< direct, rigidized, per_phase or auto
    integer :: by_phase(0:3) = coupling_direct            !< per_phase (and the single modes): Case 0..3
    type(auto_settings) :: auto                           !< auto: thresholds
  contains
    procedure :: initial => plan_initial
    procedure :: for_phase => plan_for_phase
    procedure :: uses_rigidized => plan_uses_rigidized
    procedure :: mixed => plan_mixed
  end type coupling_plan

  !> The automatic choice over time (hysteresis state).
  type :: auto_switch
    integer :: active = coupling_direct   !< the coupling in use
    !> start of the present stretch in which the other coupling is wanted (< 0: none) [s]
    real(dp) :: since = -1.0_dp
  contains
    procedure :: decide => switch_decide
  end type auto_switch

contains

  !> "direct" or "rigidized".
  pure function coupling_name(c) result(s)
    integer, intent(in) :: c
    character(len=:), allocatable :: s
    if (c == coupling_rigidized) then
      s = "rigidized"
    else
      s = "direct"
    end if
  end function coupling_name

  !> coupling_rigidized for "rigidized", else coupling_direct.
  pure integer function coupling_index(name) result(c)
    character(len=*), intent(in) :: name
    c = merge(coupling_rigidized, coupling_direct, trim(name) == "rigidized")
  end function coupling_index

  !> The coupling the run starts with (Case 0); 'auto' starts direct and
  !> switches once the indicator has said safe for the dwell time.
  pure integer function plan_initial(self) result(c)
    class(coupling_plan), intent(in) :: self
    c = self%for_phase(0)
    if (self%mode == "auto") c = coupling_direct
  end function plan_initial

  !> The coupling of a phase (0..3) for the fixed modes.
  pure integer function plan_for_phase(self, phase) result(c)
    class(coupling_plan), intent(in) :: self
    integer, intent(in) :: phase
    c = self%by_phase(max(0, min(3, phase)))
  end function plan_for_phase

  !> The run may use the rigidized coupling (its chain must then be built).
  pure logical function plan_uses_rigidized(self) result(r)
    class(coupling_plan), intent(in) :: self
    r = self%mode == "auto" .or. any(self%by_phase == coupling_rigidized)
  end function plan_uses_rigidized

  !> The coupling may change during the run (per_phase or auto): the output
  !> then records which one was active.
  pure logical function plan_mixed(self) result(r)
    class(coupling_plan), intent(in) :: self
    r = self%mode == "per_phase" .or. self%mode == "auto"
  end function plan_mixed

  !> The indicator of the line state x(3,0:N), v(3,0:N) (node 0 at the rocket,
  !> earth frame) with unstretched segment length l0, for checks every
  !> `s%interval` seconds.  No allocation.
  pure function line_indicator_of(x, v, l0, s) result(ind)
    real(dp), intent(in) :: x(:, 0:), v(:, 0:)
    real(dp), intent(in) :: l0
    type(auto_settings), intent(in) :: s
    type(line_indicator) :: ind
    real(dp) :: d(3), len_k, eps, rate, total
    integer :: k, n
    n = ubound(x, 2)
    ind%min_strain = huge(1.0_dp)
    ind%max_strain_rate = 0.0_dp
    total = 0.0_dp
    do k = 1, n
      d = x(:, k) - x(:, k-1)
      len_k = norm2(d)
      eps = len_k/l0 - 1.0_dp
      rate = 0.0_dp
      if (len_k > 0.0_dp) rate = dot_product(d, v(:, k) - v(:, k-1))/(len_k*l0)
      ind%min_strain = min(ind%min_strain, eps)
      ind%max_strain_rate = max(ind%max_strain_rate, abs(rate))
      total = total + eps
    end do
    ind%mean_strain = total/max(n, 1)
    ind%strain_change = ind%max_strain_rate*s%interval/max(ind%mean_strain, s%min_strain, tiny(1.0_dp))
  end function line_indicator_of

  !> The coupling wanted at time t with the indicator `ind` (see the module
  !> header); updates the hysteresis state (self%active is the answer).
  subroutine switch_decide(self, s, t, ind)
    class(auto_switch), intent(inout) :: self
    type(auto_settings), intent(in) :: s
    real(dp), intent(in) :: t
    type(line_indicator), intent(in) :: ind
    logical :: safe, unsafe, busy, idle
    safe = ind%min_strain >= s%min_strain .and. ind%strain_change <= s%max_strain_change
    unsafe = ind%min_strain < s%min_strain/auto_hysteresis .or. &
      ind%strain_change > s%max_strain_change*auto_hysteresis
    busy = ind%steps >= s%min_steps
    idle = ind%steps < s%min_steps/auto_hysteresis
    if (self%active == coupling_rigidized) then
      if (unsafe) then
        ! accuracy: back at once
        self%active = coupling_direct
        self%since = -1.0_dp
      else if (idle) then
        ! cost: one system is cheaper than two once the line is quiet
        call wait_then_switch(coupling_direct)
      else
        self%since = -1.0_dp
      end if
    else if (safe .and. busy) then
      call wait_then_switch(coupling_rigidized)
    else
      self%since = -1.0_dp
    end if
  contains
    subroutine wait_then_switch(to)
      integer, intent(in) :: to
      if (self%since < 0.0_dp) self%since = t
      if (t - self%since >= s%dwell*(1.0_dp - 1.0e-9_dp)) then
        self%active = to
        self%since = -1.0_dp
      end if
    end subroutine wait_then_switch
  end subroutine switch_decide
end module airlaunch_coupling_choice
