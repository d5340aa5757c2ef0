"""airlaunch-sweep under mpirun: the summary does not depend on the number of
ranks; a sweep killed with SIGKILL mid-way and run again ends with every case
exactly once, identical to an uninterrupted run; failed and invalid cases are
recorded with their message while the sweep goes on, and every case is the
single run `airlaunch` gives for the same namelist; the whole chain runs from
scripts/sweep."""
import hashlib
import os
import re
import shutil
import signal
import subprocess
import time

import numpy as np
import pytest
import xarray as xr

from test_sweep_support import (AIRLAUNCH_EXE, ENV, ROOT, SWEEP_EXE, assert_same_summary, journal_rows,
                                make_table, mpirun, run_python, run_sweep, small_definition)

N_CASES = 40


@pytest.fixture(scope="module")
def exes():
    for exe in (SWEEP_EXE, AIRLAUNCH_EXE):
        if not exe.exists():
            pytest.fail(f"{exe} is missing: run scripts/setup release first")


@pytest.fixture(scope="module")
def small(tmp_path_factory, exes):
    """The small sweep's definition (output_dir relative: one directory per run)."""
    d = tmp_path_factory.mktemp("sweep")
    return small_definition(d / "small.nml", n_cases=N_CASES)


@pytest.fixture(scope="module")
def reference(small, tmp_path_factory):
    """The uninterrupted sweep on one rank: its summary."""
    cwd = tmp_path_factory.mktemp("ranks1")
    make_table(small, cwd)
    res = run_sweep(small, cwd, 1)
    assert res.returncode == 0, res.stdout + res.stderr
    assert f"{N_CASES} cases: {N_CASES} ok" in res.stdout, res.stdout
    return cwd / "out" / "summary.nc"


@pytest.mark.parametrize("ranks", [2, 3])
def test_rank_count_does_not_change_the_summary(small, reference, tmp_path, ranks):
    """Each case depends only on its inputs: 2 and 3 ranks (3 > the 2 cores:
    oversubscribed, so the work order differs) give the 1-rank summary bit for bit."""
    make_table(small, tmp_path)
    res = run_sweep(small, tmp_path, ranks)
    assert res.returncode == 0, res.stdout + res.stderr
    assert re.search(rf"{N_CASES} run now on {ranks} ranks", res.stdout), res.stdout
    ids, bad = journal_rows(tmp_path / "out" / "journal")
    assert sorted(ids) == list(range(N_CASES)) and bad == 0
    # the work really was shared: every rank wrote rows
    per_rank = [len((tmp_path / "out" / "journal" / f"rank_{r:04d}.txt").read_text().splitlines())
                for r in range(ranks)]
    assert all(n > 0 for n in per_rank), per_rank
    assert_same_summary(reference, tmp_path / "out" / "summary.nc")


