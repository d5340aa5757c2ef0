"""The case table: one row per case, one variable per varied input, drawn with
scipy.stats.qmc (Latin hypercube, scrambled Sobol) or laid out as a full grid.

The same definition and seed give the same table, bit for bit (for one SciPy
version: the version is recorded in the table).
"""
from __future__ import annotations

import errno
import math
import os
import pathlib
import subprocess
import warnings

import numpy as np
import scipy
import scipy.stats as st
import xarray as xr
from scipy.stats import qmc

from . import files
from .definition import DefinitionError, InputSpec, SweepDefinition

#: Unit samples are kept this far inside (0, 1) so that unbounded quantile
#: functions stay finite (a scrambled point at exactly 0 has probability zero,
#: but the guard costs nothing).
U_GUARD = 1.0e-12


def unit_samples(design: str, n: int, d: int, seed: int) -> np.ndarray:
    """n points in [0, 1)^d from scipy.stats.qmc, shape (n, d)."""
    if design == "lhs":
        return qmc.LatinHypercube(d, scramble=True, rng=seed).random(n)
    if design == "sobol":
        sampler = qmc.Sobol(d, scramble=True, rng=seed)
        m = int(round(math.log2(n)))
        if 2**m == n:
            return sampler.random_base2(m)
        with warnings.catch_warnings():
            # the balance properties need n = 2^m (docs/sweep.md); the first n
            # points of the sequence are still a valid (if less even) design
            warnings.simplefilter("ignore", UserWarning)
            return sampler.random(n)
    raise DefinitionError(f"design '{design}' has no unit samples")


def quantile(spec: InputSpec, u: np.ndarray) -> np.ndarray:
    """Map probabilities u in [0, 1) to values of the input's distribution."""
    u = np.clip(u, U_GUARD, 1.0 - U_GUARD)
    if spec.distribution == "uniform":
        return st.uniform(loc=spec.lower, scale=spec.upper - spec.lower).ppf(u)
    if spec.distribution == "normal":
        return st.norm(loc=spec.mean, scale=spec.std).ppf(u)
    if spec.distribution == "truncnorm":
        a = (spec.lower - spec.mean) / spec.std
        b = (spec.upper - spec.mean) / spec.std
        x = st.truncnorm(a, b, loc=spec.mean, scale=spec.std).ppf(u)
        return np.clip(x, spec.lower, spec.upper)
    if spec.distribution == "list":
        k = len(spec.values)
        idx = np.minimum((u * k).astype(np.int64), k - 1)
        return np.asarray(spec.values, dtype=float)[idx]
    raise DefinitionError(f"distribution '{spec.distribution}' is unknown")


def grid_levels(spec: InputSpec) -> np.ndarray:
    """Grid levels of one input: the list's values, linspace(lower, upper) for a
    uniform input (one level: the midpoint), equal-probability cell medians for
    (truncated) normals."""
    if spec.distribution == "list":
        return np.asarray(spec.values, dtype=float)
    if spec.distribution == "uniform":
        if spec.levels == 1:
            return np.array([0.5 * (spec.lower + spec.upper)])
        return np.linspace(spec.lower, spec.upper, spec.levels)
    return quantile(spec, (np.arange(spec.levels) + 0.5) / spec.levels)


def draw_values(defn: SweepDefinition) -> np.ndarray:
    """The case values, shape (n_cases, n_inputs)."""
    if defn.design == "grid":
        axes = np.meshgrid(*[grid_levels(s) for s in defn.inputs], indexing="ij")
        return np.stack([a.ravel() for a in axes], axis=1)
    u = unit_samples(defn.design, defn.n_cases, len(defn.inputs), defn.seed)
    return np.stack([quantile(s, u[:, j]) for j, s in enumerate(defn.inputs)], axis=1)


def input_attrs(spec: InputSpec) -> dict:
    """Attributes that describe the input's distribution (checked by airlaunch-sweep)."""
    attrs = {"long_name": spec.description or f"varied input {spec.name}",
             "units": spec.units or "1", "distribution": spec.distribution}
    for key in ("lower", "upper", "mean", "std"):
        value = getattr(spec, key)
        if not math.isnan(value):
            attrs[key] = value
    if spec.distribution == "list":
        attrs["values"] = np.asarray(spec.values, dtype=float)
    if spec.levels:
        attrs["levels"] = np.int32(spec.levels)
    return attrs


