"""The runtime numerical environment every output file names (docs/output.md,
"Runtime numerical environment"): the BLAS/LAPACK library that computes, the
OpenBLAS kernel, LAPACK's version, glibc's libm features, SUNDIALS, HDF5, the
processor, and in a sweep MPI and every rank's own.  Each value is checked
against an independent query of the same thing: the library found by walking
`ldd`'s list and loading it with ctypes (openblas_get_corename, ilaver), the
version string inside the HDF5 library the build linked, SUNDIALS's
configuration header, /proc/cpuinfo, `mpirun --version`; and the kernel a
forced OPENBLAS_CORETYPE names.  No tolerance: the values are text."""
import json
import os
import pathlib
import platform
import re
import subprocess
import sys

import pytest
import xarray as xr

from conftest import BIN, ROOT

sys.path.insert(0, str(pathlib.Path(__file__).parent))
from test_sweep_support import SWEEP_EXE, make_table, mpirun, small_definition  # noqa: E402

DROP = ROOT / "input" / "drop_demo.nml"
NAMES = ["cpu_model", "cpu_features", "blas_library", "blas_core", "blas_config", "lapack_library",
         "lapack_version", "libm", "sundials_version", "hdf5_version"]
BASE_ENV = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_CORETYPE", "GLIBC_TUNABLES", "LD_PRELOAD")}
BASE_ENV["OPENBLAS_NUM_THREADS"] = "1"


def run_drop(tmp_path, name="run", **extra_env):
    """The drop demo (20 ms) written to tmp_path/NAME.nc: its global attributes."""
    out = tmp_path / f"{name}.nc"
    res = subprocess.run([str(BIN / "airlaunch"), str(DROP), "--output", str(out)], capture_output=True,
                         text=True, env={**BASE_ENV, **extra_env}, timeout=60)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(out) as ds:
        return dict(ds.attrs)


def cpuinfo():
    """(model name, vendor_id, flags) of the first processor in /proc/cpuinfo."""
    text = pathlib.Path("/proc/cpuinfo").read_text()
    field = lambda key: re.search(rf"^{key}\s*:\s*(.*)$", text, flags=re.M)  # noqa: E731
    return (field("model name").group(1).strip() if field("model name") else "unknown",
            field("vendor_id").group(1).strip() if field("vendor_id") else "",
            set(field("flags").group(1).split()) if field("flags") else set())


def providing_library(symbol):
    """The first library of the program's `ldd` list (the dynamic linker's
    search order) whose dynamic symbol table defines `symbol` (`nm -D`), its
    real path; None if none does."""
    res = subprocess.run(["ldd", str(BIN / "airlaunch")], capture_output=True, text=True, timeout=60)
    for path in re.findall(r"=> (/\S+)", res.stdout):
        table = subprocess.run(["nm", "-D", "--defined-only", path], capture_output=True, text=True, timeout=60)
        if re.search(rf"^\S+ [TWi] {re.escape(symbol)}$", table.stdout, flags=re.M):
            return os.path.realpath(path)
    return None


def ctypes_blas(library, **extra_env):
    """openblas_get_corename, openblas_get_config and ilaver of `library`,
    loaded by ctypes in a fresh Python whose environment is the run's (the
    kernel is chosen when the library loads)."""
    script = f"""
import ctypes, json
lib = ctypes.CDLL({str(library)!r})
out = {{"core": "unknown", "config": "unknown", "ilaver": "unknown"}}
if hasattr(lib, "openblas_get_corename"):
    lib.openblas_get_corename.restype = ctypes.c_char_p
    lib.openblas_get_config.restype = ctypes.c_char_p
    out["core"] = lib.openblas_get_corename().decode()
    out["config"] = lib.openblas_get_config().decode()
if hasattr(lib, "ilaver_"):
    v = [ctypes.c_int() for _ in range(3)]
    lib.ilaver_(*[ctypes.byref(x) for x in v])
    out["ilaver"] = ".".join(str(x.value) for x in v)
print(json.dumps(out))
"""
    res = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         env={**BASE_ENV, **extra_env}, timeout=60)
    assert res.returncode == 0, res.stderr
    return json.loads(res.stdout)


def cmake_cache(name):
    text = (ROOT / "build" / "release" / "CMakeCache.txt").read_text()
    m = re.search(rf"^{re.escape(name)}:[A-Z]+=(.*)$", text, flags=re.M)
    return m.group(1) if m else ""


