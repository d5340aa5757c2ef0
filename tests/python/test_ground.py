"""The ground (`&flight ground_altitude`): the run ends when the aircraft's or
the rocket's CG reaches it, an event located by CVODE's root finding, with
the time, the body and its speed as milestones (docs/output.md).  Before,
a long run went on below ground and failed, exit 3, when the rocket left the
atmosphere model at -2 km."""
import math

import numpy as np
import pytest
import xarray as xr

from conftest import ROOT, assert_input_error, nml_variant, run_airlaunch

G0 = 9.80665                 # m/s^2, the code's standard gravity
GRAVITY_DROP = ROOT / "input" / "airlaunch_gravity_drop.nml"


def _run(exe, nml, out):
    res = run_airlaunch(exe, nml, "--output", out)
    assert res.returncode == 0, res.stderr
    return xr.open_dataset(out), res.stdout


def test_ballistic_fall_to_the_ground_against_analytic(airlaunch_exe, tmp_path):
    """The gravity drop with the aircraft held steady and the rocket's
    aerodynamics off (c_axial = c_dn = 0, no fins, and a 1 cm diameter, which
    scales the slender-body normal force that has no coefficient down by
    2.6e4): after the separation only gravity acts, so from any record (t, y,
    v) the rocket reaches the ground 500 m below the release at
    t + (v_y + sqrt(v_y^2 + 2 g (y - ground))) / g with speed
    sqrt(v_x^2 + v_z^2 + v_y^2 + 2 g (y - ground)).  BDF is exact on a
    constant acceleration and CVODE locates the root to ~1e-14 s; what is
    left is the normal force of the 1 cm body and rtol 1e-6 over the 5 s
    before: 1e-5 s and 1e-6 relative allowed.  The run ends there: status
    completed, exit 0, the last record at the event with the rocket on the
    ground (1e-6 m: the event's own state), every earlier record above it."""
    ground = 5500.0
    nml = nml_variant(tmp_path, base=GRAVITY_DROP, edits=[
        (r"^  dynamics = 'free' .*$", "  dynamics = 'prescribed'"),
        (r"^  c_axial = 0.35$", "  c_axial = 0.0"), (r"^  c_dn = 1.2$", "  c_dn = 0.0"),
        (r"^  fin_count = 4 .*$", "  fin_count = 0"), (r"^  diameter = 1.6 .*$", "  diameter = 0.01"),
        (r"^  t_end = 12.0 .*$", "  t_end = 60.0"),
        (r"^  altitude = 6000.0 .*$", f"  altitude = 6000.0\n  ground_altitude = {ground}")])
    ds, stdout = _run(airlaunch_exe, nml, tmp_path / "fall.nc")
    assert ds.attrs["status"] == "completed" and ds.attrs["ground_body"] == "rocket"
    t_g, v_g = ds.attrs["ground_time_s"], ds.attrs["ground_speed_m_s"]
    t = ds["time"].values
    y = ds["rocket_position"].values[:, 1]
    v = ds["rocket_velocity"].values
    assert t[-1] == t_g and abs(y[-1] - ground) < 1e-6
    assert np.all(y[:-1] > ground)
    assert np.linalg.norm(v[-1]) == pytest.approx(v_g, rel=1e-12)
    t_sep = ds.attrs["separation_time_s"]
    after = np.flatnonzero(t > t_sep + 0.1)
    for k in (after[0], after[len(after) // 2]):   # two records, 4-5 s apart
        h = y[k] - ground
        t_pred = t[k] + (v[k, 1] + math.sqrt(v[k, 1] ** 2 + 2 * G0 * h)) / G0
        v_pred = math.sqrt(v[k, 0] ** 2 + v[k, 2] ** 2 + v[k, 1] ** 2 + 2 * G0 * h)
        assert t_g == pytest.approx(t_pred, abs=1e-5), k
        assert v_g == pytest.approx(v_pred, rel=1e-6), k
    assert f"ground: reached by the rocket's CG at t = {t_g:.3f} s" in stdout, stdout
    ds.close()


def _paper_to_the_ground(tmp_path, name, extra=()):
    return nml_variant(tmp_path, name, edits=[(r"^  t_end = 15.0 .*$", "  t_end = 400.0")], line=extra)


@pytest.fixture(scope="module")
def paper_to_ground(airlaunch_exe, tmp_path_factory):
    tmp = tmp_path_factory.mktemp("ground")
    ds, stdout = _run(airlaunch_exe, _paper_to_the_ground(tmp, "direct"), tmp / "direct.nc")
    yield ds, stdout
    ds.close()


def test_paper_scenario_ends_on_the_ground(paper_to_ground):
    """The paper scenario over 400 s: the rocket under its parachute reaches
    sea level after ~90 s, and the run completes there (it failed at -2 km
    before).  Independent check of the event: the rocket's altitude over the
    records crosses 0 between the last two, and the time is where the
    straight line through the last two grid records before it crosses the
    ground, extrapolated to it, within what the curvature of the track allows
    over the two record intervals (|a_y| (2 dt)^2 / (2 |v_y|) = 8e-6 s with
    |a_y| < 1 m/s^2 and |v_y| ~ 100 m/s: the parachute holds the fall near
    its terminal speed, measured |a_y| <= 0.57 m/s^2 over the last second;
    1e-4 s allowed, measured 6.2e-7 s)."""
    ds, stdout = paper_to_ground
    assert ds.attrs["status"] == "completed" and ds.attrs["ground_body"] == "rocket"
    t_g = ds.attrs["ground_time_s"]
    assert 60.0 < t_g < 120.0
    t = ds["time"].values
    y = ds["rocket_position"].values[:, 1]
    assert t[-1] == t_g and abs(y[-1]) < 1e-6 and np.all(y[:-1] > 0.0)
    t_lin = t[-2] - y[-2] * (t[-2] - t[-3]) / (y[-2] - y[-3])
    assert t_g == pytest.approx(t_lin, abs=1e-4)
    assert "(the run ends there)" in stdout


@pytest.mark.parametrize("coupling", ["rigidized", "auto"])
def test_every_coupling_reaches_the_ground_alike(airlaunch_exe, tmp_path, paper_to_ground, coupling):
    """The rigidized and automatic couplings end at the same event: the ground
    time within 10 ms of the direct coupling's (their phase times differ by up
    to 3.7 ms in the snatch, input.md; over the 85 s under the parachute the
    rigidized line's refreshes add ~2 ms, measured), the speed within 0.1 %."""
    direct, _ = paper_to_ground
    nml = _paper_to_the_ground(tmp_path, coupling, extra=[f"  coupling = '{coupling}'"])
    ds, _ = _run(airlaunch_exe, nml, tmp_path / f"{coupling}.nc")
    assert ds.attrs["status"] == "completed" and ds.attrs["ground_body"] == "rocket"
    assert ds.attrs["ground_time_s"] == pytest.approx(direct.attrs["ground_time_s"], abs=0.01)
    assert ds.attrs["ground_speed_m_s"] == pytest.approx(direct.attrs["ground_speed_m_s"], rel=1e-3)
    assert ds["time"].values[-1] == ds.attrs["ground_time_s"]
    ds.close()


def test_ground_not_reached_is_said(airlaunch_exe, tmp_path):
    """A run that ends at t_end above the ground: ground_time_s -1, no body,
    speed -1, and the summary says so."""
    ds, stdout = _run(airlaunch_exe, ROOT / "input" / "airlaunch_paper.nml", tmp_path / "p.nc")
    assert ds.attrs["ground_time_s"] == -1.0 and ds.attrs["ground_body"] == "none"
    assert ds.attrs["ground_speed_m_s"] == -1.0
    assert "ground: not reached" in stdout
    ds.close()


@pytest.mark.parametrize("value, fragment", [
    ("10001.0", "is not allowed (must be in [-1000.0, 10000.0] m: at most &flight altitude)"),
    ("-1500.0", "is not allowed (must be in [-1000.0, 10000.0] m: at most &flight altitude)"),
    ("9999.0", "is not allowed: the rocket's CG starts at 9998.7")])
def test_ground_altitude_out_of_range(airlaunch_exe, tmp_path, value, fragment):
    """A ground above the release altitude or less than 1 km above the
    atmosphere model's floor (-2 km) is refused by the reader; one above the
    rocket's CG at the start (1.26 m below the aircraft's in the paper file)
    by the set-up, naming where the CGs start: one line, exit 2, no file."""
    nml = nml_variant(tmp_path, edits=[(r"^(  altitude = 10000.0 .*)$", rf"\1\n  ground_altitude = {value}")])
    out = tmp_path / "never.nc"
    line = assert_input_error(run_airlaunch(airlaunch_exe, nml, "--output", out),
                              f"&flight: ground_altitude = {value.rstrip('0')}", out)
    assert str(nml) in line and fragment in line, line


def test_a_low_release_lands(airlaunch_exe, tmp_path):
    """A release 50 m above sea level (the default ground): the rocket reaches
    the sea within the run and the run completes there (before the ground
    existed it flew on below sea level); a release at sea level itself starts
    with the rocket's CG below the ground and is refused in one line that says
    the default is sea level."""
    nml = nml_variant(tmp_path, "low", edits=[(r"^  altitude = 10000.0 .*$", "  altitude = 50.0")])
    ds, _ = _run(airlaunch_exe, nml, tmp_path / "low.nc")
    assert ds.attrs["status"] == "completed" and ds.attrs["ground_body"] == "rocket"
    assert 0.0 < ds.attrs["ground_time_s"] < 15.0 and ds["time"].values[-1] == ds.attrs["ground_time_s"]
    assert abs(ds["rocket_position"].values[-1, 1]) < 1e-6
    ds.close()
    nml = nml_variant(tmp_path, "sea", edits=[(r"^  altitude = 10000.0 .*$", "  altitude = 0.0")])
    out = tmp_path / "sea.nc"
    line = assert_input_error(run_airlaunch(airlaunch_exe, nml, "--output", out),
                              "&flight: ground_altitude = 0.0 m is not allowed: the rocket's CG starts at", out)
    assert "the default 0 m is sea level" in line, line


LINE_FALL = """&run
  scene = 'line'
  t_end = 20.0
  output_dt = 0.1
  rtol = 1.0e-10, atol = 1.0e-10
/
&line
  length = 10.0, n_seg = 8, ea = 1.0e6, mass_per_length = 0.5
  gravity = .true., air = .false.
/
&line_scene
  a_kind = 'point_mass', a_mass = 10.0, a_position = 0.0, 100.0, 0.0, a_velocity = 5.0, 2.0, 0.0
  b_kind = 'free', b_position = 8.0, 106.0, 0.0, b_velocity = 5.0, 2.0, 0.0
  ground = .true., ground_altitude = {ground}
/
"""


def test_line_scene_falls_to_the_ground_against_analytic(airlaunch_exe, tmp_path):
    """The line scene: an unstretched straight line (10 m between a 10 kg
    point mass at 100 m and a free end 6 m higher), every node moving at
    (5, 2, 0) m/s, in vacuum: it falls as a rigid body with no tension, and its
    lowest node, the point mass (node 0), reaches a ground at 20 m at
    t = (v_y + sqrt(v_y^2 + 2 g h)) / g with speed sqrt(v^2 + 2 g h).  BDF2 is
    exact on a constant acceleration, but its start-up steps are first order:
    their error, held by rtol = atol = 1e-10, is what is left; 1e-9 allowed on
    both (measured 1.5e-10 and 1.6e-10; 1.6e-6 at the default rtol 1e-6).  The
    record at the event has the node on the ground."""
    nml = tmp_path / "fall.nml"
    nml.write_text(LINE_FALL.format(ground=20.0))
    out = tmp_path / "fall.nc"
    res = run_airlaunch(airlaunch_exe, nml, "--output", out)
    assert res.returncode == 0, res.stderr
    h, vy = 80.0, 2.0
    t_exact = (vy + math.sqrt(vy ** 2 + 2 * G0 * h)) / G0
    v_exact = math.sqrt(5.0 ** 2 + vy ** 2 + 2 * G0 * h)
    with xr.open_dataset(out) as ds:
        assert ds.attrs["status"] == "completed" and ds.attrs["ground_node"] == 0
        assert ds.attrs["ground_time_s"] == pytest.approx(t_exact, rel=1e-9)
        assert ds.attrs["ground_speed_m_s"] == pytest.approx(v_exact, rel=1e-9)
        assert ds["time"].values[-1] == ds.attrs["ground_time_s"]
        assert ds["line_node_position"].values[-1, 0, 1] == pytest.approx(20.0, abs=1e-6)


@pytest.mark.parametrize("edit, fragment", [
    ("ground = .true., ground_altitude = 100.0", "node 0 starts at altitude 100.0 m, not above it"),
    ("ground_altitude = 20.0", "is not allowed with ground = .false."),
    ("ground = .true., ground_altitude = 20.0, scheme = 'marching', dt = 1.0e-4",
     "is not allowed with scheme = 'marching'")])
def test_line_scene_ground_bad_input(airlaunch_exe, tmp_path, edit, fragment):
    """A ground at or above an integrated node's start, a ground_altitude
    without ground = .true. (which would do nothing), and the marching scheme
    (which locates no events): one line naming &line_scene and ground_altitude."""
    nml = tmp_path / "bad.nml"
    nml.write_text(LINE_FALL.replace("  ground = .true., ground_altitude = {ground}", "  " + edit))
    out = tmp_path / "never.nc"
    line = assert_input_error(run_airlaunch(airlaunch_exe, nml, "--output", out), fragment, out)
    assert "&line_scene: ground_altitude = " in line and str(nml) in line, line
