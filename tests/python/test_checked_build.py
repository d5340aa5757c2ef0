"""The Checked build's program (-fcheck=all, floating-point traps on invalid,
division by zero and overflow: scripts/setup checked) runs every example input
to its end and prints the Release build's milestones.

Until the nineteenth session the air-launch examples died there with SIGFPE
at the release (0.72 s): the solver cleared CVODE's stop time by moving it to
huge(1.0), and CVODE's stop-time test (t_n + h - t_stop) h overflowed -
harmless in Release, where nothing traps, but it hid whatever else a trap
would have caught in a whole run.  The milestones are compared as printed (3
to 9 digits; the integration statistics line is left out, as optimisation
levels may round differently); measured: every line the same, step counts
included.  Also the paper scenario in a gust, rigidized, and with its line
cut at 2 s (a breaking strength watched too).  Neither build reports a runtime
warning (thirty-fourth session: the ground event's lowest-point test and the
constraint wrench's output each made an array temporary, which the Checked
build reported on every event evaluation and write)."""
import re

import pytest

from conftest import BIN, PAPER, ROOT, nml_variant, run_airlaunch

CHECKED = ROOT / "build" / "checked" / "bin" / "airlaunch"
EXAMPLES = sorted(p.name for p in (ROOT / "input").glob("*.nml")
                  if not p.name.startswith(("sweep_", "criteria_")))


def printed(exe, nml, out):
    res = run_airlaunch(exe, nml, "--output", out)
    assert res.returncode == 0, (exe, res.returncode, res.stderr[-2000:])
    # -fcheck=all reports each array temporary made for an argument (a copy
    # of a strided section, on the heap when its size is not known): none
    assert "Fortran runtime warning" not in res.stderr, (exe, res.stderr[-2000:])
    return [line for line in res.stdout.splitlines()
            if not line.startswith(("output:", "integration:")) and "wall" not in line
            and not re.search(r"\(completed\), \d+ steps", line)]


@pytest.fixture(scope="module")
def checked_exe():
    if not CHECKED.exists():
        pytest.fail(f"{CHECKED} is missing: run scripts/setup checked first")
    return CHECKED


@pytest.mark.parametrize("example", EXAMPLES + ["airlaunch_paper.nml in a gust", "airlaunch_paper.nml rigidized",
                                     "airlaunch_paper.nml line cut"])
def test_checked_build_runs_the_example(checked_exe, tmp_path, example):
    name = example.split()[0]
    line = {"rigidized": ("  coupling = 'rigidized'",),
            "cut": ("  breaking_strength = 300.0e3", "  break_time = 2.0")}.get(example.split()[-1], ())
    nml = nml_variant(tmp_path, "case", base=ROOT / "input" / name, line=line)
    if example.endswith("gust"):
        nml.write_text(nml.read_text() + "&gust vertical = -16.6, gradient_length = 60.0, hit_time = 3.0 /\n")
    assert printed(checked_exe, nml, tmp_path / "c.nc") == printed(BIN / "airlaunch", nml, tmp_path / "r.nc")


def test_checked_build_runs_a_small_vehicle(checked_exe, tmp_path):
    """A 1:20 model of the paper scenario (test_other_vehicles.froude_scaled:
    a 0.925 m rocket with fins of 0.05 m sweep, s = 0.05) through separation
    to its first pitch maximum, in both builds.  Free flight passes the rocket
    aerodynamics an edge at huge(1.0) (nothing shields), and the exposed
    length's share (x_shield - x_tail)/length and the fins' s_e/x_r
    overflowed for a rocket under 1 m and a sweep under 1 m: the Checked
    build died with SIGFPE at the separation (thirty-fifth session; the
    paper's 18.5 m rocket and 1 m sweep never reached it)."""
    from test_other_vehicles import froude_scaled
    nml = froude_scaled(tmp_path, "model", 0.05, {("run", "t_end"): 2.5})
    assert printed(checked_exe, nml, tmp_path / "c.nc") == printed(BIN / "airlaunch", nml, tmp_path / "r.nc")
