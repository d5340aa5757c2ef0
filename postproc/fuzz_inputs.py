"""Input fuzz: every `name = value` assignment of the example scenario files set,
one at a time, to extreme and malformed values, each run checked against the
project's rule for bad input and numerical failure (README, docs/input.md):

- exit 0: completed, and no NaN or infinity in any floating-point variable of
  the output file;
- exit 2: bad input -- exactly one line on stderr, starting `airlaunch: error:`,
  and no output file;
- exit 3: numerical failure -- the first stderr line starts `airlaunch: error:`
  and names the time (`t = `), the output so far (if any) holds no NaN and has
  `status = failed`;
- anything else -- a signal, a Fortran runtime error, a multi-line input error,
  a run longer than the time limit -- is a finding; and so is a null value
  (`,` or `2*`, which a namelist read skips, keeping the default) that does not
  give an input error.

Usage: scripts/fuzz [--files input/a.nml,...] [--values 0.0,-1.0,...] [--jobs 2]
[--timeout 600] [--quick].  Prints one line per finding, a table per file and a
final `RESULT {json}` line; exit status 1 if there is any finding.
"""
import argparse
import concurrent.futures as cf
import json
import os
import pathlib
import re
import subprocess
import sys
import tempfile
import threading
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
EXE = pathlib.Path(os.environ.get("AIRLAUNCH_EXE", ROOT / "build" / "release" / "bin" / "airlaunch"))
FILES = ["airlaunch_paper", "airlaunch_gravity_drop", "drop_demo", "line_pendulum", "line_catenary",
         "line_parachute", "line_fishhook", "line_opening", "line_airdrop", "line_snapback"]
VALUES = ["0.0", "-1.0", "1.0e30", "1e-30", "nan", "-inf", "1.0, 2.0", "'abc'", ".true.", ",", "2*"]
#: values a namelist read skips (keeping the default): each must be an input error
NULL_VALUES = (",", "2*")
QUICK_VALUES = ["-1.0", "1.0e30", "nan"]
ASSIGNMENT = re.compile(r"^(\s*)([a-z_][a-z_0-9]*)(\s*=\s*)([^!]*?)(\s*(!.*)?)$", re.I)


def variants(path, values):
    """(variable, value, text) for every assignment line of the file except the
    scene and the output path."""
    lines = path.read_text().splitlines()
    for i, line in enumerate(lines):
        m = ASSIGNMENT.match(line)
        if not m or m.group(2).lower() in ("scene", "output"):
            continue
        for v in values:
            new = lines.copy()
            new[i] = f"{m.group(1)}{m.group(2)} = {v}"
            yield m.group(2), v, "\n".join(new) + "\n"


#: HDF5 (under netCDF4 and xarray) is not thread-safe: two runs' files read at
#: once crashed the fuzz ("trap stack segment" in libhdf5)
HDF5_LOCK = threading.Lock()


def output_ok(out, failed):
    """No NaN/Inf in the output's floating-point variables; `status` as expected."""
    if not out.exists():
        return False, "no output file"
    with HDF5_LOCK:
        return _output_ok(out, failed)


def _output_ok(out, failed):
    import xarray as xr
    with xr.open_dataset(out) as ds:
        for name, var in ds.variables.items():
            if var.dtype.kind == "f" and not np.isfinite(var.values).all():
                return False, f"non-finite values in {name}"
        status = ds.attrs.get("status")
        if status != ("failed" if failed else "completed"):
            return False, f"status = {status!r}"
    return True, ""


