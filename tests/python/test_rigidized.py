"""Coupling (a), `&line coupling = 'rigidized'` (the paper's equivalent
rigidization, §2.4 Steps 1-6, inside the Kane chain of §4.2), end to end on the
paper scenario against coupling (b), 'direct', its accuracy reference
(DESIGN §4).  The difference between the two is the cost of (a) in error.

Measured at the paper file's settings (docs/model.md, "Coupling (a)"):
phase times +0.059 / +0.070 ms, first pitch maximum +3.65 ms, nose elevation
within 0.073 deg and rocket CG within 11 cm over the 15 s, rocket-end tension
within 31 N (thirty-fourth session, with the potential force at the ramp edge;
+0.024 ms, +1.7 ms, 0.034 deg, 4 cm and 7 N when the tolerances were set).
Tolerances (each about 3-10x the value measured when they were set; 1.4-3x
now):
  * Case 1->2 and separation times 0.2 ms: 10x the then measured 0.024 ms and 10x
    the direct model's own integration error at these tolerances (rtol 1e-6
    vs 1e-9 moves them by 0.02 ms);
  * first pitch maximum 5 ms: the flat maximum of the Euler pitch amplifies
    attitude differences; 0.05 % of 10.5 s, half the 0.1 % bar of issue 7;
  * nose elevation 0.1 deg, rocket CG 0.2 m (after 2.9 km of flight), tension
    at the rocket end 50 N (0.06 % of the 78.8 kN pull), peak tension 10 N.
The virtual body must follow the flexible line (d_rigid = its chord, m_rigid =
its mass), B3 and the line's node N must agree (the parachute is modelled on
both sides of the coupling), and `far_end = 'chain'` (both end motions from
the chain) must show why it is not the default: d_rigid frozen and the line's
tension stuck near its initial stretch.
"""

import re

import numpy as np
import pytest
import xarray as xr

from conftest import assert_input_error, nml_variant, run_airlaunch


CONTRACT_VARS = ["phase", "aircraft_position", "aircraft_euler_deg", "aircraft_alpha_deg",
                 "rocket_position", "rocket_velocity", "rocket_euler_deg", "rocket_pitch_rate_deg_s",
                 "parachute_position", "line_tension_rocket_end_N", "line_tension_parachute_end_N",
                 "line_nodes", "constraint_force", "clearance_m"]
RIGIDIZED_VARS = ["m_rigid_kg", "j_rigid_kg_m2", "d_rigid_m", "rigid_line_force_N", "line_end_mismatch_m"]


@pytest.fixture(scope="module")
def paper_pair(airlaunch_exe, tmp_path_factory):
    d = tmp_path_factory.mktemp("rigidized")
    out = {}
    for name, line in [("direct", ()), ("rigidized", ("  coupling = 'rigidized'",))]:
        nc = d / f"{name}.nc"
        res = run_airlaunch(airlaunch_exe, nml_variant(d, name, line=line), "--output", nc)
        assert res.returncode == 0, res.stderr
        out[name] = xr.open_dataset(nc)
    yield out["direct"], out["rigidized"]
    for ds in out.values():
        ds.close()


def test_output_contract_and_rigidized_variables(paper_pair):
    direct, rig = paper_pair
    for name in CONTRACT_VARS + RIGIDIZED_VARS:
        assert name in rig, name
        assert rig[name].attrs.get("units"), f"{name} has no units"
        assert rig[name].dims[0] == "time"
    assert rig["line_nodes"].dims == ("time", "node", "xyz")
    assert rig.sizes["node"] == direct.sizes["node"] and rig.sizes["time"] == direct.sizes["time"]
    np.testing.assert_array_equal(rig["time"].values, direct["time"].values)
    assert rig.attrs["status"] == "completed"
    assert rig.attrs["line_coupling"] == "rigidized"
    assert rig.attrs["outer_dt_s"] == pytest.approx(0.02)
    assert 'COUPLING="RIGIDIZED"' in rig.attrs["input_namelist"].upper().replace(" ", "")


