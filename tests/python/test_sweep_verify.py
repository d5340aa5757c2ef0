"""The verification step (postproc/sweep/verify.py): the cases nearest the
boundary rerun with more segments and tighter tolerances.  Checked against
independent references: at factors 1 and 1 the rerun reproduces the summary's
margins bit for bit — in both scenes, with events that did not happen (NaN) —
so the margins are computed from a single run exactly as airlaunch-sweep
computes them; the refined namelist, read back by the scenario reader itself
(`airlaunch --check`), has the multiplied segments, the divided tolerances and
break segments that cover the same stretch of line; and bad arguments are one
line and status 2."""
import subprocess

import numpy as np
import pytest
import xarray as xr

from conftest import units_problems
from test_sweep_support import (AIRLAUNCH_EXE, ENV, PAPER, ROOT, make_table, run_example_sweep, run_python, run_sweep,
                                small_definition)

from postproc.sweep.verify import refine_namelist, refined_segment, segment_factor


@pytest.fixture(scope="module")
def paper_sweep(tmp_path_factory):
    """6 cases of the paper scenario to 6 s: separated (a clearance) but before
    the first pitch maximum (firing attitude and time NaN)."""
    tmp = tmp_path_factory.mktemp("verify")
    definition = small_definition(tmp / "v.nml", n_cases=6, t_end=6.0,
                                  extra_sweep=f"criteria = '{ROOT}/input/criteria_paper.nml'")
    make_table(definition, tmp)
    res = run_sweep(definition, tmp)
    assert res.returncode == 0, res.stdout + res.stderr
    return tmp, definition


def verify(tmp, definition, *args):
    return run_python(["verify", definition, *args], tmp)


def assert_same_margins(ds):
    """margin_refined == margin_sweep bit for bit, NaN where NaN."""
    a, b = ds["margin_sweep"].values, ds["margin_refined"].values
    assert np.array_equal(np.isnan(a), np.isnan(b))
    np.testing.assert_array_equal(a[~np.isnan(a)], b[~np.isnan(b)])
    assert not ds["flipped"].values.any()


def test_unrefined_rerun_is_the_summary_row(paper_sweep):
    tmp, definition = paper_sweep
    res = verify(tmp, definition, "--ids", "0,1,2,3,4,5", "--segments", "1", "--tolerance", "1")
    assert res.returncode == 0, res.stdout + res.stderr
    with xr.open_dataset(tmp / "out" / "verify.nc") as ds:
        assert list(ds["refined_status"].values) == ["ok"] * 6
        assert list(ds["segments_factor"].values) == [1] * 6 and ds.attrs["segments_factor_asked"] == 1
        assert_same_margins(ds)
        clearance = ds["margin_sweep"].sel(criterion="clearance").values
        firing = ds["margin_sweep"].sel(criterion="firing_attitude").values
        assert np.isfinite(clearance).any() and np.isnan(firing).all()   # both kinds compared
        # every variable described, as in the other outputs (docs/output.md); numbers with units
        # (the margins' and differences' were missing: found by an audit, thirty-first session)
        # (and the coordinate criterion: bare before the thirty-second session's audit);
        # units a unit library reads, the margins' those of each criterion (criterion_units)
        for name, var in ds.variables.items():
            assert var.attrs.get("long_name"), f"{name} has no long_name"
        assert units_problems(ds) == []
        assert ds["difference"].attrs["units_from"] == "criterion_units"
    assert "0 of 6 case(s) change pass/fail" in res.stdout
    # docs/sweep.md's description of verify.nc names every variable the file has
    # (criterion_units was missing: an audit of the output files, thirty-second session)
    doc = (ROOT / "docs" / "sweep.md").read_text()
    what = doc[doc.index("**What**: `verify.nc`"):]
    what = what[:what.index("Printed:")]
    with xr.open_dataset(tmp / "out" / "verify.nc") as ds:
        inputs = set(str(ds.attrs.get("inputs", "")).split()) | {n for n in ds.data_vars if "%" in n}
        for name in set(ds.variables) - inputs - {"case", "criterion"}:
            assert f"`{name}`" in what, f"docs/sweep.md does not describe verify.nc's {name}"


def test_line_scene_unrefined_rerun_is_the_summary_row(tmp_path):
    summary = run_example_sweep("sweep_airdrop", tmp_path, [("n_cases = 200", "n_cases = 3"),
                                                           ("t_end = 10.0 ", "t_end = 3.0 ")])
    assert summary.is_file()
    res = verify(tmp_path, tmp_path / "sweep_airdrop.nml", "--cases", "3", "--segments", "1", "--tolerance", "1")
    assert res.returncode == 0, res.stdout + res.stderr
    with xr.open_dataset(tmp_path / "out" / "verify.nc") as ds:
        assert ds.sizes["case"] == 3 and list(ds["criterion"].values) == ["line_tension"]
        assert np.isfinite(ds["margin_sweep"].values).all()
        assert_same_margins(ds)


