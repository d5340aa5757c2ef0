"""The air-launch scene without a line (`&line enabled = .false.`): the gravity
drop of input/airlaunch_gravity_drop.nml.  The output contract without the line
variables, the rail phase against the analytic sliding block on an inclined
plane, the free aircraft's recoil, and the one-line errors for contradictory
input."""
import math

import numpy as np
import pytest
import xarray as xr

from conftest import ROOT, assert_input_error, nml_variant, run_airlaunch

EXAMPLE = ROOT / "input" / "airlaunch_gravity_drop.nml"
G0 = 9.80665                 # m/s^2, the code's standard gravity
M_ROCKET, M_AIRCRAFT = 28000.0, 89000.0
L0 = 10.0                    # m, &bay l0: rail distance from release to the ramp edge
DECK = math.radians(7.0)     # the trimmed pitch attitude = deck angle (level flight)
LINE_VARS = ["parachute_position", "line_tension_rocket_end_N", "line_tension_parachute_end_N", "line_nodes"]


def rail_acceleration(mu):
    """Rocket acceleration along the rail relative to an aircraft in steady flight
    (a block on a plane inclined at the deck angle, Coulomb friction mu)."""
    return G0 * (math.sin(DECK) - mu * math.cos(DECK))


def _run(exe, nml, out):
    res = run_airlaunch(exe, nml, "--output", out)
    assert res.returncode == 0, res.stderr
    return xr.open_dataset(out), res.stdout


@pytest.fixture(scope="module")
def example_run(airlaunch_exe, tmp_path_factory):
    ds, stdout = _run(airlaunch_exe, EXAMPLE, tmp_path_factory.mktemp("gravity") / "gd.nc")
    yield ds, stdout
    ds.close()


PRESCRIBED = (r"^  dynamics = 'free' .*$", "  dynamics = 'prescribed'")


def test_output_without_line(example_run):
    """docs/output.md: without a line the file has no line variables, no node
    dimension and no peak-tension attributes; line_enabled = "false".  The rest
    of the contract is there and finite.  Independent check: in the trimmed
    Case 0 the locked rocket rests on the 7 deg deck, so the joint carries its
    weight's components: normal m g cos 7 deg, along the rail -m g sin 7 deg
    (the lock's force; friction_force_N is 0 until the release; the trim converges to 1e-10 of the weight; 1e-6 relative allowed)."""
    ds, stdout = example_run
    for name in LINE_VARS:
        assert name not in ds, name
    assert "node" not in ds.dims
    assert "peak_line_tension_N" not in ds.attrs and "peak_line_tension_time_s" not in ds.attrs
    assert ds.attrs["line_enabled"] == "false" and "without line" in ds.attrs["title"]
    assert ds.attrs["status"] == "completed"
    assert "peak line tension: none (no line" in stdout
    echo = ds.attrs["input_namelist"].lower()
    assert "&parachute" not in echo and "enabled=f" in echo.replace(" ", "")
    for name in ["phase", "aircraft_position", "aircraft_euler_deg", "rocket_position", "rocket_velocity",
                 "rocket_euler_deg", "constraint_force", "edge_normal_force_N", "friction_force_N",
                 "lock_force_N", "clearance_m"]:
        assert name in ds, name
        assert np.all(np.isfinite(ds[name].values)), name
    for name, value in ds.attrs.items():
        if isinstance(value, float):
            assert math.isfinite(value), name
    weight = M_ROCKET * G0
    assert ds["edge_normal_force_N"].values[0] == pytest.approx(weight * math.cos(DECK), rel=1e-6)
    # the along-rail component is the lock's reaction, not friction (output.md)
    assert ds["lock_force_N"].values[0] == pytest.approx(-weight * math.sin(DECK), rel=1e-6)
    assert ds["friction_force_N"].values[0] == 0.0
    released = ds["phase"].values >= 1
    assert np.all(ds["lock_force_N"].values[released] == 0.0)


