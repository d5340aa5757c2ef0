"""airlaunch-sweep's file errors while running (docs/sweep.md: exit status 4):
a case's scratch namelist that cannot be written, a journal row or the
journal's fingerprint lost to a full disk, a trajectory that cannot be written.
Each stops the sweep with one line naming the file and exit status 4, records
nothing false in the journal, and a rerun once the cause is gone ends with
every case ok."""
import os
import pathlib
import shutil
import subprocess
import zlib

import pytest

from test_sweep_support import SWEEP_EXE, journal_rows, make_table, run_sweep, small_definition


@pytest.fixture(scope="module")
def exes():
    if not SWEEP_EXE.exists():
        pytest.fail(f"{SWEEP_EXE} is missing: run scripts/setup release first")


def _errors(res):
    """The program's own error lines (mpirun adds its banner for a non-zero exit)."""
    return [x for x in res.stderr.splitlines() if x.startswith("airlaunch-sweep:")]


def _statuses(journal_dir):
    """Status field of every valid journal row."""
    out = []
    for path in sorted(pathlib.Path(journal_dir).glob("rank_*.txt")):
        for line in path.read_text().splitlines():
            head, _, body = line.partition(" ")
            if len(head) == 8 and int(head, 16) == zlib.adler32(body.encode()):
                out.append(int(body.split()[1]))
    return out


def test_unwritable_case_namelist_stops_the_sweep(tmp_path, exes):
    """A directory in the way of the ranks' scratch namelists: every case was
    journaled as invalid_input ("cannot write the file") and the sweep ended
    with status 0; a rerun kept the false rows.  Now the first such case stops
    the sweep (exit 4, one line naming the file), no row is written for it,
    and the rerun runs every case."""
    definition = small_definition(tmp_path / "s.nml", n_cases=12)
    make_table(definition, tmp_path)
    work = tmp_path / "out" / "work"
    for r in (0, 1):   # both ranks: whichever takes a case meets the error
        (work / f"case_rank{r}.nml").mkdir(parents=True)
    res = run_sweep(definition, tmp_path, 2)
    assert res.returncode == 4, res.stdout + res.stderr
    errors = _errors(res)
    assert len(errors) == 1 and "case_rank" in errors[0] and "cannot write" in errors[0], res.stderr
    assert "invalid input" not in res.stdout, res.stdout
    assert not (tmp_path / "out" / "summary.nc").exists()
    assert _statuses(tmp_path / "out" / "journal") == [], "a file error was journaled as a result"
    for r in (0, 1):
        (work / f"case_rank{r}.nml").rmdir()
    res = run_sweep(definition, tmp_path, 2)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "12 cases: 12 ok, 0 failed, 0 invalid input; 12 run now" in res.stdout, res.stdout