def test_virtual_body_follows_the_line(paper_pair):
    _, rig = paper_pair
    nodes = rig["line_nodes"].values
    chord = np.linalg.norm(nodes[:, -1] - nodes[:, 0], axis=1)
    # d_rigid (20) is the flexible line's chord; m_rigid (31) its mass, 0.4 kg/m x 60 m
    # (kinetic-energy equivalent in the earth frame: the taut line moves almost rigidly)
    np.testing.assert_allclose(rig["d_rigid_m"].values, chord, rtol=1e-12)
    np.testing.assert_allclose(rig["m_rigid_kg"].values, 24.0, rtol=1e-3)
    assert np.all(rig["j_rigid_kg_m2"].values > 0)
    # the line stretches and relaxes with the pull: the chain's body follows (2 m)
    assert chord.max() - chord.min() > 1.5
    # the parachute is on both sides of the coupling: B3 and the line's node N agree
    gap = np.linalg.norm(rig["parachute_position"].values - nodes[:, -1], axis=1)
    np.testing.assert_allclose(gap, rig["line_end_mismatch_m"].values, rtol=1e-9, atol=1e-12)
    assert gap.max() < 0.01
    # the rigid line pulls the rocket like the flexible line's tension (0.2 %)
    force = np.linalg.norm(rig["rigid_line_force_N"].values, axis=1)
    tension = rig["line_tension_rocket_end_N"].values
    assert np.max(np.abs(force - tension) / tension) < 2e-3
    assert rig.attrs["min_rigid_line_tension_N"] > 4e4        # never pushes (the real line cannot)


def assert_peak_tension_first_at_start(*runs):
    """The paper file's peak tension is the steady pull before the release, flat to
    1e-7 from t = 0 (the records: within rtol 1e-5 of it at t = 0), so it is first
    reached at t = 0 (before, the time was where each run's round-off ripple on the
    plateau peaked)."""
    for x in runs:
        assert x["line_tension_rocket_end_N"].values[0] >= x.attrs["peak_line_tension_N"] * (1 - 1e-5)
        assert x.attrs["peak_line_tension_time_s"] == 0.0


def assert_milestones_near_direct(direct, other):
    """The rigidized coupling's bounds on the milestones against the direct run."""
    a, b = direct.attrs, other.attrs
    assert b["release_time_s"] == pytest.approx(a["release_time_s"], abs=1e-12)
    assert b["edge_time_s"] == pytest.approx(a["edge_time_s"], abs=2e-4)
    assert b["separation_time_s"] == pytest.approx(a["separation_time_s"], abs=2e-4)
    assert b["early_separation"] == a["early_separation"]
    assert b["pitch_at_separation_deg"] == pytest.approx(a["pitch_at_separation_deg"], abs=0.01)
    assert b["pitch_max_time_s"] == pytest.approx(a["pitch_max_time_s"], abs=5e-3)
    assert b["pitch_max_deg"] == pytest.approx(a["pitch_max_deg"], abs=0.01)
    assert b["peak_line_tension_N"] == pytest.approx(a["peak_line_tension_N"], abs=10.0)
    assert_peak_tension_first_at_start(direct, other)
    assert b["min_clearance_m"] == pytest.approx(a["min_clearance_m"], abs=0.01)
    # the line's clearance from the empennage point, over the rigidized coupling's
    # line sub-steps (the point interpolated between the chain's samples) since the
    # twenty-eighth session (-1 before): as the rocket's clearance, 1 cm (measured
    # 0.024 mm in the paper file, 0.25 mm with the paper's marching)
    assert b["min_line_clearance_m"] == pytest.approx(a["min_line_clearance_m"], abs=0.01)


def assert_tracks_near_direct(direct, other):
    """The rigidized coupling's bounds on the tracks against the direct run: nose
    elevation 0.1 deg, rocket CG 0.2 m, rocket-end tension 50 N, the same phases."""
    d_elev = np.abs(other["rocket_nose_elevation_deg"].values - direct["rocket_nose_elevation_deg"].values)
    d_pos = np.linalg.norm(other["rocket_position"].values - direct["rocket_position"].values, axis=1)
    d_ten = np.abs(other["line_tension_rocket_end_N"].values - direct["line_tension_rocket_end_N"].values)
    assert d_elev.max() < 0.1, d_elev.max()
    assert d_pos.max() < 0.2, d_pos.max()
    assert d_ten.max() < 50.0, d_ten.max()
    np.testing.assert_array_equal(other["phase"].values, direct["phase"].values)


def test_milestones_match_direct(paper_pair):
    # the peak tension's largest value sat at 0.434 s here, 0.247 s direct
    assert_milestones_near_direct(*paper_pair)


def test_trajectories_match_direct(paper_pair):
    assert_tracks_near_direct(*paper_pair)


