"""Safety envelopes on synthetic summaries whose answer is known: margins equal
their defining formulas; the estimated boundary of the safe region follows a
known curve; the 95 % intervals cover the true probability (once, and about
95 % of the time on average over p) and agree with SciPy's own binomial
intervals; cases that did not compute never pass; bad criteria files are one
line and status 2."""
import math

import numpy as np
import pytest
import scipy.stats as st
import xarray as xr
from scipy.stats import qmc

from conftest import unit_string_parses, units_problems
from test_sweep_support import run_python

from postproc.sweep.criteria import parse_criteria
from postproc.sweep.definition import DefinitionError
from postproc.sweep.envelope import (clopper_pearson_interval, evaluate, pass_probability_map, wilson_interval,
                                     worst_case_table, worst_cases)

METRICS = ("min_clearance_m", "peak_line_tension_N", "max_aircraft_pitch_excursion_deg",
           "max_load_factor_excursion", "pitch_max_deg", "pitch_max_time_s")


def synthetic_summary(a, b, clearance, status=None, pitch=None):
    """A summary-shaped dataset: inputs a, b and chosen metrics (others safe)."""
    n = len(a)
    status = np.zeros(n, dtype=np.int32) if status is None else status
    ds = xr.Dataset({"a": ("case", a, {"units": "s"}), "b": ("case", b, {"units": "m2"}),
                     "status": ("case", status)}, coords={"case": np.arange(n)})
    ds["min_clearance_m"] = ("case", clearance)
    ds["peak_line_tension_N"] = ("case", np.full(n, 1.0e5))
    ds["max_aircraft_pitch_excursion_deg"] = ("case", np.full(n, 1.0))
    ds["max_load_factor_excursion"] = ("case", np.full(n, 0.2))
    ds["pitch_max_deg"] = ("case", np.full(n, 89.0) if pitch is None else pitch)
    ds["pitch_max_time_s"] = ("case", np.full(n, 8.0))
    ds.attrs.update(inputs="a b", sweep_name="synthetic")
    return ds


CRITERIA = """&criteria
  min_clearance_m = 1.5
  line_strength_n = 300e3, line_safety_factor = 1.5
  max_aircraft_pitch_excursion_deg = 3.0
  max_load_factor_excursion = 0.5
  firing_pitch_min_deg = 75.0, firing_pitch_max_deg = 90.0
  firing_time_max_s = 12.0
/
"""


def boundary(a):
    """The known boundary: safe iff b > 0.3 + 0.4 a^2."""
    return 0.3 + 0.4 * a**2


def lhs_points(n, seed):
    return qmc.LatinHypercube(2, rng=seed).random(n)


def test_margins_are_their_formulas():
    a = np.linspace(0, 1, 7)
    b = np.linspace(1, 0, 7)
    clearance = 1.5 + 2.0 * (a - 0.5)
    pitch = np.array([60.0, 74.0, 75.0, 80.0, 89.9, 90.0, 88.0])
    ds = synthetic_summary(a, b, clearance, pitch=pitch)
    env = evaluate(ds, parse_criteria(CRITERIA))
    np.testing.assert_allclose(env["margin"].sel(criterion="clearance"), 2.0 * (a - 0.5), atol=1e-15)
    np.testing.assert_allclose(env["margin"].sel(criterion="line_tension"), 2.0e5 - 1.0e5)
    np.testing.assert_allclose(env["margin"].sel(criterion="aircraft_pitch"), 2.0)
    # Euler pitch cannot exceed 90 deg: the window [75, 90] has only its lower side
    np.testing.assert_allclose(env["margin"].sel(criterion="firing_attitude"), pitch - 75.0)
    np.testing.assert_allclose(env["margin"].sel(criterion="firing_time"), 4.0)
    passed = env["passed"].sel(criterion="all").values.astype(bool)
    assert list(passed) == list((a >= 0.5) & (pitch >= 75.0))


