"""The paper's scenario end to end (Zheng & Zhang 2018, §5.2): the output
contract, the phase milestones against the paper's bands, the post-separation
attitude against the values docs/validation.md states, invariants, and the
clear errors for impossible scenarios."""
import re

import numpy as np
import pytest
import xarray as xr

from conftest import PAPER, assert_input_error, nml_variant, run_airlaunch

N_SEG = int(re.search(r"^\s*n_seg\s*=\s*(\d+)", PAPER.read_text(), flags=re.M).group(1))
RTOL = float(re.search(r"^\s*rtol\s*=\s*(\S+)", PAPER.read_text(), flags=re.M).group(1))
# the paper's own discretization (60 elements, its Fig. 8) at tight tolerances
FINE = [(r"^  rtol = \S+.*$", "  rtol = 1.0e-6"), (r"^  atol = \S+.*$", "  atol = 1.0e-7"),
        (r"^  n_seg = \d+.*$", "  n_seg = 60")]
# the paper's aircraft with the C_L0, C_m0 of its calibration, trimmed by alpha and elevator
FLY = [(r"^  trim_mode = 'calibrate' .*$", "  trim_mode = 'fly'"),
       (r"^  chord = 6.0 .*$", "  chord = 6.0\n  cl0 = 3.6566715382501136E-001\n  cm0 = -2.1003001983776220E-002")]
MILESTONES = ["edge_time_s", "separation_time_s", "edge_pull_time_s", "pitch_at_separation_deg",
              "pitch_rate_at_separation_deg_s", "pitch_max_time_s", "pitch_max_deg", "min_clearance_m",
              "peak_line_tension_N", "max_aircraft_pitch_excursion_deg", "max_load_factor_excursion"]

CONTRACT_VARS = ["phase", "aircraft_position", "aircraft_euler_deg", "aircraft_alpha_deg",
                 "rocket_position", "rocket_velocity", "rocket_euler_deg", "rocket_pitch_rate_deg_s",
                 "parachute_position", "line_tension_rocket_end_N", "line_tension_parachute_end_N",
                 "line_nodes", "constraint_force", "clearance_m"]
CONTRACT_ATTRS = ["release_time_s", "edge_time_s", "separation_time_s", "pitch_max_time_s",
                  "pitch_max_deg", "input_namelist", "code_version"]


@pytest.fixture(scope="module")
def paper_run(airlaunch_exe, tmp_path_factory):
    out = tmp_path_factory.mktemp("paper") / "paper.nc"
    res = run_airlaunch(airlaunch_exe, PAPER, "--output", out)
    assert res.returncode == 0, res.stderr
    ds = xr.open_dataset(out)
    yield ds, res.stdout
    ds.close()


@pytest.fixture(scope="module")
def paper_fine(airlaunch_exe, tmp_path_factory):
    d = tmp_path_factory.mktemp("paper_fine")
    out = d / "fine.nc"
    res = run_airlaunch(airlaunch_exe, nml_variant(d, edits=FINE), "--output", out)
    assert res.returncode == 0, res.stderr
    ds = xr.open_dataset(out)
    yield ds
    ds.close()


def test_output_contract(paper_run):
    ds, _ = paper_run
    for name in CONTRACT_VARS:
        assert name in ds, name
        assert ds[name].attrs.get("units"), f"{name} has no units"
        assert ds[name].dims[0] == "time"
    for name in CONTRACT_ATTRS:
        assert name in ds.attrs, name
    assert ds["line_nodes"].dims == ("time", "node", "xyz")
    assert ds.sizes["node"] == N_SEG + 1
    assert ds.attrs["status"] == "completed"