def test_far_end_chain_freezes_the_line(airlaunch_exe, tmp_path, paper_pair):
    """Both end motions from the chain: |x_N - x_0| is the chain's own length
    at every sample, so d_rigid never changes and the line's tension stays
    near its initial stretch, while the direct model's pull falls by 17 %
    in 6 s (the rocket slows down)."""
    direct, _ = paper_pair
    nml = nml_variant(tmp_path, "chain", line=("  coupling = 'rigidized'", "  far_end = 'chain'"),
                      edits=[(r"^  t_end = 15.0 .*$", "  t_end = 6.0")])
    out = tmp_path / "chain.nc"
    res = run_airlaunch(airlaunch_exe, nml, "--output", out)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(out) as ds:
        d = ds["d_rigid_m"].values
        assert d.max() - d.min() < 1e-6
        t_end_direct = direct["line_tension_rocket_end_N"].sel(time=6.0, method="nearest").item()
        t_end_chain = ds["line_tension_rocket_end_N"].values[-1]
        t0 = ds["line_tension_rocket_end_N"].values[0]
        assert t_end_direct < 0.85 * t0
        assert abs(t_end_chain - t0) < 0.05 * t0


@pytest.fixture(scope="module")
def paper_method(airlaunch_exe, tmp_path_factory):
    """The paper's method end to end: the rigidization with the line sub-stepped by
    the paper's explicit marching (`inner_scheme = 'marching'`), at output_dt 0.02 s
    (the file's) and 0.1 s."""
    d = tmp_path_factory.mktemp("paper_method")
    out = {}
    for dt in ("0.02", "0.1"):
        nc = d / f"m{dt}.nc"
        nml = nml_variant(d, f"m{dt}", line=("  coupling = 'rigidized'", "  inner_scheme = 'marching'"),
                          edits=[(r"^  output_dt = \S+", f"  output_dt = {dt}")])
        res = run_airlaunch(airlaunch_exe, nml, "--output", nc)
        assert res.returncode == 0, res.stderr
        out[dt] = (re.search(r"^integration: .*$", res.stdout, flags=re.M).group(0), xr.open_dataset(nc))
    yield out
    for _, ds in out.values():
        ds.close()


def marching_limit(ea=1.0e6, rho=0.4, length=60.0, n=15, c_d=1.0e3):
    """The marching scheme's stability limit for the paper file's line, by hand:
    highest axial mode w = 2c/l0, zeta = w c_d/(2 EA), h = 2/w (sqrt(1 + zeta^2) - zeta)."""
    w = 2.0 * np.sqrt(ea / rho) / (length / n)
    zeta = w * c_d / (2.0 * ea)
    return 2.0 / w * (np.sqrt(1.0 + zeta**2) - zeta)


def test_paper_method_matches_direct(paper_method, paper_pair):
    """The paper's method (rigidization + marching line) against the direct coupling,
    with the tolerances of the rigidized coupling's test above (the marching line's
    first-order time error at 0.9 of its stability limit, 1.7 ms sub-steps, is small
    against the rigidization's).  Measured (thirty-fourth session, with the potential
    force at the ramp edge): phase times within 0.05 ms, first pitch maximum 0.73 ms,
    pitch at separation 0.0005 deg, clearance 0.04 mm, nose elevation 0.047 deg (at
    15 s, the rocket tumbling; the rigidized coupling with CVODE's line 0.073 deg, the
    marching line at half its sub-step 0.042 deg), rocket CG 5 cm, rocket-end tension
    23 N, the two parachutes 6 mm apart; the peak tension first reached at t = 0 in
    both."""
    direct, _ = paper_pair
    _, ds = paper_method["0.02"]
    assert ds.attrs["status"] == "completed"
    assert ds.attrs["line_inner_scheme"] == "marching"
    assert ds.attrs["line_inner_dt_s"] == pytest.approx(0.9 * marching_limit(), rel=1e-12)
    assert_milestones_near_direct(direct, ds)   # the peak tension's largest value sat at 0.431 s here
    assert_tracks_near_direct(direct, ds)
    # the parachute on both sides of the coupling: B3 and the marched node N agree
    assert ds["line_end_mismatch_m"].values.max() < 0.05


