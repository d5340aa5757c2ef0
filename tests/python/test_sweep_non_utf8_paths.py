"""Paths that are not UTF-8 text (an audit):

- a definition file that is not UTF-8 (read as Latin-1) whose output_dir held
  a byte beyond ASCII: the table step wrote table.nc under the UTF-8 encoding
  of the Latin-1 text ('lat\\xc3\\xbfdir') while airlaunch-sweep, taking the
  bytes as they are, looked in 'lat\\xffdir' ("case table does not exist");
  now refused in one line by every Python step (and so by scripts/sweep's
  first check, before any case);
- a working directory (or output directory) whose name is not UTF-8: netCDF4
  encodes paths as strict UTF-8 and the table step ended in a traceback
  (UnicodeEncodeError), the envelope step called the summary "not a netCDF
  file"; now one line naming the path and why, exit status 2."""
import numpy as np
import xarray as xr

from test_sweep_support import PAPER, SWEEP_EXE, run_python, small_definition

from postproc.sweep.definition import read_definition
from postproc.sweep.table import make_table


def test_latin1_definition_with_a_non_ascii_output_dir_is_refused(tmp_path):
    d = tmp_path / "s.nml"
    d.write_bytes(f"&sweep name = 'x', base = '{PAPER}', output_dir = 'lat\xffdir', design = 'lhs', n_cases = 4, "
                  "seed = 1 /\n&input name = 'bay%release_time', distribution = 'uniform', lower = 0.4, upper = 1.0 /\n"
                  .encode("latin-1"))
    crit = tmp_path / "c.nml"
    crit.write_text("&criteria min_clearance_m = 1.5 /\n")
    for step in (["envelope", d, "--criteria", crit, "--check"], ["table", d]):
        res = run_python(step, tmp_path)
        lines = res.stderr.strip().splitlines()
        assert res.returncode == 2 and len(lines) == 1, res.stdout + res.stderr
        assert "output_dir = 'lat\\xffdir' is not allowed: the file is not UTF-8" in lines[0], lines[0]
    assert not [p for p in tmp_path.iterdir() if p.name.startswith("lat")]


def test_latin1_comments_and_ascii_paths_still_work(tmp_path):
    d = tmp_path / "s.nml"
    d.write_bytes(f"! caf\xe9\n&sweep name = 'x', base = '{PAPER}', output_dir = 'out', design = 'lhs', n_cases = 4, "
                  "seed = 1 /\n&input name = 'bay%release_time', distribution = 'uniform', lower = 0.4, upper = 1.0 /\n"
                  .encode("latin-1"))
    assert read_definition(d).output_dir == "out"


def _summary_of(d, n):
    t = make_table(read_definition(d))
    ds = xr.Dataset({"bay%release_time": ("case", t["bay%release_time"].values),
                     "status": ("case", np.zeros(n, np.int32)), "min_clearance_m": ("case", np.full(n, 5.0))},
                    coords={"case": np.arange(n)})
    ds.attrs.update(inputs="bay%release_time", design="lhs", seed=np.int32(7), n_cases=np.int32(n))
    return ds


def test_envelope_in_a_directory_whose_name_is_not_utf8(tmp_path):
    where = tmp_path / "caf\udce9"          # the byte 0xe9: 'café' in Latin-1
    where.mkdir()
    n = 4
    d = where / "s.nml"
    d.write_text(f"&sweep name = 'u', base = '{PAPER}', output_dir = 'out', design = 'lhs', n_cases = {n}, "
                 "seed = 7 /\n&input name = 'bay%release_time', distribution = 'uniform', lower = 0.4, "
                 "upper = 1.0 /\n")
    (where / "out").mkdir()
    # the summary written from a UTF-8 path, then moved under the Latin-1 name
    (tmp_path / "s.nml").write_text(d.read_text())
    _summary_of(tmp_path / "s.nml", n).to_netcdf(tmp_path / "summary.nc")
    (tmp_path / "summary.nc").rename(where / "out" / "summary.nc")
    (where / "c.nml").write_text("&criteria min_clearance_m = 1.5 /\n")
    res = run_python(["envelope", "s.nml", "--criteria", "c.nml", "--no-figures"], where)
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 2 and len(lines) == 1, res.stderr
    assert "Traceback" not in res.stderr
    assert "caf\\xe9/out/summary.nc: cannot read the summary: its path is not UTF-8 text" in lines[0], lines[0]


def test_table_in_a_directory_whose_name_is_not_utf8(tmp_path):
    if not SWEEP_EXE.exists():
        import pytest
        pytest.skip("airlaunch-sweep is not built")
    where = tmp_path / "caf\udce9"
    where.mkdir()
    small_definition(where / "s.nml", n_cases=4, output_dir="out")
    res = run_python(["table", "s.nml", "--exe-dir", SWEEP_EXE.parent], where)
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 2 and len(lines) == 1, res.stderr
    assert "Traceback" not in res.stderr
    assert "caf\\xe9/out/table.nc: cannot write the netCDF file: its path is not UTF-8 text" in lines[0], lines[0]
    assert not list((where / "out").glob("table.nc*"))
