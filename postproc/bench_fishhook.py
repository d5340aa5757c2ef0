#!/usr/bin/env python3
"""Work against error on the paper's parachute-opening transient (input/line_fishhook.nml:
the line released across the Mach 0.65 stream with the packed canopy, 0.6 s; §5.1, Fig. 8,
docs/validation.md): the default scheme (CVODE BDF2, lumped mass), the same with
`mass = 'mixed'`, and the paper's marching scheme, each over N and (CVODE) rtol.

    bench_fishhook.py [--core 1] [--repeats 3] [--quick]

Error: the largest distance of the canopy (node N) from the reference over the run's 121
records (every 5 ms); reference: the mixed mass at N = 480, rtol 1e-8, BDF5 (its own
distance from N = 240 is 1.5e-3 m, so it is good to ~5e-4 m, below every error compared).
Wall: the line scene's own clock of the integration (`wall` of the run's summary: no
start-up, input or file), best of `--repeats`, pinned to one core (`taskset -c CORE`),
OPENBLAS_NUM_THREADS=1.  The marching scheme runs at 0.9 of its stability limit
(line_model%stable_step: h = (2/w)(sqrt(1 + zeta^2) - zeta), w = 2c/l0), its cheapest
setting.  For every marching run: the CVODE wall at its error, as the cheapest run at least
as accurate (B) and read off the scheme's work-precision front (D, `wall_at_error` of
bench_workprecision.py), and the speed-up over the marching run.  Ends with `RESULT {json}`."""
import argparse
import json
import math
import os
import pathlib
import re
import subprocess
import sys
import tempfile

import numpy as np
import xarray as xr

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from bench_workprecision import wall_at_error  # noqa: E402  (the tested front reader)

ROOT = pathlib.Path(__file__).resolve().parents[1]
EXE = pathlib.Path(os.environ.get("AIRLAUNCH_EXE", ROOT / "build" / "release" / "bin" / "airlaunch"))
BASE = (ROOT / "input" / "line_fishhook.nml").read_text()
EA, RHO, LENGTH, C_D = 1.0e6, 0.3, 60.0, 1000.0   # the file's &line values


def stable_step(n):
    """The marching scheme's stability limit at n segments [s] (line_model%stable_step)."""
    w = 2.0 * math.sqrt(EA / RHO) / (LENGTH / n)
    zeta = w * C_D / (2.0 * EA)
    return 2.0 / w * (math.sqrt(1.0 + zeta ** 2) - zeta)


def edit(text, old, new):
    text, k = re.subn(old, new, text, flags=re.M)
    assert k == 1, old
    return text


def namelist(tmp, n, scheme, mass="lumped", rtol=1e-5, dt=None, max_order=2):
    s = edit(BASE, r"^  n_seg = 60 .*$", f"  n_seg = {n}")
    s = edit(s, r"^  rtol = .*$", f"  rtol = {rtol}\n  max_order = {max_order}\n  max_steps = 0")
    s = edit(s, r"^  atol = .*$", f"  atol = {rtol}")
    s = edit(s, r"^  output = .*$", f"  output = '{tmp / 'run.nc'}'")
    s = edit(s, r"^  air_density = .*$", f"  air_density = 0.41351\n  mass = '{mass}'")
    if scheme == "marching":
        s = edit(s, r"^  scheme = 'cvode'$", f"  scheme = 'marching'\n  dt = {dt!r}")
    path = tmp / "run.nml"
    path.write_text(s)
    return path


