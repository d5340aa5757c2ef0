!> One summary row of a sweep: the case id, its status (ok, failed, invalid
!> input), the failure message and the metrics of the base scene's result
!> (airlaunch_launch_scene's launch_result, or airlaunch_line_scene's
!> line_result: each scene its own set of summary variables, metric_set),
!> with the row's text form in the journal.
!>
!> Journal line: `<adler32> <id> <status> <environment> <n> <m_1> ... <m_n>
!> <message>`, the checksum (8 hex digits) covering everything after it, the
!> environment the tag (16 hex digits, `-` for none) of the runtime numerical
!> environment of the rank that ran the case (journal/environments.txt), the
!> reals written with 17 significant digits so that they read back bit for
!> bit.  A line cut short by a kill fails the checksum and is ignored (its case
!> runs again).
module airlaunch_sweep_row
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
  use airlaunch_kinds, only: dp, i8
  use airlaunch_launch_scene, only: launch_result
  use airlaunch_line_scene, only: line_result
  implicit none
  private
  public :: sweep_row, metric_set, metrics_of
  public :: row_from_result, row_from_line_result, invalid_row, format_row, parse_row, row_nan
  public :: status_ok, status_failed, status_invalid, status_names, adler32

  integer, parameter :: status_ok = 0       !< the case ran to its end time
  integer, parameter :: status_failed = 1   !< the integration failed (message kept)
  integer, parameter :: status_invalid = 2  !< the case's input was rejected by the scenario reader
  character(len=16), parameter :: status_names(0:2) = [character(len=16) :: "ok", "failed", "invalid_input"]

  integer, parameter :: n_metrics = 34
  !> Summary variables of the airlaunch scene (the single run's milestone attribute names).
  character(len=40), parameter :: metric_names(n_metrics) = [character(len=40) :: &
    "trim_alpha_deg", "trim_elevator_deg", "trim_thrust_N", &
    "release_time_s", "edge_time_s", "separation_time_s", "early_separation", "edge_pull_time_s", &
    "pitch_at_separation_deg", "pitch_rate_at_separation_deg_s", &
    "pitch_max_time_s", "pitch_max_deg", "nose_elevation_at_pitch_max_deg", &
    "min_clearance_m", "min_exit_clearance_m", "min_line_clearance_m", "peak_line_tension_N", &
    "peak_line_tension_time_s", &
    "line_break_time_s", "line_breaks", "line_break_segment", "max_aircraft_pitch_excursion_deg", &
    "max_load_factor_excursion", &
    "max_constraint_residual_m", "ground_time_s", "ground_speed_m_s", &
    "end_time_s", "steps", "rhs_evals", "jac_evals", "nonlin_iters", "nonlin_fails", "err_test_fails", &
    "wall_time_s"]
  character(len=12), parameter :: metric_units(n_metrics) = [character(len=12) :: &
    "degree", "degree", "N", "s", "s", "s", "1", "s", "degree", "degree s-1", "s", "degree", "degree", &
    "m", "m", "m", "N", "s", "s", "1", "1", "degree", "1", "m", "s", "m s-1", "s", "1", "1", "1", "1", "1", "1", "s"]
  character(len=120), parameter :: metric_long_names(n_metrics) = [character(len=120) :: &
    "trim angle of attack (Case 0)", "trim elevator deflection", "trim thrust", &
    "release: Case 0 -> 1 (NaN: not reached)", "rocket CG at the ramp edge: Case 1 -> 2 (NaN: not reached)", &
    "separation: Case 2 -> 3 (NaN: not reached)", "1 if the rocket left the edge early (normal force zero)", &
    "bilateral edge: first time the edge had to pull (NaN: never)", &
    "rocket Euler pitch at separation", "rocket Euler pitch rate at separation", &
    "time of the first rocket pitch maximum after separation (the firing moment; NaN: not reached)", &
    "rocket Euler pitch at its first maximum", "rocket nose elevation at the first pitch maximum", &
    "minimum distance from the rocket's surface to the empennage point after separation (NaN: not separated)", &
    "minimum rocket-empennage clearance over the exit, from the release on, every step (NaN: not released)", &
    "minimum distance from the empennage point to the line over every step (NaN: no line)", &
    "peak line tension (NaN: the scene has no line)", "time of the peak line tension (NaN: no line)", &
    "the line first parted (&line breaking_strength or break_time; NaN: it did not, or no line)", &
    "segments of the line parted (0: none, or no line)", &
    "the segment that parted first (1: at the rocket's tie-down, n_seg: at the parachute; 0: none, or no line)", &
    "largest aircraft pitch excursion from trim", "largest aircraft load factor excursion from 1", &
    "largest cut-joint position residual", &
    "the aircraft's CG or the rocket's lowest point reached &flight ground_altitude; the run ended there " // &
    "(NaN: not reached)", &
    "that point's speed there, earth frame (NaN: not reached)", "simulated time reached", &
    "CVODE steps", "right-hand-side evaluations", "Jacobian evaluations", "Newton iterations", &
    "Newton convergence failures", "error-test failures", "wall time of the case on its rank"]
  logical, parameter :: metric_is_integer(n_metrics) = [.false., .false., .false., .false., .false., .false., &
    .true., .false., .false., .false., .false., .false., .false., .false., .false., .false., .false., .false., &
    .false., .true., .true., .false., .false., .false., .false., .false., .false., .true., .true., .true., .true., .true., &
    .true., .false.]

  !> Summary variables of the line scene (scene = 'line': docs/line.md §4;
  !> the names the airlaunch scene shares mean the same).
  integer, parameter :: n_line_metrics = 19
  character(len=40), parameter :: line_metric_names(n_line_metrics) = [character(len=40) :: &
    "peak_line_tension_N", "peak_line_tension_time_s", "peak_line_tension_segment", "max_end_tension_a_N", &
    "max_end_tension_b_N", &
    "line_break_time_s", "line_breaks", "line_break_segment", "line_recoil_speed_m_s", "canopy_deploy_air_speed_m_s", &
    "final_tip_speed_m_s", "ground_time_s", "ground_speed_m_s", "end_time_s", "steps", "rhs_evals", "jac_evals", &
    "completed", "wall_time_s"]
  character(len=12), parameter :: line_metric_units(n_line_metrics) = [character(len=12) :: &
    "N", "s", "1", "N", "N", "s", "1", "1", "m s-1", "m s-1", "m s-1", "s", "m s-1", "s", "1", "1", "1", "1", "s"]
  character(len=120), parameter :: line_metric_long_names(n_line_metrics) = [character(len=120) :: &
    "largest segment tension over every step (NaN: &line_scene peak_tension = .false.)", &
    "time the peak segment tension was first reached (NaN: not tracked)", &
    "the segment carrying the peak segment tension (1: at end a, n_seg: at end b; 0: not tracked)", &
    "largest tension of segment 1, at end a, over the records", &
    "largest tension of segment n_seg, at end b, over the records", &
    "the line first parted (&line breaking_strength or break_time; NaN: it did not)", &
    "segments of the line parted (0: none)", &
    "the segment that parted first (1: at end a, n_seg: at end b; 0: none)", &
    "recoil: the largest speed change of a node since the first break, over the records (NaN: no break)", &
    "air speed of the canopy end when it deployed (NaN: no canopy, or not deployed)", &
    "speed of node n_seg (end b) at the last record", &
    "the lowest integrated node reached &line_scene ground_altitude; the run ended there (NaN: not, or no ground)", &
    "that node's speed there (NaN: not reached)", &
    "simulated time reached", "time steps", "force evaluations of the whole line", &
    "Jacobian evaluations (cvode)", "1 if the run completed (reached t_end, or the ground)", &
    "wall time of the case on its rank"]
  logical, parameter :: line_metric_is_integer(n_line_metrics) = [.false., .false., .true., .false., .false., &
    .false., .true., .true., .false., .false., .false., .false., .false., .false., .true., .true., .true., .true., &
    .false.]

  !> The summary variables of one scene's sweep (metrics_of).
  type :: metric_set
    character(len=16) :: scene = ""
    character(len=40), allocatable :: names(:)
    character(len=12), allocatable :: units(:)
    character(len=120), allocatable :: long_names(:)
    logical, allocatable :: is_integer(:)
  contains
    procedure :: size => set_size
    procedure :: index => set_index
  end type metric_set

  !> One finished case.
  type :: sweep_row
    integer :: id = -1                               !< case id
    integer :: status = status_ok                    !< status_ok, status_failed, status_invalid
    real(dp), allocatable :: metrics(:)              !< values in the order of the scene's metric_set
    character(len=:), allocatable :: message         !< failure message ("" if ok)
    !> tag of the runtime numerical environment that computed it (the FNV-1a
    !> hash of its line in journal/environments.txt; "" for none)
    character(len=16) :: environment = ""
  end type sweep_row

contains

  !> The summary variables of a sweep whose base runs `scene` ('airlaunch'
  !> or 'line'; any other has none).
  function metrics_of(scene) result(set)
    character(len=*), intent(in) :: scene   !< &run scene of the base scenario
    type(metric_set) :: set
    set%scene = scene
    select case (trim(scene))
    case ("airlaunch")
      set%names = metric_names
      set%units = metric_units
      set%long_names = metric_long_names
      set%is_integer = metric_is_integer
    case ("line")
      set%names = line_metric_names
      set%units = line_metric_units
      set%long_names = line_metric_long_names
      set%is_integer = line_metric_is_integer
    case default
      allocate(set%names(0), set%units(0), set%long_names(0), set%is_integer(0))
    end select
  end function metrics_of

  !> Number of summary variables.
  pure integer function set_size(self)
    class(metric_set), intent(in) :: self
    set_size = size(self%names)
  end function set_size

  !> Position of a summary variable in the set (0 if it has none of that name).
  pure integer function set_index(self, name)
    class(metric_set), intent(in) :: self
    character(len=*), intent(in) :: name   !< summary variable name
    integer :: i
    set_index = 0
    do i = 1, size(self%names)
      if (trim(self%names(i)) == name) set_index = i
    end do
  end function set_index

  !> Quiet NaN: "not reached" / "not defined".
  real(dp) function row_nan()
    row_nan = ieee_value(1.0_dp, ieee_quiet_nan)
  end function row_nan

  !> The row of a case that ran (completed or failed).
  function row_from_result(id, res, failed, message, wall) result(row)
    integer, intent(in) :: id                  !< case id
    type(launch_result), intent(in) :: res     !< its milestones
    logical, intent(in) :: failed              !< the run returned an error
    character(len=*), intent(in) :: message    !< the error message ("" if none)
    real(dp), intent(in) :: wall               !< wall time [s]
    type(sweep_row) :: row
    real(dp) :: nan
    nan = row_nan()
    row = ran_row(id, failed, message)
    row%metrics = [res%trim_alpha_deg, res%trim_elevator_deg, res%trim_thrust_n, &
      defined(res%release_time), defined(res%edge_time), defined(res%separation_time), &
      merge(1.0_dp, 0.0_dp, res%early_separation), defined(res%edge_pull_time), &
      merge(res%pitch_at_separation_deg, nan, res%separation_time >= 0.0_dp), &
      merge(res%pitch_rate_at_separation_deg_s, nan, res%separation_time >= 0.0_dp), &
      defined(res%pitch_max_time), merge(res%pitch_max_deg, nan, res%pitch_max_time >= 0.0_dp), &
      merge(res%nose_elevation_at_max_deg, nan, res%pitch_max_time >= 0.0_dp), &
      merge(res%min_clearance, nan, res%min_clearance < huge(1.0_dp)), &
      merge(res%min_exit_clearance, nan, res%min_exit_clearance < huge(1.0_dp)), &
      merge(res%min_line_clearance, nan, res%min_line_clearance >= 0.0_dp .and. &
        res%min_line_clearance < huge(1.0_dp)), &
      merge(res%peak_tension, nan, res%has_line), merge(defined(res%peak_tension_time), nan, res%has_line), &
      defined(res%line_break_time), real(res%line_breaks, dp), real(res%line_break_segment, dp), &
      res%max_aircraft_pitch_excursion_deg, res%max_load_factor_excursion, res%max_constraint_residual, &
      defined(res%ground_time), merge(res%ground_speed, nan, res%ground_time >= 0.0_dp), res%end_time, &
      real(res%stats%steps, dp), real(res%stats%rhs_evals, dp), real(res%stats%jac_evals, dp), &
      real(res%stats%nonlin_iters, dp), real(res%stats%nonlin_fails, dp), real(res%stats%err_test_fails, dp), &
      wall]
  end function row_from_result

  !> The row of a line-scene case that ran (completed or failed).
  function row_from_line_result(id, res, failed, message, wall) result(row)
    integer, intent(in) :: id                  !< case id
    type(line_result), intent(in) :: res       !< its milestones
    logical, intent(in) :: failed              !< the run returned an error
    character(len=*), intent(in) :: message    !< the error message ("" if none)
    real(dp), intent(in) :: wall               !< wall time [s]
    type(sweep_row) :: row
    row = ran_row(id, failed, message)
    row%metrics = [defined(res%peak_tension), defined(res%peak_tension_time), real(res%peak_tension_segment, dp), &
      defined(res%max_end_tension(1)), &
      defined(res%max_end_tension(2)), defined(res%line_break_time), real(res%line_breaks, dp), &
      real(res%line_break_segment, dp), defined(res%recoil_speed), defined(res%deploy_speed), &
      defined(res%final_tip_speed), defined(res%ground_time), defined(res%ground_speed), res%end_time, &
      real(res%stats%steps, dp), real(res%stats%rhs_evals, dp), real(res%stats%jac_evals, dp), &
      merge(1.0_dp, 0.0_dp, res%completed), wall]
  end function row_from_line_result

  !> The row of a case that ran: its id, status and message (the metrics are
  !> the caller's).
  function ran_row(id, failed, message) result(row)
    integer, intent(in) :: id                  !< case id
    logical, intent(in) :: failed              !< the run returned an error
    character(len=*), intent(in) :: message    !< the error message ("" if none)
    type(sweep_row) :: row
    row%id = id
    row%status = merge(status_failed, status_ok, failed)
    row%message = one_line(message)
  end function ran_row

  !> A result's value, NaN where it marks "not defined" by a negative value
  !> (an event that did not happen: time -1; no canopy: speed -1).
  real(dp) function defined(x)
    real(dp), intent(in) :: x
    defined = merge(x, row_nan(), x >= 0.0_dp)
  end function defined

  !> The row of a case whose input the scenario reader rejected: every
  !> summary variable of `set` NaN but the wall time, its last.
  function invalid_row(id, message, wall, set) result(row)
    integer, intent(in) :: id                  !< case id
    character(len=*), intent(in) :: message    !< the reader's message
    real(dp), intent(in) :: wall               !< wall time [s]
    type(metric_set), intent(in) :: set        !< the scene's summary variables
    type(sweep_row) :: row
    row%id = id
    row%status = status_invalid
    row%message = one_line(message)
    allocate(row%metrics(set%size()))
    row%metrics = row_nan()
    row%metrics(set%size()) = wall
  end function invalid_row

  !> The journal line of a row (no new-line character).
  function format_row(row) result(line)
    type(sweep_row), intent(in) :: row
    character(len=:), allocatable :: line, body
    character(len=32) :: buf
    integer :: i, n
    n = 0
    if (allocated(row%metrics)) n = size(row%metrics)
    write(buf, '(i0,1x,i0)') row%id, row%status
    body = trim(buf)
    if (len_trim(row%environment) > 0) then
      body = body // " " // trim(row%environment)
    else
      body = body // " -"
    end if
    write(buf, '(i0)') n
    body = body // " " // trim(buf)
    do i = 1, n
      write(buf, '(es25.16e3)') row%metrics(i)
      body = body // " " // trim(adjustl(buf))
    end do
    if (allocated(row%message)) then
      if (len(row%message) > 0) body = body // " " // row%message
    end if
    write(buf, '(z8.8)') adler32(body)
    line = trim(buf) // " " // body
  end function format_row

  !> Parse a journal line of `n_want` metrics; `ok` is false for a torn,
  !> corrupt or foreign line.
  subroutine parse_row(line, n_want, row, ok)
    character(len=*), intent(in) :: line    !< journal line
    integer, intent(in) :: n_want           !< metrics of the sweep's scene
    type(sweep_row), intent(out) :: row     !< the row (if ok)
    logical, intent(out) :: ok              !< the line is a complete row
    integer :: p, q, i, ios, n, first
    integer(i8) :: sum_want
    character(len=:), allocatable :: body
    ok = .false.
    p = index(line, " ")
    if (p /= 9) return
    read(line(1:8), '(z8)', iostat=ios) sum_want
    if (ios /= 0) return
    body = line(10:len_trim(line))
    if (adler32(body) /= sum_want) return
    ! one list-directed read for the id and status, one for the count and one
    ! for the metrics: a read statement per value cost 25 us a row, the most of a resume's or
    ! a summary's journal reading (50 000 rows: 2.5 s, read twice)
    p = 1
    do i = 1, 2
      call next_token(body, p, q)
      if (q < p) return
      p = q + 1
    end do
    read(body(1:q), *, iostat=ios) row%id, row%status
    if (ios /= 0) return
    ! the environment's tag (airlaunch_sweep_journal's environments.txt)
    call next_token(body, p, q)
    if (q < p) return
    if (body(p:q) /= "-") then
      if (q - p + 1 /= 16 .or. verify(body(p:q), "0123456789abcdefABCDEF") /= 0) return
      row%environment = body(p:q)
    end if
    p = q + 1
    call next_token(body, p, q)
    if (q < p) return
    read(body(p:q), *, iostat=ios) n
    if (ios /= 0 .or. n /= n_want) return
    p = q + 1
    allocate(row%metrics(n))
    first = q + 1
    do i = 1, n
      call next_token(body, p, q)
      if (q < p) return
      p = q + 1
    end do
    if (n > 0) then
      read(body(first:q), *, iostat=ios) row%metrics
      if (ios /= 0) return
    end if
    row%message = ""
    if (q + 2 <= len(body)) row%message = body(q+2:)
    ok = row%id >= 0 .and. row%status >= status_ok .and. row%status <= status_invalid
  end subroutine parse_row

  !> Token of `s` starting at or after p (blanks skipped): s(p:q).
  pure subroutine next_token(s, p, q)
    character(len=*), intent(in) :: s
    integer, intent(inout) :: p
    integer, intent(out) :: q
    do while (p <= len(s))
      if (s(p:p) /= " ") exit
      p = p + 1
    end do
    q = p - 1
    do while (q < len(s))
      if (s(q+1:q+1) == " ") exit
      q = q + 1
    end do
  end subroutine next_token

  !> Adler-32 checksum of a string (RFC 1950).
  pure integer(i8) function adler32(s) result(h)
    character(len=*), intent(in) :: s
    integer(i8) :: a, b
    integer :: i
    a = 1
    b = 0
    do i = 1, len(s)
      a = mod(a + iachar(s(i:i)), 65521_i8)
      b = mod(b + a, 65521_i8)
    end do
    h = ior(ishft(b, 16), a)
  end function adler32

  !> Message on one line (new lines and tabs to blanks, trimmed).
  pure function one_line(s) result(t)
    character(len=*), intent(in) :: s
    character(len=:), allocatable :: t
    integer :: i
    t = s
    do i = 1, len(t)
      if (iachar(t(i:i)) < 32) t(i:i) = " "
    end do
    t = trim(adjustl(t))
  end function one_line
end module airlaunch_sweep_row
