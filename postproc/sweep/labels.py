"""Readable axis labels of the sweep figures: one table mapping each input a
sweep can vary (namelist ``group%variable``, or an element ``group%variable(k)``
of a vector) to a readable name and its unit, and one for the summary's
metrics.

The units are those docs/input.md gives each variable (the line scene's
``&line`` and ``&line_scene`` variables that input.md does not list: docs/line.md
§4), spelled as the docs spell them; "–" (dimensionless) draws no unit.
``tests/python/test_sweep_labels.py`` parses docs/input.md and checks every
sweepable variable listed there against this table.  An input not in the table
keeps its raw name (with the units its ``&input`` declared, as before): never a
unit guessed.
"""
from __future__ import annotations

import re

#: ``group%variable`` -> (readable name, unit as docs/input.md gives it).
INPUT_LABELS = {
    # &run
    "run%t_end": ("simulated time t_end", "s"),
    "run%output_dt": ("output interval", "s"),
    "run%rtol": ("CVODE relative tolerance", "–"),
    "run%atol": ("CVODE absolute tolerance", "–"),
    "run%max_steps": ("step budget", "–"),
    "run%max_wall_time": ("wall-time budget", "s"),
    "run%max_order": ("largest BDF order", "–"),
    # &flight
    "flight%altitude": ("release altitude", "m"),
    "flight%ground_altitude": ("ground altitude", "m"),
    "flight%mach": ("flight Mach number", "–"),
    "flight%trim_alpha_deg": ("trim angle of attack", "deg"),
    # &aircraft
    "aircraft%mass": ("aircraft mass", "kg"),
    "aircraft%ixx": ("aircraft roll inertia Ixx", "kg m²"),
    "aircraft%iyy": ("aircraft yaw inertia Iyy", "kg m²"),
    "aircraft%izz": ("aircraft pitch inertia Izz", "kg m²"),
    "aircraft%wing_area": ("aircraft wing area", "m²"),
    "aircraft%span": ("aircraft span", "m"),
    "aircraft%chord": ("aircraft mean chord", "m"),
    "aircraft%cl0": ("aircraft C_L0", "–"),
    "aircraft%cm0": ("aircraft C_m0", "–"),
    "aircraft%cl_alpha": ("aircraft lift slope C_Lα", "1/rad"),
    "aircraft%cl_de": ("aircraft elevator lift slope C_Lδe", "1/rad"),
    "aircraft%cd0": ("aircraft zero-lift drag C_D0", "–"),
    "aircraft%k_induced": ("aircraft induced-drag factor k", "–"),
    "aircraft%cm_alpha": ("aircraft C_mα", "1/rad"),
    "aircraft%cm_q": ("aircraft pitch damping C_mq", "1/rad"),
    "aircraft%cm_de": ("aircraft elevator power C_mδe", "1/rad"),
    "aircraft%k_theta": ("attitude-hold gain k_θ", "rad/rad"),
    "aircraft%k_q": ("attitude-hold gain k_q", "rad s/rad"),
    "aircraft%delta_e_max_deg": ("elevator limit", "deg"),
    "aircraft%cl_alpha_tail": ("tail lift slope C_Lα,t", "1/rad"),
    "aircraft%cy_beta_fin": ("fin side-force slope C_Yβ,fin", "1/rad"),
    "aircraft%cy_beta": ("aircraft side-force slope C_Yβ", "1/rad"),
    "aircraft%croll_beta": ("aircraft C_lβ", "1/rad"),
    "aircraft%croll_p": ("aircraft roll damping C_lp", "1/rad"),
    "aircraft%croll_r": ("aircraft C_lr", "1/rad"),
    "aircraft%cn_beta": ("aircraft C_nβ", "1/rad"),
    "aircraft%cn_p": ("aircraft C_np", "1/rad"),
    "aircraft%cn_r": ("aircraft yaw damping C_nr", "1/rad"),
    # &bay
    "bay%length": ("bay length", "m"),
    "bay%width": ("bay width", "m"),
    "bay%height": ("bay height", "m"),
    "bay%ramp_edge_x": ("ramp edge x", "m"),
    "bay%floor_y": ("cargo floor y", "m"),
    "bay%friction": ("rail friction coefficient", "–"),
    "bay%release_time": ("release time", "s"),
    "bay%l0": ("rocket distance ahead of ramp edge l0", "m"),
    "bay%tail_x": ("empennage point x", "m"),
    "bay%tail_y": ("empennage point y", "m"),
    "bay%tail_half_span": ("tailplane half span", "m"),
    "bay%rail_angle_deg": ("rail angle", "deg"),
    # &rocket
    "rocket%mass": ("rocket mass", "kg"),
    "rocket%ixx": ("rocket roll inertia Ixx", "kg m²"),
    "rocket%iyy": ("rocket inertia Iyy", "kg m²"),
    "rocket%izz": ("rocket pitch inertia Izz", "kg m²"),
    "rocket%length": ("rocket length", "m"),
    "rocket%diameter": ("rocket diameter", "m"),
    "rocket%cg_from_nose": ("rocket CG from nose", "m"),
    "rocket%tie_down_from_nose": ("rocket tie-down from nose", "m"),
    "rocket%cp_pot_from_nose": ("rocket potential-flow CP from nose", "m"),
    "rocket%c_axial": ("rocket axial force coefficient", "–"),
    "rocket%c_dn": ("rocket cross-flow drag coefficient", "–"),
    "rocket%eta": ("rocket cross-flow factor η", "–"),
    "rocket%n_strips": ("rocket cross-flow strips", "–"),
    "rocket%fin_count": ("rocket fin count", "–"),
    "rocket%fin_semi_span": ("rocket fin semi-span", "m"),
    "rocket%fin_root_chord": ("rocket fin root chord", "m"),
    "rocket%fin_tip_chord": ("rocket fin tip chord", "m"),
    "rocket%fin_sweep": ("rocket fin sweep", "m"),
    "rocket%fin_root_le_from_nose": ("rocket fin root LE from nose", "m"),
    # &parachute
    "parachute%drag_area": ("parachute drag area", "m²"),
    "parachute%mass": ("parachute mass", "kg"),
    "parachute%cd0": ("parachute C_D0", "–"),
    "parachute%deploy_time": ("parachute deploy time", "s"),
    "parachute%fill_constant": ("parachute fill constant n", "–"),
    "parachute%inflation_exponent": ("parachute inflation exponent j", "–"),
    "parachute%packed_drag_area": ("parachute packed drag area", "m²"),
    "parachute%added_mass_factor": ("parachute apparent-mass factor", "–"),
    # &line
    "line%length": ("line length", "m"),
    "line%n_seg": ("line segments", "–"),
    "line%ea": ("line axial stiffness EA", "N"),
    "line%mass_per_length": ("line mass per length", "kg/m"),
    "line%damping": ("line axial damping", "N s"),
    "line%diameter": ("line diameter", "m"),
    "line%cd_normal": ("line cross-flow drag coefficient", "–"),
    "line%cd_tangential": ("line skin-friction coefficient", "–"),
    "line%outer_dt": ("rigidized outer step", "s"),
    "line%inner_rtol": ("rigidized inner rtol", "–"),
    "line%inner_dt": ("rigidized inner step", "s"),
    "line%auto_min_strain": ("auto coupling min. strain", "–"),
    "line%auto_max_strain_change": ("auto coupling max. strain change", "–"),
    "line%auto_dwell": ("auto coupling dwell", "s"),
    "line%auto_min_steps": ("auto coupling min. steps", "–"),
    "line%breaking_strength": ("line breaking strength", "N"),
    "line%break_time": ("line cut time", "s"),
    "line%break_segment": ("line cut segment", "–"),
    "line%weak_link_strength": ("weak-link strength", "N"),
    "line%weak_link_segment": ("weak-link segment", "–"),
    # &gust
    "gust%vertical": ("gust vertical speed", "m/s"),
    "gust%lateral": ("gust lateral speed", "m/s"),
    "gust%gradient_length": ("gust gradient length", "m"),
    "gust%hit_time": ("gust hit time", "s"),
    # the line scene (docs/line.md §4)
    "line%settling_damping": ("line settling damping", "1/s"),
    "line%wind": ("wind", "m/s"),
    "line%air_density": ("air density", "kg/m³"),
    "line_scene%a_position": ("end a position", "m"),
    "line_scene%b_position": ("end b position", "m"),
    "line_scene%a_velocity": ("end a velocity", "m/s"),
    "line_scene%b_velocity": ("end b velocity", "m/s"),
    "line_scene%a_amplitude": ("end a amplitude", "m"),
    "line_scene%b_amplitude": ("end b amplitude", "m"),
    "line_scene%a_frequency": ("end a frequency", "Hz"),
    "line_scene%b_frequency": ("end b frequency", "Hz"),
    "line_scene%a_phase_deg": ("end a phase", "deg"),
    "line_scene%b_phase_deg": ("end b phase", "deg"),
    "line_scene%a_t_start": ("end a motion start", "s"),
    "line_scene%b_t_start": ("end b motion start", "s"),
    "line_scene%a_mass": ("end a mass", "kg"),
    "line_scene%b_mass": ("end b mass", "kg"),
    "line_scene%a_drag_area": ("end a drag area", "m²"),
    "line_scene%b_drag_area": ("end b drag area", "m²"),
    "line_scene%initial_sag": ("initial sag", "m"),
    "line_scene%dt": ("marching time step", "s"),
    "line_scene%force_tol": ("marching force tolerance", "N"),
    "line_scene%max_iterations": ("marching far-end iterations", "–"),
    "line_scene%ground_altitude": ("ground altitude", "m"),
}