def test_rail_phase_against_analytic(airlaunch_exe, tmp_path):
    """Aircraft held steady (dynamics = 'prescribed'), rocket aerodynamics off
    (c_axial = c_dn = 0, no fins), friction 0.05 so that the mu cos(theta) term
    is 30 % of the drive: the rocket slides as a block on a 7 deg plane,
    a = g (sin 7 - mu cos 7) = 0.7085 m/s^2, and reaches the ramp edge
    sqrt(2 l0 / a) = 5.313 s after the release.
    Tolerances: 1e-3 on the time: the slender-body normal force on the part of
    the tail already out of the bay (it has no coefficient to switch off) lifts
    the rocket by at most 1.3 kN of its 272 kN on the rail, lowering the
    friction by < 0.05 % of the 19.8 kN drive (measured: 2e-4 early).  While
    the tail is still inside the bay (the first 0.75 m) nothing but gravity and
    friction acts: the sliding speed is a t (BDF is exact on a constant
    acceleration: measured 6e-11; 1e-6 relative allowed for the aircraft's
    speed differenced from positions of ~1e3 m), the normal force m g cos 7 and
    the friction -mu N within 1e-6 (measured 2e-10)."""
    mu = 0.05
    nml = nml_variant(tmp_path, base=EXAMPLE, edits=[PRESCRIBED, (r"^  friction = 0.005 .*$", f"  friction = {mu}"),
                              (r"^  c_axial = 0.35$", "  c_axial = 0.0"), (r"^  c_dn = 1.2$", "  c_dn = 0.0"),
                              (r"^  fin_count = 4 .*$", "  fin_count = 0")])
    ds, _ = _run(airlaunch_exe, nml, tmp_path / "rail.nc")
    a = rail_acceleration(mu)
    t0, t1 = ds.attrs["release_time_s"], ds.attrs["edge_time_s"]
    assert t0 == pytest.approx(0.5, abs=1e-12)
    assert t1 - t0 == pytest.approx(math.sqrt(2 * L0 / a), rel=1e-3)

    # the aircraft flies steady: straight and level at V0, pitch = deck angle
    t = ds["time"].values
    pitch = np.radians(ds["aircraft_euler_deg"].sel(angle=1).values)
    assert np.allclose(pitch, DECK, rtol=0, atol=1e-12)
    v_air = np.gradient(ds["aircraft_position"].values, t, axis=0)
    # sliding speed along the rail (aircraft -x) relative to the aircraft
    rail = np.array([-math.cos(DECK), -math.sin(DECK), 0.0])
    v_slide = (ds["rocket_velocity"].values - v_air) @ rail
    tau = t - t0
    early = (tau > 0.1) & (0.5 * a * tau**2 < 0.7)     # tail (0.75 m inside at release) still in the bay
    assert early.sum() > 50
    assert np.allclose(v_slide[early], a * tau[early], rtol=1e-6, atol=0)
    normal = ds["edge_normal_force_N"].values[early]
    assert np.allclose(normal, M_ROCKET * G0 * math.cos(DECK), rtol=1e-6, atol=0)
    assert np.allclose(ds["friction_force_N"].values[early], -mu * normal, rtol=1e-6, atol=0)
    ds.close()


def test_example_rail_phase_with_aerodynamics(airlaunch_exe, tmp_path):
    """The example as it is, only with the aircraft held steady: its rocket
    aerodynamics add the axial drag of the part of the rocket out of the bay,
    which pushes aft (up to 1.9 kN at the edge against the 32.1 kN drive, about
    3 % of the force averaged over the slide, 1-2 % of the time): the edge
    comes sooner than the drag-free sqrt(2 l0 / a) = 4.177 s, by less than
    2 % (measured 0.36 %)."""
    nml = nml_variant(tmp_path, base=EXAMPLE, edits=[PRESCRIBED])
    ds, _ = _run(airlaunch_exe, nml, tmp_path / "held.nc")
    analytic = math.sqrt(2 * L0 / rail_acceleration(0.005))
    dt = ds.attrs["edge_time_s"] - ds.attrs["release_time_s"]
    assert dt < analytic
    assert dt == pytest.approx(analytic, rel=2e-2)
    ds.close()