def test_every_file_names_its_runtime_environment(tmp_path):
    attrs = run_drop(tmp_path)
    for name in NAMES:
        assert isinstance(attrs.get(name), str) and attrs[name].strip(), f"{name} missing or empty"
    assert "mpi_library" not in attrs   # a single run does not compute with MPI

    model, vendor, flags = cpuinfo()
    assert attrs["cpu_model"] == model
    if platform.machine() == "x86_64":
        want = [{"AuthenticAMD": "AMD", "GenuineIntel": "Intel"}.get(vendor, "other")]
        want += [f for f in ("avx512f", "avx2", "fma", "fma4", "avx", "sse4_2") if f in flags]
        assert attrs["cpu_features"] == " ".join(want)

    blas, lapack = providing_library("dgemm_"), providing_library("dgetrf_")
    assert attrs["blas_library"] == blas and attrs["lapack_library"] == lapack
    own = ctypes_blas(blas)
    assert (attrs["blas_core"], attrs["blas_config"]) == (own["core"], own["config"])
    assert attrs["lapack_version"] == ctypes_blas(lapack)["ilaver"]

    libc, version = platform.libc_ver()
    if libc == "glibc":
        assert attrs["libm"].startswith(f"glibc {version}")
        if platform.machine() == "x86_64":
            usable = [f for f in ("fma", "avx2", "fma4", "avx") if f in flags]
            assert attrs["libm"] == f"glibc {version} (usable:{''.join(' ' + f for f in usable)})"

    # HDF5: the version string inside the library the build linked (static or shared)
    hdf5 = pathlib.Path(cmake_cache("HDF5_Fortran_LIBRARY_hdf5"))
    found = re.search(rb"HDF5 library version: (\d+\.\d+\.\d+)", hdf5.read_bytes())
    assert found and attrs["hdf5_version"] == found.group(1).decode()
    # SUNDIALS: the configuration header of the build it was linked with
    root = cmake_cache("AIRLAUNCH_SUNDIALS_ROOT")
    header = pathlib.Path(root, "include") if root else pathlib.Path("/usr/include")
    config = (header / "sundials" / "sundials_config.h").read_text()
    assert attrs["sundials_version"] == re.search(r'#define SUNDIALS_VERSION "([^"]+)"', config).group(1)


def test_version_prints_the_files_environment(tmp_path):
    """`airlaunch --version` prints the same names and values as a file of the
    same environment carries."""
    attrs = run_drop(tmp_path)
    res = subprocess.run([str(BIN / "airlaunch"), "--version"], capture_output=True, text=True, env=BASE_ENV,
                         timeout=60)
    assert res.returncode == 0, res.stderr
    printed = dict(re.findall(r"^  (\w+) = (.*)$", res.stdout, flags=re.M))
    assert printed == {name: attrs[name] for name in NAMES}


def test_a_forced_kernel_is_named(tmp_path):
    """OPENBLAS_CORETYPE forced to two kernels this processor runs (Prescott:
    any x86-64; Sandybridge with AVX, Haswell with AVX2): each file names the
    one forced, which ctypes' openblas_get_corename of the same library
    confirms; the two differ.  (The paper scenario's bits differ between such
    kernels: docs/validation.md, "Reproducing a result across machines".)"""
    attrs = run_drop(tmp_path)
    if attrs["blas_core"] == "unknown":
        pytest.skip("not OpenBLAS: no kernel to force")
    _, _, flags = cpuinfo()
    other = "Haswell" if {"avx2", "fma"} <= flags else "Sandybridge" if "avx" in flags else None
    if other is None:
        pytest.skip("the processor has no AVX: one kernel only")
    seen = []
    for kernel in ("Prescott", other):
        forced = run_drop(tmp_path, kernel, OPENBLAS_CORETYPE=kernel)
        assert forced["blas_core"] == kernel == ctypes_blas(attrs["blas_library"], OPENBLAS_CORETYPE=kernel)["core"]
        assert kernel in forced["blas_config"]
        seen.append(forced["blas_core"])
    assert seen[0] != seen[1]


