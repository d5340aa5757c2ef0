"""Without the trajectory output (a sweep's summary mode, `&run trajectory =
.false.`) an output record computes only what its milestones need - the bodies
and the cut joint, not the loads and the line (docs/performance.md, "Skipping
what a scene does not need") - and the milestones are the same bits as with the
trajectory: every summary variable of a sweep case equals the attribute of the
same name that `airlaunch` writes for the case's namelist alone, in each line
coupling (the direct coupling, the rigidized one, and the automatic choice in
the snatch variant, which hands over between them).  The record-only milestones
(the clearance at the end of the run, the cut joint's residual before
separation) are included; the wall time is not a milestone."""
import math
import subprocess

import pytest
import xarray as xr

from test_sweep_support import AIRLAUNCH_EXE, ENV, SWEEP_EXE, make_table, run_sweep, small_definition

#: &fixed settings of each variant: 10 segments as the other sweep tests, and the coupling.
VARIANTS = {
    "direct": [],
    "rigidized": [("line%coupling", "'rigidized'")],
    "auto_snatch": [("line%coupling", "'auto'"), ("parachute%deploy_time", "1.0")],
}


def fixed_groups(settings):
    return "\n".join(f"&fixed name = '{name}', value = \"{value}\" /"
                     for name, value in [("line%n_seg", "10"), *settings])


@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_summary_rows_are_the_single_runs_milestones(tmp_path, variant):
    for exe in (SWEEP_EXE, AIRLAUNCH_EXE):
        assert exe.exists(), f"{exe} is missing: run scripts/setup release first"
    # 12 s: past the separation (3.9 s) and the first pitch maximum (10.5 s)
    definition = small_definition(tmp_path / "d.nml", n_cases=2, t_end=12.0, fixed=fixed_groups(VARIANTS[variant]))
    make_table(definition, tmp_path)
    res = run_sweep(definition, tmp_path, None)
    assert res.returncode == 0 and "2 cases: 2 ok" in res.stdout, res.stdout + res.stderr
    with xr.open_dataset(tmp_path / "out" / "summary.nc") as s:
        summary = s.load()
    compared = 0
    for case in range(2):
        nml = tmp_path / f"case{case}.nml"
        got = run_sweep(definition, tmp_path, None, "--case-namelist", case)
        assert got.returncode == 0, got.stderr
        nml.write_text(got.stdout)
        out = tmp_path / f"case{case}.nc"
        single = subprocess.run([str(AIRLAUNCH_EXE), str(nml), "--output", str(out)], capture_output=True,
                                text=True, env=ENV, timeout=600)
        assert single.returncode == 0, single.stderr
        with xr.open_dataset(out) as ds:
            attrs = dict(ds.attrs)
        assert float(attrs["separation_time_s"]) > 0 and float(attrs["min_clearance_m"]) > 0, variant
        for name, var in summary.data_vars.items():
            if name not in attrs or name in ("wall_time_s", "status") or var.dims != ("case",):
                continue
            row, alone = var.values[case], attrs[name]
            if isinstance(alone, str):          # early_separation: "true"/"false" in the file, 1/0 in the row
                alone = {"true": 1.0, "false": 0.0}[alone]
            alone = float(alone)
            if math.isnan(row):                 # not reached / not tracked: -1 in the file
                assert alone == -1.0 or math.isnan(alone), (variant, case, name, alone)
            else:
                assert row == alone, (variant, case, name, row, alone)
            compared += 1
    # every milestone of the row, the record-only ones among them
    for name in ("min_clearance_m", "min_exit_clearance_m", "max_constraint_residual_m",
                 "max_load_factor_excursion",
                 "peak_line_tension_N", "pitch_max_time_s"):
        assert name in summary.data_vars and name in attrs, name
    assert compared >= 2 * 20, compared