def test_the_firing_window_scale_is_the_part_the_pitch_can_reach():
    """The firing-attitude scale (relative_margin = margin / scale, which ranks
    the worst criterion) is half the window up to 90 degrees: a window
    [75, 180] has the margins of [75, 90], and took the scale 52.5 of its whole
    width instead of 7.5 (a new user's walkthrough, thirty-third session)."""
    pitch = np.array([80.0, 90.0])
    a = np.array([0.2, 0.8])
    for hi in (90.0, 180.0):
        text = f"&criteria\n  firing_pitch_min_deg = 75.0, firing_pitch_max_deg = {hi}\n/\n"
        env = evaluate(synthetic_summary(a, a, a + 2.0, pitch=pitch), parse_criteria(text))
        assert float(env["criterion_scale"].sel(criterion="firing_attitude")) == 7.5
        np.testing.assert_array_equal(env["relative_margin"].sel(criterion="firing_attitude"), (pitch - 75.0) / 7.5)


def test_every_envelope_variable_is_described():
    """envelope.nc describes each variable it makes, as the run outputs and
    verify.nc do (docs/output.md: every variable and coordinate has a long_name;
    numbers have units): criterion_units, criterion_scale, criterion_description
    and the coordinates criterion and input had neither (an audit of the output
    files, thirty-second session; ncdump -h showed them bare).  The inputs and
    status are the summary's own, copied."""
    a = np.linspace(0, 1, 7)
    env = evaluate(synthetic_summary(a, 1.0 - a, 1.5 + a), parse_criteria(CRITERIA))
    made = [name for name in env.variables if name not in ("a", "b", "status", "case")]
    assert {"criterion", "input", "criterion_units", "criterion_scale", "criterion_description"} <= set(made)
    for name in made:
        assert env[name].attrs.get("long_name"), f"{name} has no long_name"
    # numbers have units a unit library reads; the margins and scales, one unit
    # per criterion, name criterion_units instead (they carried the string
    # "criterion units (see criterion_units)", which pint-xarray's quantify()
    # refuses, until the thirty-third session)
    assert units_problems(env, skip=("a", "b", "status", "case")) == []
    # the scale is in the criterion's units, as the margin; the relative margin is margin / scale
    assert env["criterion_scale"].attrs["units_from"] == env["margin"].attrs["units_from"] == "criterion_units"


def test_every_criterion_has_units_a_unit_library_reads():
    """Each criterion a criteria file can ask for (every variable of the
    criteria namelist set) carries units in the grammar of the run outputs
    (test_output_units.py), and 'all' is dimensionless."""
    from postproc.sweep.criteria import CRITERIA_VARS
    limits = {"line_safety_factor": 1.5, "firing_pitch_min_deg": 60.0, "firing_pitch_max_deg": 90.0}
    text = "&criteria\n" + "\n".join(f"  {k} = {limits.get(k, 2.0)}" for k in CRITERIA_VARS) + "\n/\n"
    criteria = parse_criteria(text)
    a = np.linspace(0, 1, 3)
    summary = synthetic_summary(a, a, a + 2.0)
    summary["min_line_clearance_m"] = ("case", a + 3.0)
    summary["ground_speed_m_s"] = ("case", a + 1.0)
    env = evaluate(summary, criteria)
    assert len(criteria) == len(set(env["criterion"].values)) - 1 >= 8
    assert [u for u in env["criterion_units"].values if not unit_string_parses(str(u))] == []
    assert str(env["criterion_units"].sel(criterion="all").values) == "1"


def test_boundary_of_the_safe_region_is_recovered():
    """Pass iff b > 0.3 + 0.4 a^2 (a, b on a Latin hypercube): the 0.5 level of
    the estimated pass probability lies within 0.05 of the curve, and the map
    classifies the plane like the true rule almost everywhere."""
    pts = lhs_points(800, seed=4)
    a, b = pts[:, 0], pts[:, 1]
    f = b - boundary(a)
    env = evaluate(synthetic_summary(a, b, 1.5 + 10.0 * f), parse_criteria(CRITERIA))
    passed = env["passed"].sel(criterion="all").values.astype(bool)
    assert np.array_equal(passed, f >= 0)
    gx, gy, prob, h = pass_probability_map(env["a"].values, env["b"].values, passed)
    truth = gy[:, None] > boundary(gx)[None, :]
    assert np.mean((prob > 0.5) != truth) < 0.03
    # along each column inside the box, where the estimate crosses 0.5
    errors = []
    for i, x in enumerate(gx):
        if not 0.05 < x < 0.95:
            continue
        col = prob[:, i]
        j = np.argmax(col > 0.5)
        y_cross = gy[j - 1] + (0.5 - col[j - 1]) * (gy[j] - gy[j - 1]) / (col[j] - col[j - 1])
        errors.append(abs(y_cross - boundary(x)))
    assert max(errors) < 0.05, (max(errors), h)