def test_masked_libm_features_are_named(tmp_path):
    """GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA takes glibc's libm off its
    FMA variants (the paper scenario then takes 624 steps instead of 622 with
    the Sandybridge kernel: docs/validation.md): the file says fma and avx2
    are not usable."""
    libc, version = platform.libc_ver()
    _, _, flags = cpuinfo()
    if libc != "glibc" or platform.machine() != "x86_64" or not {"fma", "avx2"} <= flags:
        pytest.skip("needs glibc on an x86-64 with FMA and AVX2")
    attrs = run_drop(tmp_path, GLIBC_TUNABLES="glibc.cpu.hwcaps=-AVX2,-FMA")
    usable = [f for f in ("fma4", "avx") if f in flags]
    assert attrs["libm"] == f"glibc {version} (usable:{''.join(' ' + f for f in usable)})"


def test_a_sweep_names_the_environment_of_every_case(tmp_path):
    """Two ranks on different OpenBLAS kernels (mpirun's MPMD form, each rank
    its own OPENBLAS_CORETYPE: two node types of a cluster): summary.nc lists
    both environments, and each case's `environment` names the kernel of the
    rank whose journal file holds its row; the writer's own attributes name
    the MPI library `mpirun --version` reports."""
    _, _, flags = cpuinfo()
    if ctypes_blas(providing_library("dgemm_"))["core"] == "unknown" or "avx" not in flags:
        pytest.skip("needs OpenBLAS and AVX (two kernels)")
    kernels = ["Prescott", "Sandybridge"]
    definition = small_definition(tmp_path / "d.nml", n_cases=6, t_end=1.0)
    make_table(definition, tmp_path)
    cmd = mpirun(len(kernels))
    del cmd[-2:]   # mpirun's flags; each program takes its own -np
    for kernel in kernels:
        cmd += ["-np", "1", "-x", f"OPENBLAS_CORETYPE={kernel}", "-x", "OPENBLAS_NUM_THREADS=1",
                str(SWEEP_EXE), str(definition), ":"]
    res = subprocess.run(cmd[:-1], cwd=tmp_path, capture_output=True, text=True, env=BASE_ENV, timeout=120)
    assert res.returncode == 0, res.stdout + res.stderr
    journal = tmp_path / "out" / "journal"
    recorded = journal.joinpath("environments.txt").read_text()
    assert sorted(re.findall(r"blas_core=(\w+);", recorded)) == sorted(kernels)   # every rank's, once
    ran_on = {}
    for rank, kernel in enumerate(kernels):
        for line in (journal / f"rank_{rank:04d}.txt").read_text().splitlines():
            ran_on[int(line.split()[1])] = kernel
    with xr.open_dataset(tmp_path / "out" / "summary.nc") as s:
        listed = s.attrs["environments"].splitlines()
        assert len(listed) == len(set(ran_on.values()))
        for case, index in enumerate(s["environment"].values):
            assert listed[index].startswith(f"{index}: ")
            assert f"blas_core={ran_on[case]};" in listed[index], (case, listed[index])
        version = re.search(r"\(Open MPI\) (\S+)", subprocess.run(["mpirun", "--version"], capture_output=True,
                                                                   text=True, timeout=60).stdout)
        if version:
            assert f"Open MPI v{version.group(1)}" in s.attrs["mpi_library"]
        assert s.attrs["blas_core"] == kernels[0]   # rank 0 wrote it


def test_python_files_name_their_libraries(tmp_path):
    """The sweep's Python steps write table.nc, envelope.nc and verify.nc
    through one function: each file names the Python, NumPy, SciPy, xarray,
    netCDF4-python and the netCDF-C and HDF5 libraries that wrote it, as
    this Python reports them."""
    import netCDF4
    import numpy as np
    import scipy

    sys.path.insert(0, str(ROOT))
    from postproc.sweep.table import write_atomic

    ds = xr.Dataset({"x": ("case", np.arange(3.0), {"units": "1", "long_name": "x"})})
    write_atomic(ds, tmp_path / "t.nc")
    assert "numpy_version" not in ds.attrs   # the caller's dataset is left as it was
    with xr.open_dataset(tmp_path / "t.nc") as back:
        assert {k: back.attrs[k] for k in back.attrs if k.endswith("_version")} == {
            "python_version": platform.python_version(), "numpy_version": np.__version__,
            "scipy_version": scipy.__version__, "xarray_version": xr.__version__,
            "netcdf4_python_version": netCDF4.__version__, "netcdf_version": netCDF4.__netcdf4libversion__,
            "hdf5_version": netCDF4.__hdf5libversion__}
