"""The rail and ramp-edge contact (Cases 1-3) against an independent planar
reference (audit, thirty-first session): a rocket on the deck of a prescribed (steady)
aircraft, no line, the rocket's aerodynamics off (c_axial = c_dn = 0, no fins;
the slender-body term, which has no coefficient, made negligible by a high,
slow flight and a tiny diameter or a heavy rocket).  The reference is Newton-
Euler in the aircraft's pitch plane with the contact point's axial coordinate
xi and the pitch phi relative to the deck as coordinates, written from
docs/model.md and docs/multibody.md (edge force along the rocket's y, Coulomb
friction mu |N| along its axis, edge point on the rocket's lower generatrix R
below the axis), integrated by scipy's DOP853 at 1e-13 with event location.
Measured at rtol 1e-10: event times within 1e-7 s, pitch within 2e-6 deg, the
edge force within 6e-8 of the weight."""
import math

import numpy as np
import pytest
import xarray as xr
from scipy.integrate import solve_ivp

from conftest import run_airlaunch

G0 = 9.80665
BASE = """
&run
  scene = 'airlaunch'
  t_end = 12.0
  output_dt = 0.01
  rtol = 1.0e-10
  atol = 1.0e-12
/
&flight
  altitude = 20000.0
  mach = 0.05
  trim_alpha_deg = 7.0
/
&aircraft
  dynamics = 'prescribed'
/
&bay
  friction = {mu}
  release_time = 0.5
  l0 = 10.0
  edge_contact = '{edge}'
/
&rocket
  mass = {m}
  izz = {j}
  length = 18.5
  diameter = {d}
  cg_from_nose = {cg}
  c_axial = 0.0
  c_dn = 0.0
  fin_count = 0
/
&line
  enabled = .false.
/
"""
CASES = {
    # frictionless, one-sided edge (separates when N = 0), a 1 cm rocket (R = 5 mm)
    "frictionless_one_sided": dict(mu=0.0, edge="one_sided", m=28000.0, j=545000.0, d=0.01, cg=9.25),
    # friction on rail and edge, bilateral edge (N < 0 after the pull time), R = 0.8 m;
    # mass and inertia x1000 make the slender-body force 1e-7 of the weight
    "friction_bilateral_thick": dict(mu=0.05, edge="bilateral", m=28.0e6, j=545.0e6, d=1.6, cg=14.0),
}


def reference(m, J, R, l0, xnose, deck, mu, edge, t0, one_sided):
    """Event times, pitch (deg) and rate at separation, and N(t) in Case 2."""
    gv = G0 * np.array([-math.sin(deck), -math.cos(deck)])

    def case2(y):
        xi, xid, ph, phd = y
        u = np.array([math.cos(ph), math.sin(ph)])
        n = np.array([-math.sin(ph), math.cos(ph)])
        for sn in (1.0, -1.0):          # friction mu |N| against the slip -xid u
            sg = (1.0 if xid >= 0 else -1.0) * sn
            A = np.array([[-m, -m * R, -mu * sg], [0.0, -m * xi, -1.0], [0.0, J, -(xi + R * mu * sg)]])
            b = np.array([m * gv @ u - m * xi * phd**2, m * gv @ n + 2 * m * xid * phd + m * R * phd**2, 0.0])
            xidd, phdd, N = np.linalg.solve(A, b)
            if N >= 0 or sn < 0:
                return xidd, phdd, N

    a1 = G0 * (math.sin(deck) - mu * math.cos(deck))
    t_edge = t0 + math.sqrt(2 * l0 / a1)
    ev_nose = lambda t, y: y[0] - xnose
    ev_nose.terminal, ev_nose.direction = True, 1
    ev_n = lambda t, y: case2(y)[2]
    ev_n.terminal, ev_n.direction = True, -1
    sol = solve_ivp(lambda t, y: [y[1], case2(y)[0], y[3], case2(y)[1]], (t_edge, 30.0),
                    [0.0, a1 * (t_edge - t0), 0.0, 0.0], method="DOP853", rtol=1e-13, atol=1e-13,
                    events=[ev_nose, ev_n] if one_sided else [ev_nose], dense_output=True)
    t_sep = min(te[0] for te in sol.t_events if len(te))
    y = sol.sol(t_sep)
    return t_edge, t_sep, math.degrees(deck + y[2]), math.degrees(y[3]), sol, case2