def run(tmp, core, repeats, **kw):
    """(best wall [s], steps, canopy track (records, 3))."""
    nml = namelist(tmp, **kw)
    best, steps = math.inf, 0
    for _ in range(repeats):
        res = subprocess.run(["taskset", "-c", str(core), str(EXE), str(nml)], capture_output=True, text=True,
                             env=dict(os.environ, OPENBLAS_NUM_THREADS="1"))
        if res.returncode != 0:
            raise SystemExit(f"bench fishhook: {kw}: {res.stderr.strip()}")
        m = re.search(r"end of run .*?, (\d+) steps.*wall ([0-9.Ee+-]+) s", res.stdout)
        steps, best = int(m.group(1)), min(best, float(m.group(2)))
    with xr.open_dataset(tmp / "run.nc") as ds:
        tip = ds["line_tip_position"].values.copy()
    return best, steps, tip


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--core", type=int, default=1)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="N = 15, 30 and rtol 1e-3, 1e-4 only")
    a = ap.parse_args()
    ns = [15, 30] if a.quick else [15, 30, 60, 120]
    rtols = [1e-3, 1e-4] if a.quick else [1e-2, 3e-3, 1e-3, 3e-4, 1e-4, 3e-5, 1e-5]
    with tempfile.TemporaryDirectory() as d:
        tmp = pathlib.Path(d)
        _, _, ref = run(tmp, a.core, 1, n=480, scheme="cvode", mass="mixed", rtol=1e-8, max_order=5)
        rows = []
        print("bench fishhook: input/line_fishhook.nml, 0.6 s; error = largest canopy distance from the "
              "reference (mixed, N = 480, rtol 1e-8) over 121 records; wall = the run's own clock, best of "
              f"{a.repeats}, core {a.core}")
        print(f"{'scheme':>10} {'mass':>7} {'N':>4} {'setting':>10} {'wall [s]':>11} {'steps':>7} {'error [m]':>11}")
        for scheme, masses, settings in (("marching", ["lumped"], [None]), ("cvode", ["lumped", "mixed"], rtols)):
            for mass in masses:
                for n in ns:
                    for rtol in settings:
                        dt = 0.9 * stable_step(n) if scheme == "marching" else None
                        wall, steps, tip = run(tmp, a.core, a.repeats, n=n, scheme=scheme, mass=mass,
                                               rtol=rtol or 1e-5, dt=dt)
                        err = float(np.linalg.norm(tip - ref, axis=1).max())
                        rows.append(dict(scheme=scheme, mass=mass, n=n, rtol=rtol, dt=dt, wall=wall, steps=steps,
                                         error=err))
                        setting = f"dt {dt:.2e}" if dt else f"rtol {rtol:.0e}"
                        print(f"{scheme:>10} {mass:>7} {n:>4} {setting:>10} {wall:11.4e} {steps:7d} {err:11.3e}",
                              flush=True)
    print()
    print("speed-up over each marching run at its error (B: cheapest run at least as accurate; D: on the front)")
    print(f"{'N':>4} {'marching [s]':>13} {'error [m]':>10} {'default B':>10} {'default D':>10} {'mixed D':>10}")
    out = []
    for r in (r for r in rows if r["scheme"] == "marching"):
        s = dict(n=r["n"], marching_wall_s=r["wall"], error_m=r["error"])
        for mass in ("lumped", "mixed"):
            pts = [(c["wall"], c["error"]) for c in rows if c["scheme"] == "cvode" and c["mass"] == mass]
            ok = [w for w, e in pts if e <= r["error"]]
            front = wall_at_error(pts, r["error"])
            s[f"{mass}_speedup_cheapest"] = r["wall"] / min(ok) if ok else 0.0
            s[f"{mass}_speedup_on_front"] = r["wall"] / front if front else 0.0
        out.append(s)
        print(f"{r['n']:>4} {r['wall']:13.4e} {r['error']:10.3e} {s['lumped_speedup_cheapest']:9.2f}x "
              f"{s['lumped_speedup_on_front']:9.2f}x {s['mixed_speedup_on_front']:9.2f}x")
    result = {"bench": "fishhook", "core": a.core, "repeats": a.repeats, "rows": rows, "speedups": out,
              "min_default_speedup_on_front": min(s["lumped_speedup_on_front"] for s in out),
              "min_mixed_speedup_on_front": min(s["mixed_speedup_on_front"] for s in out)}
    print()
    print("RESULT " + json.dumps(result))


if __name__ == "__main__":
    main()