def test_trim_and_phase_milestones(paper_run):
    """Bands of issue 5: trim 1.2174 +- 0.001 deg; Case 1->2 at 3.0 +- 0.3 s;
    separation at 4.0 +- 0.3 s (the paper's Fig. 9)."""
    ds, stdout = paper_run
    assert ds.attrs["trim_alpha_deg"] == pytest.approx(1.2174, abs=1e-3)
    assert ds["aircraft_alpha_deg"].values[0] == pytest.approx(1.2174, abs=1e-3)
    assert ds.attrs["edge_time_s"] == pytest.approx(3.0, abs=0.3)
    assert ds.attrs["separation_time_s"] == pytest.approx(4.0, abs=0.3)
    assert ds.attrs["release_time_s"] < ds.attrs["edge_time_s"] < ds.attrs["separation_time_s"]
    # the phase variable agrees with the event times and never goes back
    t, ph = ds["time"].values, ds["phase"].values
    assert np.all(np.diff(ph) >= 0)
    assert np.all(ph[t < ds.attrs["release_time_s"] - 1e-9] == 0)
    assert np.all(ph[t > ds.attrs["separation_time_s"] + 1e-9] == 3)
    assert "separation (Case 2->3)" in stdout


def test_attitude_after_separation(paper_run):
    """docs/validation.md: with the documented X fins the rocket's Euler pitch
    reaches its first maximum, 90 deg (the nose passes the vertical), at
    10.48 s; the paper reports ~90 deg at ~10.5 s (band 90 +- 5 at 10.5 +- 0.7)."""
    ds, _ = paper_run
    assert ds.attrs["pitch_max_deg"] == pytest.approx(90.0, abs=5.0)
    assert ds.attrs["pitch_max_time_s"] == pytest.approx(10.5, abs=0.7)
    # the continuous nose elevation crosses 90 deg within one output step of the event
    t = ds["time"].values
    elev = ds["rocket_nose_elevation_deg"].values
    k = np.argmax(elev >= 90.0)
    assert abs(t[k] - ds.attrs["pitch_max_time_s"]) <= 2 * float(t[1] - t[0])
    # Euler pitch never exceeds 90 deg (it folds back); the nose elevation does not fold
    assert np.nanmax(ds["rocket_euler_deg"].sel(angle=1).values) <= 90.0 + 1e-9


@pytest.mark.parametrize("which", ["default", "fine"])
def test_invariants(paper_run, paper_fine, which):
    ds = paper_run[0] if which == "default" else paper_fine
    # a tension-only line
    assert np.all(ds["line_tension_rocket_end_N"].values >= 0.0)
    assert np.all(ds["line_tension_parachute_end_N"].values >= 0.0)
    # in steady trimmed flight the line carries the parachute's drag,
    # 1/2 rho V^2 CdS = 1/2 0.41351 (0.65 * 299.532)^2 * 10 = 78.4 kN (ISA 10 km)
    q = 0.5 * 0.41351 * (0.65 * 299.532) ** 2
    assert ds["line_tension_parachute_end_N"].values[0] == pytest.approx(10.0 * q, rel=2e-3)
    # the constraint drift control keeps the joint residual small (Baumgarte):
    # 0.1 mm at the paper's discretization (rtol 1e-6, positions held to
    # 1e-5 m); at the defaults (positions held to 1e-4 m) it follows the
    # integration error: below the 10 rtol x (size of the positions) of the
    # stress suite, the positions being ~10 m (the rocket's travel)
    limit = 1e-4 if which == "fine" else 10 * RTOL * 10.0
    assert ds.attrs["max_constraint_residual_m"] < limit
    # the rocket rests on the floor in Case 0: normal force = weight component
    n0 = ds["edge_normal_force_N"].values[0]
    assert n0 == pytest.approx(28000 * 9.80665 * np.cos(np.radians(1.2174)), rel=2e-2)
    assert not np.any(np.isnan(ds["rocket_position"].values))
    # the scenario is symmetric about the aircraft's plane of symmetry: nothing
    # leaves it (the launch Jacobian grouped by the stored band read couplings
    # beyond it into wrong entries, and the run drifted 1.4 mm and 3.8 mm sideways)
    for name in ("rocket_position", "aircraft_position", "parachute_position"):
        assert np.abs(ds[name].values[:, 2]).max() < 1e-9, name


