#!/usr/bin/env python3
"""Work-precision of the paper scenario: wall time against the error of the
milestones, for a ladder of tolerances and line resolutions, both line
couplings and the paper's own method, each against a converged reference.

    bench_workprecision.py [--quick] [--figure docs/figures/workprecision_paper.png]
                           [--couplings direct,rigidized,paper]

Couplings ("schemes"): direct = the default (the line's nodes integrated with
the bodies by CVODE); rigidized = the paper's equivalent rigidization with the
line sub-stepped by CVODE; paper = the paper's method end to end: the
rigidization with the line sub-stepped by its explicit marching (Eqs. (12)-(17),
`&line inner_scheme = 'marching'`, at 0.9 of its stability limit; rtol then sets
the chain's CVODE only).  The speed-up of the default over the paper's method
at equal error is read off both fronts (wall_at_error) for every paper run.

Error of a run = the largest relative error of its milestones (every milestone
the run reports: phase times, attitude at separation, first pitch maximum,
clearance, peak line tension, aircraft excursions; and the time-averaged line
tension at the rocket end) against the reference (rtol 1e-9, atol 1e-10,
N = 240).  Wall time: one core, no output file.  Prints a table, marks the
Pareto front, says whether the default settings are on it, and ends with
`RESULT {json}`."""
import argparse
import json
import math
import os
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
EXE = pathlib.Path(os.environ.get("AIRLAUNCH_EXE", ROOT / "build" / "release" / "bin" / "airlaunch"))
BASE = (ROOT / "input" / "airlaunch_paper.nml").read_text()
DEFAULT = ("direct", 1e-5, 15)
MILESTONES = ["edge_time_s", "separation_time_s", "edge_pull_time_s", "pitch_at_separation_deg",
              "pitch_rate_at_separation_deg_s", "pitch_max_time_s", "pitch_max_deg", "min_clearance_m",
              "peak_line_tension_N", "max_aircraft_pitch_excursion_deg", "max_load_factor_excursion"]


def scenario(coupling, rtol, n, out):
    text = re.sub(r"^\s*rtol\s*=.*$", f"  rtol = {rtol:.1e}", BASE, flags=re.M)
    text = re.sub(r"^\s*atol\s*=.*$", f"  atol = {rtol / 10:.1e}", text, flags=re.M)
    text = re.sub(r"^\s*n_seg\s*=.*$", f"  n_seg = {n}", text, flags=re.M)
    text = re.sub(r"^\s*output\s*=.*$", f"  output = '{out}'", text, flags=re.M)
    if coupling == "paper":
        text = re.sub(r"^(&line\b.*)$", r"\1\n  coupling = 'rigidized'\n  inner_scheme = 'marching'", text,
                      count=1, flags=re.M)
        # its sub-step shrinks with 1/N: 1.3 million at N = 240, over the default budget
        text = re.sub(r"^(\s*rtol\s*=.*)$", r"\1\n  max_steps = 0", text, count=1, flags=re.M)
    elif coupling != "direct":
        text = re.sub(r"^(&line\b.*)$", rf"\1\n  coupling = '{coupling}'", text, count=1, flags=re.M)
    return text


def run(coupling, rtol, n, repeats=1):
    """Milestones and the best-of-`repeats` wall time of one setting."""
    import xarray as xr
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        # timing run: no output file
        nml = tmp / "t.nml"
        nml.write_text(re.sub(r"^\s*output\s*=.*$", "  trajectory = .false.",
                              scenario(coupling, rtol, n, tmp / "x.nc"), flags=re.M))
        cmd = [str(EXE), str(nml)]
        if shutil.which("taskset"):
            cmd = ["taskset", "-c", os.environ.get("AIRLAUNCH_BENCH_CORE", "0")] + cmd
        env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
        walls = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            res = subprocess.run(cmd, capture_output=True, text=True, env=env)
            walls.append(time.perf_counter() - t0)
            if res.returncode != 0:
                return {"failed": (res.stderr.strip().splitlines() or ["no message"])[0]}
            if walls[-1] > 2.0:
                break   # a long run: its timing noise is small, the repeats would cost minutes
        # milestone run: with output (the tension history)
        out = tmp / "m.nc"
        nml2 = tmp / "m.nml"
        nml2.write_text(scenario(coupling, rtol, n, out))
        res = subprocess.run([str(EXE), str(nml2)], capture_output=True, text=True, env=env)
        if res.returncode != 0:
            return {"failed": (res.stderr.strip().splitlines() or ["no message"])[0]}
        with xr.open_dataset(out) as ds:
            m = {k: float(ds.attrs[k]) for k in MILESTONES}
            m["mean_tension"] = float(ds["line_tension_rocket_end_N"].mean())
        steps = re.search(r"(\d+) steps", res.stdout)
        return {"wall": min(walls), "steps": int(steps.group(1)) if steps else None, **m}


