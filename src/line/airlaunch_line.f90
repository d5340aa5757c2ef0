!> The flexible line's one door (STYLE.md habit 1): re-exports the model, the
!> end conditions, the initial shapes, both integrators and the equivalent
!> rigidization, and builds the integrator a `line_scheme_options` asks for.
module airlaunch_line
  use airlaunch_kinds, only: dp
  use airlaunch_error, only: error_type
  use airlaunch_line_model, only: line_params, line_model, line_energy, node_state_name, marching_stable_step, &
    marching_diverged, far_end_not_converged, weakest_segment, segment_strengths, cascade_note
  use airlaunch_line_ends, only: line_end, end_kind_code, end_kind_name, end_fixed, end_prescribed, &
    end_free, end_point_mass, end_body
  use airlaunch_line_shape, only: straight_shape, sagged_shape, parabola_length, parabola_sag_for_length
  use airlaunch_line_scheme, only: line_scheme, line_scheme_options, line_scheme_stats, check_scheme_options
  use airlaunch_line_cvode, only: line_system, line_cvode, new_line_cvode, line_band_upper, line_band_lower, &
    line_force_jacobian
  use airlaunch_line_marching, only: line_marching, new_line_marching
  use airlaunch_rigidization, only: rigid_equivalent, rigidize, whole_piece
  implicit none
  private
  public :: line_params, line_model, line_energy, node_state_name, marching_stable_step, marching_diverged, &
    far_end_not_converged, weakest_segment, segment_strengths, cascade_note
  public :: line_end, end_kind_code, end_kind_name, end_fixed, end_prescribed, end_free, end_point_mass, end_body
  public :: straight_shape, sagged_shape, parabola_length, parabola_sag_for_length
  public :: line_scheme, line_scheme_options, line_scheme_stats, check_scheme_options
  public :: line_system, line_cvode, new_line_cvode, line_band_upper, line_band_lower, line_force_jacobian
  public :: line_marching, new_line_marching
  public :: rigid_equivalent, rigidize, whole_piece
  public :: new_line_scheme

contains

  !> Build the integrator named by opts%scheme ("cvode" or "marching") for the
  !> line `model` with ends `end_a` (node 0) and `end_b` (node N), starting from
  !> the node state x0(3,0:N), v0(3,0:N) at time t0.
  subroutine new_line_scheme(scheme, model, end_a, end_b, x0, v0, t0, opts, error)
    class(line_scheme), allocatable, intent(inout) :: scheme  !< the integrator
    type(line_model), intent(in) :: model                     !< the line
    type(line_end), intent(in) :: end_a, end_b                !< ends at node 0 and node N
    real(dp), intent(in) :: x0(:, 0:), v0(:, 0:)              !< initial node state
    real(dp), intent(in) :: t0                                !< initial time [s]
    type(line_scheme_options), intent(in) :: opts             !< scheme and its settings
    type(error_type), allocatable, intent(inout) :: error     !< set on bad input
    call check_scheme_options(opts, error)
    if (allocated(error)) return
    if (allocated(scheme)) then
      call scheme%free()
      deallocate(scheme)
    end if
    select case (trim(opts%scheme))
    case ("marching")
      allocate(line_marching :: scheme)
    case default
      allocate(line_cvode :: scheme)
    end select
    select type (scheme)
    type is (line_cvode)
      call new_line_cvode(scheme, model, end_a, end_b, x0, v0, t0, opts, error)
    type is (line_marching)
      call new_line_marching(scheme, model, end_a, end_b, x0, v0, t0, opts, error)
    end select
  end subroutine new_line_scheme
end module airlaunch_line