def test_defaults_within_0p1_percent_of_the_paper_discretization(paper_run, paper_fine):
    """Issue 7: the default settings (n_seg and tolerances of the input) give
    every milestone within 0.1 % of a finer solution.  The paper's 60 elements
    at rtol 1e-6 are 2e-5 from the converged answer (docs/performance.md), so
    the 0.1 % is checked against it with that margin to spare.  Milestones that
    are angles or excursions are compared relative to their size."""
    ds, _ = paper_run
    for key in MILESTONES:
        assert ds.attrs[key] == pytest.approx(paper_fine.attrs[key], rel=1e-3), key
    mean, mean_fine = (float(d["line_tension_rocket_end_N"].mean()) for d in (ds, paper_fine))
    assert mean == pytest.approx(mean_fine, rel=1e-3)


@pytest.mark.parametrize("edits,fragment", [
    ([(r"^  length = 24.5$", "  length = 12.0")], "the rocket does not fit the bay"),
    ([(r"^  length = 60.0 .*$", "  length = 10.0")], "&line: length = 10.0 is not allowed (shorter than"),
    ([(r"^  drag_area = 10.0 .*$", "  drag_area = 0.0")], "&parachute: drag_area = 0.0 is not allowed"),
    ([(r"^  l0 = 10.0 .*$", "  l0 = 5.0")], "&bay: l0 = 5.0 is not allowed"),
    ([(r"^  fin_semi_span = 1.34 .*$", "  fin_semi_span = 2.0")], "&rocket: fin_semi_span = 2.0 is not allowed"),
    # fins without a span (its default, 0): the message says the span is required, not only "> 0"
    ([(r"^  fin_semi_span = 1.34 .*$", "")],
     "&rocket: fin_semi_span = 0.0 is not allowed (must be > 0 m; required with fin_count = 4)"),
    ([(r"^  deploy_time = -1.0 .*$", "  deploy_time = 20.0")], "the parachute would never inflate"),
    # an aircraft that cannot fly the trim: the paper's aircraft (C_L0, C_m0 of
    # its calibration, as input/sweep_paper.nml freezes them) flown too slowly
    # trims at 60.8 deg with -56.5 deg elevator (was accepted, the hold then
    # clamped the elevator to 25 deg and the run started out of trim) ...
    (FLY + [(r"^  mach = 0.65 .*$", "  mach = 0.15")],
     "&flight: trim_mode = 'fly' cannot trim the Case 0 flight at mach = 0.15"),
    (FLY + [(r"^  mach = 0.65 .*$", "  mach = 0.15")], "beyond the elevator limit and the alpha range (allowed"),
    # ... at Mach 0.25 only the angle of attack is beyond its range (28 deg, -18 deg elevator) ...
    (FLY + [(r"^  mach = 0.65 .*$", "  mach = 0.25")], "deg, beyond the alpha range (allowed"),
    # ... at Mach 0.35 only the elevator (-7.3 deg at 13.3 deg) beyond a 5 deg limit
    (FLY + [(r"^  mach = 0.65 .*$", "  mach = 0.35"), (r"^  delta_e_max_deg = 25.0$", "  delta_e_max_deg = 5.0")],
     "deg, beyond the elevator limit (allowed: |elevator| <= 5.0 deg"),
])
def test_impossible_scenarios_give_one_clear_line(airlaunch_exe, tmp_path, edits, fragment):
    """... and `--check` finds each of them too, the untrimmable flights included
    (it runs the set-up a run starts with: the Case 0 trim)."""
    nml = nml_variant(tmp_path, edits=edits)
    out = tmp_path / "x.nc"
    res = run_airlaunch(airlaunch_exe, nml, "--output", out)
    line = assert_input_error(res, fragment, out)
    res = run_airlaunch(airlaunch_exe, nml, "--output", out, "--check")
    assert assert_input_error(res, fragment, out) == line