def test_interval_covers_the_true_probability_of_a_known_region():
    """Pass iff a + b < 1.2 with a, b uniform: P = 1 - 0.8^2/2 = 0.68."""
    pts = lhs_points(400, seed=9)
    a, b = pts[:, 0], pts[:, 1]
    env = evaluate(synthetic_summary(a, b, 1.5 + (1.2 - a - b)), parse_criteria("&criteria min_clearance_m = 1.5 /"))
    row = env.sel(criterion="all")
    assert float(row["wilson_low"]) <= 0.68 <= float(row["wilson_high"])
    assert float(row["clopper_pearson_low"]) <= 0.68 <= float(row["clopper_pearson_high"])
    assert abs(float(row["probability"]) - 0.68) < 0.03


def test_intervals_cover_95_percent_on_average_over_p():
    """Exact coverage (binomial pmf, n = 60) over p in [0.05, 0.95]: the exact
    interval never covers less than 95 %; Wilson's covers 95 % on average and
    never less than 92 % (Brown, Cai & DasGupta 2001, Stat. Sci. 16: 101)."""
    n = 60
    k = np.arange(n + 1)
    wl, wh = wilson_interval(k, np.full_like(k, n))
    cl, ch = clopper_pearson_interval(k, np.full_like(k, n))
    ps = np.linspace(0.05, 0.95, 181)
    wilson = np.array([st.binom.pmf(k, n, p)[(wl <= p) & (p <= wh)].sum() for p in ps])
    exact = np.array([st.binom.pmf(k, n, p)[(cl <= p) & (p <= ch)].sum() for p in ps])
    assert exact.min() >= 0.95, exact.min()
    assert abs(wilson.mean() - 0.95) < 0.005, wilson.mean()
    assert wilson.min() > 0.92, wilson.min()


@pytest.mark.parametrize("k,n", [(0, 20), (7, 20), (20, 20), (613, 1000)])
def test_intervals_agree_with_scipy(k, n):
    wl, wh = wilson_interval(k, n)
    cl, ch = clopper_pearson_interval(k, n)
    ref_w = st.binomtest(k, n).proportion_ci(0.95, method="wilson")
    ref_c = st.binomtest(k, n).proportion_ci(0.95, method="exact")
    assert math.isclose(wl, ref_w.low, abs_tol=1e-12) and math.isclose(wh, ref_w.high, abs_tol=1e-12)
    assert math.isclose(cl, ref_c.low, abs_tol=1e-12) and math.isclose(ch, ref_c.high, abs_tol=1e-12)


def test_cases_not_computed_never_pass_and_come_first_among_the_worst():
    a = np.array([0.1, 0.2, 0.3, 0.4])
    status = np.array([0, 1, 0, 2], dtype=np.int32)
    clearance = np.array([10.0, 10.0, 1.6, 10.0])   # case 1 "looks" safe but failed numerically
    env = evaluate(synthetic_summary(a, a, clearance, status=status), parse_criteria(CRITERIA))
    assert env["passed"].sel(case=[1, 3]).values.sum() == 0
    assert np.isnan(env["margin"].sel(case=1, criterion="clearance"))
    assert list(worst_cases(env, 4)) == [1, 3, 2, 0]
    assert float(env["probability"].sel(criterion="all")) == 0.5