def make_table(defn: SweepDefinition) -> xr.Dataset:
    """The case table of a definition as an xarray Dataset over dimension `case`."""
    with np.errstate(over="ignore", invalid="ignore"):   # named below instead
        values = draw_values(defn)
    for j, s in enumerate(defn.inputs):
        bad = ~np.isfinite(values[:, j])
        if bad.any():
            raise DefinitionError(f"{defn.path}: &input #{j + 1} '{s.name}': the {s.distribution} distribution "
                                  f"drew {float(values[bad, j][0])!r} for case {int(np.argmax(bad))} (its parameters are "
                                  "beyond what double precision spans: narrow them)")
    if values.shape[0] != defn.n_cases:
        raise DefinitionError(f"{defn.path}: the design gave {values.shape[0]} cases, "
                              f"n_cases = {defn.n_cases}")
    data = {s.name: ("case", values[:, j], input_attrs(s)) for j, s in enumerate(defn.inputs)}
    ds = xr.Dataset(data, coords={"case": ("case", np.arange(defn.n_cases, dtype=np.int32),
                                           {"long_name": "case id", "units": "1"})})
    ds.attrs.update({
        "title": f"airlaunch sweep case table: {defn.name}",
        "sweep_name": defn.name,
        "design": defn.design,
        "seed": np.int32(defn.seed),
        "n_cases": np.int32(defn.n_cases),
        "n_inputs": np.int32(len(defn.inputs)),
        "inputs": " ".join(s.name for s in defn.inputs),
        "base": defn.base,
        "sampler": {"lhs": "scipy.stats.qmc.LatinHypercube(scramble=True)",
                    "sobol": "scipy.stats.qmc.Sobol(scramble=True)",
                    "grid": "full grid (first input varies slowest)"}[defn.design],
        "scipy_version": scipy.__version__,
        "numpy_version": np.__version__,
    })
    return ds


def encoding(ds: xr.Dataset) -> dict:
    """No fill values: every case has every input."""
    return {name: {"_FillValue": None} for name in list(ds.data_vars) + list(ds.coords)}


def require_utf8_path(path, what) -> None:
    """A DefinitionError (one line) for a path that netCDF cannot take: its
    absolute form (as xarray passes it) is not UTF-8 text, e.g. a directory
    named in Latin-1 (netCDF4 encodes paths as strict UTF-8: a traceback,
    before; found by an audit)."""
    full = os.path.abspath(path)
    try:
        full.encode("utf-8")
    except UnicodeEncodeError:
        shown = os.fsencode(full).decode("utf-8", "backslashreplace")
        raise DefinitionError(f"{shown}: cannot {what}: its path is not UTF-8 text, which netCDF requires (run "
                              "from, and write to, directories whose names are UTF-8)") from None


def python_versions() -> dict:
    """The Python, libraries and netCDF/HDF5 that compute and write the sweep's
    Python files (table.nc, envelope.nc, verify.nc): their global attributes,
    as the Fortran files name their runtime environment (docs/sweep.md)."""
    import platform

    import netCDF4

    return {"python_version": platform.python_version(), "numpy_version": np.__version__,
            "scipy_version": scipy.__version__, "xarray_version": xr.__version__,
            "netcdf4_python_version": netCDF4.__version__, "netcdf_version": netCDF4.__netcdf4libversion__,
            "hdf5_version": netCDF4.__hdf5libversion__}


def write_atomic(ds: xr.Dataset, path) -> pathlib.Path:
    """Write a netCDF-4 file under a temporary name and rename it; on any
    failure the temporary file is removed and the exception goes on.  The file
    carries python_versions() (the caller's dataset is left as it is)."""
    path = pathlib.Path(path)
    require_utf8_path(path, "write the netCDF file")
    path.parent.mkdir(parents=True, exist_ok=True)
    ds = ds.assign_attrs(python_versions())
    return files.write_atomic(path, lambda tmp: ds.to_netcdf(tmp, engine="netcdf4", encoding=encoding(ds)))


#: Free space below which a write error without its own reason (netCDF's
#: "NetCDF: HDF error") is put down to a full device.
LOW_SPACE_BYTES = 1 << 20


def free_space(path):
    """Bytes free to an unprivileged user on the file system of `path` (or of
    its nearest existing parent); None if it cannot be told."""
    p = pathlib.Path(path).absolute()
    for q in (p, *p.parents):
        try:
            st_ = os.statvfs(q)
        except OSError:
            continue
        return st_.f_bavail * st_.f_frsize
    return None


def write_error_reason(target, exc) -> str:
    """The reason a write of `target` failed, in words: the OS's (strerror),
    else the first line of the message; a reason that does not say why
    ("NetCDF: HDF error"; netCDF even says "Permission denied" when its file
    does not fit at all) gets the likely cause when the device is (nearly)
    full.  A read-only file system is its own reason: it gets none."""
    if isinstance(exc, OSError) and exc.errno == errno.ENOSPC:
        return os.strerror(errno.ENOSPC)
    why = getattr(exc, "strerror", None) or (str(exc).strip().splitlines() or [type(exc).__name__])[0]
    if isinstance(exc, OSError) and exc.errno == errno.EROFS:
        return why
    free = free_space(pathlib.Path(target).parent)
    if free is not None and free < LOW_SPACE_BYTES:
        why += f" (likely: no space left on the device, {free} bytes free)"
    return why