def test_one_sided_edge_separates_early(airlaunch_exe, tmp_path, paper_run):
    """With a one-sided ramp edge the rocket leaves the edge when the normal
    force would have to pull: at the time the bilateral run reports (the two
    runs are the same motion up to that instant; 1 ms covers the tolerances)."""
    paper, _ = paper_run
    nml = nml_variant(tmp_path, edits=[(r"^  edge_contact = 'bilateral'.*$", "  edge_contact = 'one_sided'"),
                              (r"^  t_end = 15.0 .*$", "  t_end = 4.5")])
    out = tmp_path / "one.nc"
    res = run_airlaunch(airlaunch_exe, nml, "--output", out)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(out) as ds:
        assert ds.attrs["early_separation"] == "true"
        t_sep = ds.attrs["separation_time_s"]
        assert ds.attrs["edge_time_s"] < t_sep < 4.0
        assert t_sep == pytest.approx(paper.attrs["edge_pull_time_s"], abs=1e-3)
        # after the early separation the contact force is zero
        assert np.all(ds["edge_normal_force_N"].values[ds["time"].values > t_sep + 1e-9] == 0.0)


def test_numerical_failure_keeps_readable_output(airlaunch_exe, tmp_path):
    """A run that fails (here: its step budget, &run max_steps = 500, is spent
    in free flight, where the paper scenario needs ~680 steps to 15 s) ends
    with status 3 and one line naming the phase, the time and the quantity
    (the state with the largest local error estimate); what was computed is
    kept, readable, with status = "failed".  (Before the ground event this
    run fell out of the atmosphere model from 300 m.)"""
    nml = nml_variant(tmp_path, edits=[(r"^(  t_end = 15.0 .*)$", r"\1\n  max_steps = 500")])
    out = tmp_path / "fail.nc"
    res = run_airlaunch(airlaunch_exe, nml, "--output", out)
    assert res.returncode == 3, res.stderr
    first = res.stderr.strip().splitlines()[0]
    assert "free flight" in first.lower() and "t = " in first and "largest local error estimate in" in first, first
    with xr.open_dataset(out) as ds:
        assert ds.attrs["status"] == "failed"
        assert "step budget" in ds.attrs["failure"]
        t_fail = float(re.search(r"t = ([0-9.]+) s", first).group(1))
        assert ds["time"].values[-1] <= t_fail + 1e-9
        assert ds["time"].values[-1] > ds.attrs["separation_time_s"] > 0.0


def test_stop_when_final_keeps_the_milestones(airlaunch_exe, tmp_path, paper_run):
    """&run stop_when_final (sweeps' summary mode) ends the run once the
    milestones are final; they equal those of the full 15 s run."""
    paper, _ = paper_run
    nml = nml_variant(tmp_path, edits=[(r"^  rtol = (\S+)", "  stop_when_final = .true.\n  rtol = \\1")])
    out = tmp_path / "swf.nc"
    res = run_airlaunch(airlaunch_exe, nml, "--output", out)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(out) as ds:
        assert ds["time"].values[-1] < 14.0
        for key in ("edge_time_s", "separation_time_s", "pitch_max_time_s", "pitch_max_deg", "min_clearance_m",
                    "peak_line_tension_N", "max_aircraft_pitch_excursion_deg", "max_load_factor_excursion"):
            assert ds.attrs[key] == pytest.approx(paper.attrs[key], rel=1e-9, abs=1e-12), key
        # the calibrated aircraft constants are recorded (sweeps freeze them)
        assert ds.attrs["trim_cl0"] == pytest.approx(paper.attrs["trim_cl0"])


def test_output_cadence_changes_no_step(airlaunch_exe, tmp_path, paper_run):
    """The integrator's steps do not depend on output_dt (docs/input.md): the
    same steps and the same event times, bit for bit, with outputs every 0.1 s as
    every 0.02 s (before, CVODE sized its first step after each restart by the
    next output time and stopped its event search there: 637 against 858 steps)."""
    paper, stdout = paper_run
    nml = nml_variant(tmp_path, edits=[(r"^  output_dt = \S+", "  output_dt = 0.1")])
    out = tmp_path / "coarse.nc"
    res = run_airlaunch(airlaunch_exe, nml, "--output", out)
    assert res.returncode == 0, res.stderr
    steps = [re.search(r"^integration: .*$", text, flags=re.M).group(0) for text in (stdout, res.stdout)]
    assert steps[0] == steps[1]
    with xr.open_dataset(out) as ds:
        assert ds.sizes["time"] == 151 and paper.sizes["time"] == 751
        for key in ("release_time_s", "edge_time_s", "edge_pull_time_s", "separation_time_s",
                    "pitch_at_separation_deg", "pitch_rate_at_separation_deg_s", "pitch_max_time_s",
                    "min_clearance_m"):
            assert ds.attrs[key] == paper.attrs[key], key
        # and the same states at the common output times (every 0.1 s; k*0.1 and 5k*0.02
        # differ in the last bit, so the interpolant is read 1 ulp apart: 1e-13)
        np.testing.assert_allclose(ds["time"].values, paper["time"].values[::5], rtol=1e-15)
        np.testing.assert_allclose(ds["rocket_position"].values, paper["rocket_position"].values[::5],
                                   rtol=1e-13, atol=1e-12)


