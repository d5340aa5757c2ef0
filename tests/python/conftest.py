"""Shared fixtures: paths of the built programs, a runner, input variants."""
import os
import pathlib
import re
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
BIN = pathlib.Path(os.environ.get("AIRLAUNCH_BIN", ROOT / "build" / "release" / "bin"))
PAPER = ROOT / "input" / "airlaunch_paper.nml"


@pytest.fixture(scope="session")
def root():
    return ROOT


@pytest.fixture(scope="session")
def airlaunch_exe():
    exe = BIN / "airlaunch"
    if not exe.exists():
        pytest.fail(f"{exe} is missing: run scripts/setup release first")
    return exe


def run_airlaunch(exe, nml_path, *args, cwd=None):
    """Run the program; return the CompletedProcess (text mode)."""
    return subprocess.run([str(exe), str(nml_path), *map(str, args)], capture_output=True,
                          text=True, cwd=cwd, timeout=600, env=dict(os.environ))


def assert_input_error(res, fragment, out):
    """Bad input: exit status 2, one line on stderr containing `fragment`,
    and no output file left behind (README: errors)."""
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and fragment in lines[0], res.stderr
    assert not pathlib.Path(out).exists()
    return lines[0]


def nml_scalar(path, name):
    """A scalar set in an example file (`  name = value`, exactly once)."""
    found = re.findall(rf"^  {name} = ([-0-9.eE+]+)", pathlib.Path(path).read_text(), flags=re.M)
    assert len(found) == 1, name
    return float(found[0])


def nml_variant(tmp_path, name="variant", edits=(), line=(), base=PAPER):
    """A copy of the input file `base` (default: the paper scenario) with regex
    `edits` (each must match exactly one line) and extra `&line` assignments
    (inserted after its cd_tangential line), written to tmp_path/name.nml."""
    text = pathlib.Path(base).read_text()
    for old, new in edits:
        text, n = re.subn(old, new, text, flags=re.M)
        assert n == 1, old
    if line:
        text, n = re.subn(r"^(  cd_tangential = 0.01 .*)$", lambda m: m.group(1) + "\n" + "\n".join(line), text,
                          flags=re.M)
        assert n == 1
    p = tmp_path / f"{name}.nml"
    p.write_text(text)
    return p
