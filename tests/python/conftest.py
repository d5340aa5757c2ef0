"""Shared fixtures: paths of the built programs and a runner."""
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
BIN = pathlib.Path(os.environ.get("AIRLAUNCH_BIN", ROOT / "build" / "release" / "bin"))


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