def test_minimum_clearance_is_exact(airlaunch_exe, tmp_path):
    """min_clearance_m is the clearance at the separation or at a local minimum
    located as an event (the rising zero of its rate), not the smallest record:
    the same at output_dt 0.1 s and 0.5 ms (the records alone gave 8.866 and
    8.791 m), below every record of Case 3, and within (largest clearance rate)
    x (record spacing) of the smallest record at 0.5 ms."""
    values, fine = {}, None
    for dt in ("0.1", "0.0005"):
        out = tmp_path / f"c{dt}.nc"
        nml = nml_variant(tmp_path, f"c{dt}", edits=[(r"^  output_dt = \S+", f"  output_dt = {dt}"),
                                                      (r"^  t_end = \S+", "  t_end = 5.0")])
        res = run_airlaunch(airlaunch_exe, nml, "--output", out)
        assert res.returncode == 0, res.stderr
        with xr.open_dataset(out) as ds:
            values[dt] = float(ds.attrs["min_clearance_m"])
            if dt == "0.0005":
                free = ds["phase"].values == 3
                fine = (ds["clearance_m"].values[free], ds["time"].values[free])
    assert values["0.1"] == pytest.approx(values["0.0005"], rel=1e-12)
    c, t = fine
    rate = np.max(np.abs(np.diff(c) / np.diff(t)))
    assert values["0.0005"] <= c.min() <= values["0.0005"] + rate * 0.0005


@pytest.mark.parametrize("n_seg", [60, 240])
def test_newton_converges_in_the_trimmed_case_0(airlaunch_exe, tmp_path, n_seg):
    """Case 0 is the trimmed system at rest: Newton's iteration has no reason to
    fail.  CVODE's difference-quotient Jacobian lost the line's dashpot there (its
    increment for a state at 0 fell below the rounding of V0 + v), and at
    rtol 1e-9 Newton failed on most steps: 6 130 failures in 9 690 steps at
    N = 60, 107 183 in 153 303 (130 s) at N = 240 to t = 0.8 s; with the
    system's own increments 0 and 3."""
    edits = [(r"^  t_end = \S+", "  t_end = 0.8"), (r"^  rtol = \S+", "  rtol = 1.0e-9"),
             (r"^  atol = \S+", "  atol = 1.0e-10"), (r"^  n_seg = \d+", f"  n_seg = {n_seg}"),
             (r"^  output = .*$", "  trajectory = .false.")]
    res = run_airlaunch(airlaunch_exe, nml_variant(tmp_path, edits=edits))
    assert res.returncode == 0, res.stderr
    m = re.search(r"integration: (\d+) steps, .* (\d+) convergence failures", res.stdout)
    steps, failures = int(m.group(1)), int(m.group(2))
    assert failures <= 10 and steps < 5000, m.group(0)


