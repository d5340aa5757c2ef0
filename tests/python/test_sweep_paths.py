"""The sweep's Python steps and verify with paths a cluster user may have
(found by an audit, thirtieth session), each against the project's rule: the
step succeeds, or says what went wrong in one line with a non-zero exit.

- an output_dir starting with '-': verify's reruns passed their namelist to
  airlaunch unprotected, which took it for an option; the refused reruns were
  reported as pass/fail flips with exit 0;
- an output_dir long enough that a rerun's output name passes airlaunch's 256
  characters: the same false flips, exit 0; now one line naming the refusal;
- a step's standard output that cannot be written (/dev/full): a traceback
  after envelope.nc was written and before the figures; now the step
  finishes its files and says so in one line, exit 4 (as airlaunch does);
- OUTPUT_DIR/verify an existing file: a traceback; now one line, exit 2;
- a definition named like an option (-s.nml): refused by airlaunch-sweep and
  scripts/sweep with no way to give it; now it goes after `--` (thirty-first
  session).
"""
import subprocess
import sys

import pytest
import xarray as xr

from test_sweep_support import ROOT, ENV, SWEEP_EXE, make_table, run_python, run_sweep, small_definition

CRITERIA = f"criteria = '{ROOT}/input/criteria_paper.nml'"


def finished_sweep(tmp_path, output_dir):
    d = small_definition(tmp_path / "s.nml", n_cases=3, t_end=1.0, output_dir=output_dir, extra_sweep=CRITERIA)
    make_table(d, tmp_path)
    res = run_sweep(d, tmp_path)
    assert res.returncode == 0, res.stdout + res.stderr
    res = run_python(["envelope", d, "--no-figures"], tmp_path)
    assert res.returncode == 0, res.stdout + res.stderr
    return d


def test_verify_with_an_output_dir_starting_with_a_dash(tmp_path):
    d = finished_sweep(tmp_path, "-dash")
    res = run_python(["verify", d, "--ids", "0", "--jobs", "1"], tmp_path)
    assert res.returncode == 0, res.stdout + res.stderr
    with xr.open_dataset(tmp_path / "-dash" / "verify.nc") as ds:
        assert list(ds["refined_status"].values) == ["ok"], ds["refined_message"].values
        assert not ds["flipped"].values.any()


def test_verify_whose_reruns_airlaunch_refuses_is_one_line(tmp_path):
    """output_dir of 240 characters: the sweep runs (its files fit), but a
    rerun's output, OUTPUT_DIR/verify/case_000000.nc, has 262 characters
    against airlaunch's 256."""
    long_dir = "d" * 240
    d = finished_sweep(tmp_path, long_dir)
    res = run_python(["verify", d, "--ids", "0", "--jobs", "1"], tmp_path)
    assert res.returncode == 2, res.stdout + res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("sweep: error: the rerun of case 0 was refused: "), lines
    assert "characters long" in lines[0] and "flip" not in res.stdout
    assert not (tmp_path / long_dir / "verify.nc").exists()


@pytest.mark.parametrize("step", ["table", "envelope"])
def test_a_step_whose_stdout_is_full_finishes_and_says_so(tmp_path, step):
    d = finished_sweep(tmp_path, "out")
    made = tmp_path / "out" / ("table.nc" if step == "table" else "envelope.nc")
    made.unlink()   # the step must write it again
    args = [step, d] + (["--exe-dir", str(ROOT / "build" / "release" / "bin")] if step == "table" else [])
    with open("/dev/full", "w") as full:
        res = subprocess.run([sys.executable, "-m", "postproc.sweep", *map(str, args)], cwd=tmp_path, env=ENV,
                             stdout=full, stderr=subprocess.PIPE, text=True, timeout=600)
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 4, res.stderr
    assert len(lines) == 1 and lines[0].startswith("sweep: error: the standard output could not be written ("), lines
    assert "Traceback" not in res.stderr
    assert made.is_file()
    if step == "envelope":
        assert (tmp_path / "out" / "figures" / "drawn_from.txt").is_file()


def test_verify_dir_in_the_way_is_one_line(tmp_path):
    d = finished_sweep(tmp_path, "out")
    (tmp_path / "out" / "verify").write_text("in the way\n")
    res = run_python(["verify", d, "--ids", "0", "--jobs", "1"], tmp_path)
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 2 and len(lines) == 1 and lines[0].startswith("sweep: error: "), res.stderr
    assert "verify" in lines[0] and "Traceback" not in res.stderr


def test_a_definition_named_like_an_option_goes_after_a_double_dash(tmp_path):
    """airlaunch-sweep, like airlaunch, ends its options at `--`: a definition
    named `-s.nml` is refused as an unknown option with the way to give it,
    and read after `--` (its check names the file and its 3 cases)."""
    small_definition(tmp_path / "-s.nml", n_cases=3, t_end=1.0)
    res = subprocess.run([str(SWEEP_EXE), "-s.nml"], cwd=tmp_path, capture_output=True, text=True, env=ENV,
                         timeout=60)
    assert res.returncode == 2 and res.stderr.count("\n") == 1, res.stdout + res.stderr
    assert "unknown option -s.nml" in res.stderr and "goes after --" in res.stderr
    res = subprocess.run([str(SWEEP_EXE), "--check", "--", "-s.nml"], cwd=tmp_path, capture_output=True,
                         text=True, env=ENV, timeout=60)
    assert res.returncode == 0, res.stdout + res.stderr
    assert res.stdout.startswith("airlaunch-sweep: -s.nml: ok: design lhs, 3 cases"), res.stdout


def test_scripts_sweep_takes_a_definition_named_like_an_option_after_a_double_dash(tmp_path):
    """scripts/sweep: `-s.nml` alone is an unknown option (exit 2, the way to
    give it named); after `--` every step (table, check, run, envelope) reads
    it, passed on as ./-s.nml, and the sweep's files are all there."""
    small_definition(tmp_path / "-s.nml", n_cases=3, t_end=1.0, extra_sweep=CRITERIA)
    script = str(ROOT / "scripts" / "sweep")
    res = subprocess.run([script, "-n", "1", "-s.nml"], cwd=tmp_path, capture_output=True, text=True, env=ENV,
                         timeout=60)
    assert res.returncode == 2 and "unknown option -s.nml" in res.stderr and "goes after --" in res.stderr
    res = subprocess.run([script, "-n", "1", "--", "-s.nml"], cwd=tmp_path, capture_output=True, text=True,
                         env=ENV, timeout=600)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "3 cases: 3 ok" in res.stdout, res.stdout
    for name in ("table.nc", "summary.nc", "envelope.nc"):
        assert (tmp_path / "out" / name).is_file(), name


def test_a_line_break_in_the_definitions_name_keeps_the_error_on_one_line(tmp_path):
    """airlaunch-sweep writes a control character of a name it reports as \\n
    (thirty-first session): the one-line error stays one line."""
    odd = tmp_path / "s\nx.nml"
    odd.write_text("&sweep name = 'x' /\n")
    res = subprocess.run([str(SWEEP_EXE), str(odd)], capture_output=True, text=True, env=ENV, timeout=60)
    assert res.returncode == 2 and res.stderr.count("\n") == 1, res.stderr
    assert res.stderr.startswith(f"airlaunch-sweep: error: {tmp_path}/s\\nx.nml: no &input group"), res.stderr
