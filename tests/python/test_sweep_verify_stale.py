"""A verification that stops after it removed the earlier one's reruns (a
rerun refused, an interrupt) left the earlier verify.nc beside the new runs:
a file naming reruns that were gone, under the verification's final name
(an audit). verify.nc now goes with the earlier reruns, before any new one."""
import os

from test_sweep_support import ROOT, SWEEP_EXE, make_table, run_python, run_sweep, small_definition

CRITERIA = f"criteria = '{ROOT}/input/criteria_paper.nml'"


def test_a_verification_that_fails_leaves_no_earlier_verify_nc(tmp_path):
    d = small_definition(tmp_path / "s.nml", n_cases=3, t_end=1.0, output_dir="out", extra_sweep=CRITERIA)
    make_table(d, tmp_path)
    assert run_sweep(d, tmp_path).returncode == 0
    res = run_python(["verify", d, "--ids", "0", "--jobs", "1"], tmp_path)
    assert res.returncode == 0, res.stdout + res.stderr
    assert (tmp_path / "out" / "verify.nc").is_file()
    # programs whose airlaunch refuses every rerun: the verification stops after its start
    fake = tmp_path / "bin"
    fake.mkdir()
    os.symlink(SWEEP_EXE, fake / "airlaunch-sweep")
    (fake / "airlaunch").write_text("#!/bin/sh\necho 'airlaunch: error: refused for the test' >&2\nexit 2\n")
    (fake / "airlaunch").chmod(0o755)
    res = run_python(["verify", d, "--ids", "1", "--jobs", "1", "--exe-dir", fake], tmp_path)
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 2 and len(lines) == 1 and "the rerun of case 1 was refused" in lines[0], res.stderr
    assert not (tmp_path / "out" / "verify.nc").exists()
    assert not list((tmp_path / "out" / "verify").glob("case_000000*"))
