"""The envelope step (and verify) refuse a summary whose &sweep t_end is not
the definition's (twenty-sixth session), but only compared a t_end > 0: a
sweep run at t_end = 4 s whose definition then said t_end = 0 (the base's
&run t_end, 15 s for the paper scenario) was evaluated as the new
definition's, and verify would rerun its cases at 15 s (an audit). t_end = 0
is now compared with the base's &run t_end as the summary records it."""
import numpy as np
import pytest
import xarray as xr

from test_sweep_support import PAPER, run_python

from postproc.sweep.definition import read_definition
from postproc.sweep.table import make_table

BASE_NAMELIST = "&RUN\n SCENE=\"airlaunch\",\n T_END=  15.000000000000000     ,\n OUTPUT_DT=  2.0E-002,\n /\n" \
                "&LINE_SCENE\n T_END_X=  3.0 ,\n /\n"


def sweep(tmp_path, t_end_def, t_end_ran, n=4):
    d = tmp_path / "s.nml"
    d.write_text(f"&sweep name = 'u', base = '{PAPER}', output_dir = 'out', design = 'lhs', n_cases = {n}, "
                 f"seed = 7, t_end = {t_end_def} /\n&input name = 'bay%release_time', distribution = 'uniform', "
                 "lower = 0.4, upper = 1.0 /\n")
    t = make_table(read_definition(d))
    ds = xr.Dataset({"bay%release_time": ("case", t["bay%release_time"].values),
                     "status": ("case", np.zeros(n, np.int32)), "min_clearance_m": ("case", np.full(n, 5.0))},
                    coords={"case": np.arange(n)})
    ds.attrs.update(inputs="bay%release_time", design="lhs", seed=np.int32(7), n_cases=np.int32(n),
                    t_end_s=float(t_end_ran), base_namelist=BASE_NAMELIST)
    (tmp_path / "out").mkdir()
    ds.to_netcdf(tmp_path / "out" / "summary.nc")
    (tmp_path / "c.nml").write_text("&criteria min_clearance_m = 1.5 /\n")
    return d


@pytest.mark.parametrize("t_end_def,t_end_ran,refused", [(0.0, 4.0, True), (0.0, 15.0, False), (4.0, 4.0, False),
                                                         (5.0, 4.0, True)])
def test_t_end_zero_is_the_base_t_end(tmp_path, t_end_def, t_end_ran, refused):
    d = sweep(tmp_path, t_end_def, t_end_ran)
    res = run_python(["envelope", d, "--criteria", tmp_path / "c.nml", "--no-figures"], tmp_path)
    if not refused:
        assert res.returncode == 0, res.stderr
        return
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 2 and len(lines) == 1, res.stderr
    assert "the definition changed since the sweep ran" in lines[0]
    if t_end_def == 0:
        assert "(&sweep t_end = 0, the base's 15 s, the sweep ran 4 s)" in lines[0], lines[0]
