#!/usr/bin/env python3
"""Median wall time of the paper scenario (input/airlaunch_paper.nml) at its
default settings, pinned to one core, trajectory output off (no file, no
plot).  Prints one row per run and ends with `RESULT {json}`."""
import json
import os
import pathlib
import re
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
EXE = pathlib.Path(os.environ.get("AIRLAUNCH_EXE", ROOT / "build" / "release" / "bin" / "airlaunch"))


def main():
    runs = int(sys.argv[1]) if len(sys.argv) > 1 else 5
    text = (ROOT / "input" / "airlaunch_paper.nml").read_text()
    text = re.sub(r"^\s*output\s*=.*$", "  trajectory = .false.", text, flags=re.M)
    with tempfile.TemporaryDirectory() as tmp:
        nml = pathlib.Path(tmp) / "paper.nml"
        nml.write_text(text)
        cmd = [str(EXE), str(nml)]
        if shutil_which("taskset"):
            cmd = ["taskset", "-c", os.environ.get("AIRLAUNCH_BENCH_CORE", "0")] + cmd
        env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
        times, out = [], ""
        print(f"{'run':>4} {'wall [s]':>9}")
        for k in range(runs):
            t0 = time.perf_counter()
            res = subprocess.run(cmd, capture_output=True, text=True, env=env)
            dt = time.perf_counter() - t0
            if res.returncode != 0:
                sys.exit(f"bench paper: run failed: {res.stderr.strip()}")
            times.append(dt)
            out = res.stdout
            print(f"{k + 1:>4} {dt:9.3f}")
    milestones = {}
    for key, pat in (("edge_time_s", r"edge \(Case 1->2\):\s+t = (\S+)"),
                     ("separation_time_s", r"separation \(Case 2->3\):\s+t = (\S+)"),
                     ("pitch_max_time_s", r"maximum: t = (\S+) s"),
                     ("pitch_max_deg", r"maximum: t = \S+ s, pitch (\S+)"),
                     ("steps", r"integration: (\d+) steps")):
        m = re.search(pat, out)
        milestones[key] = float(m.group(1)) if m else None
    med = statistics.median(times)
    print(f"median {med:.3f} s over {runs} runs (one core, no output)")
    print("RESULT " + json.dumps({"bench": "paper", "median_wall_s": round(med, 4), "runs": runs,
                                  "min_wall_s": round(min(times), 4), **milestones}))


def shutil_which(name):
    import shutil
    return shutil.which(name)


if __name__ == "__main__":
    main()