def test_nothing_to_verify_is_said_not_an_error(paper_sweep):
    tmp, definition = paper_sweep
    res = verify(tmp, definition, "--cases", "3")   # the paper criteria: firing attitude NaN in every case
    assert res.returncode == 0 and "nothing near the boundary to verify" in res.stdout, res.stdout + res.stderr


def test_refined_rerun_reports_consistent_differences(paper_sweep):
    """Default factors (segments x 4, tolerances / 100): the two nearest cases;
    the difference is the two margins' and a flip is a change of sign."""
    tmp, definition = paper_sweep
    criteria = tmp / "criteria_no_firing.nml"   # 6 s: no pitch maximum yet, so no firing criteria
    criteria.write_text("&criteria\n  min_clearance_m = 1.5\n  line_strength_n = 300e3, line_safety_factor = 1.5\n"
                        "  max_aircraft_pitch_excursion_deg = 3.0\n  max_load_factor_excursion = 0.5\n/\n")
    res = verify(tmp, definition, "--cases", "2", "--criteria", criteria)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "line%n_seg 10 -> 40" in res.stdout and "run%rtol 1e-05 -> 1e-07" in res.stdout
    with xr.open_dataset(tmp / "out" / "verify.nc") as ds, xr.open_dataset(tmp / "out" / "summary.nc") as s:
        assert ds.sizes["case"] == 2 and list(ds["refined_status"].values) == ["ok"] * 2
        a, b = ds["margin_sweep"].values, ds["margin_refined"].values
        np.testing.assert_array_equal(ds["difference"].values, a - b)
        flipped = (np.where(np.isnan(a), False, a >= 0) != np.where(np.isnan(b), False, b >= 0))
        np.testing.assert_array_equal(ds["flipped"].values.astype(bool), flipped)
        # the nearest cases: no other computed case has a smaller |relative margin| of 'all'
        rel = np.min([ds["margin_sweep"].sel(criterion=c).values / scale for c, scale in
                      (("clearance", 1.5), ("line_tension", 200e3), ("aircraft_pitch", 3.0), ("load_factor", 0.5))],
                     axis=0)
        others = np.min([(s["min_clearance_m"].values - 1.5) / 1.5, (200e3 - s["peak_line_tension_N"].values) / 200e3,
                         (3.0 - s["max_aircraft_pitch_excursion_deg"].values) / 3.0,
                         (0.5 - s["max_load_factor_excursion"].values) / 0.5], axis=0)
        others = np.delete(others, ds["case"].values)
        assert np.abs(rel).max() <= np.nanmin(np.abs(others))
        refined = (tmp / "out" / "verify" / f"case_{int(ds['case'].values[0]):06d}_refined.nml").read_text()
        assert "N_SEG=40" in refined.replace(" ", "")


def resolved(path, tmp_path):
    res = subprocess.run([str(AIRLAUNCH_EXE), str(path), "--check", "--output", str(tmp_path / "x.nc")],
                         capture_output=True, text=True, env=ENV, timeout=60)
    assert res.returncode == 0, res.stderr
    return res.stdout.split("\n", 1)[1]


@pytest.mark.parametrize("segment", [1, 7, 15])
def test_refined_namelist_read_back_by_the_scenario_reader(tmp_path, segment):
    text = PAPER.read_text().replace("&line", f"&line\n  break_time = 5.0, break_segment = {segment}", 1)
    base = tmp_path / "base.nml"
    base.write_text(text)
    refined, changes, factor = refine_namelist(resolved(base, tmp_path), 4, 100.0)
    out = tmp_path / "refined.nml"
    out.write_text(refined)
    back = resolved(out, tmp_path)   # the reader accepts it, and says what it holds
    flat = back.replace(" ", "")
    assert "N_SEG=60," in flat and factor == 4
    assert f"BREAK_SEGMENT={refined_segment(segment, 15, 4)}," in flat
    import f90nml
    nml = f90nml.reads(back)
    assert nml["run"]["rtol"] == pytest.approx(1e-7, rel=1e-15)
    assert nml["run"]["atol"] == pytest.approx(1e-8, rel=1e-15)


