"""Sweeps of the standalone line scene (&run scene = 'line' in the base
scenario; docs/sweep.md, "Sweeping the line scene"): input/sweep_airdrop.nml,
the heavy airdrop's opening shock, cut down to a few short cases.

What is checked: every summary variable of a case is what a single `airlaunch`
run of that case's namelist (`airlaunch-sweep --case-namelist ID`) reports in
its output file - the peak segment tension over every step, the largest end
tensions over the records, the canopy's deployment speed, the tip's final
speed, the steps - so the sweep runs the line scene as `airlaunch` does; two
ranks give the one-rank summary bit for bit; keep_worst keeps the largest peak
tensions; the envelope judges the peak against the criteria's allowable load;
and criteria or a worst_by of the airlaunch scene are refused in one line."""
import re
import subprocess

import numpy as np
import pytest
import xarray as xr

from conftest import run_airlaunch
from test_sweep_support import (AIRLAUNCH_EXE, ENV, ROOT, SWEEP_EXE, assert_line_row_is_the_run, assert_same_summary,
                                make_table, run_example_sweep, run_python, run_sweep)

#: 6 Latin-hypercube cases of 4 s: deployment by 1 s, the peak by ~2.5 s
EDITS = [("n_cases = 200", "n_cases = 6"), ("t_end = 10.0 ", "t_end = 4.0 ")]


