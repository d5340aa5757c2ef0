"""Re-creating a run from its own file (docs/output.md, "Reproducing a run"):
the file's `input_namelist`, run again, gives every variable bit for bit, and
the global attributes differ only where the docs say they may (`created`, the
`OUTPUT` line of the echo, the line scene's `wall_time_s`); the file names the
build it came from by `code_digest`, the digest `airlaunch --version` and
`airlaunch-sweep --version` print (sources and build settings: the git
description in `code_version` names neither the compiler flags nor an
uncommitted edit, and the docs promise the same bits on one build only).  The
digest was missing from the files: a reader could not tell whether their build
was the one that made them."""
import re

import numpy as np
import pytest
import xarray as xr

from conftest import BIN, ROOT, run_airlaunch

#: global attributes that may differ between two runs of one input (output.md)
MAY_DIFFER = {"created", "input_namelist", "wall_time_s"}


def printed_digest(program):
    res = run_airlaunch(BIN / program, "--version")
    assert res.returncode == 0, res.stderr
    found = re.findall(r"^code digest \(sources and build settings\): ([0-9a-f]{16})$", res.stdout, flags=re.M)
    assert len(found) == 1, res.stdout
    return found[0]


@pytest.mark.parametrize("name", ["airlaunch_paper", "line_airdrop", "drop_demo"])
def test_a_run_is_reproduced_from_its_own_file(airlaunch_exe, tmp_path, name):
    first = tmp_path / "first.nc"
    res = run_airlaunch(airlaunch_exe, ROOT / "input" / f"{name}.nml", "--output", first)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(first) as a:
        echo = a.attrs["input_namelist"]
    again = tmp_path / "again.nc"
    assert echo.count(f'OUTPUT="{first}"') == 1
    (tmp_path / "echo.nml").write_text(echo.replace(f'OUTPUT="{first}"', f'OUTPUT="{again}"'))
    res = run_airlaunch(airlaunch_exe, tmp_path / "echo.nml")
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(first) as a, xr.open_dataset(again) as b:
        assert sorted(a.variables) == sorted(b.variables)
        for var in a.variables:
            assert a[var].values.tobytes() == b[var].values.tobytes(), var
            assert a[var].attrs == b[var].attrs, var
        assert set(a.attrs) == set(b.attrs)
        differ = {k for k in a.attrs if not np.array_equal(np.asarray(a.attrs[k]), np.asarray(b.attrs[k]))}
        assert differ <= MAY_DIFFER, differ
        lines_a, lines_b = a.attrs["input_namelist"].splitlines(), b.attrs["input_namelist"].splitlines()
        assert [(x, y) for x, y in zip(lines_a, lines_b) if x != y] == [(f' OUTPUT="{first}",', f' OUTPUT="{again}",')]
        assert len(lines_a) == len(lines_b)
        # the build: both programs print the digest the file carries
        assert a.attrs["code_digest"] == b.attrs["code_digest"] == printed_digest("airlaunch") \
            == printed_digest("airlaunch-sweep")
