"""Every `units` attribute of a run's output is a unit string that unit
libraries read: UDUNITS-2 (which CF tools use) and pint (pint-xarray's
`quantify`) reject the whole file's quantification on one string they cannot
parse, as the air-launch scene's `N or N m` was before version 0.2.0.

The reference is the UDUNITS-2 grammar for the strings these files need: "1",
or a product of unit symbols separated by blanks, each with an optional
integer power written after it ("m s-2", "kg m2", "degree s-1"), the symbols
taken from the UDUNITS-2 SI and accepted-unit tables (the library is not a
dependency of the suite).
"""
import pytest
import xarray as xr

from conftest import ROOT, run_airlaunch, unit_string_parses


def bad_units(ds):
    """The (variable, units) pairs of `ds` that are not such a string."""
    return [(name, var.attrs["units"]) for name, var in ds.variables.items()
            if "units" in var.attrs and not unit_string_parses(var.attrs["units"])]


@pytest.mark.parametrize("example, edits", [
    ("airlaunch_paper.nml", ()),
    ("airlaunch_gravity_drop.nml", ()),
    ("line_airdrop.nml", (("t_end = 200.0", "t_end = 2.0"),)),
    ("drop_demo.nml", ()),
])
def test_every_unit_string_parses(airlaunch_exe, tmp_path, example, edits):
    text = (ROOT / "input" / example).read_text()
    for old, new in edits:
        assert old in text
        text = text.replace(old, new)
    nml = tmp_path / example
    nml.write_text(text)
    out = tmp_path / "run.nc"
    res = run_airlaunch(airlaunch_exe, nml, "--output", out)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(out) as ds:
        assert len(ds.variables) >= 5
        assert bad_units(ds) == []


def test_the_rule_rejects_what_it_must():
    """The grammar above refuses the strings it exists to catch."""
    ds = xr.Dataset({"a": ((), 0.0, {"units": "N or N m"}), "b": ((), 0.0, {"units": "m s-1"}),
                     "c": ((), 0.0, {"units": "criterion units (see criterion_units)"}),
                     "d": ((), 0.0, {"units": "1"}), "e": ((), 0.0, {"units": "degree s-1"}),
                     "f": ((), 0.0, {"units": "furlong"})})
    assert bad_units(ds) == [("a", "N or N m"), ("c", "criterion units (see criterion_units)"), ("f", "furlong")]


def test_created_carries_its_offset_from_utc(airlaunch_exe, tmp_path):
    """`created` is ISO 8601 with the offset from UTC (files made at different
    sites compare): read by Python's own ISO parser, it is this moment, in the
    time zone the run was given (a POSIX TZ string, needing no tz database: India's
    +05:30, a half-hour offset)."""
    import datetime
    import os
    import subprocess
    out = tmp_path / "drop.nc"
    before = datetime.datetime.now(datetime.timezone.utc)
    res = subprocess.run([str(airlaunch_exe), str(ROOT / "input" / "drop_demo.nml"), "--output", str(out)],
                         capture_output=True, text=True, timeout=60, env={**os.environ, "TZ": "IST-5:30"})
    after = datetime.datetime.now(datetime.timezone.utc)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(out) as ds:
        created = datetime.datetime.fromisoformat(ds.attrs["created"])
    assert created.utcoffset() == datetime.timedelta(hours=5, minutes=30)
    # (the stamp has whole seconds)
    assert before.replace(microsecond=0) <= created <= after
