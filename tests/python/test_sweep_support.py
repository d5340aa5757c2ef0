"""Helpers shared by the sweep tests (this module holds no test): the programs,
a small sweep of the paper scenario (10 line segments, 4 s simulated, so a case
costs a fraction of a second), running airlaunch-sweep under mpirun, and
comparing summaries bit for bit."""
import os
import pathlib
import re
import subprocess
import sys

import numpy as np
import xarray as xr

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

SWEEP_EXE = ROOT / "build" / os.environ.get("AIRLAUNCH_SWEEP_BUILD", "release") / "bin" / "airlaunch-sweep"
AIRLAUNCH_EXE = ROOT / "build" / os.environ.get("AIRLAUNCH_SWEEP_BUILD", "release") / "bin" / "airlaunch"
PAPER = ROOT / "input" / "airlaunch_paper.nml"
ENV = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", PYTHONPATH=str(ROOT),
           MPLBACKEND="Agg")

#: Three continuous inputs around the paper scenario; short and coarse for speed.
SMALL_INPUTS = """
&input name = 'bay%release_time', distribution = 'uniform', lower = 0.4, upper = 1.0, units = 's' /
&input name = 'parachute%drag_area', distribution = 'truncnorm', mean = 10.0, std = 1.5,
       lower = 7.0, upper = 13.0, units = 'm2' /
&input name = 'flight%mach', distribution = 'normal', mean = 0.65, std = 0.02 /
"""


def small_definition(path, n_cases=40, output_dir="out", extra_sweep="", inputs=SMALL_INPUTS,
                     design="lhs", seed=5, t_end=4.0, fixed="&fixed name = 'line%n_seg', value = '10' /"):
    """Write a small sweep definition of the paper scenario; return its path."""
    path = pathlib.Path(path)
    path.write_text(f"""&sweep
  name = 'small'
  base = '{PAPER}'
  output_dir = '{output_dir}'
  design = '{design}'
  n_cases = {n_cases}
  seed = {seed}
  t_end = {t_end}
  progress_interval = 0.5
  {extra_sweep}
/
{fixed}
{inputs}
""")
    return path


def make_table(definition, cwd):
    """Draw the table of a definition with paths relative to cwd."""
    from postproc.sweep.definition import read_definition
    from postproc.sweep.table import write_table

    defn = read_definition(definition)
    return write_table(defn, pathlib.Path(cwd) / defn.table_path)


def run_example_sweep(name, tmp_path, edits):
    """input/NAME.nml with its paths made absolute (base, criteria) and its
    output in tmp_path/out, cut down by the text `edits` (old, new: each must
    match), written to tmp_path; its table drawn, checked (--check) and run on
    one rank: returns the summary's path."""
    text = (ROOT / "input" / f"{name}.nml").read_text()
    # the base scenario and the criteria file from input/, whichever they are
    text, n = re.subn(r"^(\s*(?:base|criteria)\s*=\s*')input/", lambda m: f"{m.group(1)}{ROOT / 'input'}/", text,
                      flags=re.M)
    assert n >= 1
    for old, new in [(f"output_dir = 'output/{name}'", "output_dir = 'out'"), *edits]:
        assert old in text, old
        text = text.replace(old, new)
    definition = tmp_path / f"{name}.nml"
    definition.write_text(text)
    make_table(definition, tmp_path)
    for args in (("--check",), ()):
        res = run_sweep(definition, tmp_path, None, *args)
        assert res.returncode == 0, res.stderr
    return tmp_path / "out" / "summary.nc"


def mpirun(ranks):
    """mpirun with the flags this machine needs (root, more ranks than cores)."""
    cmd = ["mpirun"]
    if os.geteuid() == 0:
        cmd.append("--allow-run-as-root")
    if ranks > (os.cpu_count() or 1):
        cmd.append("--oversubscribe")
    return cmd + ["-np", str(ranks)]


def run_sweep(definition, cwd, ranks=None, *args, timeout=600):
    """airlaunch-sweep (under mpirun -np ranks, or alone if ranks is None)."""
    cmd = (mpirun(ranks) if ranks else []) + [str(SWEEP_EXE), str(definition), *map(str, args)]
    return subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, env=ENV, timeout=timeout)


def run_python(args, cwd):
    """python -m postproc.sweep ARGS."""
    return subprocess.run([sys.executable, "-m", "postproc.sweep", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, env=ENV, timeout=600)


def assert_same_summary(a_path, b_path, ignore_vars=("wall_time_s",), ignore_attrs=("created",)):
    """Every variable (bit for bit) and attribute of two summaries agree, except the
    per-case wall time and the creation stamp."""
    with xr.open_dataset(a_path) as a, xr.open_dataset(b_path) as b:
        assert sorted(a.variables) == sorted(b.variables)
        for name in a.variables:
            if name in ignore_vars:
                continue
            va, vb = a[name].values, b[name].values
            if va.dtype.kind in "OUS":
                assert list(va) == list(vb), name
            else:
                assert va.dtype == vb.dtype and va.tobytes() == vb.tobytes(), f"{name} differs"
        for key in set(a.attrs) | set(b.attrs):
            if key not in ignore_attrs:
                assert np.array_equal(np.asarray(a.attrs.get(key)), np.asarray(b.attrs.get(key))), key


def assert_line_row_is_the_run(row, ds, t_end):
    """A line-scene sweep's summary row (`row`: variable -> value) holds what the
    single run of its case namelist (`ds`, its output) reports."""
    assert row["peak_line_tension_N"] == ds.attrs["peak_tension_N"]
    assert row["peak_line_tension_time_s"] == ds.attrs["peak_tension_time_s"]
    assert row["peak_line_tension_segment"] == ds.attrs["peak_tension_segment"]
    ends = ds["line_end_tension"].values
    assert row["max_end_tension_a_N"] == ends[:, 0].max()
    assert row["max_end_tension_b_N"] == ends[:, 1].max()
    assert row["canopy_deploy_air_speed_m_s"] == ds.attrs["canopy_deploy_air_speed_m_s"]
    # (Fortran's norm2 and numpy's norm may round the last bit apart)
    tip_speed = np.linalg.norm(ds["line_tip_velocity"].values[-1])
    assert abs(row["final_tip_speed_m_s"] - tip_speed) <= 1e-15 * tip_speed
    assert row["end_time_s"] == ds["time"].values[-1] == t_end
    assert row["steps"] == ds.attrs["steps"]


def journal_rows(journal_dir):
    """(valid case ids, bad lines) of the journal files, checked with zlib's Adler-32."""
    import zlib

    ids, bad = [], 0
    for path in sorted(pathlib.Path(journal_dir).glob("rank_*.txt")):
        for line in path.read_text().splitlines():
            if not line.strip():
                continue
            head, _, body = line.partition(" ")
            if len(head) == 8 and int(head, 16) == zlib.adler32(body.encode()):
                ids.append(int(body.split()[0]))
            else:
                bad += 1
    return ids, bad