@pytest.mark.parametrize("n, k", [(15, 4), (10, 3), (7, 2), (1, 5)])
def test_refined_segment_covers_the_same_stretch_of_line(n, k):
    """Segment j of n spans [(j-1)/n, j/n] of the line; its refined index spans
    a piece inside it; the ends stay the ends (a one-segment line: the end the
    variable means)."""
    for last in (False, True):
        for j in range(1, n + 1):
            r = refined_segment(j, n, k, last)
            assert (j - 1) / n <= (r - 1) / (n * k) and r / (n * k) <= j / n, (j, r)
    if n > 1:
        assert refined_segment(1, n, k) == 1 and refined_segment(n, n, k) == n * k
    else:
        assert refined_segment(1, 1, k, False) == 1 and refined_segment(1, 1, k, True) == k


@pytest.mark.parametrize("args, match", [
    (["--ids", "0,99"], "--ids 0,99: case 99 is not in 0 ... 5"),
    (["--ids", "a"], "not a comma-separated list"),
    (["--ids", "1,1"], "--ids 1,1: case 1 is given twice (give each case once)"),
    (["--segments", "0"], "is not a positive integer"),
    (["--tolerance", "0.5"], "is not a factor >= 1"),
])
def test_bad_arguments_are_one_line(paper_sweep, args, match):
    tmp, definition = paper_sweep
    res = verify(tmp, definition, *args)
    assert res.returncode == 2 and match in res.stderr, res.stderr
    assert len(res.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("present", [[], ["airlaunch-sweep"]], ids=["empty-dir", "no-airlaunch"])
def test_exe_dir_without_the_programs_is_one_line(paper_sweep, tmp_path, present):
    """--exe-dir naming a directory without airlaunch-sweep or airlaunch: one
    line naming the missing program, exit 2, as for every bad argument (it was
    a FileNotFoundError traceback, exit 1, once the first rerun started)."""
    tmp, definition = paper_sweep
    for name in present:
        (tmp_path / name).symlink_to(ROOT / "build" / "release" / "bin" / name)
    res = verify(tmp, definition, "--ids", "0", "--exe-dir", str(tmp_path))
    missing = "airlaunch" if present else "airlaunch-sweep"
    assert res.returncode == 2, res.stderr
    assert f"{tmp_path / missing}: no such program to rerun the cases with" in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1 and "Traceback" not in res.stderr


def test_segment_factor_is_capped_at_1000_segments():
    """--segments 1000 on 15 segments multiplies them by 66 (990 segments), and
    verify.nc records that factor per case (it recorded the 1000 asked for)."""
    assert segment_factor(15, 1000) == 66 and segment_factor(15, 4) == 4 and segment_factor(1000, 4) == 1
    for n in (1, 7, 15, 60, 999):
        for k in (1, 2, 4, 100, 1000):
            f = segment_factor(n, k)
            assert 1 <= f <= k and (n * f <= 1000 or f == 1)


def test_verify_keeps_its_own_reruns_and_a_new_sweep_drops_it(paper_sweep):
    """verify/ holds the last verification's reruns only, and verify.nc goes
    with the summary when the sweep's cases run again (--restart): before the
    twenty-sixth session both stayed beside the new sweep."""
    tmp, definition = paper_sweep
    for ids in ("0", "1"):
        res = verify(tmp, definition, "--ids", ids, "--segments", "1", "--tolerance", "1")
        assert res.returncode == 0, res.stdout + res.stderr
        names = sorted(p.name for p in (tmp / "out" / "verify").iterdir())
        assert names and all(n.startswith(f"case_{int(ids):06d}") for n in names), names
    assert (tmp / "out" / "verify.nc").is_file()
    res = run_sweep(definition, tmp, None, "--restart")
    assert res.returncode == 0, res.stdout + res.stderr
    assert not (tmp / "out" / "verify.nc").exists()


def test_the_printed_table_gives_each_margin_its_criterion_units():
    """The verification's printed table writes a margin with its criterion's
    units, and a dimensionless one (the load factor's, units "1") bare: it
    read "0.0213 1" (a new user's walkthrough, thirty-third session)."""
    from postproc.sweep.verify import verification_table
    ds = xr.Dataset({"margin_sweep": (("criterion", "case"), [[0.5], [0.0213]]),
                     "margin_refined": (("criterion", "case"), [[0.25], [np.nan]]),
                     "difference": (("criterion", "case"), [[0.25], [np.nan]]),
                     "flipped": (("criterion", "case"), [[0], [1]]),
                     "refined_status": (("case",), ["ok"]),
                     "criterion_units": (("criterion",), ["m", "1"])},
                    coords={"case": [7], "criterion": ["clearance", "load_factor"]})
    rows = verification_table(ds).splitlines()[2:]
    assert rows == ["| 7 | ok | clearance | 0.5 m | 0.25 m | 0.25 m | no |",
                    "| 7 | ok | load_factor | 0.0213 | n/a | n/a | **yes** |"]