#: The vectors (three elements, earth or body x, y, z): an element's label
#: names its component.
VECTOR_COMPONENTS = ("x", "y", "z")

#: The summary's metrics (docs/sweep.md "The summary"; docs/output.md): readable
#: name and unit.
METRIC_LABELS = {
    "min_clearance_m": ("min. rocket–empennage clearance", "m"),
    "min_exit_clearance_m": ("min. rocket–empennage clearance over the exit", "m"),
    "min_line_clearance_m": ("min. line–empennage clearance", "m"),
    "peak_line_tension_N": ("peak line tension", "N"),
    "peak_line_tension_time_s": ("time of peak line tension", "s"),
    "max_aircraft_pitch_excursion_deg": ("max. aircraft pitch excursion", "degree"),
    "max_load_factor_excursion": ("max. load-factor excursion", "–"),
    "pitch_max_deg": ("rocket's first pitch maximum", "degree"),
    "pitch_max_time_s": ("time of the rocket's first pitch maximum", "s"),
    "ground_speed_m_s": ("touchdown speed", "m s-1"),
    "separation_time_s": ("separation time", "s"),
    "line_break_time_s": ("line break time", "s"),
    "max_end_tension_a_N": ("peak end-a tension", "N"),
    "max_end_tension_b_N": ("peak end-b tension", "N"),
    "line_recoil_speed_m_s": ("line recoil speed", "m s-1"),
    "final_tip_speed_m_s": ("final tip speed", "m s-1"),
}