@pytest.fixture(scope="module")
def airdrop_sweep(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("airdrop")
    summary = run_example_sweep("sweep_airdrop", tmp, EDITS)
    return tmp, summary


def test_rows_are_the_single_runs_of_the_cases(airdrop_sweep):
    tmp, summary = airdrop_sweep
    with xr.open_dataset(summary) as s:
        assert s.attrs["scene"] == "line"
        # no attribute that CF readers (netCDF-Java, Panoply: case-insensitive) take for the
        # file's Conventions: the rows' reading guide is a comment
        assert [k for k in s.attrs if k.lower() == "conventions"] == []
        assert s.attrs["comment"].startswith("one row per case, sorted by case id")
        assert (s["status"].values == 0).all() and (s["completed"].values == 1).all()
        for case in (0, 3, 5):
            nml = tmp / f"case_{case}.nml"
            res = subprocess.run([str(SWEEP_EXE), str(tmp / "sweep_airdrop.nml"), "--case-namelist", str(case)],
                                 cwd=tmp, capture_output=True, text=True, env=ENV, timeout=60)
            assert res.returncode == 0, res.stderr
            out = tmp / f"case_{case}.nc"
            nml.write_text(res.stdout)
            run = run_airlaunch(AIRLAUNCH_EXE, nml, "--output", out)
            assert run.returncode == 0, run.stderr
            row = {k: s[k].values[case] for k in s.variables if s[k].dims == ("case",)}
            with xr.open_dataset(out) as ds:
                assert_line_row_is_the_run(row, ds, 4.0)
                assert row["line_breaks"] == 0 and np.isnan(row["line_break_time_s"])
                assert np.isnan(row["line_recoil_speed_m_s"]) and ds.attrs["line_recoil_speed_m_s"] == -1.0
        # the opening shock: the peak of every case is an opening load of several g on the
        # ~1 t platform (a 580 m^2 canopy at ~67 m/s), and lies after its deployment
        g = 9.80665
        peak = s["peak_line_tension_N"].values
        assert (peak > 3 * g * s["line_scene%a_mass"].values).all()
        assert (s["peak_line_tension_time_s"].values > s["parachute%deploy_time"].values).all()


def test_two_ranks_give_the_one_rank_summary(airdrop_sweep, tmp_path):
    """... and without worst_by the line scene's default, the peak tension,
    ranks the worst cases (before the twenty-sixth session the airlaunch
    scene's min_clearance_m was the default, and was refused here)."""
    tmp, summary = airdrop_sweep
    definition = tmp_path / "sweep_airdrop.nml"
    text = (tmp / "sweep_airdrop.nml").read_text()
    assert "  worst_by = 'peak_line_tension_N'\n" in text
    definition.write_text(text.replace("  worst_by = 'peak_line_tension_N'\n", ""))
    make_table(definition, tmp_path)
    res = run_sweep(definition, tmp_path, 2)
    assert res.returncode == 0, res.stderr
    # (the same cases from a copy of the definition elsewhere: its path differs)
    assert_same_summary(summary, tmp_path / "out" / "summary.nc", ignore_attrs=("created", "definition"))
    kept = [sorted(p.name for p in (d / "out" / "trajectories").glob("case_*.nc")) for d in (tmp, tmp_path)]
    assert len(kept[0]) == 3 and kept[1] == kept[0]


def test_keep_worst_keeps_the_largest_peak_tensions(airdrop_sweep):
    tmp, summary = airdrop_sweep
    with xr.open_dataset(summary) as s:
        worst = np.argsort(-s["peak_line_tension_N"].values)[:3]
    kept = sorted(int(p.stem.split("_")[1]) for p in (tmp / "out" / "trajectories").glob("case_*.nc"))
    assert kept == sorted(worst.tolist())
    with xr.open_dataset(tmp / "out" / "trajectories" / f"case_{kept[0]:06d}.nc") as ds:
        assert ds.attrs["status"] == "completed" and "line_node_position" in ds


def test_envelope_of_the_peak_tension(airdrop_sweep):
    """The line-tension criterion passes a case exactly where its peak is at most
    line_strength_n / line_safety_factor (input/criteria_airdrop.nml: 100 kN / 2)."""
    tmp, summary = airdrop_sweep
    res = run_python(["envelope", tmp / "sweep_airdrop.nml", "--no-figures"], tmp)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(summary) as s, xr.open_dataset(tmp / "out" / "envelope.nc") as env:
        peak = s["peak_line_tension_N"].values
        line = env.sel(criterion="line_tension")
        np.testing.assert_array_equal(line["margin"].values, 50.0e3 - peak)
        np.testing.assert_array_equal(line["passed"].values, (peak <= 50.0e3).astype(np.int8))


@pytest.mark.parametrize("check", [True, False], ids=["before-the-cases", "envelope"])
def test_criteria_of_the_airlaunch_scene_are_refused(airdrop_sweep, check):
    """Refused by `envelope --check`, which scripts/sweep runs before any case
    (from the base's &run scene), and by the envelope step (from the summary)."""
    tmp, _ = airdrop_sweep
    res = run_python(["envelope", tmp / "sweep_airdrop.nml", "--no-figures", "--criteria",
                      ROOT / "input" / "criteria_paper.nml"] + (["--check"] if check else []), tmp)
    assert res.returncode == 2
    assert res.stderr.strip().count("\n") == 0
    assert "&criteria: min_clearance_m is not allowed for a sweep of scene 'line': its summary has no " \
           "min_clearance_m" in res.stderr


def test_worst_by_of_the_airlaunch_scene_is_refused(airdrop_sweep, tmp_path):
    tmp, _ = airdrop_sweep
    definition = tmp_path / "bad.nml"
    definition.write_text((tmp / "sweep_airdrop.nml").read_text().replace(
        "worst_by = 'peak_line_tension_N'", "worst_by = 'min_clearance_m'"))
    res = run_sweep(definition, tmp_path, None, "--check")
    assert res.returncode == 2
    assert res.stderr.strip().count("\n") == 0
    assert "&sweep: worst_by = 'min_clearance_m' is not allowed with a base scenario of scene 'line' (with " \
           "keep_worst > 0 it must be one of its summary variables: peak_line_tension_N, max_end_tension_a_N, " \
           "max_end_tension_b_N, line_recoil_speed_m_s, final_tip_speed_m_s, ground_speed_m_s)" in res.stderr


def test_keep_worst_by_the_touchdown_speed(tmp_path):
    """worst_by = 'ground_speed_m_s' keeps the fastest touchdowns: the airdrop's
    platform leaves at 70 m/s at 1500 m onto grounds 6 to 18 m below while its
    canopy (opening from 0.5 s) brakes it, so the nearer grounds see the faster
    touchdowns; a ground 100 m below is not reached in the 3 s (NaN touchdown
    speed: no event, not kept, as a sweep without a break keeps no recoil)."""
    base = tmp_path / "drop.nml"
    base.write_text((ROOT / "input" / "line_airdrop.nml").read_text()
                    .replace("t_end = 200.0", "t_end = 3.0")
                    .replace("a_kind = 'point_mass'", "a_kind = 'point_mass', ground = .true."))
    definition = tmp_path / "touchdown.nml"
    definition.write_text(f"""&sweep
  name = 'touchdown'
  base = '{base}'
  output_dir = 'out'
  design = 'grid'
  keep_worst = 2
  worst_by = 'ground_speed_m_s'
/
&input name = 'line_scene%ground_altitude', distribution = 'list', values = 1494.0, 1482.0, 1400.0, 1490.0, 1486.0,
       units = 'm' /
""")
    make_table(definition, tmp_path)
    res = run_sweep(definition, tmp_path, None)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(tmp_path / "out" / "summary.nc") as s:
        speed = s["ground_speed_m_s"].values
        ground = s["line_scene%ground_altitude"].values
    assert np.isnan(speed[ground == 1400.0]).all()
    landed = ~np.isnan(speed)
    assert landed.sum() == 4
    # the touchdown speed rises with the ground's altitude (a nearer ground: less time to brake) ...
    order = np.argsort(ground[landed])
    assert (np.diff(speed[landed][order]) > 0).all()
    # ... and the two kept are the two fastest, the two nearest grounds
    fastest = sorted(np.flatnonzero(landed)[np.argsort(-speed[landed])[:2]].tolist())
    assert fastest == sorted(np.flatnonzero(np.isin(ground, [1494.0, 1490.0])).tolist())
    kept = sorted(int(p.stem.split("_")[1]) for p in (tmp_path / "out" / "trajectories").glob("case_*.nc"))
    assert kept == fastest
    for case in kept:
        with xr.open_dataset(tmp_path / "out" / "trajectories" / f"case_{case:06d}.nc") as ds:
            assert ds.attrs["ground_speed_m_s"] == speed[case]


def test_invalid_and_failed_cases_of_a_line_sweep(tmp_path):
    """input/line_snapback.nml (a 1 % stretched line, 20 kN) swept over its
    strength and damping: a strength the initial tension already reaches is
    the case's invalid input (the line scene's own one-line message, status
    2, no metrics); an absurd damping of 1e30 N s fails numerically (status 1,
    the message naming the time; keep_failed keeps its trajectory); the sound
    case runs (status 0) and its scheduled cut is recorded."""
    definition = tmp_path / "snap.nml"
    definition.write_text(f"""&sweep
  name = 'snap'
  base = '{ROOT / "input" / "line_snapback.nml"}'
  output_dir = 'out'
  design = 'grid'
  keep_failed = .true.
/
&input name = 'line%breaking_strength', distribution = 'list', values = 1.0e4, 3.0e4, units = 'N' /
&input name = 'line%damping', distribution = 'list', values = 300.0, 1.0e30, units = 'N s' /
""")
    make_table(definition, tmp_path)
    res = run_sweep(definition, tmp_path)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(tmp_path / "out" / "summary.nc") as s:
        assert s["status"].values.tolist() == [2, 2, 0, 1]
        for case in (0, 1):
            assert str(s["failure"].values[case]).startswith(
                f"case {case}: &line: breaking_strength = 10000.0 N is not allowed: the initial shape's tension "
                "is already 2")
            assert np.isnan(s["peak_line_tension_N"].values[case]) and s["completed"].values[case] == -1
        assert s["line_break_time_s"].values[2] == 0.005 and s["completed"].values[2] == 1
        # its recoil: every node at c eps0 = sqrt(EA / rho) 0.01 = 20 m/s (the base's grid-scale damping)
        assert s["line_recoil_speed_m_s"].values[2] == pytest.approx(20.0, rel=5e-3)
        assert "integration failed at t = " in str(s["failure"].values[3]) and s["completed"].values[3] == 0
    assert sorted(p.name for p in (tmp_path / "out" / "trajectories").glob("*.nc")) == ["case_000003.nc"]


def absolute_definition(name, tmp_path, extra):
    """input/NAME.nml with its base and criteria paths absolute and the text
    `extra` appended, in tmp_path."""
    text = re.sub(r"^(\s*(?:base|criteria)\s*=\s*')input/", lambda m: f"{m.group(1)}{ROOT / 'input'}/",
                  (ROOT / "input" / f"{name}.nml").read_text(), flags=re.M)
    definition = tmp_path / f"{name}.nml"
    definition.write_text(text + extra)
    return definition


@pytest.mark.parametrize("name, fixed, refused", [
    ("sweep_airdrop", "&fixed name = 'line_scene%peak_tension', value = '.false.' /",
     "line_safety_factor, line_strength_n is not allowed for this sweep: &fixed 'line_scene%peak_tension' sets "
     "&line_scene peak_tension = .false. (the peak tension is not tracked: every case's margin would be NaN, "
     "failing; leave the criterion out or change peak_tension)"),
    ("sweep_paper", "&fixed name = 'line%enabled', value = 'F' /",
     "min_line_clearance_m is not allowed for this sweep: &fixed 'line%enabled' sets &line "
     "enabled = .false. (the scene has no line"),
    ("sweep_paper", "&fixed name = 'line%coupling', value = \"'Rigidized'\" /", None),
], ids=["peak-tension-off", "no-line", "rigidized-with-line-clearance"])
def test_criteria_the_base_never_computes_are_refused(tmp_path, name, fixed, refused):
    """A criterion whose metric the base (with the sweep's &fixed) never
    computes would fail every case silently (a NaN margin fails): refused
    before any case, in one line naming the setting (the first such
    criterion of the file).  criteria_paper.nml has a line-clearance
    criterion, which the rigidized coupling tracks: accepted."""
    definition = absolute_definition(name, tmp_path, fixed + "\n")
    res = run_python(["envelope", definition, "--no-figures", "--check"], tmp_path)
    if refused is None:
        assert res.returncode == 0, res.stderr
        return
    assert res.returncode == 2, res.stderr
    assert res.stderr.strip().count("\n") == 0
    assert refused in res.stderr


def test_line_clearance_under_the_rigidized_coupling_is_judged(tmp_path):
    """The rigidized coupling tracks the line's clearance over its line's
    sub-steps since the twenty-eighth session (docs/sweep.md): a criterion on
    it is accepted (it was refused in one line, every margin NaN, before)."""
    definition = absolute_definition("sweep_paper", tmp_path, "&fixed name = 'line%coupling', value = "
                                     "\"'rigidized'\" /\n")
    criteria = tmp_path / "criteria.nml"
    criteria.write_text("&criteria min_line_clearance_m = 2.0 /\n")
    res = run_python(["envelope", definition, "--no-figures", "--check", "--criteria", criteria], tmp_path)
    assert res.returncode == 0 and res.stderr == "", res.stderr
    # the same definition with the line switched off is still refused (that check stands)
    definition = absolute_definition("sweep_paper", tmp_path, "&fixed name = 'line%enabled', value = '.false.' /\n")
    res = run_python(["envelope", definition, "--no-figures", "--check", "--criteria", criteria], tmp_path)
    assert res.returncode == 2 and "the scene has no line" in res.stderr, res.stderr


TOUCHDOWN_CRITERIA = "&criteria max_ground_speed_m_s = 5.7 /\n"


def test_touchdown_speed_criterion(tmp_path):
    """The heavy airdrop swept to the ground (&fixed line_scene%ground = .true.,
    t_end 400 s): every case lands, at the steady descent rate of its own
    platform mass and canopy drag area, sqrt(2 W / (rho sum Cd A)), the
    independent reference of test_line_airdrop.py (1e-4 as there: the swing
    left after ~260 s of descent); the touchdown criterion's margin is the
    limit less that speed, and the cases pass where it is below the limit
    (5.7 m/s: near the nominal 5.68 m/s, so that the sweep has both)."""
    edits = [("n_cases = 200", "n_cases = 6"), ("t_end = 10.0 ", "t_end = 400.0 "),
             ("keep_worst = 3", "keep_worst = 0"),
             ("&input name = 'parachute%drag_area'",
              "&fixed name = 'line_scene%ground', value = '.true.' /\n&input name = 'parachute%drag_area'")]
    summary = run_example_sweep("sweep_airdrop", tmp_path, edits)
    criteria = tmp_path / "touchdown.nml"
    criteria.write_text(TOUCHDOWN_CRITERIA)
    res = run_python(["envelope", tmp_path / "sweep_airdrop.nml", "--no-figures", "--criteria", criteria], tmp_path)
    assert res.returncode == 0, res.stderr
    g = 9.80665
    with xr.open_dataset(summary) as s, xr.open_dataset(tmp_path / "out" / "envelope.nc") as env:
        v = s["ground_speed_m_s"].values
        assert np.isfinite(v).all() and (s["ground_time_s"].values == s["end_time_s"].values).all()
        weight = (s["line_scene%a_mass"].values + 60.0 + 0.2 * 20.0) * g
        drag_area = s["parachute%drag_area"].values + 1.0 + 0.01 * np.pi * 0.02 * 20.0
        steady = np.sqrt(2 * weight / (1.1117 * drag_area))
        np.testing.assert_allclose(v, steady, rtol=1e-4)
        touchdown = env.sel(criterion="touchdown")
        np.testing.assert_array_equal(touchdown["margin"].values, 5.7 - v)
        np.testing.assert_array_equal(touchdown["passed"].values, (v <= 5.7).astype(np.int8))
        assert 0 < touchdown["passed"].values.sum() < len(v)


def test_touchdown_criterion_needs_a_ground(tmp_path):
    """A line-scene base without a ground (the default) never lands: the
    touchdown criterion is refused before any case, in one line; with
    &fixed line_scene%ground = .true. it is accepted."""
    criteria = tmp_path / "touchdown.nml"
    criteria.write_text(TOUCHDOWN_CRITERIA)
    definition = absolute_definition("sweep_airdrop", tmp_path, "")
    res = run_python(["envelope", definition, "--no-figures", "--check", "--criteria", criteria], tmp_path)
    assert res.returncode == 2 and res.stderr.strip().count("\n") == 0, res.stderr
    assert "max_ground_speed_m_s is not allowed for this sweep: the base scenario" in res.stderr
    assert "(by default) sets &line_scene ground = .false. (the scene has no ground, the default" in res.stderr
    definition = absolute_definition("sweep_airdrop", tmp_path, "&fixed name = 'line_scene%ground', value = 'T' /\n")
    res = run_python(["envelope", definition, "--no-figures", "--check", "--criteria", criteria], tmp_path)
    assert res.returncode == 0, res.stderr


@pytest.mark.parametrize("name", ["line%wind", "line_scene%a_position"])
def test_a_vector_cannot_be_varied(tmp_path, name):
    """A vector (the line scene's wind, an end's position) holds three values:
    a case's one drawn number assigned to it is a vector of one value, which
    the scenario readers refuse, so every case of such a sweep was
    invalid_input while the check (and so the table step) passed it (found by
    a new user's walkthrough varying the airdrop's wind).  Refused before any
    case, in one line naming its elements, which can be varied one by one
    (test_sweep_vector_elements.py); the whole vector can still be set with
    &fixed, which the check passes."""
    definition = absolute_definition(
        "sweep_airdrop", tmp_path,
        f"&input name = '{name}', distribution = 'uniform', lower = -5.0, upper = 5.0, units = 'm' /\n")
    res = run_sweep(definition, tmp_path, None, "--check")
    assert res.returncode == 2 and res.stderr.strip().count("\n") == 0, res.stdout + res.stderr
    assert (f"&input #5 '{name}': {name} is a vector of 3 values; a sweep varies one value: vary its elements "
            f"one by one (allowed: {name}(1) to {name}(3), each an &input)") in res.stderr
    definition = absolute_definition("sweep_airdrop", tmp_path,
                                     "&fixed name = 'line%wind', value = '5.0, 0.0, 0.0' /\n")
    res = run_sweep(definition, tmp_path, None, "--check")
    assert res.returncode == 0, res.stderr
