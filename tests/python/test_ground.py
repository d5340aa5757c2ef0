"""The ground (`&flight ground_altitude`): the run ends when the aircraft's CG
or the rocket's lowest point (its envelope, a cylinder of its length and
diameter) reaches it, an event located by CVODE's root finding, with the
time, the body, the point and its speed as milestones (docs/output.md).  Before,
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


ROCKET_NOSE, ROCKET_LENGTH = 9.25, 18.5    # the gravity drop's and the paper file's rocket: cg_from_nose, length [m]


def _lowest_point(y_cg, elevation_deg, radius):
    """Height of the rocket envelope's lowest point (a cylinder of `radius`
    from the tail at ROCKET_NOSE - ROCKET_LENGTH to the nose at ROCKET_NOSE
    on the axis, its elevation from the records), and which end it is on:
    the lower end's centre less the radius times the cosine of the axis
    elevation (its end face's rim, tilted; the output's elevation runs over
    (-90, 270] deg, so the cosine's magnitude)."""
    s, c = math.sin(math.radians(elevation_deg)), abs(math.cos(math.radians(elevation_deg)))
    ends = {"nose": ROCKET_NOSE * s, "tail": (ROCKET_NOSE - ROCKET_LENGTH) * s}
    end = min(ends, key=ends.get)
    return y_cg + ends[end] - radius * c, end


def test_ballistic_fall_to_the_ground_against_analytic(airlaunch_exe, tmp_path):
    """The gravity drop with the aircraft held steady and the rocket's
    aerodynamics off (c_axial = c_dn = 0, no fins, and a 1 cm diameter, which
    scales the slender-body normal force that has no coefficient down by
    2.6e4): after the separation only gravity acts, so the CG falls on a
    parabola and the rocket turns in its plane of symmetry at the constant
    rate it left the edge with (30 deg/s here: it tumbles).  From a record
    (t_k, CG, velocity, axis angle phi_k) and the rate between it and the next
    record (t_k, CG, velocity, axis angle phi_k, turn rate) the envelope's
    lowest point (18.5 m cylinder, nose 9.25 m ahead of the CG) is predicted
    in closed form over time, and its first crossing of the ground 500 m
    below the release is found by bisection.  BDF is exact on a constant
    acceleration and CVODE locates the root to ~1e-14 s; what is left is the
    normal force of the 1 cm body and rtol 1e-6 over the 10 s before (the
    turn rate wanders by 2e-5 of itself: 3e-6 s at the ground): 1e-5 s
    allowed, measured 1.0e-6 and 3.3e-6 s.  The speed is the touching point's, from the event's own
    record: the CG's plus the turn rate times the point's arm (1e-9: the
    same state, only the geometry differs).  The run ends there:
    status completed, exit 0, the last record at the event with the lowest
    point on the ground (1e-6 m: the event's own state), at the end the
    closed form says, every earlier record above it.  The CG alone, as
    before, would land 7.7 m lower, 0.05 s later."""
    ground, radius = 5500.0, 0.005
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
    pos = ds["rocket_position"].values
    v = ds["rocket_velocity"].values
    elev = ds["rocket_nose_elevation_deg"].values
    euler = np.radians(ds["rocket_euler_deg"].values)
    low = [_lowest_point(pos[k, 1], elev[k], radius) for k in range(len(t))]
    assert t[-1] == t_g and abs(low[-1][0] - ground) < 1e-6
    assert all(h > ground for h, _ in low[:-1])
    assert ds.attrs["ground_point"] == low[-1][1]
    assert pos[-1, 1] - ground > 1.0        # the CG is well above: the extent counts
    # the axis angle in the plane of the fall (yaw and roll are 0 or 180 deg)
    phi = np.arctan2(np.sin(euler[:, 1]), np.cos(euler[:, 1]) * np.cos(euler[:, 0]))
    assert np.all(np.abs(pos[:, 2]) < 1e-9) and np.all(np.abs(np.sin(euler[:, 2])) < 1e-9)
    # the turn rate about the earth's z axis (Euler pitch rate, its sign flipped by a yaw of 180 deg)
    rate = np.radians(ds["rocket_pitch_rate_deg_s"].values) * np.cos(euler[:, 0])
    assert np.all(np.abs(np.degrees(rate[t > ds.attrs["separation_time_s"] + 0.1])) > 10.0)   # it tumbles
    after = np.flatnonzero(t > ds.attrs["separation_time_s"] + 0.1)
    for k in (after[0], after[len(after) // 2]):   # two records, 4-5 s apart

        def height(tt, k=k):
            dt = tt - t[k]
            y_cg = pos[k, 1] + v[k, 1] * dt - 0.5 * G0 * dt ** 2
            return _lowest_point(y_cg, math.degrees(math.asin(math.sin(phi[k] + rate[k] * dt))), radius)[0] - ground

        grid = np.arange(t[k], t[-1] + 1.0, 1e-3)
        first = next(i for i, tt in enumerate(grid) if height(tt) <= 0.0)
        lo, hi = grid[first - 1], grid[first]
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if height(mid) > 0.0 else (lo, mid)
        assert t_g == pytest.approx(lo, abs=1e-5), k
    # the speed is the touching point's: the CG's and the turn rate times its arm
    # (the lower end's centre, and the radius toward the ground), at the event's record
    axis = np.array([math.cos(phi[-1]), math.sin(phi[-1])])
    x_end = ROCKET_NOSE if low[-1][1] == "nose" else ROCKET_NOSE - ROCKET_LENGTH
    normal = np.array([-axis[1], axis[0]])
    arm = x_end * axis - radius * normal * math.copysign(1.0, normal[1])
    v_point = v[-1, :2] + rate[-1] * np.array([-arm[1], arm[0]])
    assert v_g == pytest.approx(np.linalg.norm(v_point), rel=1e-9)
    assert abs(v_g - np.linalg.norm(v[-1])) > 1.0      # not the CG's
    assert f"ground: reached by the rocket's {low[-1][1]} at t = {t_g:.3f} s" in stdout, stdout
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
    before).  It hangs from its nose-end tie-down nearly level (nose 3.4 deg
    up), so its tail's rim touches first, its CG 1.34 m above the sea.
    Independent check of the event: the envelope's lowest point, computed
    here from the records' CG and axis elevation, crosses 0 between the last
    two records, and the time is where the straight line through the last
    two grid records before it crosses the ground, extrapolated to it, within
    what the curvature of the track allows over the two record intervals
    (|a_y| (2 dt)^2 / (2 |v_y|) = 8e-6 s with |a_y| < 1 m/s^2 and |v_y| ~
    100 m/s: the parachute holds the fall near its terminal speed, measured
    |a_y| <= 0.57 m/s^2 over the last second, and the pitch changes by
    < 0.01 deg per record; 1e-4 s allowed, measured 3.1e-8 s)."""
    ds, stdout = paper_to_ground
    assert ds.attrs["status"] == "completed" and ds.attrs["ground_body"] == "rocket"
    assert ds.attrs["ground_point"] == "tail"
    t_g = ds.attrs["ground_time_s"]
    assert 60.0 < t_g < 120.0
    t = ds["time"].values
    y_cg = ds["rocket_position"].values[:, 1]
    elev = ds["rocket_nose_elevation_deg"].values
    y = np.array([_lowest_point(y_cg[k], elev[k], 0.8)[0] for k in range(len(t))])
    assert t[-1] == t_g and abs(y[-1]) < 1e-6 and np.all(y[:-1] > 0.0)
    assert 1.0 < y_cg[-1] < 2.0
    t_lin = t[-2] - y[-2] * (t[-2] - t[-3]) / (y[-2] - y[-3])
    assert t_g == pytest.approx(t_lin, abs=1e-4)
    assert "(the run ends there)" in stdout


@pytest.mark.parametrize("coupling", ["rigidized", "auto"])
def test_every_coupling_reaches_the_ground_alike(airlaunch_exe, tmp_path, paper_to_ground, coupling):
    """The rigidized and automatic couplings end at the same event: the ground
    time within 10 ms of the direct coupling's (their phase times differ by up
    to 3.7 ms in the snatch, input.md; over the 85 s under the parachute the
    rigidized line's refreshes add ~3 ms, measured), the speed within 0.1 %."""
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
    assert ds.attrs["ground_point"] == "none"
    assert ds.attrs["ground_speed_m_s"] == -1.0
    assert "ground: not reached" in stdout
    ds.close()


@pytest.mark.parametrize("value, fragment", [
    ("10001.0", "is not allowed (must be in [-1000.0, 10000.0] m: at most &flight altitude)"),
    ("-1500.0", "is not allowed (must be in [-1000.0, 10000.0] m: at most &flight altitude)"),
    ("9999.0", "is not allowed: the rocket's lowest point starts at 9997.74")])
def test_ground_altitude_out_of_range(airlaunch_exe, tmp_path, value, fragment):
    """A ground above the release altitude or less than 1 km above the
    atmosphere model's floor (-2 km) is refused by the reader; one above the
    rocket's lowest point at the start (its CG 1.26 m below the aircraft's
    in the paper file, its rim 0.8 m lower, its tail 0.2 m lower still at
    1.2 deg nose up) by the set-up, naming where the rocket's lowest point and the
    aircraft's CG start: one line, exit 2, no file."""
    nml = nml_variant(tmp_path, edits=[(r"^(  altitude = 10000.0 .*)$", rf"\1\n  ground_altitude = {value}")])
    out = tmp_path / "never.nc"
    line = assert_input_error(run_airlaunch(airlaunch_exe, nml, "--output", out),
                              f"&flight: ground_altitude = {value.rstrip('0')}", out)
    assert str(nml) in line and fragment in line, line


def test_a_low_release_lands(airlaunch_exe, tmp_path):
    """A release 50 m above sea level (the default ground): the rocket reaches
    the sea within the run and the run completes there (before the ground
    existed it flew on below sea level), the envelope's lowest point on the
    sea at the last record; a release at sea level itself starts with the
    rocket below the ground and is refused in one line that says the default
    is sea level."""
    nml = nml_variant(tmp_path, "low", edits=[(r"^  altitude = 10000.0 .*$", "  altitude = 50.0")])
    ds, _ = _run(airlaunch_exe, nml, tmp_path / "low.nc")
    assert ds.attrs["status"] == "completed" and ds.attrs["ground_body"] == "rocket"
    assert 0.0 < ds.attrs["ground_time_s"] < 15.0 and ds["time"].values[-1] == ds.attrs["ground_time_s"]
    low = _lowest_point(ds["rocket_position"].values[-1, 1], ds["rocket_nose_elevation_deg"].values[-1], 0.8)
    assert abs(low[0]) < 1e-6 and low[1] == ds.attrs["ground_point"]
    ds.close()
    nml = nml_variant(tmp_path, "sea", edits=[(r"^  altitude = 10000.0 .*$", "  altitude = 0.0")])
    out = tmp_path / "sea.nc"
    line = assert_input_error(run_airlaunch(airlaunch_exe, nml, "--output", out),
                              "&flight: ground_altitude = 0.0 m is not allowed: the rocket's lowest point starts at",
                              out)
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


def test_the_figure_draws_the_ground_where_the_run_ended_on_it():
    """plot_run's 2-D track draws the ground of a run that ended on it, at the
    &flight ground_altitude the file's resolved input records (as the
    program writes it: upper case, padded), and none for a run that did
    not reach it."""
    from postproc.plot_run import _ground_altitude

    echo = "&FLIGHT\n ALTITUDE=  10000.000000000000     ,\n GROUND_ALTITUDE= -250.00000000000000     ,\n/\n"
    landed = xr.Dataset(attrs={"ground_time_s": 89.5, "input_namelist": echo})
    assert _ground_altitude(landed) == -250.0
    above = xr.Dataset(attrs={"ground_time_s": -1.0, "input_namelist": echo})
    assert _ground_altitude(above) is None
