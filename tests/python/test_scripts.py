"""The command-line scripts' help and usage errors (README, "What is where"): asking for
help prints it and exits 0 without building, installing or running anything; misuse
is exit 2 with the usage; the program's own messages name it once."""
import os
import subprocess

import pytest

from conftest import ROOT


def run(*args, env=None):
    return subprocess.run([str(a) for a in args], capture_output=True, text=True, timeout=60, cwd="/",
                          env=dict(os.environ, **(env or {})))


def test_bench_help_lists_the_benchmarks():
    res = run(ROOT / "scripts" / "bench", "--help")
    assert res.returncode == 0, res.stderr
    names = {p.name.removeprefix("bench_") for p in (ROOT / "scripts").glob("bench_*")}
    assert names and all(f"  {n}" in res.stdout for n in names)


@pytest.mark.parametrize("name", ["paper", "line", "sweep", "workprecision", "moordyn", "couplings", "fishhook"])
def test_a_benchmark_help_is_its_header_without_running(name):
    """--help used to be a traceback (paper, sweep), a Fortran runtime error (line)
    or the whole benchmark (workprecision, moordyn: installing MoorDyn first)."""
    res = run(ROOT / "scripts" / "bench", name, "--help")
    assert res.returncode == 0, res.stderr
    assert f"bench {name}" in res.stdout and res.stderr == ""
    assert not any(line.startswith("RESULT {") for line in res.stdout.splitlines())


def test_bench_misuse_is_exit_2():
    res = run(ROOT / "scripts" / "bench", "no_such_bench")
    assert res.returncode == 2 and "usage: scripts/bench NAME" in res.stderr


def test_sweep_help_exits_0_and_misuse_2():
    res = run(ROOT / "scripts" / "sweep", "--help")
    assert res.returncode == 0 and "scripts/sweep SWEEP.nml" in res.stdout
    res = run(ROOT / "scripts" / "sweep", "--no-such-option")
    assert res.returncode == 2 and "unknown option --no-such-option" in res.stderr


def test_airlaunch_names_itself_once(airlaunch_exe):
    res = run(airlaunch_exe)
    assert res.returncode == 2
    assert "airlaunch: error: no scenario file given" in res.stderr
    assert "airlaunch: error: airlaunch:" not in res.stderr


def test_figures_help_lists_every_figure_and_misuse_is_exit_2():
    """scripts/figures --help (or --list) names every file of docs/figures with its command,
    without building or running anything; an unknown figure or option is exit 2 before either."""
    res = run(ROOT / "scripts" / "figures", "--help")
    assert res.returncode == 0 and res.stderr == "", res.stderr
    figures = [p.stem for p in (ROOT / "docs" / "figures").glob("*.png")]
    assert figures and all(f"  {name} " in res.stdout for name in figures), res.stdout
    for args, message in ((("--only", "no_such_figure"), "no figure no_such_figure"),
                          (("--no-such-option",), "unknown argument --no-such-option")):
        res = run(ROOT / "scripts" / "figures", *args)
        assert res.returncode == 2 and message in res.stderr, (res.returncode, res.stderr)