def test_paper_method_steps_do_not_depend_on_outputs(paper_method):
    """The marching sub-steps cut each outer step into equal pieces; an output time
    inside one reads the sub-step's linear interpolant and changes no sub-step: the
    same counts, event times and safety maxima (over every sub-step) at output_dt
    0.1 and 0.02 s.  At least t_end / (0.9 limit) sub-steps were taken."""
    (steps_a, a), (steps_b, b) = paper_method["0.02"], paper_method["0.1"]
    assert steps_a == steps_b
    n = int(re.search(r"(\d+) steps", steps_a).group(1))
    assert n >= 15.0 / (0.9 * marching_limit())
    for key in ("edge_time_s", "separation_time_s", "pitch_max_time_s", "peak_line_tension_N",
                "peak_line_tension_time_s", "max_aircraft_pitch_excursion_deg", "max_load_factor_excursion"):
        assert a.attrs[key] == pytest.approx(b.attrs[key], rel=1e-12, abs=1e-12), key
    for ds in (a, b):   # a maximum over every step is never below a record
        assert ds.attrs["peak_line_tension_N"] >= ds["line_tension_rocket_end_N"].values.max()


@pytest.mark.parametrize("line,fragment", [
    (("  inner_scheme = 'marching'",),
     "&line: inner_scheme = 'marching' is not allowed with coupling = 'direct'"),
    (("  coupling = 'auto'", "  inner_scheme = 'marching'"),
     "&line: inner_scheme = 'marching' is not allowed with coupling = 'auto'"),
    (("  coupling = 'rigidized'", "  inner_scheme = 'euler'"),
     "&line: inner_scheme = 'euler' is not allowed (one of: cvode, marching)"),
    (("  coupling = 'rigidized'", "  inner_dt = 0.001"),
     "&line: inner_dt = 0.001 s is not allowed with inner_scheme = 'cvode'"),
    (("  coupling = 'rigidized'", "  inner_scheme = 'marching'", "  inner_dt = 0.01"),
     "&line: inner_dt = 0.01 s is not allowed: above the marching line's stability limit 0.0017202"),
])
def test_bad_marching_input_gives_one_clear_line(airlaunch_exe, tmp_path, line, fragment):
    out = tmp_path / "x.nc"
    res = run_airlaunch(airlaunch_exe, nml_variant(tmp_path, "bad", line=line), "--output", out)
    assert_input_error(res, fragment, out)


def test_tiny_marching_step_stops_on_the_step_budget(airlaunch_exe, tmp_path):
    """inner_dt = 1e-30 s: 2e28 sub-steps per outer step.  The count once
    overflowed an integer, the march took garbage steps and the run failed 0.16 s
    later on an ill-conditioned Kane matrix; now the step budget (&run max_steps,
    500 000) stops it at once with the time, and the record so far is kept."""
    out = tmp_path / "tiny.nc"
    nml = nml_variant(tmp_path, "tiny", line=("  coupling = 'rigidized'", "  inner_scheme = 'marching'",
                                              "  inner_dt = 1e-30"))
    res = run_airlaunch(airlaunch_exe, nml, "--output", out)
    assert res.returncode == 3, res.stderr
    first = res.stderr.splitlines()[0]
    assert first.startswith("airlaunch: error:") and "step budget of 500000 sub-steps" in first and "t = " in first
    with xr.open_dataset(out) as ds:
        assert ds.attrs["status"] == "failed"


@pytest.mark.parametrize("line,fragment", [
    (("  coupling = 'paper'",), "&line: coupling = 'paper' is not allowed (one of: direct, rigidized, per_phase, auto)"),
    (("  coupling = 'rigidized'", "  outer_dt = 0.0"), "&line: outer_dt = 0.0 is not allowed"),
    (("  coupling = 'rigidized'", "  inner_rtol = 0.5"), "&line: inner_rtol = 0.5 is not allowed"),
    (("  coupling = 'rigidized'", "  far_end = 'aircraft'"), "&line: far_end = 'aircraft' is not allowed"),
])
def test_bad_rigidized_input_gives_one_clear_line(airlaunch_exe, tmp_path, line, fragment):
    out = tmp_path / "x.nc"
    res = run_airlaunch(airlaunch_exe, nml_variant(tmp_path, "bad", line=line), "--output", out)
    assert_input_error(res, fragment, out)


