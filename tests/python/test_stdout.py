"""What the programs print must reach the standard output, or they say so.

gfortran's buffered unit 6 drops write errors without a word: before, `airlaunch
--check scenario.nml > resolved.nml` on a full disk exited 0 with a truncated
(or empty) resolved input, and a run's summary could be lost the same way.  The
programs now print by write(2) and end with exit 4 and one line on stderr when
a byte did not reach its destination (docs/output.md, "Exit status").  The
reference for each case is the same command with its standard output to a
file: exit 0 and the text in the file, so the failure is the device's."""
import os
import pathlib
import subprocess

import pytest
import xarray as xr

from conftest import BIN, PAPER

FULL = pathlib.Path("/dev/full")   # every write fails with ENOSPC
pytestmark = pytest.mark.skipif(not FULL.exists(), reason="no /dev/full on this system")


def _run(args, stdout, cwd):
    return subprocess.run([str(a) for a in args], stdout=stdout, stderr=subprocess.PIPE, text=True,
                          cwd=cwd, timeout=300, env=dict(os.environ))


def _closed_stdout():
    os.close(1)


CASES = {
    "check": (["airlaunch", PAPER, "--check", "--output", "run.nc"], "the resolved input printed is incomplete"),
    "help": (["airlaunch", "--help"], "the usage is incomplete"),
    "version": (["airlaunch", "--version"], "the version is incomplete"),
    "sweep version": (["airlaunch-sweep", "--version"], "what it printed is incomplete"),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_a_full_standard_output_is_an_error(tmp_path, case):
    """To a file: exit 0 and the text there.  To /dev/full: exit 4, one line
    on stderr naming the standard output, the reason and what is
    incomplete, and nothing else."""
    args, what = CASES[case]
    args = [BIN / args[0], *args[1:]]
    with open(tmp_path / "out.txt", "w") as out:
        ok = _run(args, out, tmp_path)
    assert ok.returncode == 0 and ok.stderr == "", ok.stderr
    assert len((tmp_path / "out.txt").read_text()) > 10
    with open(FULL, "w") as full:
        res = _run(args, full, tmp_path)
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 4 and len(lines) == 1, res.stderr
    prog = args[0].name
    assert lines[0] == (f"{prog}: error: the standard output could not be written "
                        f"(write: No space left on device; {what})"), lines[0]


def test_a_closed_standard_output_is_an_error(tmp_path):
    """stdout closed by the caller (`airlaunch ... >&-`): exit 4, the reason
    is the bad descriptor."""
    res = subprocess.run([str(BIN / "airlaunch"), "--version"], stderr=subprocess.PIPE, text=True,
                         preexec_fn=_closed_stdout, timeout=60)
    assert res.returncode == 4, res.stderr
    assert "the standard output could not be written (write: Bad file descriptor" in res.stderr, res.stderr


def test_a_run_whose_summary_is_lost_keeps_its_file(tmp_path):
    """A run to a full stdout: its file is written whole (status completed,
    the same milestones as a run that printed them), exit 4, and the one
    line says the run completed and where its output is."""
    out = tmp_path / "run.nc"
    with open(FULL, "w") as full:
        res = _run([BIN / "airlaunch", PAPER, "--output", out], full, tmp_path)
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 4 and len(lines) == 1, res.stderr
    assert lines[0].endswith(f"; the run completed, its output is {out})"), lines[0]
    ref = tmp_path / "ref.nc"
    with open(tmp_path / "summary.txt", "w") as text:
        assert _run([BIN / "airlaunch", PAPER, "--output", ref], text, tmp_path).returncode == 0
    with xr.open_dataset(out) as a, xr.open_dataset(ref) as b:
        assert a.attrs["status"] == "completed"
        for name in ("separation_time_s", "pitch_max_deg", "min_clearance_m"):
            assert a.attrs[name] == b.attrs[name], name
    assert "separation" in (tmp_path / "summary.txt").read_text()
