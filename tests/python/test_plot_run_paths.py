"""plot_run.py on an output whose path is not UTF-8 text (a directory named in
Latin-1; an audit): netCDF cannot open it, and the one line said "cannot read
it as netCDF ('utf-8' codec can't encode character '\\udcff' ...)"; it now
names the path (its bytes escaped) and why. The figure is drawn once the file
is at a UTF-8 path."""
import subprocess
import sys

import numpy as np
import xarray as xr

ROOT = __import__("pathlib").Path(__file__).resolve().parents[2]


def drop_output(path):
    t = np.linspace(0.0, 1.0, 5)
    pos = np.stack([t, 100.0 - t**2, 0 * t], axis=1)
    ds = xr.Dataset({"store_position": (("time", "xyz"), pos), "store_mach": ("time", 0.5 + 0 * t)},
                    coords={"time": t})
    ds.attrs.update(scene="drop", title="drop", status="completed")
    ds.to_netcdf(path)


def plot(*args):
    return subprocess.run([sys.executable, str(ROOT / "postproc" / "plot_run.py"), *map(str, args)],
                          capture_output=True, text=True, timeout=120)


def test_output_under_a_path_that_is_not_utf8(tmp_path):
    drop_output(tmp_path / "run.nc")
    where = tmp_path / "caf\udce9"   # the byte 0xe9
    where.mkdir()
    (tmp_path / "run.nc").rename(where / "run.nc")
    res = plot(where / "run.nc", tmp_path / "f.png")
    assert res.returncode == 2, res.stderr
    assert res.stderr.count("\n") == 1, res.stderr
    assert "caf\\xe9/run.nc: cannot read it: its path is not UTF-8 text" in res.stderr, res.stderr
    assert not (tmp_path / "f.png").exists()
    (where / "run.nc").rename(tmp_path / "run.nc")
    res = plot(tmp_path / "run.nc", tmp_path / "f.png")
    assert res.returncode == 0, res.stderr
    assert (tmp_path / "f.png").stat().st_size > 1000