def test_far_end_chain_needs_two_segments(airlaunch_exe, tmp_path):
    nml = nml_variant(tmp_path, "one", line=("  coupling = 'rigidized'", "  far_end = 'chain'"),
                      edits=[(r"^  n_seg = \d+ .*$", "  n_seg = 1")])
    res = run_airlaunch(airlaunch_exe, nml, "--output", tmp_path / "x.nc")
    assert res.returncode == 2
    assert "n_seg = 1 is not allowed with far_end = 'chain'" in res.stderr


def test_output_cadence_changes_no_step(airlaunch_exe, tmp_path):
    """The rigidized coupling's steps do not depend on output_dt: its outer steps
    end on the grid k outer_dt (they ended on an output time a rounding away from
    it) and both solvers size their first step after a restart by the outer step,
    not by the next output (2985 / 2784 / 2709 / 2455 steps at output_dt 0.1 /
    0.02 / 0.005 / 0.003 s before): the same steps and event times with outputs
    every 0.1 s (fewer than the outer steps) and every 0.004 s (several per outer
    step)."""
    runs = {}
    for dt in ("0.1", "0.004"):
        out = tmp_path / f"r{dt}.nc"
        nml = nml_variant(tmp_path, f"r{dt}", edits=[(r"^  output_dt = \S+", f"  output_dt = {dt}")],
                          line=("  coupling = 'rigidized'",))
        res = run_airlaunch(airlaunch_exe, nml, "--output", out)
        assert res.returncode == 0, res.stderr
        runs[dt] = (re.search(r"^integration: .*$", res.stdout, flags=re.M).group(0), xr.open_dataset(out))
    (steps_a, a), (steps_b, b) = runs["0.1"], runs["0.004"]
    assert steps_a == steps_b
    for key in ("release_time_s", "edge_time_s", "edge_pull_time_s", "separation_time_s", "pitch_max_time_s"):
        assert a.attrs[key] == b.attrs[key], key
    a.close()
    b.close()


def test_records_inside_an_outer_step(airlaunch_exe, tmp_path):
    """outer_dt 0.1 s with outputs every 0.02 s: the records inside an outer step
    are the chain's and the line's states at their own times.  A solver step
    that landed on the outer step's end returned that end's state for an earlier
    output time: the line's far end read 15.6 m from the parachute (helper-34).
    The two parachutes (B3 in the chain, node N in the line) part within an outer
    step and meet at its end: 5 mm at the default 0.02 s, 26 mm at 0.1 s (measured;
    bound 0.05 m)."""
    out = tmp_path / "outer.nc"
    nml = nml_variant(tmp_path, "outer", line=("  coupling = 'rigidized'", "  outer_dt = 0.1"))
    res = run_airlaunch(airlaunch_exe, nml, "--output", out)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(out) as ds:
        assert ds.sizes["time"] == 751
        assert ds["line_end_mismatch_m"].values.max() < 0.05


def _isa_density(h):
    """ISA troposphere density at geometric altitude h [m] (US Std Atm 1976:
    geopotential H = R h/(R + h), T = 288.15 - 0.0065 H, p = p0 (T/T0)^(g0/(L R_air)))."""
    hg = 6356766.0 * h / (6356766.0 + h)
    temp = 288.15 - 0.0065 * hg
    return 101325.0 * (temp / 288.15) ** (9.80665 / (0.0065 * 287.05287)) / (287.05287 * temp)


def _rotation(axis, a):
    c, s = np.cos(a), np.sin(a)
    return {"x": np.array([[1, 0, 0], [0, c, -s], [0, s, c]]),
            "y": np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]),
            "z": np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])}[axis]


