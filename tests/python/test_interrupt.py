"""Runs stopped before their end on the user's behalf.

Ctrl-C (SIGINT) or SIGTERM (kill, a batch system's time limit) during a
single run: the integrator stops between two steps, the output so far is
written whole with status "interrupted" and the failure naming the signal and
the time, the lock and the .part are gone, and the program exits 128 + the
signal, as the signal's default action would (docs/output.md).  Before, the
process died at once: no output, a stale OUTPUT.part and OUTPUT.part.lock.

&run max_wall_time: an integrator that has run that long stops the run as a
numerical failure (exit 3), as the step budget &run max_steps does."""
import re
import signal
import subprocess
import time

import pytest
import xarray as xr

from conftest import ROOT, nml_variant

#: the pendulum of input/line_pendulum.nml at 100 segments over 6000 s: minutes of work
SLOW_LINE = [("  t_end = 6.0 ", "  t_end = 6000.0 "), ("  n_seg = 10\n", "  n_seg = 100\n")]
#: the paper scenario at 240 segments and rtol 1e-9, atol 1e-10: ~15 s on this machine
SLOW_LAUNCH = [(r"^  rtol = 1.0e-5 .*$", "  rtol = 1.0e-9"), (r"^  atol = 1.0e-6 .*$", "  atol = 1.0e-10"),
               (r"^  n_seg = 15 .*$", "  n_seg = 240")]


def _interrupted_run(exe, nml, out, signo):
    proc = subprocess.Popen([str(exe), str(nml), "--output", str(out)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    time.sleep(1.0)
    assert proc.poll() is None, "the run ended before the signal: make it longer"
    proc.send_signal(signo)
    try:
        stdout, stderr = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        proc.kill()
        pytest.fail("no end within 60 s of the signal")
    return proc.returncode, stdout, stderr


def _check(exe, nml, out, signo, name):
    code, stdout, stderr = _interrupted_run(exe, nml, out, signo)
    assert code == 128 + signo, (code, stderr)
    lines = stderr.strip().splitlines()
    assert len(lines) == 2, lines
    m = re.search(rf"interrupted by {name} at t = ([0-9.]+) s$", lines[0])
    assert lines[0].startswith("airlaunch: ") and m, lines[0]
    assert lines[1] == f"airlaunch: output so far (status=interrupted): {out}", lines[1]
    t_stop = float(m.group(1))
    with xr.open_dataset(out) as ds:
        assert ds.attrs["status"] == "interrupted"
        assert f"interrupted by {name}" in ds.attrs["failure"]
        t = ds["time"].values
        # every output time the integrator passed was recorded (the record at
        # t = 0 at least): the stop lies within one output interval after the
        # last record - the integrator polls before a step towards the next
        # output time, which it has not reached
        output_dt = float(re.search(r"OUTPUT_DT=\s*([0-9.Ee+-]+)", ds.attrs["input_namelist"].upper()).group(1))
        assert t[0] == 0.0 and t[-1] <= t_stop + 1e-9 < t[-1] + output_dt, (t[-1], t_stop, output_dt)
    leftovers = sorted(p.name for p in out.parent.iterdir() if p.name.startswith(out.name + "."))
    assert leftovers == [], leftovers
    return t_stop


def test_sigint_ends_the_line_scene_with_its_output(airlaunch_exe, tmp_path):
    text = (ROOT / "input" / "line_pendulum.nml").read_text()
    for old, new in SLOW_LINE:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    nml = tmp_path / "slow_line.nml"
    nml.write_text(text)
    t_stop = _check(airlaunch_exe, nml, tmp_path / "line.nc", signal.SIGINT, "SIGINT")
    assert 0.0 <= t_stop < 6000.0
    # docs/line.md lists the line scene's status values: "interrupted" among them (it gave
    # "completed" | "failed" only: an audit of the output files, thirty-second session)
    doc = (ROOT / "docs" / "line.md").read_text()
    listed = re.search(r"`status`\s*\(([^)]*)\)", doc)
    assert listed and '"interrupted"' in listed.group(1), listed and listed.group(1)


def test_sigterm_ends_the_launch_scene_with_its_output(airlaunch_exe, tmp_path):
    nml = nml_variant(tmp_path, "slow_launch", edits=SLOW_LAUNCH)
    t_stop = _check(airlaunch_exe, nml, tmp_path / "launch.nc", signal.SIGTERM, "SIGTERM")
    assert 0.0 <= t_stop < 15.0   # (0: the signal came during the set-up, seen at the first step)


def test_wall_time_budget_stops_a_crawling_run(airlaunch_exe, tmp_path):
    """&run max_wall_time: the paper scenario with a pitch-rate gain so high
    (k_q = 1e30) that the elevator chatters at its limit from the release and
    CVODE crawls at steps of ~2e-7 s (input.md, max_steps: 146 s before the
    step budget stops it) ends once its integrator has run 1 s: exit 3, one
    line naming the phase, the time, the budget and the state with the largest
    local error estimate, the output so far with status "failed".  The process
    cannot end before the budget (its integrator alone takes it) and ends well
    before the step budget would have stopped it (30 s allowed for a loaded
    machine's start-up and output)."""
    nml = nml_variant(tmp_path, "crawl", edits=[(r"^  k_q = 2.0 .*$", "  k_q = 1.0e30"),
                                               (r"^(  t_end = 15.0 .*)$", r"\1\n  max_wall_time = 1.0")])
    out = tmp_path / "crawl.nc"
    start = time.monotonic()
    res = subprocess.run([str(airlaunch_exe), str(nml), "--output", str(out)], capture_output=True, text=True,
                         timeout=120)
    wall = time.monotonic() - start
    assert res.returncode == 3, res.stderr
    first = res.stderr.strip().splitlines()[0]
    assert re.search(r"phase \d .*t = [0-9.]+ s: the wall-time budget is spent \(1\.0 s since the run started; "
                     r"this integrator took \d+ steps, &run max_wall_time\); step size .* largest local error "
                     r"estimate in ", first), first
    assert 1.0 <= wall < 30.0, wall
    with xr.open_dataset(out) as ds:
        assert ds.attrs["status"] == "failed" and "wall-time budget" in ds.attrs["failure"]


def test_wall_time_budget_refuses_a_negative_value(airlaunch_exe, tmp_path):
    nml = nml_variant(tmp_path, "negative", edits=[(r"^(  t_end = 15.0 .*)$", r"\1\n  max_wall_time = -1.0")])
    out = tmp_path / "never.nc"
    res = subprocess.run([str(airlaunch_exe), str(nml), "--output", str(out)], capture_output=True, text=True,
                         timeout=60)
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "&run: max_wall_time = -1.0 is not allowed" in lines[0], lines
    assert not out.exists()
