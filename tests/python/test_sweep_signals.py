"""Stopping a sweep's steps by a signal (docs/sweep.md, "Interrupting a step"):
Ctrl-C (SIGINT) or SIGTERM to a Python step is one line and exit status 130 or
143, not a traceback, and leaves no file cut short under its final name nor a
child process running; SIGTERM to scripts/sweep or scripts/sweep.slurm alone
reaches mpirun and its ranks (they are in process groups of their own)."""
import os
import pathlib
import signal
import subprocess
import sys
import time

import pytest

from test_sweep_support import ENV, ROOT, SWEEP_EXE, make_table, run_sweep, small_definition

CRITERIA = f"criteria = '{ROOT}/input/criteria_paper.nml'"


def _start(cmd, cwd, env=ENV):
    """A process with SIGINT's default action (a background job of a
    non-interactive shell, or its children, would ignore it)."""
    return subprocess.Popen([str(c) for c in cmd], cwd=cwd, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def _wait_for(predicate, timeout=60.0, what="the step to start"):
    t0 = time.monotonic()
    while not predicate():
        if time.monotonic() - t0 > timeout:
            pytest.fail(f"timed out waiting for {what}")
        time.sleep(0.05)


def _alive(pid):
    try:
        return pathlib.Path(f"/proc/{pid}/stat").read_text().split(")")[-1].split()[0] != "Z"
    except OSError:
        return False


def _fake_exe(directory, name, pid_dir):
    """An executable that records its pid (one file per process) and sleeps."""
    directory.mkdir(parents=True, exist_ok=True)
    pid_dir.mkdir(parents=True, exist_ok=True)
    path = directory / name
    path.write_text(f"#!/bin/sh\necho $$ > {pid_dir}/$$\nexec sleep 120\n")
    path.chmod(0o755)
    return path


def _pids(pid_dir):
    return [int(p.name) for p in pid_dir.iterdir()]


def test_interrupted_table_step_is_one_line_and_leaves_no_table(tmp_path):
    """Ctrl-C during the table step (here while it waits for airlaunch-sweep
    --check) printed a KeyboardInterrupt traceback. Now: `sweep: interrupted`,
    exit 130, no table.nc (the earlier one is removed before the check, and
    no new one is written) nor .part, and the check's process is gone."""
    definition = small_definition(tmp_path / "d.nml", n_cases=4)
    make_table(definition, tmp_path)   # an earlier table
    assert (tmp_path / "out" / "table.nc").exists()
    pid_dir = tmp_path / "pids"
    _fake_exe(tmp_path / "bin", "airlaunch-sweep", pid_dir)
    proc = _start([sys.executable, "-m", "postproc.sweep", "table", definition, "--exe-dir", tmp_path / "bin"],
                  tmp_path)
    _wait_for(lambda: pid_dir.exists() and _pids(pid_dir))
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, out + err
    assert err == "sweep: interrupted\n", err
    assert not (tmp_path / "out" / "table.nc").exists() and not list((tmp_path / "out").glob("table.nc*.part"))
    _wait_for(lambda: not any(_alive(p) for p in _pids(pid_dir)), 10, "the check's process to end")


def test_terminated_verify_ends_its_reruns(tmp_path):
    """SIGTERM during verify ended Python by the signal and left the refined
    runs going (Ctrl-C waited for every queued case in the thread pool). Now:
    one line, exit 143, the runs in flight are ended and no other starts, no
    verify.nc."""
    if not SWEEP_EXE.exists():
        pytest.fail(f"{SWEEP_EXE} is missing: run scripts/setup release first")
    definition = small_definition(tmp_path / "d.nml", n_cases=6, extra_sweep=CRITERIA)
    make_table(definition, tmp_path)
    assert run_sweep(definition, tmp_path, None).returncode == 0
    bin_dir, pid_dir = tmp_path / "bin", tmp_path / "pids"
    _fake_exe(bin_dir, "airlaunch", pid_dir)
    (bin_dir / "airlaunch-sweep").symlink_to(SWEEP_EXE)
    proc = _start([sys.executable, "-m", "postproc.sweep", "verify", definition, "--ids", "0,1,2,3,4,5",
                   "--jobs", "2", "--exe-dir", bin_dir], tmp_path)
    _wait_for(lambda: pid_dir.exists() and len(_pids(pid_dir)) == 2, what="two reruns")
    proc.send_signal(signal.SIGTERM)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, out + err
    assert err == "sweep: interrupted (SIGTERM)\n", err
    assert len(_pids(pid_dir)) == 2, "a queued rerun started after the signal"
    _wait_for(lambda: not any(_alive(p) for p in _pids(pid_dir)), 10, "the reruns to end")
    assert not (tmp_path / "out" / "verify.nc").exists()


def test_figure_writes_are_atomic_and_name_the_file(tmp_path):
    """A figure cut short (an interrupt, a full disk) stays under .part only,
    and is removed; savefig's OSError without a file name (a full disk) names
    the figure: the envelope step blamed the figures directory instead."""
    import errno

    from postproc.sweep.figures import write_atomic

    target = tmp_path / "margins.png"

    def cut_short(exc):
        def write(tmp):
            pathlib.Path(tmp).write_bytes(b"\x89PNG half")
            raise exc
        return write

    with pytest.raises(KeyboardInterrupt):
        write_atomic(target, cut_short(KeyboardInterrupt()))
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(OSError) as info:
        write_atomic(target, cut_short(OSError(errno.ENOSPC, "No space left on device")))
    assert info.value.filename == str(target) and info.value.strerror == "No space left on device"
    assert list(tmp_path.iterdir()) == []
    write_atomic(target, lambda tmp: pathlib.Path(tmp).write_bytes(b"whole"))
    assert [p.name for p in tmp_path.iterdir()] == ["margins.png"] and target.read_bytes() == b"whole"


def _fake_srun(directory):
    """srun for a machine without Slurm: mpirun with this machine's flags, and
    srun's signals as its manual gives them: SIGTERM goes on to the tasks; a
    single SIGINT only reports the tasks' status and the step goes on (a second
    within one second ends it), unless --quit-on-interrupt ("quit immediately
    on single SIGINT")."""
    directory.mkdir(parents=True, exist_ok=True)
    flags = "--allow-run-as-root " if os.geteuid() == 0 else ""
    path = directory / "srun"
    path.write_text(f"""#!/bin/bash
quit=0
while [[ "$1" == --* ]]; do [ "$1" = --quit-on-interrupt ] && quit=1; shift; done   # --mpi=pmix, ...
mpirun {flags}--oversubscribe -np 2 "$@" &
pid=$!
trap 'kill -TERM $pid' TERM
trap 'if [ $quit = 1 ]; then kill -TERM $pid; else echo "srun: interrupt (one more within 1 sec to abort)" >&2; fi' INT
while :; do
  wait $pid; rc=$?
  kill -0 $pid 2>/dev/null || exit $rc
done
""")
    path.chmod(0o755)


@pytest.mark.parametrize("script, sig", [("sweep", signal.SIGTERM), ("sweep.slurm", signal.SIGTERM),
                                         ("sweep.slurm", signal.SIGINT)])
def test_term_to_the_script_reaches_the_ranks(tmp_path, script, sig):
    """kill -TERM to scripts/sweep (or the batch script) alone ended the script
    and left mpirun and its ranks running to the end of the sweep (Slurm's
    time-limit SIGTERM did not stop the ranks). Now the signal is passed on:
    the ranks end at once, the script exits with 143 and a rerun resumes.
    SIGINT to the batch script reached srun, which takes a single SIGINT as a
    request for the tasks' status and goes on: the script waited for every
    case. It now runs srun --quit-on-interrupt, and ends with 130 at once."""
    if not SWEEP_EXE.exists():
        pytest.fail(f"{SWEEP_EXE} is missing: run scripts/setup release first")
    out = tmp_path / "out"
    definition = small_definition(tmp_path / "d.nml", n_cases=1000, output_dir=out, extra_sweep=CRITERIA)
    env = dict(ENV)
    if script == "sweep":
        cmd, cwd = [ROOT / "scripts" / "sweep", definition, "-n", "2", "--step", "run"], tmp_path
        make_table(definition, tmp_path)
    else:
        _fake_srun(tmp_path / "bin")
        env["PATH"] = f"{tmp_path / 'bin'}:{env['PATH']}"
        cmd, cwd = ["bash", ROOT / "scripts" / "sweep.slurm", definition], ROOT
    proc = _start(cmd, cwd, env)
    journal = out / "journal"

    def rows():
        return sum(len(p.read_text().splitlines()) for p in journal.glob("rank_*.txt")) if journal.is_dir() else 0

    _wait_for(lambda: rows() >= 20 or proc.poll() is not None, 120, "the first rows")
    assert proc.poll() is None, proc.communicate()
    proc.send_signal(sig)
    stdout, stderr = proc.communicate(timeout=60)
    assert rows() < 1000, f"after {sig.name} the ranks went on to the end of the sweep"
    assert proc.returncode == 128 + sig, stdout + stderr
    assert f"stopped by {sig.name}" in stderr.splitlines()[-1], stderr
    ranks = subprocess.run(["pgrep", "-f", f"airlaunch-sweep {definition}"], capture_output=True, text=True)
    assert ranks.stdout == "", f"ranks still running: {ranks.stdout}"
    n = rows()
    assert 0 < n < 1000 and not (out / "summary.nc").exists()
    time.sleep(1.0)
    assert rows() == n, "the ranks went on after the script ended"
    if sig == signal.SIGINT:
        return   # the resume is the SIGTERM cases' (the journal is the same)
    res = run_sweep(definition, tmp_path, 2)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "resuming:" in res.stdout and "1000 cases: 1000 ok" in res.stdout, res.stdout


def test_the_batch_script_names_what_it_misses_in_one_line(tmp_path):
    """scripts/sweep.slurm submitted from another directory, or run outside
    Slurm, ended with bash's 'command not found' (exit 127) after its first
    step's name; now one line says what is missing and what to do, exit 2,
    before any step runs."""
    script = str(ROOT / "scripts" / "sweep.slurm")
    definition = small_definition(tmp_path / "d.nml", n_cases=2)
    res = subprocess.run(["bash", script, str(definition)], cwd=tmp_path, capture_output=True, text=True,
                         env=ENV, timeout=60)
    assert res.returncode == 2 and res.stderr.count("\n") == 1, res.stderr
    assert f"{tmp_path}/.venv/bin/python is missing: submit from the repository root" in res.stderr
    no_srun = dict(ENV, PATH="/usr/bin:/bin")
    assert subprocess.run(["sh", "-c", "command -v srun"], env=no_srun, capture_output=True).returncode != 0
    res = subprocess.run(["bash", script, str(definition)], cwd=ROOT, capture_output=True, text=True,
                         env=no_srun, timeout=60)
    assert res.returncode == 2 and res.stderr.count("\n") == 1, res.stderr
    assert "srun is not on PATH" in res.stderr and "scripts/sweep" in res.stderr
    assert not (tmp_path / "out").exists()


def test_two_writers_of_one_file_each_rename_a_whole_file(tmp_path):
    """Two steps writing the same file at once (two envelope runs on one
    sweep): with a shared PATH.part the second writer truncated the first
    one's temporary file, and the first one's rename put the second one's
    half-written bytes under the final name, then its own rename failed.
    Now each call writes under a name of its own.  Reference: whatever the
    interleaving, the final file is one writer's whole content and both
    calls succeed.  Threads force the interleaving (the first writer pauses
    after half its bytes until the second has renamed)."""
    import threading

    from postproc.sweep.files import write_atomic

    target = tmp_path / "envelope.nc"
    half_written, second_done = threading.Event(), threading.Event()
    errors = []

    def first(tmp):
        with open(tmp, "w") as f:
            f.write("A" * 1000)
            f.flush()
            half_written.set()
            assert second_done.wait(10)
            f.write("A" * 1000)

    def second(tmp):
        assert half_written.wait(10)
        pathlib.Path(tmp).write_text("B" * 2000)

    def run(writer, done=None):
        try:
            write_atomic(target, writer)
        except BaseException as exc:   # reported below: a thread's exception is lost otherwise
            errors.append(exc)
        finally:
            if done is not None:
                done.set()

    threads = [threading.Thread(target=run, args=(first,)), threading.Thread(target=run, args=(second, second_done))]
    for t in threads:
        t.start()
    for t in threads:
        t.join(20)
    assert errors == []
    assert target.read_text() in ("A" * 2000, "B" * 2000)
    assert [p.name for p in tmp_path.iterdir()] == ["envelope.nc"]