def test_free_aircraft_recoil(example_run):
    """The example (free aircraft): the rocket's weight component along the deck
    is an internal force now, it also pushes the aircraft forward, so the
    relative acceleration is (1 + m_r/m_a) times the held aircraft's (momentum
    balance with the aircraft's aerodynamic force unchanged): 4.177 s becomes
    3.643 s.  Tolerance 3 %: the attitude hold lets the deck steepen by up to
    1.2 deg under the weight moving aft (alone about 3 % shorter), the recoil
    (1 m/s) changes the aircraft's drag and lift (measured: 1.4 % shorter).
    The rocket then tips over the edge and flies free: separation after the
    edge, phase 3 to the end, clear of the empennage."""
    ds, _ = example_run
    a_held = rail_acceleration(0.005)
    dt = ds.attrs["edge_time_s"] - ds.attrs["release_time_s"]
    assert dt == pytest.approx(math.sqrt(2 * L0 / (a_held * (1 + M_ROCKET / M_AIRCRAFT))), rel=3e-2)
    assert dt < 0.9 * math.sqrt(2 * L0 / a_held)
    assert ds.attrs["edge_time_s"] < ds.attrs["separation_time_s"] < ds.attrs["pitch_max_time_s"]
    phase = ds["phase"].values
    assert np.all(np.diff(phase) >= 0) and phase[-1] == 3
    assert ds.attrs["min_clearance_m"] > 0.0


@pytest.mark.parametrize("edits,fragment", [
    ([(r"^&line$", "&parachute\n  drag_area = 10.0\n/\n&line")],
     "&parachute: drag_area = 10.0 is not allowed with &line enabled = .false."),
    ([(r"^&line$", "&parachute\n/\n&line")], "&parachute: the group is not allowed with &line enabled = .false."),
    ([(r"^  enabled = .false. .*$", "  enabled = .false.\n  length = 60.0")],
     "&line: length = 60.0 is not allowed with enabled = .false."),
    ([(r"^  enabled = .false. .*$", "  enabled = .false.\n  coupling = 'rigidized'")],
     "&line: coupling = 'rigidized' is not allowed with enabled = .false."),
    ([(r"^  enabled = .false. .*$", "  enabled = 'no'")], "variable 'enabled' = 'no' is not .true. or .false."),
])
def test_contradictory_input_gives_one_clear_line(airlaunch_exe, tmp_path, edits, fragment):
    """docs/input.md: a scene without a line has no parachute and no line
    properties; saying otherwise is rejected before anything runs."""
    nml = nml_variant(tmp_path, base=EXAMPLE, edits=edits)
    out = tmp_path / "x.nc"
    res = run_airlaunch(airlaunch_exe, nml, "--output", out)
    assert str(nml) in assert_input_error(res, fragment, out)


def test_fins_leave_the_bay_without_a_step(airlaunch_exe, tmp_path):
    """The fins' force grows with the share of their planform out of the bay
    (model.md, "Rocket"): the end-to-end wiring of the fin geometry into the
    aerodynamics (a scenario whose fins lost their chord would fall back to
    the all-or-nothing rule silently).  Reference: a force on a body moving
    continuously through a continuous field is continuous.  Records every
    2 ms over the fins' passage (1.5-2.6 s): the ramp edge's normal force
    changes by at most 200 N between records (its steady rate is ~7 N per
    record; the all-or-nothing fins made it jump 2 585 N at 2.086 s, the
    moment the fins' centre of pressure passed the edge; measured now 24 N)."""
    nml = nml_variant(tmp_path, base=EXAMPLE, edits=[(r"^  output_dt = .*$", "  output_dt = 0.002")])
    ds, _ = _run(airlaunch_exe, nml, tmp_path / "fins.nc")
    t = ds["time"].values
    assert t[1] - t[0] == pytest.approx(0.002)
    window = (t > 1.5) & (t < 2.6)
    jump = np.abs(np.diff(ds["edge_normal_force_N"].values[window]))
    assert jump.size > 500 and jump.max() < 200.0, (jump.max(), t[window][np.argmax(jump)])
    ds.close()
