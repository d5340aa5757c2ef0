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
module airlaunch_line_scene
  use airlaunch_kinds, only: dp, g0
  use airlaunch_error, only: error_type, fatal_error
  use airlaunch_strings, only: str
  use airlaunch_line
  implicit none
  private
  public :: line_scene_config, line_scene

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
  end type line_scene_config

  !> Largest initial end separation, as strain of the unstretched line: the
  !> model assumes small axial strain (assumption 3 of §2.1).
  real(dp), parameter :: max_initial_strain = 0.5_dp

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
    real(dp), allocatable :: end_tension(:, :)       !< T_1 and T_N (2, n_out) [N]
    real(dp), allocatable :: end_force(:, :, :)      !< force of the line on node 0 / node N (3, 2, n_out) [N]
    real(dp), allocatable :: energy(:, :)            !< kinetic, elastic, potential (3, n_out) [J]
    type(rigid_equivalent), allocatable :: rigid(:)  !< equivalent rigid body (n_out)
    real(dp) :: wall_time = 0.0_dp                   !< wall-clock time of `run` [s]
    type(line_scheme_stats) :: stats                 !< integrator work
    logical :: completed = .false.                   !< reached t_end
    logical :: ready = .false.                       !< init succeeded
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
    integer :: n, n_max
    real(dp) :: xa(3), xb(3), va(3), vb(3), sep, strain

    call self%free()
    self%cfg = cfg
    call self%model%init(cfg%line, error)
    if (allocated(error)) return
    call cfg%end_a%check("end_a", error)
    if (allocated(error)) return
    call cfg%end_b%check("end_b", error)
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
    ! initial velocities: linear between the ends' initial velocities
    call straight_shape(n, va, vb, self%v)

    call new_line_scheme(self%scheme, self%model, cfg%end_a, cfg%end_b, self%x, self%v, 0.0_dp, &
      cfg%integration, error)
    if (allocated(error)) return

    n_max = ceiling(cfg%t_end/cfg%output_interval - 1.0e-9_dp) + 1
    allocate(self%time(n_max), self%tip(3, n_max), self%tip_velocity(3, n_max), &
      self%end_tension(2, n_max), self%end_force(3, 2, n_max), self%energy(3, n_max), self%rigid(n_max))
    if (cfg%record_nodes) allocate(self%nodes(3, 0:n, n_max))
    if (cfg%record_tensions) allocate(self%tensions(n, n_max))
    self%n_out = 0
    self%ready = .true.
  end subroutine scene_init

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
      call self%scheme%advance(t_out, error)
      if (allocated(error)) exit
      call record(self, error)
    end do
    self%completed = .not. allocated(error)
    self%stats = self%scheme%stats()
    call system_clock(c1)
    self%wall_time = real(c1 - c0, dp)/real(rate, dp)
  end subroutine scene_run

  !> Append one record at the scheme's current time; a non-finite state is an
  !> error naming the node and the time (and is not recorded).
  subroutine record(self, error)
    type(line_scene), intent(inout) :: self                !< scene
    type(error_type), allocatable, intent(inout) :: error  !< set on a non-finite state
    integer :: n, k, st, m, i
    real(dp) :: t
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
    m = self%n_out + 1
    self%time(m) = t
    self%tip(:, m) = self%x(:, n)
    self%tip_velocity(:, m) = self%v(:, n)
    self%end_tension(:, m) = [self%tension(1), self%tension(n)]
    self%end_force(:, 1, m) = self%f(:, 0)
    self%end_force(:, 2, m) = self%f(:, n)
    e = self%model%energy(self%x, self%v)
    do i = 1, 2
      en = self%cfg%end_b
      if (i == 1) en = self%cfg%end_a
      if (en%kind /= end_point_mass) cycle
      k = merge(0, n, i == 1)
      e%kinetic = e%kinetic + 0.5_dp*en%mass*dot_product(self%v(:, k), self%v(:, k))
      if (self%cfg%line%gravity) e%potential = e%potential + en%mass*g0*self%x(2, k)
    end do
    self%energy(:, m) = [e%kinetic, e%elastic, e%potential]
    self%rigid(m) = rigidize(self%model, self%x, self%v)
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
    if (allocated(self%time)) deallocate(self%time, self%tip, self%tip_velocity, self%end_tension, &
      self%end_force, self%energy, self%rigid)
    if (allocated(self%nodes)) deallocate(self%nodes)
    if (allocated(self%tensions)) deallocate(self%tensions)
    if (allocated(self%x)) deallocate(self%x, self%v, self%f, self%tension)
    self%n_out = 0
    self%completed = .false.
    self%ready = .false.
  end subroutine scene_free
end module airlaunch_line_scene
