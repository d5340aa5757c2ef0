"""A criterion that no computed case can evaluate is named, not failed in
silence (an audit): the touchdown speed `max_ground_speed_m_s` judged on an
air-launch sweep whose cases end at altitude (every ground_speed_m_s NaN), or
the firing attitude of a sweep whose t_end comes before the first pitch
maximum, made every case fail with P = 0 and no word of why. The envelope step
now says so under the probabilities (stdout: a warning for a criterion whose
metric is NaN in every computed case, a note when in some; exit status and
stderr unchanged), and says when no case computed at all."""
import numpy as np
import xarray as xr

from test_sweep_support import PAPER, run_python

from postproc.sweep.criteria import parse_criteria
from postproc.sweep.definition import read_definition
from postproc.sweep.envelope import evaluate
from postproc.sweep.table import make_table


def sweep_with_summary(tmp_path, metrics, status=None, n=6):
    """A definition of the paper scenario (no table.nc: the envelope step
    compares the summary with the table the definition draws) and a summary
    of that table with the given metric columns."""
    d = tmp_path / "s.nml"
    d.write_text(f"&sweep name = 'u', base = '{PAPER}', output_dir = 'out', design = 'lhs', n_cases = {n}, "
                 "seed = 7 /\n&input name = 'bay%release_time', distribution = 'uniform', lower = 0.4, "
                 "upper = 1.0 /\n")
    t = make_table(read_definition(d))
    ds = xr.Dataset({"bay%release_time": ("case", t["bay%release_time"].values),
                     "status": ("case", np.zeros(n, np.int32) if status is None else np.asarray(status, np.int32))},
                    coords={"case": np.arange(n)})
    for name, values in metrics.items():
        ds[name] = ("case", np.asarray(values, dtype=float))
    ds.attrs.update(inputs="bay%release_time", design="lhs", seed=np.int32(7), n_cases=np.int32(n))
    (tmp_path / "out").mkdir()
    ds.to_netcdf(tmp_path / "out" / "summary.nc")
    return d


def envelope(tmp_path, d, criteria):
    crit = tmp_path / "c.nml"
    crit.write_text(criteria)
    return run_python(["envelope", d, "--criteria", crit, "--no-figures"], tmp_path)


def test_touchdown_criterion_that_no_case_reaches_is_named(tmp_path):
    n = 6
    d = sweep_with_summary(tmp_path, {"min_clearance_m": np.full(n, 5.0), "ground_speed_m_s": np.full(n, np.nan)})
    res = envelope(tmp_path, d, "&criteria min_clearance_m = 1.5, max_ground_speed_m_s = 10.0 /\n")
    assert res.returncode == 0 and res.stderr == "", res.stderr
    lines = [x for x in res.stdout.splitlines() if "warning:" in x or "note:" in x]
    assert len(lines) == 1, res.stdout
    assert lines[0].startswith("  warning: touchdown: ground_speed_m_s is NaN in every computed case (6 of 6)")
    assert "ground" in lines[0] and "t_end" in lines[0]
    with xr.open_dataset(tmp_path / "out" / "envelope.nc") as env:   # the verdicts are unchanged: failing
        assert env["passed"].sel(criterion="touchdown").values.sum() == 0
        assert env["passed"].sel(criterion="clearance").values.sum() == n


def test_metric_nan_in_some_cases_is_a_note_and_no_warning(tmp_path):
    pitch = [80.0, np.nan, 85.0, np.nan, 89.0, 70.0]
    d = sweep_with_summary(tmp_path, {"pitch_max_deg": pitch})
    res = envelope(tmp_path, d, "&criteria firing_pitch_min_deg = 75.0 /\n")
    assert res.returncode == 0 and res.stderr == "", res.stderr
    notes = [x for x in res.stdout.splitlines() if "note:" in x or "warning:" in x]
    assert len(notes) == 1 and "firing_attitude: pitch_max_deg is NaN in 2 of 6 computed cases" in notes[0], \
        res.stdout


def test_no_case_computed_is_said(tmp_path):
    n = 4
    d = sweep_with_summary(tmp_path, {"min_clearance_m": np.full(n, np.nan)}, status=[1, 2, 1, 2], n=n)
    res = envelope(tmp_path, d, "&criteria min_clearance_m = 1.5 /\n")
    assert res.returncode == 0 and res.stderr == "", res.stderr
    lines = [x for x in res.stdout.splitlines() if "warning:" in x or "note:" in x]
    assert len(lines) == 1 and "warning: no case was computed (4 failed or had invalid input" in lines[0], res.stdout


def test_undefined_metrics_counts_computed_cases_only():
    from postproc.sweep.envelope import undefined_metrics

    ds = xr.Dataset({"a": ("case", np.arange(5.0)), "status": ("case", np.array([0, 0, 0, 1, 2], np.int32)),
                     "ground_speed_m_s": ("case", [np.nan, 3.0, np.nan, np.nan, np.nan]),
                     "min_clearance_m": ("case", [2.0, 3.0, 4.0, np.nan, np.nan])}, coords={"case": np.arange(5)})
    ds.attrs["inputs"] = "a"
    criteria = parse_criteria("&criteria min_clearance_m = 1, max_ground_speed_m_s = 5 /")
    env = evaluate(ds, criteria)
    assert undefined_metrics(env, criteria) == [("touchdown", ("ground_speed_m_s",), 2, 3)]


def test_line_clearance_description_names_no_coupling():
    """Every coupling tracks the line's clearance since the twenty-eighth
    session (docs/sweep.md); the criterion's description in envelope.nc still
    said '(direct coupling)' (an audit)."""
    (c,) = parse_criteria("&criteria min_line_clearance_m = 3.0 /")
    assert "coupling" not in c.description
