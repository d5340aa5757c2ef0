"""airlaunch-sweep's file errors while running (docs/sweep.md: exit status 4):
a case's scratch namelist that cannot be written, a journal row or the
journal's fingerprint lost to a full disk, a trajectory that cannot be written.
Each stops the sweep with one line naming the file and exit status 4, records
nothing false in the journal, and a rerun once the cause is gone ends with
every case ok.  Also: --restart removes every kept trajectory, and a torn
journal line whose case has run again is not reported again."""
import contextlib
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


# --- a full disk: a small tmpfs (root only) -----------------------------------

PAGE = 4096
TMPFS_PAGES = 16


@contextlib.contextmanager
def small_tmpfs(path, free_pages, pages=TMPFS_PAGES):
    """A tmpfs of `pages` pages (default 64 KiB) mounted at `path` with
    `free_pages` pages left free (a filler file takes the rest); unmounted on
    exit.  Skips the test where mounting is impossible (not root, no tmpfs, a
    container without CAP_SYS_ADMIN)."""
    path = pathlib.Path(path)
    path.mkdir(parents=True, exist_ok=True)
    if os.geteuid() != 0 or shutil.which("mount") is None:
        pytest.skip("a full disk is made with a small tmpfs: needs root and mount(8)")
    res = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={pages * PAGE}", "tmpfs", str(path)],
                         capture_output=True, text=True)
    if res.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs to make a full disk: {res.stderr.strip()}")
    try:
        filler = path / ".filler"
        with open(filler, "wb") as f:
            f.write(b"\0" * ((pages - free_pages) * PAGE))
        st = os.statvfs(path)
        assert st.f_bavail * st.f_frsize == free_pages * PAGE, "the tmpfs does not count pages as expected"
        yield filler
    finally:
        if subprocess.run(["umount", str(path)], capture_output=True).returncode != 0:
            subprocess.run(["umount", "-l", str(path)], capture_output=True)


def test_full_disk_stops_the_sweep_at_the_first_lost_journal_row(tmp_path, exes):
    """The journal on a full disk: gfortran's buffered write, flush and close
    reported no error, rows were lost while the cases went on, and the loss was
    found only after the last case ("N cases have no row after the run").  Now
    the first row that cannot be written in full stops the sweep (exit 4, one
    line naming the journal file and ENOSPC); every row the journal holds is
    whole or torn (never a wrong row), and a rerun from it ends with every case."""
    n = 40
    definition = small_definition(tmp_path / "s.nml", n_cases=n)
    make_table(definition, tmp_path)
    journal = tmp_path / "out" / "journal"
    saved = tmp_path / "journal_saved"
    # 3 free pages: the fingerprint, and one page (about 5 rows) per rank file
    with small_tmpfs(journal, free_pages=3):
        res = run_sweep(definition, tmp_path, 2)
        shutil.copytree(journal, saved, ignore=shutil.ignore_patterns(".filler"))
    assert res.returncode == 4, res.stdout + res.stderr
    errors = _errors(res)
    assert len(errors) == 1, res.stderr
    assert "rank_000" in errors[0] and "No space left on device" in errors[0], errors[0]
    assert not (tmp_path / "out" / "summary.nc").exists()
    ids, _ = journal_rows(saved)
    assert 0 < len(ids) < n // 2, f"{len(ids)} rows: the sweep did not stop at the first lost row"
    assert len(set(ids)) == len(ids)
    # the journal kept on a real disk: the rerun resumes from its rows
    shutil.rmtree(journal)
    shutil.copytree(saved, journal)
    res = run_sweep(definition, tmp_path, 2)
    assert res.returncode == 0, res.stdout + res.stderr
    assert f"resuming: {len(ids)} of {n}" in res.stdout, res.stdout
    assert f"{n} cases: {n} ok" in res.stdout, res.stdout


def test_fingerprint_on_a_full_disk_is_an_error_and_leaves_no_empty_file(tmp_path, exes):
    """The fingerprint written to a full disk was left as a 0-byte file without
    an error, and every later run refused "fingerprints differ".  Now the run
    stops before any case (exit 4, one line naming the file and ENOSPC), no
    fingerprint is left, and once there is space the run ends with every case."""
    definition = small_definition(tmp_path / "s.nml", n_cases=4)
    make_table(definition, tmp_path)
    journal = tmp_path / "out" / "journal"
    with small_tmpfs(journal, free_pages=0) as filler:
        res = run_sweep(definition, tmp_path, 2)
        assert res.returncode == 4, res.stdout + res.stderr
        errors = _errors(res)
        assert len(errors) == 1 and "fingerprint.txt" in errors[0] and "No space left on device" in errors[0], \
            res.stderr
        assert "cases to run" not in res.stdout, res.stdout
        # the run's empty lock file (journal/lock, one run per output directory) needs no space
        assert sorted(p.name for p in journal.iterdir() if p.name != "lock") == [".filler"], \
            "a partial fingerprint was left"
        filler.unlink()
        res = run_sweep(definition, tmp_path, 2)
        assert res.returncode == 0, res.stdout + res.stderr
        assert "4 cases: 4 ok" in res.stdout, res.stdout
        assert (journal / "fingerprint.txt").stat().st_size > 0