def output_dir_error(defn: SweepDefinition, target, exc) -> DefinitionError:
    """One-line error naming &sweep output_dir when `target` under it cannot
    be written: the file and the reason (write_error_reason)."""
    target = pathlib.Path(target)
    out = pathlib.Path(defn.output_dir)
    why = f"cannot write {target}: {write_error_reason(target, exc)}"
    try:
        if out.exists() and not out.is_dir():
            why = "it is an existing file, not a directory"
        elif isinstance(exc, OSError) and exc.errno == errno.EISDIR and target.is_dir():
            why = f"{target} is a directory"
    except OSError:
        pass
    return DefinitionError(f"{defn.path}: &sweep: output_dir = '{defn.output_dir}' is not usable: {why} "
                           "(allowed: a directory that can be created and written)")


def open_netcdf(path, what, hint):
    """Open a netCDF file and load it; a file that is not one (empty, text,
    truncated, damaged) is a one-line DefinitionError."""
    require_utf8_path(path, f"read the {what}")
    try:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            return ds.load()
    except Exception as exc:  # netCDF4/HDF5/xarray raise OSError, RuntimeError, ValueError, KeyError...
        lines = str(exc).strip().splitlines() or [type(exc).__name__]
        raise DefinitionError(f"{path}: cannot read the {what}: not a netCDF file, or a truncated or damaged one "
                              f"({lines[0]}) ({hint})") from None


def write_table(defn: SweepDefinition, path=None) -> pathlib.Path:
    """Draw the table of `defn` and write it (default: OUTPUT_DIR/table.nc)."""
    return write_atomic(make_table(defn), path or defn.table_path)


#: The definition check takes well under a second; past this it is stuck.
CHECK_TIMEOUT_S = 300


def check_with_sweep(defn: SweepDefinition, sweep_exe) -> None:
    """Raise DefinitionError with airlaunch-sweep's own message if
    `airlaunch-sweep DEFINITION --check` refuses the definition: the base
    scenario (its scene, its text), every varied and fixed name and value
    against the scenario readers, worst_by, output_dir and, if
    OUTPUT_DIR/table.nc exists, the table.  Those checks need the scenario
    readers, so they are the Fortran program's, not repeated here."""
    try:
        res = subprocess.run([str(sweep_exe), str(defn.path), "--check"], capture_output=True, text=True,
                             errors="replace", check=False, timeout=CHECK_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        raise DefinitionError(f"{sweep_exe} {defn.path} --check did not end within {CHECK_TIMEOUT_S} s "
                              "(a singleton MPI start that hangs?)") from None
    except OSError as exc:
        raise DefinitionError(f"{sweep_exe}: cannot run airlaunch-sweep to check {defn.path} "
                              f"({exc.strerror or exc}; build it with scripts/setup release, or give --exe-dir)"
                              ) from None
    if res.returncode != 0:
        lines = res.stderr.strip().splitlines() or [f"airlaunch-sweep --check ended with exit status "
                                                    f"{res.returncode} and no message"]
        prefix = "airlaunch-sweep: error: "
        line = next((x for x in lines if x.startswith(prefix)), lines[-1])
        raise DefinitionError(line.removeprefix(prefix))


def check_table(defn: SweepDefinition, path=None) -> None:
    """Raise DefinitionError unless the table at `path` is exactly the table of `defn`."""
    path = pathlib.Path(path or defn.table_path)
    if not path.is_file():
        raise DefinitionError(f"{path}: case table does not exist (run the table step first)")
    want = make_table(defn)
    have = open_netcdf(path, "case table", "run the table step again")
    names = [s.name for s in defn.inputs]
    if sorted(have.data_vars) != sorted(names):
        raise DefinitionError(f"{path}: the table's inputs ({', '.join(have.data_vars)}) are not "
                              f"those of {defn.path} ({', '.join(names)})")
    for name in names:
        if have[name].dims != ("case",):
            raise DefinitionError(f"{path}: the table's {name} has dimensions {have[name].dims}, not (case,) "
                                  "(run the table step again)")
    if have.sizes.get("case") != defn.n_cases:
        raise DefinitionError(f"{path}: the table has {have.sizes.get('case')} cases, {defn.path} "
                              f"asks for {defn.n_cases}")
    for name in names:
        if not np.array_equal(have[name].values, want[name].values):
            raise DefinitionError(f"{path}: the values of {name} are not those that {defn.path} "
                                  "draws (definition changed since the table was made?)")