def run_one(job):
    base, name, value, text, timeout, tmp = job
    tag = f"{base}_{name}_{abs(hash((name, value))) % 10**8}"
    nml = tmp / f"{tag}.nml"
    out = tmp / f"{tag}.nc"
    nml.write_text(re.sub(r"^(\s*)output\s*=.*$", rf"\1output = '{out}'", text, flags=re.M))
    t0 = time.perf_counter()
    try:
        res = subprocess.run([str(EXE), str(nml)], capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return base, name, value, "finding", f"no answer within {timeout:.0f} s", time.perf_counter() - t0
    wall = time.perf_counter() - t0
    err = res.stderr.strip().splitlines()
    first = err[0] if err else ""
    try:
        if value in NULL_VALUES and res.returncode != 2:
            return base, name, value, "finding", f"null value not refused: exit {res.returncode}", wall
        if res.returncode == 0:
            ok, why = output_ok(out, failed=False)
            return base, name, value, ("completed" if ok else "finding"), why, wall
        if res.returncode == 2:
            ok = len(err) == 1 and first.startswith("airlaunch: error: ") and not out.exists()
            return base, name, value, ("input error" if ok else "finding"), first if ok else \
                f"exit 2 but {len(err)} stderr lines: {' | '.join(err[:3])}", wall
        if res.returncode == 3:
            ok = first.startswith("airlaunch: error: ") and "t = " in first
            why = first
            if ok and (out.exists() or "output so far" in res.stderr):
                ok, why2 = output_ok(out, failed=True)
                why = first if ok else why2
            return base, name, value, ("numerical failure" if ok else "finding"), why, wall
        return base, name, value, "finding", f"exit {res.returncode}: {' | '.join(err[:3])}", wall
    finally:
        for p in (nml, out):
            p.unlink(missing_ok=True)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--files", default=",".join(FILES), help="input names (input/NAME.nml) or paths")
    ap.add_argument("--values", default=None, help="comma-free list separated by ';' (default: %s)" % VALUES)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--timeout", type=float, default=600.0, help="s per run (a default-budget crawl takes ~3 min)")
    ap.add_argument("--slow", type=float, default=20.0, help="print runs longer than this [s]")
    ap.add_argument("--quick", action="store_true", help="three values (%s) only" % QUICK_VALUES)
    args = ap.parse_args(argv)
    values = args.values.split(";") if args.values else (QUICK_VALUES if args.quick else VALUES)
    paths = [pathlib.Path(f) if f.endswith(".nml") else ROOT / "input" / f"{f}.nml" for f in args.files.split(",")]
    for p in paths:
        if not p.is_file():
            ap.error(f"--files: {p} is not a file (give input/NAME.nml paths or names of input/*.nml)")
    results = []
    with tempfile.TemporaryDirectory(prefix="airlaunch_fuzz_") as d:
        tmp = pathlib.Path(d)
        jobs = [(p.stem, n, v, t, args.timeout, tmp) for p in paths for n, v, t in variants(p, values)]
        print(f"fuzz: {len(jobs)} runs of {EXE} ({len(paths)} files, {len(values)} values, {args.jobs} jobs)",
              flush=True)
        with cf.ThreadPoolExecutor(args.jobs) as pool:
            for r in pool.map(run_one, jobs):
                results.append(r)
                if r[3] == "finding":
                    print(f"FINDING {r[0]}: {r[1]} = {r[2]}: {r[4]}", flush=True)
                elif r[5] > args.slow:
                    print(f"slow    {r[0]}: {r[1]} = {r[2]}: {r[3]} after {r[5]:.1f} s: {r[4][:160]}",
                          flush=True)
    print(f"\n{'file':<24} {'runs':>5} {'completed':>9} {'input err':>9} {'num fail':>8} {'findings':>8} "
          f"{'slowest [s]':>11}")
    summary = {}
    for p in paths:
        rs = [r for r in results if r[0] == p.stem]
        c = {k: sum(r[3] == k for r in rs) for k in ("completed", "input error", "numerical failure", "finding")}
        slow = max((r[5] for r in rs), default=0.0)
        summary[p.stem] = dict(runs=len(rs), **{k.replace(" ", "_"): v for k, v in c.items()}, slowest_s=round(slow, 2))
        print(f"{p.stem:<24} {len(rs):>5} {c['completed']:>9} {c['input error']:>9} {c['numerical failure']:>8} "
              f"{c['finding']:>8} {slow:>11.2f}")
    findings = sum(s["finding"] for s in summary.values())
    print("RESULT " + json.dumps({"bench": "fuzz_inputs", "values": values, "files": summary,
                                  "findings": findings}))
    return 1 if findings else 0


if __name__ == "__main__":
    sys.exit(main())