def error(r, ref):
    return max(abs(r[k] - ref[k]) / abs(ref[k]) for k in MILESTONES + ["mean_tension"])


def pareto(points):
    """Indices of the points no other point beats in both time and error."""
    front = []
    for i, (t, e) in enumerate(points):
        if not any((t2 <= t and e2 <= e) and (t2 < t or e2 < e) for j, (t2, e2) in enumerate(points) if j != i):
            front.append(i)
    return front


def wall_at_error(points, target):
    """Wall time at which a scheme reaches the error `target`, read off its work-precision
    front: the points (wall, error) no other beats in both, joined by straight lines in
    log-log (each segment a power law between two measured runs).  A target above the
    cheapest run's error costs that run (no extrapolation to cheaper, less accurate runs);
    below the most accurate run's error it is out of reach: None.

    This is the companion of the "cheapest run at least as accurate" rule: on a ladder
    of settings that rule jumps by a whole rung when a run misses the target by a hair
    (a chaotic track, a 1-2-5 or decade ladder), the interpolated figure does not."""
    pts = [p for p in points if p[0] > 0 and p[1] > 0]
    front = sorted((pts[i] for i in pareto(pts)), key=lambda p: p[0])   # wall up, error down
    if not front or target < front[-1][1]:
        return None
    if target >= front[0][1]:
        return front[0][0]
    for (w1, e1), (w2, e2) in zip(front, front[1:]):
        if e2 <= target <= e1:
            s = math.log(target / e1) / math.log(e2 / e1)
            return w1 * (w2 / w1) ** s
    return None


def speedup_over_paper(rows):
    """For every run of the paper's method: the default scheme's wall at its error on the
    direct coupling's front (all N and rtol), and the ratio."""
    direct = [(r["wall"], r["error"]) for r in rows if r["coupling"] == "direct"]
    out = []
    for r in rows:
        if r["coupling"] != "paper" or not direct:
            continue
        w = wall_at_error(direct, r["error"])
        out.append({"n": r["n"], "rtol": r["rtol"], "error": float(f"{r['error']:.4g}"),
                    "wall": float(f"{r['wall']:.4g}"), "direct_wall": float(f"{w:.4g}") if w else None,
                    "speedup": float(f"{r['wall'] / w:.3g}") if w else None})
    return out


#: The legends' type size (points): 6 pt was too small to read on the page.
LEGEND_FONTSIZE = 8


def outside_legend(ax, ncol=1):
    """The panel's legend at LEGEND_FONTSIZE below the axes (under the x label):
    at a legible size the 16 entries of the paper's figure would cover curves
    inside the axes, wherever placed.  The figure is saved with
    bbox_inches="tight", which takes the legend in."""
    return ax.legend(fontsize=LEGEND_FONTSIZE, ncol=ncol, loc="upper center", bbox_to_anchor=(0.5, -0.13),
                     frameon=False)