@pytest.mark.parametrize("name", list(CASES))
def test_rail_and_edge_against_planar_reference(airlaunch_exe, tmp_path, name):
    c = CASES[name]
    nml = tmp_path / f"{name}.nml"
    nml.write_text(BASE.format(**c))
    out = tmp_path / f"{name}.nc"
    res = run_airlaunch(airlaunch_exe, nml, "--output", out)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(out) as ds:
        deck = math.radians(float(ds.aircraft_euler_deg[0, 1]))
        t_edge, t_sep, p_sep, r_sep, sol, case2 = reference(
            c["m"], c["j"], c["d"] / 2, 10.0, c["cg"], deck, c["mu"], c["edge"], 0.5, c["edge"] == "one_sided")
        assert ds.attrs["edge_time_s"] == pytest.approx(t_edge, abs=1e-6)
        assert ds.attrs["separation_time_s"] == pytest.approx(t_sep, abs=1e-6)
        assert ds.attrs["pitch_at_separation_deg"] == pytest.approx(p_sep, abs=2e-5)
        assert ds.attrs["pitch_rate_at_separation_deg_s"] == pytest.approx(r_sep, abs=2e-5)
        weight = c["m"] * G0
        inside = (ds.phase.values == 2) & (ds.time.values > t_edge) & (ds.time.values < t_sep)
        assert inside.sum() > 20
        for t, pitch, rate, n_edge in zip(ds.time.values[inside], ds.rocket_euler_deg.values[inside, 1],
                                          ds.rocket_pitch_rate_deg_s.values[inside],
                                          ds.edge_normal_force_N.values[inside]):
            y = sol.sol(t)
            assert pitch == pytest.approx(math.degrees(deck + y[2]), abs=2e-5)
            assert rate == pytest.approx(math.degrees(y[3]), abs=2e-5)
            assert n_edge == pytest.approx(case2(y)[2], abs=1e-6 * weight)


def test_rocket_stuck_on_the_rail_at_a_tight_atol_does_not_crawl(airlaunch_exe, tmp_path):
    """A rocket that friction holds on the rail (mu = 0.3 > tan 7 deg) sticks
    (Karnopp: s'' + stick_rate s' = 0, rate 1000/s).  Without a line the Newton
    matrix came from CVODE's dense difference quotients, whose increment for a
    state near 0 (the rocket's velocity relative to the frame moving at V0) fell
    below the rounding of V0 + v at atol 1e-12: the stick row was lost and CVODE
    crawled at h ~ 1 ms (3 s: 2 849 steps, 2 064 convergence failures).  With the
    scene's own increments (launch_jacobian, as with a line): 8 steps.  And it
    stays put (no creep)."""
    c = dict(CASES["frictionless_one_sided"], mu=0.3)
    nml = tmp_path / "stuck.nml"
    nml.write_text(BASE.format(**c).replace("t_end = 12.0", "t_end = 3.0"))
    out = tmp_path / "stuck.nc"
    res = run_airlaunch(airlaunch_exe, nml, "--output", out)
    assert res.returncode == 0, res.stderr
    steps = int(next(l for l in res.stdout.splitlines() if l.startswith("integration:")).split()[1])
    assert steps < 100, res.stdout
    with xr.open_dataset(out) as ds:
        rel = (ds.rocket_position - ds.aircraft_position).values[:, :2]
        assert np.abs(rel - rel[0]).max() < 1e-8
        assert (ds.phase.values[ds.time.values > 0.5] == 1).all()
