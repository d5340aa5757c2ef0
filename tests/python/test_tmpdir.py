"""A full temporary directory ($TMPDIR, else /tmp: small on many cluster
nodes) must not change what the programs read or write, or must stop them
with one clear line.  gfortran puts its scratch files there and loses their
lines without an error when it is full: before, the resolved input a run
records (`input_namelist`) and `--check` prints came out empty, a file whose
last line has no newline read as if its groups were empty ("cannot read the
group: End of file"), and `airlaunch-sweep --case-namelist` failed with
"unknown group".  The reference for each case is the same command with an
ordinary $TMPDIR."""
import os
import subprocess

import pytest
import xarray as xr

from conftest import BIN, PAPER
from test_sweep_file_errors import small_tmpfs
from test_sweep_support import SWEEP_EXE, make_table, small_definition


@pytest.fixture
def full_tmpdir(tmp_path):
    """A $TMPDIR on a tmpfs with no page free (skipped where one cannot be mounted)."""
    with small_tmpfs(tmp_path / "fulltmp", free_pages=0) as filler:
        yield filler.parent


def _run(args, cwd, tmpdir):
    # Open MPI's singleton start-up keeps its session directory in $TMPDIR too:
    # give it its own, so that only the program's files meet the full one
    env = dict(os.environ, TMPDIR=str(tmpdir), OMPI_MCA_orte_tmpdir_base=str(cwd), OPENBLAS_NUM_THREADS="1")
    return subprocess.run([str(a) for a in args], cwd=cwd, capture_output=True, text=True, env=env, timeout=300)


def test_the_resolved_input_does_not_depend_on_tmpdir(tmp_path, full_tmpdir):
    """--check's printed input and a run's input_namelist attribute with a
    full $TMPDIR are those of an ordinary one, byte for byte (the echo is
    written in memory now)."""
    ok_tmp = tmp_path / "tmp"
    ok_tmp.mkdir()
    ref = _run([BIN / "airlaunch", PAPER, "--check", "--output", "c.nc"], tmp_path, ok_tmp)
    res = _run([BIN / "airlaunch", PAPER, "--check", "--output", "c.nc"], tmp_path, full_tmpdir)
    assert ref.returncode == 0 and res.returncode == 0, res.stderr
    assert res.stdout == ref.stdout and "&LINE" in res.stdout
    for name, tmpdir in (("full.nc", full_tmpdir), ("ok.nc", ok_tmp)):
        run = _run([BIN / "airlaunch", PAPER, "--output", name], tmp_path, tmpdir)
        assert run.returncode == 0, run.stderr
    with xr.open_dataset(tmp_path / "full.nc") as a, xr.open_dataset(tmp_path / "ok.nc") as b:
        echo_a = a.attrs["input_namelist"].replace("full.nc", "X")
        echo_b = b.attrs["input_namelist"].replace("ok.nc", "X")
        assert echo_a == echo_b and "&FLIGHT" in echo_a


def test_an_unterminated_file_with_a_full_tmpdir_is_one_clear_line(tmp_path, full_tmpdir):
    """A scenario whose last line has no newline is read through a terminated
    copy in $TMPDIR: with an ordinary one it runs; with a full one it stops
    in one line saying so (exit 2), not with an empty group."""
    nml = tmp_path / "unterminated.nml"
    nml.write_text("&run\n  scene = 'drop'\n  output = 'd.nc'\n/\n&store\n  mass = 100.0\n/")
    ok_tmp = tmp_path / "tmp"
    ok_tmp.mkdir()
    assert _run([BIN / "airlaunch", nml], tmp_path, ok_tmp).returncode == 0
    res = _run([BIN / "airlaunch", nml, "--output", "e.nc"], tmp_path, full_tmpdir)
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 2 and len(lines) == 1, res.stderr
    assert f"{nml}: its last line has no newline" in lines[0] and "is it full?" in lines[0], lines[0]
    assert not (tmp_path / "e.nc").exists()


def test_case_namelist_with_a_full_tmpdir(tmp_path, full_tmpdir):
    """airlaunch-sweep --case-namelist checks the base through a scratch file
    of its own in $TMPDIR (mkstemps, removed after): with a full one it stops
    in one line naming that file and the reason (exit 2) — which shows the
    file goes there — and leaves nothing; with an ordinary one it prints the
    case."""
    definition = small_definition(tmp_path / "small.nml", n_cases=4)
    make_table(definition, tmp_path)
    ok_tmp = tmp_path / "tmp"
    ok_tmp.mkdir()
    ok = _run([SWEEP_EXE, definition, "--case-namelist", "1"], tmp_path, ok_tmp)
    assert ok.returncode == 0 and "&run" in ok.stdout, ok.stderr
    assert list(ok_tmp.iterdir()) == []
    res = _run([SWEEP_EXE, definition, "--case-namelist", "1"], tmp_path, full_tmpdir)
    lines = [x for x in res.stderr.splitlines() if x.startswith("airlaunch-sweep:")]
    assert res.returncode == 2 and len(lines) == 1, res.stderr
    assert f"{full_tmpdir}/airlaunch_sweep_check_" in lines[0] and "No space left on device" in lines[0], lines[0]
    assert sorted(p.name for p in full_tmpdir.iterdir()) == [".filler"]