@pytest.mark.parametrize("text,match", [
    ("&criteria min_clearence_m = 1.0 /", "unknown criterion 'min_clearence_m' .*did you mean 'min_clearance_m'"),
    ("&criteria firing_pitch_min_deg = 80, firing_pitch_max_deg = 70 /", "reversed window"),
    # the Euler pitch never exceeds 90 (output.md): a minimum of 95 is named itself, not the default maximum
    ("&criteria firing_pitch_min_deg = 95 /", r"firing_pitch_min_deg = 95 is not allowed \(must be < 90"),
    ("&criteria line_safety_factor = 2 /", "needs line_strength_n"),
    ("&criteria /", "sets no criterion"),
    ("&limits min_clearance_m = 1.0 /", "unknown group &limits"),
])
def test_bad_criteria_are_one_line_errors(text, match):
    with pytest.raises(DefinitionError, match=match) as exc:
        parse_criteria(text, "c.nml")
    assert "\n" not in str(exc.value)


def test_unknown_criterion_on_the_command_line(tmp_path):
    sweep = tmp_path / "s.nml"
    sweep.write_text("&sweep base = 'b.nml', design = 'lhs', n_cases = 4, seed = 1 /\n"
                     "&input name = 'bay%release_time', distribution = 'uniform', lower = 0, upper = 1 /\n")
    crit = tmp_path / "c.nml"
    crit.write_text("&criteria max_mach = 0.9 /\n")
    res = run_python(["envelope", sweep, "--criteria", crit], tmp_path)
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "unknown criterion 'max_mach'" in lines[0], res.stderr


