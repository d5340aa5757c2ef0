"""Shared fixtures: paths of the built programs, a runner, input variants."""
import os
import pathlib
import re
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
BIN = pathlib.Path(os.environ.get("AIRLAUNCH_BIN", ROOT / "build" / "release" / "bin"))
PAPER = ROOT / "input" / "airlaunch_paper.nml"

#: unit symbols of UDUNITS-2's SI base/derived and accepted tables that the
#: outputs may use (test_output_units.py: the grammar and why)
UDUNITS_SYMBOLS = {"m", "s", "kg", "N", "J", "W", "Pa", "K", "rad", "degree", "sr"}
_UNIT_TERM = r"([A-Za-z]+)(-?[0-9]+)?"
_UNIT_STRING = re.compile(rf"^(1|{_UNIT_TERM}( {_UNIT_TERM})*)$")


def unit_string_parses(units):
    """True if `units` is in the UDUNITS-2 grammar the outputs need: "1", or
    blank-separated unit symbols each with an optional integer power
    ("m s-2", "kg m2"), the symbols from UDUNITS_SYMBOLS."""
    return _UNIT_STRING.match(units) is not None and (
        units == "1" or all(symbol in UDUNITS_SYMBOLS for symbol, _ in re.findall(_UNIT_TERM, units)))


def units_problems(ds, skip=()):
    """Numeric variables of `ds` (except `skip`) without readable units: each
    needs a `units` string that parses, or, along a dimension whose rows have
    different units (a sweep's criteria), no `units` but `units_from` naming a
    string variable on that dimension whose every entry parses."""
    problems = []
    for name, var in ds.variables.items():
        if name in skip or var.dtype.kind in "OSU":
            continue
        if "units" in var.attrs:
            if not unit_string_parses(str(var.attrs["units"])):
                problems.append(f"{name}: units {var.attrs['units']!r} do not parse")
        elif "units_from" in var.attrs:
            source = ds[var.attrs["units_from"]]
            if source.ndim != 1 or source.dims[0] not in var.dims:
                problems.append(f"{name}: units_from {source.name} is not along one of its dimensions")
            problems += [f"{name}: {source.name} entry {u!r} does not parse"
                         for u in map(str, source.values) if not unit_string_parses(u)]
        else:
            problems.append(f"{name} has no units")
    return problems


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