def test_line_and_parachute_momentum_balance(paper_pair):
    """Audit (thirty-second session): the chain's line body B2 and parachute B3
    against Newton's second law rebuilt from the records alone.  B2 is the rod
    from the rocket's tie-down point to B3 (|B3 - tie-down| = the d_rigid of the
    outer step), so with n = (B3 - tie-down)/|B3 - tie-down|, smooth across the
    refreshes, a_B2 = a_tie + (d/2) n'', a_B3 = a_tie + d n'' (central differences
    of the records), and
        m_rigid a_B2 + m3 a_B3 = -F_joint + weights + line drag + canopy drag
    with every load written here from docs/model.md and the input: the line's
    true weight and the canopy's (not the apparent mass's), the canopy drag
    -1/2 rho CdS |v|v at B3's velocity plus V_eps, the line's strips
    1/2 rho (C_dn d |u_n| u_n + C_dt pi d |u_t| u_t) with the V_eps share growing
    from the rocket end, m3 = canopy + apparent mass rho pi/6 (0.7 D0)^3, ISA
    density; V_eps estimated as d(d_rigid)/dt along the chord.
    Measured: |imbalance| <= 7.6e-5 |F_joint| (median 6e-6; thirty-fourth
    session: 1.4e-4, 10 N of 71 kN in phase 2, before), limited by the differences at 0.02 s and the V_eps estimate.  Without
    V_eps it is 2e-3 to 3.4e-3, with V_eps of the wrong sign 3e-3 to 6.8e-3: the
    tolerance 5e-4 separates them.  Records within 0.07 s of an event (a refresh
    off the grid, a restart) are left out."""
    import f90nml

    _, rig = paper_pair
    nml = f90nml.reads(rig.attrs["input_namelist"])
    line, chute, rocket = nml["line"], nml["parachute"], nml["rocket"]
    assert chute["deploy_time"] < 0          # open from the start: no filling terms
    t = rig["time"].values
    h = t[1] - t[0]
    eu = np.radians(rig["rocket_euler_deg"].values)
    rot = np.array([_rotation("y", e[0]) @ _rotation("z", e[1]) @ _rotation("x", e[2]) for e in eu])
    tie_body = [rocket["cg_from_nose"] - rocket["tie_down_from_nose"], 0.0, 0.0]
    tie = rig["rocket_position"].values + np.einsum("tij,j->ti", rot, tie_body)
    b3 = rig["parachute_position"].values
    nodes = rig["line_nodes"].values
    # node 0 rides on the rocket's tie-down point (the Hermite path meets it at the step ends)
    np.testing.assert_allclose(nodes[:, 0], tie, rtol=0, atol=1e-9)
    rod = np.linalg.norm(b3 - tie, axis=1)
    n = (b3 - tie) / rod[:, None]
    g = 9.80665
    mline = line["mass_per_length"] * line["length"]
    dia = line["diameter"]
    s_area = chute["drag_area"]
    d0 = np.sqrt(4.0 * s_area / (np.pi * chute["cd0"]))
    m_rigid = rig["m_rigid_kg"].values
    d_rigid = rig["d_rigid_m"].values
    force = rig["rigid_line_force_N"].values
    events = [rig.attrs[k] for k in ("release_time_s", "edge_time_s", "separation_time_s",
                                     "edge_pull_time_s", "pitch_max_time_s")]
    worst = 0.0
    checked = 0
    for i in range(2, len(t) - 2):
        if min(abs(t[i] - e) for e in events) < 3.5 * h:
            continue
        v_tie = (tie[i + 1] - tie[i - 1]) / (2 * h)
        a_tie = (tie[i + 1] - 2 * tie[i] + tie[i - 1]) / h**2
        n_dot = (n[i + 1] - n[i - 1]) / (2 * h)
        n_ddot = (n[i + 1] - 2 * n[i] + n[i - 1]) / h**2
        d = rod[i]
        v_eps = (d_rigid[i + 1] - d_rigid[i - 1]) / (2 * h) * n[i]
        rho3 = _isa_density(b3[i, 1])
        m3 = chute["mass"] + chute["added_mass_factor"] * rho3 * np.pi / 6 * (0.7 * d0) ** 3
        va = v_tie + d * n_dot + v_eps
        canopy = -0.5 * rho3 * s_area * np.linalg.norm(va) * va
        drag = np.zeros(3)
        strips = 16
        ds = d / strips
        for j in range(strips):
            s = (j + 0.5) * ds
            u = -(v_tie + s * n_dot + (s / d) * v_eps)
            ut = (u @ n[i]) * n[i]
            un = u - ut
            rho = _isa_density(tie[i, 1] + s * n[i, 1])
            drag += 0.5 * rho * ds * (line["cd_normal"] * dia * np.linalg.norm(un) * un
                                      + line["cd_tangential"] * np.pi * dia * np.linalg.norm(ut) * ut)
        weight = np.array([0.0, -(mline + chute["mass"]) * g, 0.0])
        lhs = m_rigid[i] * (a_tie + 0.5 * d * n_ddot) + m3 * (a_tie + d * n_ddot)
        rhs = -force[i] + weight + drag + canopy
        worst = max(worst, np.linalg.norm(lhs - rhs) / np.linalg.norm(force[i]))
        checked += 1
    assert checked > 600
    assert worst < 5e-4, worst
