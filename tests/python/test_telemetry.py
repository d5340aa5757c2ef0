"""The air-launch scene's telemetry outputs (docs/output.md, "Telemetry"): what a
flight-test engineer compares with the aircraft's INS and air data and the
rocket's accelerometers, rate gyros and line load cell.  Each recorded quantity
is checked against an independent computation from the other records, with the
documented frames: the direction cosine matrix rebuilt from the Euler angles as
docs/model.md states it, C = R_y(psi) R_z(theta) R_x(gamma) (body to earth).

The paper scenario is run to 6 s (every phase) at rtol 1e-9, so that the
integration error (~1e-9 relative) is far below the finite differences' own
truncation error, h^2/6 |x'''| for the central difference at the output step
h = 5 ms.  That bound is estimated from the records' third differences and
taken 3x: the third differences sample x''' at the records only, and miss the
largest value between them, by up to 1.6x here (measured)."""
import numpy as np
import pytest
import xarray as xr

from conftest import nml_variant, run_airlaunch

G0 = 9.80665           # m/s^2, the code's standard gravity (earth y is up)
M_ROCKET = 28000.0     # kg, input/airlaunch_paper.nml
H = 0.005              # s, output step of the run below


def dcm(euler_deg):
    """Body-to-earth DCMs (n, 3, 3) of yaw psi about y, pitch theta about z,
    roll gamma about x (docs/model.md, "Frames")."""
    psi, th, ga = np.radians(np.asarray(euler_deg)).T
    o, z = np.ones_like(psi), np.zeros_like(psi)

    def m(rows):
        return np.stack([np.stack(r, -1) for r in rows], -2)
    ry = m([[np.cos(psi), z, np.sin(psi)], [z, o, z], [-np.sin(psi), z, np.cos(psi)]])
    rz = m([[np.cos(th), -np.sin(th), z], [np.sin(th), np.cos(th), z], [z, z, o]])
    rx = m([[o, z, z], [z, np.cos(ga), -np.sin(ga)], [z, np.sin(ga), np.cos(ga)]])
    return ry @ rz @ rx


def to_body(c, v):
    """Earth components v (n, 3) in body axes: C^T v."""
    return np.einsum("nji,nj->ni", c, v)


@pytest.fixture(scope="module")
def run(airlaunch_exe, tmp_path_factory):
    tmp = tmp_path_factory.mktemp("telemetry")
    nml = nml_variant(tmp, edits=[(r"^  t_end = 15.0 .*$", "  t_end = 6.0"),
                                  (r"^  output_dt = 0.02 .*$", f"  output_dt = {H}"),
                                  (r"^  rtol = 1.0e-5 .*$", "  rtol = 1.0e-9"),
                                  (r"^  atol = 1.0e-6 .*$", "  atol = 1.0e-10")])
    res = run_airlaunch(airlaunch_exe, nml, "--output", tmp / "t.nc")
    assert res.returncode == 0, res.stderr
    ds = xr.open_dataset(tmp / "t.nc")
    yield ds
    ds.close()


@pytest.fixture(scope="module")
def smooth(run):
    """Records k whose neighbours k-2 .. k+2 lie in the same phase, away from
    the events (where accelerations jump) and the run's ends."""
    t = run.time.values
    ok = np.zeros(len(t), bool)
    ok[2:-2] = True
    for name in ("release_time_s", "edge_time_s", "separation_time_s"):
        ok &= np.abs(t - run.attrs[name]) > 2.5 * H
    assert np.allclose(np.diff(t), H)
    return np.nonzero(ok)[0]


def central(x, k):
    """Central difference of x (n, ...) at records k, and 3x its truncation
    bound h^2/6 max|x'''| (per component) from the third differences."""
    d = (x[k + 1] - x[k - 1]) / (2 * H)
    third = np.abs(x[k + 2] - 3 * x[k + 1] + 3 * x[k] - x[k - 1]) / H**3
    return d, 3 * H**2 / 6 * third.max(axis=0) + 1e-6


@pytest.mark.parametrize("body", ["rocket", "aircraft"])
def test_specific_force_is_the_velocitys_derivative_less_gravity(run, smooth, body):
    k = smooth
    a, tol = central(run[f"{body}_velocity"].values, k)
    c = dcm(run[f"{body}_euler_deg"].values)[k]
    expected = to_body(c, a + [0.0, G0, 0.0])
    got = run[f"{body}_specific_force_m_s2"].values[k]
    assert np.all(np.abs(got - expected) <= tol), (np.abs(got - expected).max(axis=0), tol)
    # the y component is the load factor's own definition (one rounding apart)
    if body == "aircraft":
        np.testing.assert_allclose(got[:, 1], run.aircraft_load_factor.values[k] * G0, rtol=1e-13)