def draw(rows, couplings, ns, default, path):
    """The figure: one curve per scheme and N (colour: N, line and marker: scheme)."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(7.5, 5.5))
        styles = {"direct": ("-", "o"), "rigidized": ("--", "s"), "paper": (":", "^")}
        colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
        for c in couplings:
            ls, mk = styles.get(c, ("-.", "x"))
            for i, n in enumerate(ns):
                pts = [(r["wall"], max(r["error"], 1e-8)) for r in rows if r["coupling"] == c and r["n"] == n]
                if pts:
                    ax.loglog(*zip(*pts), linestyle=ls, marker=mk, color=colours[i % len(colours)],
                              label=f"{c}, N = {n}")
        if default is not None:
            ax.loglog(default["wall"], max(default["error"], 1e-8), "k*", ms=14, label="default")
        ax.set_xlabel("wall time per run [s] (one core)")
        ax.set_ylabel("largest relative milestone error")
        meaning = {"direct": "direct = default", "rigidized": "rigidized = §2.4 with CVODE's line",
                   "paper": "paper = §2.4 with the marching line"}
        ax.set_title("paper scenario: work-precision (tolerance ladder along each curve)\n"
                     + ", ".join(meaning.get(c, c) for c in couplings))
        ax.grid(True, which="both", alpha=0.3)
        outside_legend(ax, ncol=3)
        pathlib.Path(path).parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=110, bbox_inches="tight")
        print(f"figure: {path}")
    except Exception as exc:  # the table and RESULT are the product; the figure is a convenience
        print(f"figure not drawn: {exc}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer settings (a smoke run)")
    ap.add_argument("--figure", default=str(ROOT / "output" / "workprecision_paper.png"))
    ap.add_argument("--couplings", default="direct,rigidized,paper", help="comma list: direct,rigidized,paper")
    ap.add_argument("--rtols", default=None, help="comma list of rtol (default: 1e-3 ... 1e-8)")
    ap.add_argument("--ns", default=None, help="comma list of segment counts (default: 15 ... 240)")
    args = ap.parse_args()
    rtols = [1e-3, 1e-5, 1e-6, 1e-7] if args.quick else [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8]
    ns = [15, 60] if args.quick else [15, 30, 60, 120, 240]
    if args.rtols:
        rtols = [float(x) for x in args.rtols.split(",")]
    if args.ns:
        ns = [int(x) for x in args.ns.split(",")]
    couplings = args.couplings.split(",")
    print("reference: rtol 1e-9, atol 1e-10, N = 240, direct coupling ...", flush=True)
    ref = run("direct", 1e-9, 240)
    if "failed" in ref:
        sys.exit(f"bench workprecision: the reference run failed: {ref['failed']}")
    print(f"  {ref}")
    rows = []
    for c in couplings:
        for n in ns:
            for rtol in rtols:
                r = run(c, rtol, n, repeats=3)
                if "failed" in r:
                    print(f"{c:10s} N={n:4d} rtol={rtol:.0e}: failed: {r['failed']}")
                    continue
                rows.append({"coupling": c, "n": n, "rtol": rtol, **r, "error": error(r, ref)})
    front = set(pareto([(r["wall"], r["error"]) for r in rows]))
    print(f"\n{'coupling':10s} {'N':>4s} {'rtol':>7s} {'steps':>7s} {'wall [s]':>9s} {'error':>9s}  front")
    for i, r in enumerate(rows):
        print(f"{r['coupling']:10s} {r['n']:4d} {r['rtol']:7.0e} {r['steps'] or 0:7d} {r['wall']:9.3f} "
              f"{r['error']:9.2e}  {'*' if i in front else ''}")
    default = next((i for i, r in enumerate(rows) if (r["coupling"], r["rtol"], r["n"]) == DEFAULT), None)
    on_front = default in front if default is not None else None
    print(f"\ndefault ({DEFAULT[0]}, rtol {DEFAULT[1]:.0e}, N = {DEFAULT[2]}) on the Pareto front: {on_front}")
    speedups = speedup_over_paper(rows)
    if speedups:
        print("\nthe default scheme (direct, any N and rtol) against the paper's method at equal error, "
              "each read off its front:")
        for s in speedups:
            print(f"  paper N = {s['n']:4d} rtol {s['rtol']:.0e}: error {s['error']:.2e} in {s['wall']:.3f} s; "
                  f"direct {s['direct_wall']:.3f} s -> {s['speedup']:.1f}x" if s["speedup"] else
                  f"  paper N = {s['n']:4d} rtol {s['rtol']:.0e}: error {s['error']:.2e}: below every direct run")
        found = [s["speedup"] for s in speedups if s["speedup"]]
        if found:
            print(f"  min {min(found):.1f}x, max {max(found):.1f}x; 30x met: {min(found) >= 30}")
    draw(rows, couplings, ns, rows[default] if default is not None else None, args.figure)
    found = [s["speedup"] for s in speedups if s["speedup"]]
    print("RESULT " + json.dumps({"bench": "workprecision_paper", "reference": ref, "default_on_pareto_front": on_front,
                                  "speedup_over_paper_method": speedups,
                                  "min_speedup_over_paper_method": min(found) if found else None,
                                  "meets_30x": (min(found) >= 30) if found else None,
                                  "runs": [{k: (float(f"{v:.6g}") if isinstance(v, float) else v) for k, v in r.items()}
                                           for r in rows]}))


if __name__ == "__main__":
    main()