def test_case_namelist_cut_by_a_full_disk_stops_the_sweep(tmp_path, exes):
    """A case namelist cut short by a full disk (gfortran: no error) could be
    read and run on the base's defaults: a wrong row.  Now the first case whose
    namelist cannot be written in full stops the sweep (exit 4, one line naming
    the namelist and ENOSPC) and nothing is journaled.  The tmpfs on work/
    leaves room for the ranks' check namelists (written before any case) and
    one page less than a case namelist needs."""
    definition = small_definition(tmp_path / "s.nml", n_cases=4)
    make_table(definition, tmp_path)
    res = run_sweep(definition, tmp_path, None, "--check")
    assert res.returncode == 0, res.stderr
    check_size = (tmp_path / "out" / "work" / "check_rank0.nml").stat().st_size
    res = run_sweep(definition, tmp_path, None, "--case-namelist", 0)
    case_size = len(res.stdout.encode())

    def pages(n):
        return -(-n // PAGE)

    shutil.rmtree(tmp_path / "out" / "work")
    with small_tmpfs(tmp_path / "out" / "work", free_pages=2 * pages(check_size) + pages(case_size) - 1):
        res = run_sweep(definition, tmp_path, 2)
    assert res.returncode == 4, res.stdout + res.stderr
    errors = _errors(res)
    assert len(errors) == 1 and "case_rank" in errors[0] and "No space left on device" in errors[0], res.stderr
    assert journal_rows(tmp_path / "out" / "journal")[0] == [], "a case was run from a cut namelist"


# --- trajectories ---------------------------------------------------------------

def test_unwritable_trajectories_are_an_error_not_written_files(tmp_path, exes):
    """Directories in the way of the kept trajectories (their .part names): the
    sweep printed "trajectories: 3 written", exit 0, and no file existed.  Now
    the write failure stops the pass (exit 4, one line naming the file); once
    the way is clear, the rerun writes them and counts the files it wrote."""
    definition = small_definition(tmp_path / "s.nml", n_cases=12, extra_sweep="keep_ids = 1, 2, 3")
    make_table(definition, tmp_path)
    traj = tmp_path / "out" / "trajectories"
    for k in (1, 2, 3):
        (traj / f"case_{k:06d}.nc.part").mkdir(parents=True)
    res = run_sweep(definition, tmp_path, 2)
    assert res.returncode == 4, res.stdout + res.stderr
    errors = _errors(res)
    assert len(errors) == 1 and ".nc.part" in errors[0] and "trajector" in errors[0], res.stderr
    assert "written" not in res.stdout, res.stdout
    assert sorted(p.name for p in traj.glob("*.nc")) == []
    for k in (1, 2, 3):
        (traj / f"case_{k:06d}.nc.part").rmdir()
    res = run_sweep(definition, tmp_path, 2)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "trajectories: 3 written" in res.stdout, res.stdout
    assert sorted(p.name for p in traj.glob("*.nc")) == [f"case_{k:06d}.nc" for k in (1, 2, 3)]


def test_directories_in_place_of_the_summary_or_a_trajectory_are_errors_on_every_rerun(tmp_path, exes):
    """A directory named summary.nc, or named like a kept trajectory: the first
    run ends with exit 4 naming it; so must the rerun, which has no case left
    to run.  An audit found the rerun taking the directory for the journal's
    summary ("left as it is", exit 0, no summary) and for a written trajectory
    (nothing written, nothing said, exit 0).  Once the way is clear, the rerun
    writes both."""
    definition = small_definition(tmp_path / "s.nml", n_cases=4, extra_sweep="keep_ids = 1")
    make_table(definition, tmp_path)
    out = tmp_path / "out"
    (out / "summary.nc").mkdir(parents=True)
    for attempt in ("first", "rerun"):
        res = run_sweep(definition, tmp_path, 1)
        assert res.returncode == 4, (attempt, res.stdout + res.stderr)
        errors = _errors(res)
        assert len(errors) == 1 and "summary.nc" in errors[0], (attempt, res.stderr)
        assert "left as it is" not in res.stdout
    (out / "summary.nc").rmdir()
    (out / "trajectories" / "case_000001.nc").mkdir(parents=True)
    res = run_sweep(definition, tmp_path, 1)
    assert res.returncode == 4, res.stdout + res.stderr
    assert (out / "summary.nc").is_file()
    errors = _errors(res)
    assert len(errors) == 1 and "case_000001.nc" in errors[0], res.stderr
    (out / "trajectories" / "case_000001.nc").rmdir()
    res = run_sweep(definition, tmp_path, 1)
    assert res.returncode == 0 and "trajectories: 1 written" in res.stdout, res.stdout + res.stderr
    assert (out / "trajectories" / "case_000001.nc").is_file()


def test_restart_removes_every_kept_trajectory(tmp_path, exes):
    """--restart removed the kept trajectories only for ids below the new
    sweep's n_cases: a restart with fewer cases left the earlier sweep's
    case_000010.nc beside the new ones.  Now every case file goes (a stray
    .part too); other files in the directory stay."""
    definition = small_definition(tmp_path / "s.nml", n_cases=12, extra_sweep="keep_ids = 1, 10")
    make_table(definition, tmp_path)
    res = run_sweep(definition, tmp_path, 2)
    assert res.returncode == 0, res.stdout + res.stderr
    traj = tmp_path / "out" / "trajectories"
    assert sorted(p.name for p in traj.iterdir()) == ["case_000001.nc", "case_000010.nc"]
    (traj / "case_000011.nc.part").write_text("an interrupted write\n")
    (traj / "notes.txt").write_text("not a case file\n")
    definition = small_definition(tmp_path / "s.nml", n_cases=4, seed=11)
    make_table(definition, tmp_path)
    res = run_sweep(definition, tmp_path, 2, "--restart")
    assert res.returncode == 0, res.stdout + res.stderr
    assert sorted(p.name for p in traj.iterdir()) == ["notes.txt"]


def test_torn_line_of_a_case_run_again_is_not_reported_again(tmp_path, exes):
    """"N torn journal lines ignored (their cases run again)" was printed on
    every later run, after those cases had run again.  Now a torn line whose
    case has a valid row is not counted; one whose case has none still is."""
    definition = small_definition(tmp_path / "s.nml", n_cases=4)
    make_table(definition, tmp_path)
    assert run_sweep(definition, tmp_path, None).returncode == 0
    rank0 = tmp_path / "out" / "journal" / "rank_0000.txt"
    lines = rank0.read_text().splitlines()
    # the row of the first case cut by a "kill" in its metrics: it ran again since
    rank0.write_text("\n".join(lines + [lines[0][:60]]) + "\n")
    res = run_sweep(definition, tmp_path, None)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "resuming: 4 of 4" in res.stdout and "torn" not in res.stdout, res.stdout
    # the row of the last case torn, with no whole row left: reported, and the case runs again
    rank0.write_text("\n".join(lines[:-1] + [lines[-1][:60]]) + "\n")
    res = run_sweep(definition, tmp_path, None)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "resuming: 3 of 4" in res.stdout and "1 torn journal lines ignored" in res.stdout, res.stdout


# --- the envelope step -------------------------------------------------------------

def _leave_free(filler, pages_free):
    """Resize the filler so that `pages_free` pages of its tmpfs stay free."""
    st = os.statvfs(filler.parent)
    free = st.f_bavail * st.f_frsize // PAGE
    size = filler.stat().st_size + (free - pages_free) * PAGE
    if size < filler.stat().st_size:
        os.truncate(filler, size)
    else:
        with open(filler, "ab") as f:
            f.write(b"\0" * (size - filler.stat().st_size))
    st = os.statvfs(filler.parent)
    assert st.f_bavail * st.f_frsize == pages_free * PAGE


def test_envelope_on_a_full_disk_names_the_file_and_the_reason(tmp_path, exes):
    """The envelope step on a full disk said "output_dir = ... is not usable:
    .../figures is a directory" (savefig's OSError names no file), and for
    envelope.nc only "NetCDF: HDF error". Now the line names the figure and
    "No space left on device", or envelope.nc with the likely cause; neither is
    left cut short under its final name (nor as .part)."""
    from test_sweep_support import ROOT, run_python

    sm = tmp_path / "sm"
    definition = small_definition(tmp_path / "s.nml", n_cases=6, output_dir="sm/out",
                                  extra_sweep=f"criteria = '{ROOT}/input/criteria_paper.nml'")
    with small_tmpfs(sm, free_pages=248, pages=256) as filler:
        make_table(definition, tmp_path)
        assert run_sweep(definition, tmp_path, None).returncode == 0
        out = sm / "out"
        res = run_python(["envelope", definition, "--no-figures"], tmp_path)
        assert res.returncode == 0, res.stdout + res.stderr
        envelope_pages = -(-(out / "envelope.nc").stat().st_size // PAGE)
        (out / "envelope.nc").unlink()
        _leave_free(filler, 2)
        res = run_python(["envelope", definition], tmp_path)
        assert res.returncode == 2, res.stdout + res.stderr
        line = res.stderr.strip()
        assert len(line.splitlines()) == 1, res.stderr
        assert "cannot write sm/out/envelope.nc: NetCDF: HDF error (likely: no space left on the device" in line, line
        assert not [p.name for p in out.iterdir() if p.name.startswith("envelope")]
        # room for envelope.nc, not for the first figure (tens of KiB)
        _leave_free(filler, envelope_pages + 2)
        res = run_python(["envelope", definition], tmp_path)
        assert res.returncode == 2, res.stdout + res.stderr
        line = res.stderr.strip()
        assert len(line.splitlines()) == 1, res.stderr
        assert "is not usable: cannot write sm/out/figures/passfail_map.png: No space left on device" in line, line
        assert "is a directory" not in line
        assert (out / "envelope.nc").is_file()
        assert sorted(p.name for p in (out / "figures").iterdir()) == []
        filler.unlink()
        res = run_python(["envelope", definition], tmp_path)
        assert res.returncode == 0, res.stdout + res.stderr
        assert not list(out.rglob("*.part"))


def test_an_os_reason_is_not_put_down_to_a_full_disk(tmp_path, monkeypatch):
    """On a read-only file system with less than 1 MiB free the table step said
    "cannot write OUT/table.nc: Read-only file system (likely: no space left on
    the device, 180224 bytes free)": the guess is for what netCDF says when its
    file does not fit ("NetCDF: HDF error", or "Permission denied" with almost
    nothing free, measured on a tmpfs), not for a read-only file system."""
    import errno

    from postproc.sweep import table

    monkeypatch.setattr(table, "free_space", lambda path: 4096)
    target = tmp_path / "table.nc"
    why = table.write_error_reason(target, OSError(errno.EROFS, os.strerror(errno.EROFS), str(target)))
    assert why == os.strerror(errno.EROFS), why
    hint = " (likely: no space left on the device, 4096 bytes free)"
    assert table.write_error_reason(target, RuntimeError("NetCDF: HDF error")) == "NetCDF: HDF error" + hint
    why = table.write_error_reason(target, PermissionError(errno.EACCES, "Permission denied", str(target)))
    assert why == "Permission denied" + hint, why
    assert table.write_error_reason(target, OSError(errno.ENOSPC, "x")) == os.strerror(errno.ENOSPC)


def test_case_namelist_of_a_sweep_that_cannot_be_written(exes, tmp_path):
    """--case-namelist is a query: it reads the definition, the base and the
    table and prints one case's namelist, so it must work on a finished sweep
    that cannot be written (an archive, a read-only mount; here a file where
    its work/ would be, which stops root too).  Reference: the same query
    while work/ could be made prints the same bytes, and makes nothing there.
    Its scratch check file goes to $TMPDIR and leaves nothing there (that
    it goes there: test_tmpdir.py).  --check still refuses the blocked sweep
    in one line naming output_dir: a run needs to write there."""
    definition = small_definition(tmp_path / "small.nml", n_cases=4)
    make_table(definition, tmp_path)
    ref = run_sweep(definition, tmp_path, None, "--case-namelist", 2)
    assert ref.returncode == 0, ref.stderr
    assert not (tmp_path / "out" / "work").exists()      # the query made nothing there
    (tmp_path / "out" / "work").write_text("not a directory\n")
    scratch = tmp_path / "tmpdir"
    scratch.mkdir()

    def query(tmpdir):
        env = dict(os.environ, TMPDIR=str(tmpdir), OPENBLAS_NUM_THREADS="1")
        return subprocess.run([str(SWEEP_EXE), str(definition), "--case-namelist", "2"], cwd=tmp_path,
                              capture_output=True, text=True, env=env, timeout=120)

    res = query(scratch)
    assert res.returncode == 0, res.stderr
    assert res.stdout == ref.stdout and "&run" in res.stdout
    assert list(scratch.iterdir()) == []
    res = run_sweep(definition, tmp_path, None, "--check")
    errors = _errors(res)
    assert res.returncode == 2 and len(errors) == 1 and "output_dir = 'out' is not usable" in errors[0], res.stderr
