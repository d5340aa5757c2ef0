#!/usr/bin/env python3
"""Run the stress cases (postproc/stress_cases.py) and print a Markdown table:
status, wall time, steps, joint residual, quaternion norm error, peak tension.

    stress_table.py [--exe build/release/bin/airlaunch]
"""
import argparse
import pathlib
import re
import subprocess
import tempfile
import time

import xarray as xr

from stress_cases import CASES, ROOT, variant


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--exe", default=str(ROOT / "build" / "release" / "bin" / "airlaunch"))
    args = ap.parse_args()
    print("| case | t_end [s] | status | wall [s] | steps | separation [s] | joint residual [m] | "
          "\\| \\|q\\| − 1 \\| | peak tension [kN] |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, (edits, t_end) in CASES.items():
        with tempfile.TemporaryDirectory() as tmp:
            tmp = pathlib.Path(tmp)
            nml = variant(tmp, edits, t_end)
            out = tmp / "s.nc"
            t0 = time.perf_counter()
            res = subprocess.run([args.exe, str(nml), "--output", str(out)], capture_output=True, text=True)
            wall = time.perf_counter() - t0
            steps = re.search(r"(\d+) steps", res.stdout + res.stderr)
            with xr.open_dataset(out) as ds:
                a = ds.attrs
                print(f"| {name} | {t_end} | {a['status']} | {wall:.2f} | {steps.group(1) if steps else '-'} | "
                      f"{a['separation_time_s']:.3f} | {a['max_constraint_residual_m']:.1e} | "
                      f"{a['max_quaternion_norm_error']:.1e} | {a['peak_line_tension_N'] / 1e3:.1f} |")


if __name__ == "__main__":
    main()
