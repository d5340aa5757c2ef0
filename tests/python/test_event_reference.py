"""The air-launch scene's phase events (an audit's independent checks).

An event within one rounding unit of `t_end` ends the run there (before the
fix, CVODE refused to restart: "tout too close to t0", exit 3).
"""
import math

import pytest
import xarray as xr

from conftest import nml_variant, run_airlaunch


@pytest.mark.parametrize("what", ["release", "deploy", "break"])
def test_an_event_one_rounding_unit_before_t_end(airlaunch_exe, tmp_path, what):
    """A release, a canopy deployment or a scheduled line cut 1 ulp before
    `t_end` (all allowed: each must be < t_end): the event happens, the run
    completes with its last record at t_end. Before the fix CVODE's restart at
    the event refused its first step ("tout too close to t0", CV_TOO_CLOSE:
    t_end - t below two rounding units) and the run failed with exit 3."""
    t_end = 1.0
    t_ev = math.nextafter(t_end, 0.0)
    edits = [(r"^  t_end = .*$", f"  t_end = {t_end!r}")]
    line = []
    if what == "release":
        edits.append((r"^  release_time = .*$", f"  release_time = {t_ev!r}"))
    elif what == "deploy":
        edits.append((r"^  deploy_time = .*$", f"  deploy_time = {t_ev!r}"))
    else:
        line = [f"  break_time = {t_ev!r}"]
    out = tmp_path / f"{what}.nc"
    res = run_airlaunch(airlaunch_exe, nml_variant(tmp_path, what, edits=edits, line=line), "--output", out)
    assert res.returncode == 0, res.stderr
    ds = xr.open_dataset(out)
    assert ds.attrs["status"] == "completed"
    assert ds.time.values[-1] == t_end
    if what == "release":
        assert ds.attrs["release_time_s"] == t_ev and ds.phase.values[-1] == 1
    if what == "break":
        assert ds.attrs["line_break_time_s"] == t_ev and ds.attrs["line_breaks"] == 1