def _session_pids(sid):
    """Processes of a session (mpirun and the ranks it started)."""
    pids = []
    for p in os.listdir("/proc"):
        if not p.isdigit():
            continue
        try:
            with open(f"/proc/{p}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[3]) == sid:
            pids.append(int(p))
    return pids


def test_killed_sweep_resumes_to_the_same_summary(small, reference, tmp_path):
    """SIGKILL to mpirun and every rank mid-way; the rerun of the same command
    skips the journaled cases, runs the rest once, and the summary equals the
    uninterrupted one (on one rank), and so does the envelope drawn from it."""
    make_table(small, tmp_path)
    journal = tmp_path / "out" / "journal"
    proc = subprocess.Popen(mpirun(2) + [str(SWEEP_EXE), str(small)], cwd=tmp_path, env=ENV,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    deadline = time.time() + 120
    while time.time() < deadline:
        if len(journal_rows(journal)[0]) >= N_CASES // 4:
            break
        time.sleep(0.01)
    pids = _session_pids(proc.pid)
    for pid in pids:
        os.kill(pid, signal.SIGKILL)
    proc.wait()
    assert proc.returncode == -signal.SIGKILL
    done_before, _ = journal_rows(journal)
    assert N_CASES // 4 <= len(done_before) < N_CASES, "the kill did not land mid-way"
    assert len(pids) >= 3, pids   # mpirun and both ranks were killed
    assert not (tmp_path / "out" / "summary.nc").exists()

    res = run_sweep(small, tmp_path, 2)
    assert res.returncode == 0, res.stdout + res.stderr
    assert f"resuming: {len(set(done_before))} of {N_CASES}" in res.stdout, res.stdout
    assert f"{N_CASES - len(set(done_before))} run now" in res.stdout, res.stdout
    ids, bad = journal_rows(journal)
    assert sorted(ids) == list(range(N_CASES)), "every case exactly once in the journal"
    assert bad <= 2   # at most one torn line per killed rank
    with xr.open_dataset(tmp_path / "out" / "summary.nc") as s:
        assert list(s["case"].values) == list(range(N_CASES))
    assert_same_summary(reference, tmp_path / "out" / "summary.nc")
    # and so is the envelope drawn from it: every variable, row order and attribute
    # (the envelope step reads neither wall_time_s nor created)
    envelopes = []
    for cwd in (reference.parents[1], tmp_path):
        res = run_python(["envelope", small, "--criteria", ROOT / "input" / "criteria_paper.nml", "--no-figures"],
                         cwd)
        assert res.returncode == 0, res.stdout + res.stderr
        envelopes.append(cwd / "out" / "envelope.nc")
    assert_same_summary(*envelopes, ignore_vars=(), ignore_attrs=())


def _version_module(tree, out):
    """(code_version, code_digest) that cmake/airlaunch_version.cmake writes for
    the source tree `tree` (as every build does)."""
    res = subprocess.run(["cmake", f"-DSOURCE_DIR={tree}", f"-DINPUT={tree}/src/base/airlaunch_version.f90.in",
                          f"-DOUTPUT={out}", "-DPROJECT_VERSION=0.2.0", "-DBUILD_SETTINGS=Release | GNU",
                          "-DAIRLAUNCH_SUNDIALS=static", "-P", f"{tree}/cmake/airlaunch_version.cmake"],
                         capture_output=True, text=True, timeout=60)
    assert res.returncode == 0, res.stderr
    text = out.read_text()
    found = [re.search(rf'{name} = "([^"]*)"', text) for name in ("code_version", "code_digest")]
    assert all(found), text
    return tuple(m.group(1) for m in found)


def test_an_edit_outside_the_code_does_not_refuse_the_resume(tmp_path, exes):
    """The journal's fingerprint named the code by its git description: one
    comment added to input/criteria_paper.nml made it '...-dirty' (scripts/sweep
    rebuilds first), and the rerun of an interrupted sweep was refused, the
    documented way out, --restart, discarding every finished case. The code is
    now named by the digest of its sources and build settings (cmake/
    airlaunch_version.cmake): an edit of an input leaves it, as does committing
    the same code; an edit of src/ changes it. Shown on a copy of the tree
    under git; the journal of a run holds that digest, not the description."""
    tree = tmp_path / "tree"
    for name in ("src", "cmake"):
        shutil.copytree(ROOT / name, tree / name)
    shutil.copy(ROOT / "CMakeLists.txt", tree)
    (tree / "input").mkdir()
    shutil.copy(ROOT / "input" / "criteria_paper.nml", tree / "input")
    git = ["git", "-C", str(tree), "-c", "user.name=t", "-c", "user.email=t@t"]
    for args in (["init", "-q"], ["add", "-A"], ["commit", "-qm", "a"]):
        subprocess.run(git + args, check=True, capture_output=True)
    version, digest = _version_module(tree, tmp_path / "v.f90")
    with open(tree / "input" / "criteria_paper.nml", "a") as f:
        f.write("! a comment of the user's\n")
    edited = _version_module(tree, tmp_path / "v.f90")
    assert edited[0] == version.replace(")", "-dirty)") and edited[1] == digest, (version, edited)
    subprocess.run(git + ["commit", "-qam", "b"], check=True, capture_output=True)
    committed = _version_module(tree, tmp_path / "v.f90")
    assert committed[0] != version and committed[1] == digest, (version, committed)
    with open(tree / "src" / "sweep" / "airlaunch_sweep_plan.f90", "a") as f:
        f.write("! a change of the code\n")
    assert _version_module(tree, tmp_path / "v.f90")[1] != digest

    definition = small_definition(tmp_path / "d.nml", n_cases=2)
    make_table(definition, tmp_path)
    assert run_sweep(definition, tmp_path, None).returncode == 0
    shown = subprocess.run([str(SWEEP_EXE), "--version"], capture_output=True, text=True, env=ENV, timeout=60)
    own = re.search(r"code digest \(sources and build settings\): (\w+)", shown.stdout).group(1)
    fingerprint = (tmp_path / "out" / "journal" / "fingerprint.txt").read_text().splitlines()
    assert fingerprint[0] == f"code_digest = {own}", fingerprint
    described = re.search(r"\((.*)\)", shown.stdout.splitlines()[0]).group(1)
    assert not [line for line in fingerprint if described in line], fingerprint


FAILING_INPUTS = """
&input name = 'run%max_steps', distribution = 'list', values = 300, 500000, units = '1' /
&input name = 'parachute%drag_area', distribution = 'list', values = 0.0, 10.0, units = 'm2' /
"""


def _single_run(tmp_path, cwd, definition, case):
    """The case's namelist from airlaunch-sweep, run by airlaunch on its own."""
    res = run_sweep(definition, cwd, None, "--case-namelist", case)
    assert res.returncode == 0, res.stderr
    nml = tmp_path / f"case{case}.nml"
    nml.write_text(res.stdout)
    out = tmp_path / f"case{case}.nc"
    return subprocess.run([str(AIRLAUNCH_EXE), str(nml), "--output", str(out)], capture_output=True, text=True,
                          env=ENV, timeout=600), out


def test_failed_and_invalid_cases_are_recorded_and_the_sweep_goes_on(tmp_path, exes):
    """Grid of step budget {300, 500 000} x drag area {0, 10} m^2 over 40 s: 300
    steps are spent before the end (a numerical failure); a zero
    drag area is rejected by the scenario reader.  Every case gets its row and
    the one good case completes; each row is what `airlaunch` gives alone.
    keep_failed keeps the failed case only (it also took the invalid ones, which
    can never have a trajectory: "3 written" for 1 file, retried at every rerun):
    the count is the files on disk, and a rerun has nothing left to write."""
    definition = small_definition(tmp_path / "fail.nml", n_cases=4, design="grid", inputs=FAILING_INPUTS,
                                  t_end=40.0, extra_sweep="keep_failed = .true.")
    make_table(definition, tmp_path)
    res = run_sweep(definition, tmp_path, 2)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "4 cases: 1 ok, 1 failed, 2 invalid input" in res.stdout, res.stdout
    assert "trajectories: 1 written" in res.stdout, res.stdout
    assert sorted(p.name for p in (tmp_path / "out" / "trajectories").iterdir()) == ["case_000001.nc"]
    with xr.open_dataset(tmp_path / "out" / "summary.nc") as s:
        budget = s["run%max_steps"].values
        area = s["parachute%drag_area"].values
        status = s["status"].values
        failure = list(s["failure"].values)
        sep = s["separation_time_s"].values
    # grid order: the first input varies slowest
    assert list(budget) == [300, 300, 500000, 500000] and list(area) == [0.0, 10.0, 0.0, 10.0]
    assert list(status) == [2, 1, 2, 0]
    for k in (0, 2):
        assert "drag_area" in failure[k] and failure[k].startswith(f"case {k}:"), failure[k]
    assert "step budget" in failure[1], failure[1]
    assert failure[3] == ""

    # the failed case: the same message and milestones as a single run
    single, out = _single_run(tmp_path, tmp_path, definition, 1)
    assert single.returncode == 3, single.stderr
    assert failure[1] in single.stderr.splitlines()[0], (failure[1], single.stderr)
    with xr.open_dataset(out) as ds:
        assert ds.attrs["status"] == "failed"
        assert float(ds.attrs["separation_time_s"]) == sep[1]
    # the failed case kept its trajectory (keep_failed)
    with xr.open_dataset(tmp_path / "out" / "trajectories" / "case_000001.nc") as ds:
        assert ds.attrs["status"] == "failed"
    # the good case: the same milestones as a single run, to the last bit
    single, out = _single_run(tmp_path, tmp_path, definition, 3)
    assert single.returncode == 0, single.stderr
    with xr.open_dataset(out) as ds, xr.open_dataset(tmp_path / "out" / "summary.nc") as s:
        for name in ("separation_time_s", "edge_time_s", "peak_line_tension_N", "pitch_at_separation_deg",
                     "max_aircraft_pitch_excursion_deg", "trim_alpha_deg"):
            assert float(ds.attrs[name]) == float(s[name].values[3]), name
    rerun = run_sweep(definition, tmp_path, 2)
    assert rerun.returncode == 0 and "trajectories:" not in rerun.stdout, rerun.stdout + rerun.stderr


def test_scripts_sweep_runs_the_whole_chain(tmp_path, exes):
    """scripts/sweep: table -> check -> mpirun -> envelope, with every output."""
    definition = small_definition(tmp_path / "chain.nml", n_cases=12, output_dir=str(tmp_path / "out"),
                                  extra_sweep=f"criteria = '{ROOT}/input/criteria_paper.nml'")
    res = subprocess.run([str(ROOT / "scripts" / "sweep"), str(definition), "-n", "2", "--verify", "2"], cwd=tmp_path,
                         capture_output=True, text=True, env=ENV, timeout=900)
    assert res.returncode == 0, res.stdout + res.stderr
    out = tmp_path / "out"
    for name in ("table.nc", "summary.nc", "envelope.nc", "figures/passfail_map.png", "figures/margins.png",
                 "figures/probability.png", "figures/worst_cases.png", "figures/worst_cases.md",
                 "figures/sensitivity.png"):
        assert (out / name).is_file(), name
    assert "12 cases: 12 ok" in res.stdout
    assert "drivers (standardised rank regression coefficient" in res.stdout
    # 4 s: no case reaches its pitch maximum, so none has a margin on every criterion to verify
    assert "== verify (2 case(s)" in res.stdout and "nothing near the boundary to verify" in res.stdout
    with xr.open_dataset(out / "envelope.nc") as env:
        assert env.sizes["case"] == 12
        assert set(env["criterion"].values) >= {"clearance", "line_tension", "firing_attitude", "all"}
        p = env["probability"].sel(criterion="all").values
        assert 0.0 <= env["wilson_low"].sel(criterion="all") <= p <= env["wilson_high"].sel(criterion="all") <= 1.0
        assert np.all(np.isin(env["passed"].values, [0, 1]))


def test_restart_removes_the_old_summary_and_envelope_before_any_case(tmp_path, exes):
    """`--restart` left the earlier sweep's summary.nc and envelope.nc in place,
    so a restart killed before its own summary left them to be taken as the new
    sweep's. They are now removed before the first case runs (checked by killing
    the run the moment it announces its cases)."""
    small = small_definition(tmp_path / "s.nml", n_cases=4)
    make_table(small, tmp_path)
    assert run_sweep(small, tmp_path).returncode == 0
    out = tmp_path / "out"
    assert (out / "summary.nc").is_file()
    (out / "envelope.nc").write_text("the envelope of the earlier sweep\n")
    small = small_definition(tmp_path / "s.nml", n_cases=400, seed=99)   # a long sweep: killed long before its end
    make_table(small, tmp_path)
    proc = subprocess.Popen([str(SWEEP_EXE), str(small), "--restart"], cwd=tmp_path, env=ENV, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    try:
        for line in proc.stdout:
            if "cases to run" in line:
                break
        else:
            pytest.fail("the run did not announce its cases")
        assert "400 cases to run" in line, line
        proc.kill()
    finally:
        proc.kill()
        proc.wait()
    assert len(journal_rows(out / "journal")[0]) < 400, "the kill came too late"
    assert not (out / "summary.nc").exists()
    assert not (out / "envelope.nc").exists()


def test_figures_of_an_earlier_summary_are_known_stale(tmp_path, exes):
    """`--restart` makes the summary again and removes envelope.nc, but
    figures/ stayed, showing the earlier summary with nothing to say so.  The
    envelope step now records in figures/drawn_from.txt the envelope and the
    summary it drew them from (their SHA-256); envelope --check and verify warn
    (one line on stderr, exit 0) while the figures are not those of the files
    beside them, envelope --no-figures removes them, the envelope step redraws."""
    crit = f"criteria = '{ROOT}/input/criteria_paper.nml'"
    d = small_definition(tmp_path / "s.nml", n_cases=4, extra_sweep=crit)
    out, figures = tmp_path / "out", tmp_path / "out" / "figures"

    def step(*args):
        res = run_python(list(args), tmp_path)
        assert res.returncode == 0, res.stdout + res.stderr
        return res

    def assert_drawn_from_the_files_beside_them():
        stamp = dict(line.split(" = ", 1) for line in (figures / "drawn_from.txt").read_text().splitlines()
                     if not line.startswith("#"))
        for name in ("envelope", "summary"):
            assert stamp[f"{name}_sha256"] == hashlib.sha256((out / f"{name}.nc").read_bytes()).hexdigest(), name
        assert not step("envelope", d, "--check").stderr

    step("table", d)
    assert run_sweep(d, tmp_path).returncode == 0
    step("envelope", d)
    assert (figures / "passfail_map.png").is_file()
    assert_drawn_from_the_files_beside_them()
    # a rerun with no case left keeps the journal's summary byte for byte (it was
    # written again with a new `created`, which made these figures stale)
    before = (out / "summary.nc").read_bytes()
    res = run_sweep(d, tmp_path)
    assert res.returncode == 0 and "0 cases to run" in res.stdout and "left as it is" in res.stdout, res.stdout
    assert (out / "summary.nc").read_bytes() == before
    assert_drawn_from_the_files_beside_them()
    # the cases run again at another setting: a new summary; airlaunch-sweep removes envelope.nc, not figures/
    d = small_definition(tmp_path / "s.nml", n_cases=4, extra_sweep=crit,
                         fixed="&fixed name = 'line%n_seg', value = '12' /")
    assert run_sweep(d, tmp_path, None, "--restart").returncode == 0
    assert not (out / "envelope.nc").exists() and (figures / "passfail_map.png").is_file()
    for args in (("envelope", d, "--check"), ("verify", d, "--cases", "1")):
        lines = step(*args).stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("sweep: warning: out/figures is stale: "), lines
        assert "envelope.nc, which they were drawn from, is gone" in lines[0]
    res = step("envelope", d, "--no-figures")   # a new envelope.nc, the old one's figures removed
    assert "figures: removed those of" in res.stdout and not figures.exists()
    step("envelope", d)
    assert_drawn_from_the_files_beside_them()


@pytest.mark.parametrize("criteria,words", [
    ([], "&sweep: no criteria file (set criteria = 'FILE' or give --criteria)"),
    (["--criteria", "bad.nml"], "unknown criterion 'max_mach'"),
], ids=["none", "invalid"])
def test_scripts_sweep_without_criteria_stops_before_any_case(tmp_path, exes, criteria, words):
    """A definition without `criteria` ran every case and then failed at the
    envelope step, whose message said "give --criteria", an option scripts/sweep
    did not have. The chain now checks the criteria first (one line, exit 2,
    no table, no case run)."""
    (tmp_path / "bad.nml").write_text("&criteria max_mach = 0.9 /\n")
    definition = small_definition(tmp_path / "nocrit.nml", n_cases=4, output_dir=str(tmp_path / "out"))
    res = subprocess.run([str(ROOT / "scripts" / "sweep"), str(definition), "-n", "1", *criteria], cwd=tmp_path,
                         capture_output=True, text=True, env=ENV, timeout=900)
    assert res.returncode == 2, res.stdout + res.stderr
    errors = [x for x in res.stderr.splitlines() if "error" in x]
    assert len(errors) == 1 and errors[0].startswith("sweep: error: ") and words in errors[0], res.stderr
    assert "== table" not in res.stdout
    assert not (tmp_path / "out").exists()


def test_scripts_sweep_passes_criteria_to_the_envelope(tmp_path, exes):
    """--criteria FILE reaches the envelope step (the definition has none)."""
    definition = small_definition(tmp_path / "nocrit.nml", n_cases=4, output_dir=str(tmp_path / "out"))
    crit = tmp_path / "c.nml"
    crit.write_text("&criteria min_clearance_m = 1.5 /\n")
    res = subprocess.run([str(ROOT / "scripts" / "sweep"), str(definition), "-n", "1", "--criteria", str(crit)],
                         cwd=tmp_path, capture_output=True, text=True, env=ENV, timeout=900)
    assert res.returncode == 0, res.stdout + res.stderr
    with xr.open_dataset(tmp_path / "out" / "envelope.nc") as env:
        assert list(env["criterion"].values) == ["clearance", "all"]
        assert env.attrs["criteria_file"] == str(crit)
    res = subprocess.run([str(ROOT / "scripts" / "sweep"), str(definition), "--step", "envelope", "--criteria",
                          str(crit)], cwd=tmp_path, capture_output=True, text=True, env=ENV, timeout=900)
    assert res.returncode == 0, res.stdout + res.stderr


def test_summary_attributes_describe_inputs_and_clearance(tmp_path, exes):
    """An input's `description` was read but written to the summary nowhere
    (docs/sweep.md: copied to the table and the summary); min_clearance_m's
    long_name said 'ramp edge' while the value is the rocket-empennage clearance
    (docs/output.md). The input's long_name is its description in both files
    (the default text without one), its units the definition's."""
    desc = "release time after the extraction canopy is established"
    inputs = (f"&input name = 'bay%release_time', distribution = 'uniform', lower = 0.4, upper = 1.0, units = 's', "
              f"description = '{desc}' /\n"
              "&input name = 'flight%mach', distribution = 'uniform', lower = 0.6, upper = 0.7 /\n")
    definition = small_definition(tmp_path / "d.nml", n_cases=2, inputs=inputs)
    make_table(definition, tmp_path)
    res = run_sweep(definition, tmp_path)
    assert res.returncode == 0, res.stdout + res.stderr
    for name in ("table.nc", "summary.nc"):
        with xr.open_dataset(tmp_path / "out" / name) as ds:
            assert ds["bay%release_time"].attrs["long_name"] == desc, name
            assert ds["bay%release_time"].attrs["units"] == "s", name
            assert "flight%mach" in ds["flight%mach"].attrs["long_name"], name
    with xr.open_dataset(tmp_path / "out" / "summary.nc") as ds:
        long_name = ds["min_clearance_m"].attrs["long_name"]
        assert "empennage" in long_name and "ramp edge" not in long_name, long_name
        assert ds["flight%mach"].attrs["long_name"] == "varied input flight%mach (uniform)"


def test_a_second_run_on_the_same_output_is_refused(tmp_path, exes):
    """Two airlaunch-sweep runs on one output directory interleaved their journals
    and both ended with 'a journal write was lost' (exit 4); the run now holds a
    lock on OUTPUT_DIR/journal/lock, and a second run is refused at once (exit 2,
    one line) while the first holds it.  The lock is taken here with flock, as a
    running sweep holds it; released, the same command runs."""
    import fcntl
    definition = small_definition(tmp_path / "lock.nml", n_cases=2)
    make_table(definition, tmp_path)
    (tmp_path / "out" / "journal").mkdir(parents=True, exist_ok=True)
    with open(tmp_path / "out" / "journal" / "lock", "w") as held:
        fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
        res = run_sweep(definition, tmp_path, None)
        assert res.returncode == 2, res.stdout + res.stderr
        line = res.stderr.strip().splitlines()[-1]
        assert "another airlaunch-sweep is running this sweep" in line, res.stderr
        assert journal_rows(tmp_path / "out" / "journal") == ([], 0)
    res = run_sweep(definition, tmp_path, None)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "2 cases: 2 ok" in res.stdout, res.stdout


def test_the_table_of_a_running_sweep_is_not_replaced(tmp_path, exes):
    """A second submission of a job (scripts/sweep, scripts/sweep.slurm) runs the
    table step before its run is refused by the lock: the table step removed and
    redrew OUTPUT_DIR/table.nc under the running sweep, whose envelope step then
    refused its own summary ('the values of ... are not those that ... draws',
    exit 2 after every case had run).  The table step now takes the run's lock:
    while a run holds it (taken here with flock, as a running sweep holds it),
    the table step is refused in one line (exit 2) and the table is left byte for
    byte; released, the same command draws its table."""
    import fcntl
    running = small_definition(tmp_path / "running.nml", n_cases=2)
    make_table(running, tmp_path)
    table = tmp_path / "out" / "table.nc"
    before = table.read_bytes()
    other = small_definition(tmp_path / "other.nml", n_cases=3, seed=6)   # same output_dir
    (tmp_path / "out" / "journal").mkdir(parents=True, exist_ok=True)
    with open(tmp_path / "out" / "journal" / "lock", "w") as held:
        fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
        res = run_python(["table", other], tmp_path)
        assert res.returncode == 2, res.stdout + res.stderr
        lines = res.stderr.strip().splitlines()
        assert len(lines) == 1 and "another airlaunch-sweep is running this sweep" in lines[0], res.stderr
        assert "table.nc is left as it is" in lines[0], lines[0]
        assert table.read_bytes() == before
    res = run_python(["table", other], tmp_path)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "3 cases" in res.stdout and table.read_bytes() != before


def test_one_rank_in_a_multi_task_slurm_job_is_refused(tmp_path, exes):
    """srun without the MPI plug-in starts every task as its own one-rank job: with
    SLURM_NTASKS > 1 and an MPI world of one rank the run is refused with the fix
    (exit 2, one line) before any case; --check is not affected."""
    definition = small_definition(tmp_path / "slurm.nml", n_cases=2)
    make_table(definition, tmp_path)
    env = dict(ENV, SLURM_NTASKS="4")
    res = subprocess.run([str(SWEEP_EXE), str(definition)], cwd=tmp_path, capture_output=True, text=True,
                         env=env, timeout=120)
    assert res.returncode == 2, res.stdout + res.stderr
    assert "SLURM_NTASKS = 4 but MPI started one rank" in res.stderr and "srun --mpi=pmix" in res.stderr
    assert not (tmp_path / "out" / "journal").exists()
    res = subprocess.run([str(SWEEP_EXE), str(definition), "--check"], cwd=tmp_path, capture_output=True,
                         text=True, env=env, timeout=120)
    assert res.returncode == 0, res.stdout + res.stderr


def test_case_namelists_asked_at_once_are_each_the_case_alone(tmp_path, exes):
    """airlaunch-sweep --case-namelist is a query that scripts run many at once
    (the verification step, users' own): each process checks the base in a
    scratch file of its own and removes it.  (They shared work/check_rank0.nml,
    and one of 8 at once failed with "cannot read the group: End of file".)
    Eight at once, three times: each the sequential answer, no scratch left."""
    definition = small_definition(tmp_path / "q.nml", n_cases=8)
    make_table(definition, tmp_path)
    scratch = tmp_path / "tmpdir"      # where each query's scratch check file goes
    scratch.mkdir()
    # Open MPI keeps its session directory in $TMPDIR too, and eight singletons
    # starting at once where it does not exist yet race to make it ("File
    # exists", MPI_Init fails): keep it in /tmp, made by the sequential queries
    env = dict(ENV, TMPDIR=str(scratch), OMPI_MCA_orte_tmpdir_base="/tmp")
    alone = [subprocess.run([str(SWEEP_EXE), str(definition), "--case-namelist", str(i)], cwd=tmp_path,
                            capture_output=True, text=True, env=env, timeout=120).stdout for i in range(8)]
    assert all(text.strip() for text in alone)
    for _ in range(3):
        procs = [subprocess.Popen([str(SWEEP_EXE), str(definition), "--case-namelist", str(i)], cwd=tmp_path,
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
                 for i in range(8)]
        for i, p in enumerate(procs):
            out, err = p.communicate(timeout=120)
            assert p.returncode == 0, err
            assert out == alone[i]
    assert not list(scratch.iterdir())