def test_specific_force_on_the_locked_rocket_is_its_reactions(run):
    """Case 0 (locked, trimmed level flight, the rocket shielded in the bay: no
    air load): m f = C^T (R_H + line force), the line's force taken as the first
    segment's tension along it.  The line's end force adds half a segment's
    weight and air load (docs/model.md): 0.8 kg x g = 7.8 N and ~12 N of skin
    friction on 2 m at q = 7.8 kPa, so 25 N."""
    k = np.nonzero(run.phase.values == 0)[0]
    assert len(k) > 100
    nodes = run.line_nodes.values[k]
    u = nodes[:, 1] - nodes[:, 0]
    u /= np.linalg.norm(u, axis=1)[:, None]
    force = run.constraint_force.values[k] + run.line_tension_rocket_end_N.values[k][:, None] * u
    expected = to_body(dcm(run.rocket_euler_deg.values)[k], force) / M_ROCKET
    got = run.rocket_specific_force_m_s2.values[k]
    assert np.abs(got - expected).max() <= 25.0 / M_ROCKET
    # the normal reaction holds the rocket up: ~1 g along its y axis
    assert np.all(np.abs(got[:, 1] / G0 - 1.0) < 0.01)


def test_accelerometer_at_a_station_is_the_documented_rigid_body_formula(run, smooth):
    """An accelerometer at the nose (body x = cg_from_nose = 9.25 m ahead of the
    CG): f_P = f + wdot x r_P + w x (w x r_P) from the records (output.md), against
    the finite difference of the nose's earth velocity v + C (w x r_P)."""
    k = smooth
    r_p = np.array([9.25, 0.0, 0.0])
    c = dcm(run.rocket_euler_deg.values)
    w = np.radians(run.rocket_body_rates_deg_s.values)
    wdot = np.radians(run.rocket_angular_acceleration_deg_s2.values)
    v_p = run.rocket_velocity.values + np.einsum("nij,nj->ni", c, np.cross(w, r_p))
    a_p, tol = central(v_p, k)
    expected = to_body(c[k], a_p + [0.0, G0, 0.0])
    got = run.rocket_specific_force_m_s2.values[k] + np.cross(wdot[k], r_p) + np.cross(w[k], np.cross(w[k], r_p))
    assert np.all(np.abs(got - expected) <= tol), (np.abs(got - expected).max(axis=0), tol)


@pytest.mark.parametrize("body", ["rocket", "aircraft"])
def test_body_rates_are_the_attitudes_rate(run, smooth, body):
    """[w]x = C^T dC/dt, C from the recorded Euler angles."""
    k = smooth
    c = dcm(run[f"{body}_euler_deg"].values)
    dc, tol = central(c, k)
    skew = np.einsum("nji,njk->nik", c[k], dc)
    expected = np.degrees(np.stack([skew[:, 2, 1], skew[:, 0, 2], skew[:, 1, 0]], -1))
    got = run[f"{body}_body_rates_deg_s"].values[k]
    tol = np.degrees(np.abs(tol).max())
    assert np.abs(got - expected).max() <= tol, (np.abs(got - expected).max(axis=0), tol)
    # the existing pitch-rate outputs are these rates
    w = run[f"{body}_body_rates_deg_s"].values
    if body == "aircraft":
        assert np.array_equal(run.aircraft_pitch_rate_deg_s.values, w[:, 2])
    else:
        gamma = np.radians(run.rocket_euler_deg.values[:, 2])
        np.testing.assert_allclose(run.rocket_pitch_rate_deg_s.values,
                                   np.sin(gamma) * w[:, 1] + np.cos(gamma) * w[:, 2], rtol=0, atol=1e-12)


def test_angular_acceleration_is_the_body_rates_derivative(run, smooth):
    k = smooth
    dw, tol = central(run.rocket_body_rates_deg_s.values, k)
    got = run.rocket_angular_acceleration_deg_s2.values[k]
    assert np.all(np.abs(got - dw) <= tol), (np.abs(got - dw).max(axis=0), tol)
    assert np.abs(got[:, 2]).max() > 10.0   # the rocket's pitch-up on the edge (deg/s^2)


def isa_troposphere(y):
    """ISA 1976 below 11 km geopotential (docs/model.md): density, sound speed."""
    r0 = 6356766.0
    geopotential = r0 * y / (r0 + y)
    temperature = 288.15 - 0.0065 * geopotential
    r_air = 287.05287
    rho = 1.225 * (temperature / 288.15) ** (G0 / (0.0065 * r_air) - 1.0)
    return rho, np.sqrt(1.4 * r_air * temperature)


