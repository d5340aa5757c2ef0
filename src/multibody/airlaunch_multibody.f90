!> One door to the multibody area (STYLE.md habit 1): rigid bodies and force
!> sources, the Kane chain, the cut joint with its CFA, and the separation scene
!> with its phase machine.  See docs/multibody.md for the equations and choices.
module airlaunch_multibody
  use airlaunch_rigid_body, only: rigid_body, body_state_size, new_rigid_body, check_mass_properties, &
    newton_euler, body_state_derivative, quaternion_drift_rate, cross, body_state_name
  use airlaunch_force_source, only: force_source, force_source_slot, add_point_force, gravity_source, &
    constant_load_source, pair_force_source
  use airlaunch_kane_chain, only: kane_chain, chain_link, max_chain_bodies
  use airlaunch_cut_joint, only: cut_joint, cut_joint_geometry, cut_joint_options, joint_state, &
    phase_preparation, phase_extraction, phase_rotation, phase_free, phase_name, joint_components
  use airlaunch_cfa, only: cfa_workspace, cfa_solve, slide_locked, slide_free, slide_coulomb
  use airlaunch_separation, only: separation_system, separation_nroots
  implicit none
  private
  public :: rigid_body, body_state_size, new_rigid_body, check_mass_properties, body_state_name
  public :: newton_euler, body_state_derivative, quaternion_drift_rate, cross
  public :: force_source, force_source_slot, add_point_force, gravity_source
  public :: constant_load_source, pair_force_source
  public :: kane_chain, chain_link, max_chain_bodies
  public :: cut_joint, cut_joint_geometry, cut_joint_options, joint_state
  public :: phase_preparation, phase_extraction, phase_rotation, phase_free, phase_name, joint_components
  public :: cfa_workspace, cfa_solve, slide_locked, slide_free, slide_coulomb
  public :: separation_system, separation_nroots
end module airlaunch_multibody
