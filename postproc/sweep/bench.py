"""Sweep throughput on 1 and 2 ranks: scripts/bench sweep [N_CASES] [REPEATS].

Runs the first N_CASES cases of input/sweep_paper.nml's design (same base,
fixed settings and ranges; default 480 cases: at ~25 ms a case, fewer make MPI start-up and the summary a visible share of the wall) with airlaunch-sweep under
mpirun, from a fresh journal each time, and reports cases per second of the
running phase (from airlaunch-sweep's tally) and the parallel efficiency
rate(2) / (2 rate(1)).  On a shared machine the other users' work shows up
in those numbers, so two more figures separate the sweep's own overhead from
the contention for the cores: the busy fraction (the cases' summed wall time /
(ranks x running time): 1 means no rank ever waited for work or for the
others) and the CPU seconds per case (from getrusage of the children: it
does not grow when the ranks merely share a core with other work).  The load
average before each run is printed too.  Ends with one line `RESULT {json}`.
"""
from __future__ import annotations

import json
import os
import resource
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


def busy_fraction(summary: pathlib.Path, ranks: int, elapsed: float) -> float:
    """Summed case wall times over ranks x running time."""
    import xarray as xr

    with xr.open_dataset(summary) as s:
        return float(s["wall_time_s"].sum()) / (ranks * elapsed)


def run(ranks: int, definition: pathlib.Path, summary: pathlib.Path) -> dict:
    """One sweep from a fresh journal: cases/s of the running phase, wall s,
    busy fraction, CPU s per case, load before."""
    load = os.getloadavg()[0]
    cpu0 = resource.getrusage(resource.RUSAGE_CHILDREN)
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
    cpu1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (cpu1.ru_utime - cpu0.ru_utime) + (cpu1.ru_stime - cpu0.ru_stime)
    if res.returncode != 0:
        raise SystemExit(f"bench sweep: {' '.join(cmd)} failed:\n{res.stdout}\n{res.stderr}")
    m = TALLY.search(res.stdout)
    if not m or int(m.group(1)) != ranks:
        raise SystemExit(f"bench sweep: no tally line in the output:\n{res.stdout}")
    n = int(re.search(r"cases: (\d+) ok", res.stdout).group(1)) if "ok," in res.stdout else 0
    elapsed = float(m.group(2))
    return {"rate": float(m.group(3)), "wall": wall, "load": load, "busy": busy_fraction(summary, ranks, elapsed),
            "cpu_per_case": cpu / max(n, 1)}


def main(argv) -> int:
    """Measure and print the table and the RESULT line."""
    n_cases = int(argv[0]) if argv else 480
    repeats = int(argv[1]) if len(argv) > 1 else 2
    with tempfile.TemporaryDirectory(prefix="bench_sweep_") as tmp:
        tmp = pathlib.Path(tmp)
        definition = tmp / "sweep_bench.nml"
        definition.write_text(bench_definition(n_cases, tmp / "out"))
        env = dict(os.environ, PYTHONPATH=str(ROOT))
        subprocess.run([sys.executable, "-m", "postproc.sweep", "table", str(definition)], check=True,
                       env=env, capture_output=True)
        runs = {1: [], 2: []}
        print(f"{n_cases} cases of input/sweep_paper.nml (each stops once its milestones are final, at most 15 s simulated), {repeats} runs per rank count")
        print(f"{'ranks':>5} {'cases/s':>9} {'wall [s]':>9} {'busy':>6} {'CPU s/case':>11} {'load before':>12}")
        for _ in range(repeats):
            for ranks in (1, 2):
                r = run(ranks, definition, tmp / "out" / "summary.nc")
                runs[ranks].append(r)
                print(f"{ranks:5d} {r['rate']:9.3f} {r['wall']:9.2f} {r['busy']:6.3f} {r['cpu_per_case']:11.3f} "
                      f"{r['load']:12.2f}")

    def med(ranks, key):
        return statistics.median(r[key] for r in runs[ranks])

    r1, r2 = med(1, "rate"), med(2, "rate")
    eff = r2 / (2 * r1)
    print(f"median: 1 rank {r1:.3f} cases/s, 2 ranks {r2:.3f} cases/s, parallel efficiency {100 * eff:.1f} %; "
          f"busy fraction {med(1, 'busy'):.3f} / {med(2, 'busy'):.3f}, CPU per case {med(1, 'cpu_per_case'):.3f} / "
          f"{med(2, 'cpu_per_case'):.3f} s")
    print(f"(this machine has {os.cpu_count()} cores; a load above 0 before a run means other work shared them)")
    result = {"bench": "sweep", "cases": n_cases, "repeats": repeats, "cases_per_s_1": round(r1, 4),
              "cases_per_s_2": round(r2, 4), "parallel_efficiency_2": round(eff, 4),
              "busy_fraction_1": round(med(1, "busy"), 4), "busy_fraction_2": round(med(2, "busy"), 4),
              "cpu_s_per_case_1": round(med(1, "cpu_per_case"), 4),
              "cpu_s_per_case_2": round(med(2, "cpu_per_case"), 4),
              "median_wall_s_1": round(med(1, "wall"), 3), "median_wall_s_2": round(med(2, "wall"), 3),
              "max_load_before": round(max(r["load"] for v in runs.values() for r in v), 2),
              "cores": os.cpu_count()}
    print("RESULT " + json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