@pytest.mark.parametrize("body", ["rocket", "aircraft"])
def test_air_data_from_the_recorded_state(run, body):
    """Still air (no &gust): Mach = V/a and q = rho V^2/2 with V the recorded
    speed and ISA at the recorded altitude (1e-6: the rounding of ISA's
    constants here against the code's), alpha = atan2(-v_y, v_x) and
    beta = asin(v_z/V) of C^T v (the aircraft's recorded alpha is its
    aerodynamics' own: that checks aircraft_velocity as well)."""
    v = run[f"{body}_velocity"].values
    speed = np.linalg.norm(v, axis=1)
    rho, a = isa_troposphere(run[f"{body}_position"].values[:, 1])
    np.testing.assert_allclose(run[f"{body}_mach"].values, speed / a, rtol=1e-6)
    np.testing.assert_allclose(run[f"{body}_dynamic_pressure_Pa"].values, 0.5 * rho * speed**2, rtol=1e-6)
    vb = to_body(dcm(run[f"{body}_euler_deg"].values), v)
    np.testing.assert_allclose(run[f"{body}_alpha_deg"].values, np.degrees(np.arctan2(-vb[:, 1], vb[:, 0])),
                               rtol=0, atol=1e-10)
    np.testing.assert_allclose(run[f"{body}_beta_deg"].values, np.degrees(np.arcsin(vb[:, 2] / speed)),
                               rtol=0, atol=1e-10)


def test_rocket_relative_to_the_aircraft_in_its_axes(run):
    """Relative position C0^T (r1 - r0) at the release is the documented placement
    (&bay ramp_edge_x + l0, floor_y + diameter/2 = (-3, -1.2, 0) m); the relative
    velocity seen in the aircraft's axes, C0^T (v1 - v0) - w0 x r, is zero while
    locked and along the rail (x) alone in Case 1 (to the joint's drift, 1e-8)."""
    c0 = dcm(run.aircraft_euler_deg.values)
    r = to_body(c0, run.rocket_position.values - run.aircraft_position.values)
    v = to_body(c0, run.rocket_velocity.values - run.aircraft_velocity.values) \
        - np.cross(np.radians(run.aircraft_body_rates_deg_s.values), r)
    k = int(np.argmin(np.abs(run.time.values - run.attrs["release_time_s"])))
    np.testing.assert_allclose(r[k], [-3.0, -1.2, 0.0], rtol=0, atol=1e-9)
    phase = run.phase.values
    assert np.abs(v[phase == 0]).max() < 1e-8
    assert np.abs(v[phase == 1][:, 1:]).max() < 1e-7
    assert v[phase == 1][-1, 0] < -5.0      # aft along the rail


def test_rocket_on_the_deck_in_level_flight_reads_the_normal_reaction(airlaunch_exe, tmp_path):
    """The gravity drop (no line) locked in the bay of an aircraft trimmed in
    level flight at 7 deg pitch: the aircraft does not accelerate, the rocket is
    shielded, so its accelerometer reads the deck's reaction to gravity alone,
    f = C^T (0, g, 0) = (g sin 7 deg, g cos 7 deg, 0) (1e-9 m/s^2: the trim's
    residual acceleration and 0.5 s of drift at rtol 1e-6; measured 9e-12)."""
    from conftest import ROOT
    nml = nml_variant(tmp_path, base=ROOT / "input" / "airlaunch_gravity_drop.nml",
                      edits=[(r"^  t_end = 12.0 .*$", "  t_end = 1.0")])
    res = run_airlaunch(airlaunch_exe, nml, "--output", tmp_path / "gd.nc")
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(tmp_path / "gd.nc") as ds:
        f = ds.rocket_specific_force_m_s2.values[ds.phase.values == 0]
        deck = np.radians(7.0)
        np.testing.assert_allclose(f, np.broadcast_to([G0 * np.sin(deck), G0 * np.cos(deck), 0.0], f.shape),
                                   rtol=0, atol=1e-9)
        # the aircraft's own accelerometer: 1 g up its y axis, tilted by the same 7 deg
        fa = ds.aircraft_specific_force_m_s2.values[ds.phase.values == 0]
        np.testing.assert_allclose(fa, np.broadcast_to([G0 * np.sin(deck), G0 * np.cos(deck), 0.0], fa.shape),
                                   rtol=0, atol=1e-9)