def test_probability_map_in_chunks_equals_the_one_piece_map():
    """The map is evaluated in chunks of cases (memory bound), as products of
    the kernel's per-axis factors; every chunking gives the one-piece map (the
    direct formula, computed here with the full (grid, case) kernel matrix) to
    round-off, 1e-13."""
    a, b = lhs_points(300, 3).T
    passed = b > boundary(a)
    h = 0.08
    u = np.linspace(0.0, 1.0, 81)
    gu, gv = np.meshgrid(u, u)
    pa, pb = (a - a.min()) / np.ptp(a), (b - b.min()) / np.ptp(b)
    w = np.exp(-0.5 * ((gu.ravel()[:, None] - pa) ** 2 + (gv.ravel()[:, None] - pb) ** 2) / h**2)
    direct = ((w @ passed.astype(float)) / w.sum(axis=1)).reshape(81, 81)
    for chunk in (1, 299, 300, 301, 12345, 81 * 81 * 300, 10**9):
        gx, gy, prob, hh = pass_probability_map(a, b, passed, bandwidth=h, chunk_elements=chunk)
        assert hh == h
        np.testing.assert_allclose(prob, direct, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(gx, a.min() + u * np.ptp(a), rtol=1e-15)
    np.testing.assert_allclose(gy, b.min() + u * np.ptp(b), rtol=1e-15)


def test_probability_map_takes_two_exponentials_per_grid_level_and_case(monkeypatch):
    """The plane's Gaussian kernel is the product of one per axis, so the map
    needs exp of 2 x 81 x n values (the per-axis factors), not 81^2 x n (the
    kernel at every grid point and case: 2.7 s per pair of inputs at 50 000
    cases, 16 s of a 4-input envelope's 40). Counted through numpy's exp."""
    import postproc.sweep.envelope as envelope

    counted = []
    real_exp = np.exp

    def counting_exp(v, *args, **kwargs):
        counted.append(np.size(v))
        return real_exp(v, *args, **kwargs)

    a, b = lhs_points(500, 5).T
    monkeypatch.setattr(envelope.np, "exp", counting_exp)
    envelope.pass_probability_map(a, b, b > boundary(a), bandwidth=0.08)
    assert sum(counted) == 2 * 81 * 500, f"{sum(counted)} exponentials for 81 x 81 grid points and 500 cases"


@pytest.mark.parametrize("status,clearance", [([2, 2, 2], [np.nan] * 3), ([0, 0, 1, 2], [5.0, 0.5, np.nan, np.nan])],
                         ids=["none computed", "mixed"])
def test_one_input_map_draws_every_case(status, clearance):
    """With one varied input the cases not computed were not drawn (3 invalid
    cases: an empty axis titled '0 of 3 cases pass'). Every case is drawn once,
    those not computed with the 2-input map's marker, inside the padded axis."""
    from postproc.sweep.figures import passfail_figure

    n = len(status)
    x = np.array([-1.0, -1.0, -1.0]) if n == 3 else np.array([7.0, 8.0, 9.0, 10.0])
    ds = xr.Dataset({"parachute%drag_area": ("case", x), "status": ("case", np.array(status, dtype=np.int32)),
                     "min_clearance_m": ("case", np.array(clearance))}, coords={"case": np.arange(n)})
    ds.attrs["inputs"] = "parachute%drag_area"
    env = evaluate(ds, parse_criteria("&criteria min_clearance_m = 1.0 /"))
    fig = passfail_figure(env)
    try:
        ax = fig.axes[0]
        drawn = {c.get_label(): c.get_offsets() for c in ax.collections}
        assert sum(len(v) for v in drawn.values()) == n, drawn
        bad = np.array(status) != 0
        nc = np.asarray(drawn["not computed"])
        assert sorted(nc[:, 0]) == sorted(x[bad]), nc
        lo, hi = ax.get_xlim()
        assert lo < x.min() and x.max() < hi
        n_pass = int(np.sum((np.array(status) == 0) & (np.nan_to_num(clearance, nan=-1.0) >= 1.0)))
        assert f"{n_pass} of {n} cases pass" in fig._suptitle.get_text()
    finally:
        import matplotlib.pyplot as plt
        plt.close(fig)


def test_worst_cases_not_computed_before_computed_cases_with_a_nan_metric():
    """Computed cases whose metric is NaN (the event never came: relative margin
    -inf) shared the key of the cases not computed and interleaved with them by
    case id; docs/sweep.md puts the cases not computed first."""
    a = np.linspace(0.1, 0.6, 6)
    status = np.array([0, 1, 0, 0, 2, 0], dtype=np.int32)
    clearance = np.array([np.nan, 10.0, 1.6, np.nan, 10.0, 20.0])   # cases 0 and 3: never separated
    env = evaluate(synthetic_summary(a, a, clearance, status=status), parse_criteria(CRITERIA))
    assert np.isneginf(env["relative_margin"].sel(criterion="all", case=[0, 3]).values).all()
    # by hand: not computed (1, 4), then the NaN metrics (0, 3), then by margin (2: 0.1 m, 5: 18.5 m)
    assert list(worst_cases(env, 6)) == [1, 4, 0, 3, 2, 5]
    assert list(worst_cases(env, 3)) == [1, 4, 0]



def test_worst_case_table_says_its_columns_are_margins():
    """The table's criterion columns hold margins (limit less metric, or metric less
    limit), in the metric's units: a header `touchdown [m s-1]` over 0.004 read as a
    touchdown speed of 0.004 m/s (a new user's walkthrough). Two cases by hand:
    clearance 1.6 and 20 m against 1.5 m, margins 0.1 and 18.5 m."""
    a = np.array([0.1, 0.2])
    env = evaluate(synthetic_summary(a, a, np.array([1.6, 20.0])), parse_criteria("&criteria min_clearance_m = 1.5 /"))
    head, _, first, second = worst_case_table(env, 2).splitlines()
    assert head == "| case | status | a | b | worst | clearance margin [m] |"
    assert first == "| 0 | ok | 0.1 | 0.1 | clearance | 0.1 |"
    assert second == "| 1 | ok | 0.2 | 0.2 | clearance | 18.5 |"

@pytest.mark.parametrize("limit_var, limit, bad, criterion, metric, values, margins", [
    # min_line_clearance_m: margin = min_line_clearance_m - limit; NaN: no line
    ("min_line_clearance_m", 5.0, "-1", "line_clearance", "min_line_clearance_m", [6.6, 4.0, 5.0, np.nan, 7.5],
     [1.6, -1.0, 0.0, np.nan, 2.5]),
    # max_ground_speed_m_s: margin = limit - ground_speed_m_s; NaN: the case ended above the ground
    ("max_ground_speed_m_s", 8.5, "0", "touchdown", "ground_speed_m_s", [5.0, 9.0, 8.5, np.nan, 7.0],
     [3.5, -0.5, 0.0, np.nan, 1.5]),
], ids=["line-clearance", "touchdown"])
def test_margin_of_a_one_metric_criterion(limit_var, limit, bad, criterion, metric, values, margins):
    """A criterion on one summary variable: its margin in its own units and,
    divided by the limit, the relative margin; a case whose variable is NaN
    (not computed: no line, no landing) fails it, as any NaN metric; a limit
    out of its range is refused in one line."""
    a = np.linspace(0, 1, 5)
    ds = synthetic_summary(a, a, np.full(5, 9.0))
    ds[metric] = ("case", np.array(values))
    env = evaluate(ds, parse_criteria(f"&criteria\n  {limit_var} = {limit}\n/\n"))
    np.testing.assert_allclose(env["margin"].sel(criterion=criterion).values, margins, atol=1e-12)
    assert list(env["passed"].sel(criterion=criterion).values) == [1, 0, 1, 0, 1]
    np.testing.assert_allclose(env["relative_margin"].sel(criterion=criterion).values[[0, 1]],
                               np.array(margins[:2]) / limit, rtol=1e-12)
    with pytest.raises(DefinitionError, match=f"{limit_var} = {bad} is not allowed"):
        parse_criteria(f"&criteria\n  {limit_var} = {bad}.0\n/\n")


def test_the_figures_record_knows_a_file_by_its_stat_or_its_bytes(tmp_path):
    """stamp.unchanged: the same size and modification time is the recorded
    file without reading it (a summary of 10^7 cases is gigabytes); a file
    touched since (another mtime) is still the recorded one if its SHA-256
    is; other bytes of the same size are not."""
    import os

    from postproc.sweep import stamp

    f = tmp_path / "summary.nc"
    f.write_bytes(b"0123456789")
    record = {"summary_sha256": stamp.sha256(f), "summary_stat": stamp.file_stat(f)}
    assert stamp.unchanged(f, record, "summary")
    st = f.stat()
    os.utime(f, ns=(st.st_atime_ns, st.st_mtime_ns + 10**9))       # touched, same bytes
    assert stamp.unchanged(f, record, "summary")
    f.write_bytes(b"9876543210")                                     # same size, other bytes
    assert not stamp.unchanged(f, record, "summary")
    # without the stat (a record of before), the bytes decide
    assert stamp.unchanged(f, {"summary_sha256": stamp.sha256(f)}, "summary")


@pytest.mark.parametrize("design", ["sobol 2^17", "sobol 2^18", "grid 1500 x 3"])
def test_bandwidth_subset_spans_every_input(design):
    """The bandwidth is chosen on at most 2000 cases.  Every k-th case (the
    earlier subset) aliased with the design's order: a scrambled Sobol sweep of
    2^17 cases (k = 66) kept its second input in [0.5, 1), of 2^18 (k = 132)
    its first in [0, 0.5) too; a grid whose last input has 3 levels (k = 3)
    kept that input at one level.  The random subset spans every input: both
    halves of each Sobol input hold 40-60 % of it (binomial sd 1.1 %), and the
    grid's last input keeps its 3 levels."""
    from postproc.sweep.envelope import bandwidth_subset

    if design.startswith("sobol"):
        m = int(design.split("^")[1])
        u = qmc.Sobol(3, scramble=True, rng=5).random_base2(m)
        keep = bandwidth_subset(len(u))
        assert len(keep) == 2000 and len(np.unique(keep)) == 2000
        low_half = (u[keep] < 0.5).mean(axis=0)
        assert np.all((low_half > 0.4) & (low_half < 0.6)), f"share of each input below 0.5: {low_half}"
    else:
        levels = np.tile(np.arange(3), 1500)   # the last input varies fastest
        keep = bandwidth_subset(len(levels))
        assert set(levels[keep]) == {0, 1, 2}
    assert np.array_equal(bandwidth_subset(1500), np.arange(1500))   # a small sweep: every case
