"""Sweep throughput on 1 and 2 ranks: scripts/bench sweep [N_CASES] [REPEATS].

Runs the first N_CASES cases of input/sweep_paper.nml's design (same base,
fixed settings and ranges; default 48 cases) with airlaunch-sweep under
mpirun, from a fresh journal each time, and reports cases per second of the
running phase (from airlaunch-sweep's tally) and the parallel efficiency
rate(2) / (2 rate(1)).  The load average before each run is printed: on a
shared machine the other users' work shows up in the numbers.  Ends with one
line `RESULT {json}`.
"""
from __future__ import annotations

import json
import os
import pathlib
import re
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
EXE = ROOT / "build" / "release" / "bin" / "airlaunch-sweep"
PAPER = ROOT / "input" / "sweep_paper.nml"
TALLY = re.compile(r"run now on (\d+) ranks? in ([0-9.]+) s \(([0-9.]+) cases/s\)")


def bench_definition(n_cases: int, out_dir: pathlib.Path) -> str:
    """The paper sweep's definition with n_cases cases, no kept trajectories, into out_dir."""
    text = PAPER.read_text()
    subs = [(r"n_cases = \d+", f"n_cases = {n_cases}"),
            (r"output_dir = '[^']*'", f"output_dir = '{out_dir}'"),
            (r"name = 'paper'", "name = 'bench'"),
            (r"keep_failed = \.true\.", "keep_failed = .false."),
            (r"keep_worst = \d+", "keep_worst = 0"),
            (r"progress_interval = [0-9.]+", "progress_interval = 1000.0"),
            (r"base = 'input/", f"base = '{ROOT}/input/"),
            (r"criteria = 'input/", f"criteria = '{ROOT}/input/")]
    for pattern, repl in subs:
        text, n = re.subn(pattern, repl, text, count=1)
        if n != 1:
            raise SystemExit(f"bench sweep: {PAPER} has no '{pattern}'")
    return text


def run(ranks: int, definition: pathlib.Path) -> tuple:
    """One sweep from a fresh journal; returns (cases/s of the running phase, wall s, load)."""
    load = os.getloadavg()[0]
    cmd = ["mpirun"]
    if os.geteuid() == 0:
        cmd.append("--allow-run-as-root")
    if ranks > (os.cpu_count() or 1):
        cmd.append("--oversubscribe")
    cmd += ["-np", str(ranks), str(EXE), str(definition), "--restart"]
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    t0 = time.perf_counter()
    res = subprocess.run(cmd, capture_output=True, text=True, env=env, check=False)
    wall = time.perf_counter() - t0
    if res.returncode != 0:
        raise SystemExit(f"bench sweep: {' '.join(cmd)} failed:\n{res.stdout}\n{res.stderr}")
    m = TALLY.search(res.stdout)
    if not m or int(m.group(1)) != ranks:
        raise SystemExit(f"bench sweep: no tally line in the output:\n{res.stdout}")
    return float(m.group(3)), wall, load


def main(argv) -> int:
    """Measure and print the table and the RESULT line."""
    n_cases = int(argv[0]) if argv else 48
    repeats = int(argv[1]) if len(argv) > 1 else 2
    with tempfile.TemporaryDirectory(prefix="bench_sweep_") as tmp:
        tmp = pathlib.Path(tmp)
        definition = tmp / "sweep_bench.nml"
        definition.write_text(bench_definition(n_cases, tmp / "out"))
        env = dict(os.environ, PYTHONPATH=str(ROOT))
        subprocess.run([sys.executable, "-m", "postproc.sweep", "table", str(definition)], check=True,
                       env=env, capture_output=True)
        rates = {1: [], 2: []}
        walls = {1: [], 2: []}
        loads = []
        print(f"{n_cases} cases of input/sweep_paper.nml (15 s simulated each), {repeats} runs per rank count")
        print(f"{'ranks':>5} {'cases/s':>9} {'wall [s]':>9} {'load before':>12}")
        for _ in range(repeats):
            for ranks in (1, 2):
                rate, wall, load = run(ranks, definition)
                rates[ranks].append(rate)
                walls[ranks].append(wall)
                loads.append(load)
                print(f"{ranks:5d} {rate:9.3f} {wall:9.2f} {load:12.2f}")
    r1 = statistics.median(rates[1])
    r2 = statistics.median(rates[2])
    eff = r2 / (2 * r1)
    print(f"median: 1 rank {r1:.3f} cases/s, 2 ranks {r2:.3f} cases/s, parallel efficiency {100 * eff:.1f} %")
    print(f"(this machine has {os.cpu_count()} cores; a load above 0 before a run means other work shared them)")
    result = {"bench": "sweep", "cases": n_cases, "repeats": repeats, "cases_per_s_1": round(r1, 4),
              "cases_per_s_2": round(r2, 4), "parallel_efficiency_2": round(eff, 4),
              "median_wall_s_1": round(statistics.median(walls[1]), 3),
              "median_wall_s_2": round(statistics.median(walls[2]), 3),
              "max_load_before": round(max(loads), 2), "cores": os.cpu_count()}
    print("RESULT " + json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