@pytest.mark.parametrize("n_seg", [120, 240])
def test_weak_pull_line_settles_at_fine_resolution(airlaunch_exe, tmp_path, n_seg):
    """A packed canopy pulls only ~0.4 kN: the trailing line then streams
    under its own cross-flow drag, far from the straight start, where Newton's
    method used to meet slack segments (a singular matrix at N >= 120).  The
    set-up restarts from the line's force balance (model.md).  Check: the run
    starts, and at t = 0 the line at the canopy carries the packed canopy's
    drag and weight, |(q CdS_packed, m_canopy g)| (1 %: the last half segment's
    weight and air load, ~1 N, are lumped with the canopy node)."""
    nml = nml_variant(tmp_path, edits=[(r"^  deploy_time = -1.0 .*$", "  deploy_time = 1.0"),
                              (r"^  n_seg = \d+.*$", f"  n_seg = {n_seg}"),
                              (r"^  t_end = \S+.*$", "  t_end = 1.1")])
    out = tmp_path / "weak.nc"
    res = run_airlaunch(airlaunch_exe, nml, "--output", out)
    assert res.returncode == 0, res.stderr
    q = 0.5 * 0.41351 * (0.65 * 299.532) ** 2
    with xr.open_dataset(out) as ds:
        assert ds["time"].values[-1] == pytest.approx(1.1)
        tension0 = float(ds["line_tension_parachute_end_N"].values[0])
    assert tension0 == pytest.approx(np.hypot(q * 0.05, 1.798 * 9.80665), rel=1e-2)


def test_rail_forces_obey_coulomb_and_the_lock(paper_run):
    """Coulomb's law on the rail and the edge: |friction| <= mu |N| at every record
    (mu = the paper's 0.005; 1e-9 of N for rounding), friction 0 while the lock
    holds the rocket (Case 0), where the along-rail reaction is the lock's force
    (more than friction could hold: the rocket sits on a nose-up deck pulled by
    the line) and the lock carries nothing after the release."""
    ds, _ = paper_run
    mu = float(re.search(r"^\s*friction\s*=\s*(\S+)", PAPER.read_text(), flags=re.M).group(1))
    phase = ds["phase"].values
    normal = ds["edge_normal_force_N"].values
    friction = ds["friction_force_N"].values
    lock = ds["lock_force_N"].values
    attached = (phase >= 1) & (phase <= 2)
    assert attached.any() and (phase == 0).any()
    assert np.all(np.abs(friction[attached]) <= mu * np.abs(normal[attached]) * (1 + 1e-9))
    assert np.all(friction[phase == 0] == 0.0)
    # more than the rail's friction could hold (84.6 kN against mu N = 1.4 kN): the lock is needed
    assert np.all(np.abs(lock[phase == 0]) > mu * np.abs(normal[phase == 0]))
    assert np.all(lock[phase >= 1] == 0.0)


def test_milestones_of_events_not_reached(airlaunch_exe, tmp_path):
    """A run that ends before the separation (t_end = 2 s): the event times are
    -1 and the angles measured at those events NaN (output.md), not 0 - a 0 deg
    pitch would pass for a value."""
    nml = nml_variant(tmp_path, edits=[(r"^  t_end = 15.0 .*$", "  t_end = 2.0")])
    out = tmp_path / "short.nc"
    res = run_airlaunch(airlaunch_exe, nml, "--output", out)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(out) as ds:
        assert ds.attrs["separation_time_s"] == -1.0 and ds.attrs["pitch_max_time_s"] == -1.0
        for key in ("pitch_at_separation_deg", "pitch_rate_at_separation_deg_s", "pitch_max_deg",
                    "nose_elevation_at_pitch_max_deg"):
            assert np.isnan(ds.attrs[key]), key


def test_the_sweep_freezes_the_calibrated_aircraft(paper_run):
    """input/sweep_paper.nml freezes C_L0 and C_m0 at the values the paper input's
    calibrate trim finds (its comment: the nominal case trims back to 1.2174 deg
    with zero elevator); a change of the trim's physics must update them (the
    eleventh session's trim with the line's weight moved them by 1e-4)."""
    ds, _ = paper_run
    text = (PAPER.parent / "sweep_paper.nml").read_text()
    frozen = {k: float(re.search(rf"name = 'aircraft%{k}', value = '(\S+)'", text).group(1)) for k in ("cl0", "cm0")}
    assert frozen["cl0"] == pytest.approx(ds.attrs["trim_cl0"], rel=1e-12)
    assert frozen["cm0"] == pytest.approx(ds.attrs["trim_cm0"], rel=1e-12)