#: Each criterion's metric (criteria.py; docs/sweep.md "The criteria file").
CRITERION_METRIC = {
    "clearance": "min_clearance_m",
    "line_clearance": "min_line_clearance_m",
    "line_tension": "peak_line_tension_N",
    "aircraft_pitch": "max_aircraft_pitch_excursion_deg",
    "load_factor": "max_load_factor_excursion",
    "firing_attitude": "pitch_max_deg",
    "firing_time": "pitch_max_time_s",
    "touchdown": "ground_speed_m_s",
}

_ELEMENT = re.compile(r"^(?P<base>[A-Za-z_]\w*%[A-Za-z_]\w*)\((?P<k>\d+)\)$")


def _with_unit(name, unit):
    return name if unit in ("", "–", "1", "-") else f"{name} [{unit}]"


def input_entry(name):
    """(readable name, unit) of a varied input, or None when the table has none."""
    key = name.strip().lower()
    if key in INPUT_LABELS:
        return INPUT_LABELS[key]
    m = _ELEMENT.match(key)
    if m and m.group("base") in INPUT_LABELS:
        k = int(m.group("k"))
        if 1 <= k <= len(VECTOR_COMPONENTS):
            text, unit = INPUT_LABELS[m.group("base")]
            return f"{text} {VECTOR_COMPONENTS[k - 1]}", unit
    return None


def input_label(name, declared_units=None):
    """The axis label of a varied input: "parachute drag area [m²]"; an input
    the table lacks keeps its raw name, with the units its definition declared
    (if any, other than "1")."""
    entry = input_entry(name)
    if entry is not None:
        return _with_unit(*entry)
    return _with_unit(name, declared_units or "")


def metric_label(metric):
    """The label of a summary metric: "min. rocket–empennage clearance [m]";
    the raw name if the table has none."""
    entry = METRIC_LABELS.get(metric)
    return _with_unit(*entry) if entry else metric


def margin_label(criterion, units):
    """The axis label of a criterion's margin: the metric's readable name,
    "margin", the margin's units (as the envelope records them)."""
    metric = CRITERION_METRIC.get(criterion)
    text = METRIC_LABELS[metric][0] if metric in METRIC_LABELS else criterion
    return f"{text}\nmargin [{units}]" if units not in ("", "1", "–") else f"{text}\nmargin"
