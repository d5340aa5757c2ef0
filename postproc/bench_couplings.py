#!/usr/bin/env python3
"""Time saved and error cost of choosing the line coupling per phase or
automatically (issue 7 item 3; docs/performance.md "Skipping what a scene
does not need").

    bench_couplings.py [--runs 5] [--scenarios paper,snatch] [--core 1]

For each scenario (the paper file at its defaults; the snatch: the same with
the canopy inflating at 1 s) it times direct, rigidized, every per-phase split
(Case 0..3, 16 in all: d = direct, r = rigidized), auto, auto on the
line's state alone (auto_min_steps = 0) and the paper's method end to end
(rigidized with `inner_scheme = 'marching'`): wall time of the
process, pinned to one core (`taskset -c CORE`), OPENBLAS_NUM_THREADS=1,
`trajectory = .false.`; the runs of all variants are interleaved round by
round so that a busy machine slows them alike; median of `--runs`.  Error: the
largest relative milestone error against a converged reference — the paper
scenario's (N = 240, rtol 1e-9, docs/performance.md), the snatch's computed
here (N = 60, rtol 1e-9, with `&run max_steps = 0`: it takes more than the
default 500 000 steps).  Ends with `RESULT {json}`."""
import argparse
import itertools
import json
import os
import pathlib
import re
import shutil
import statistics
import subprocess
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
EXE = pathlib.Path(os.environ.get("AIRLAUNCH_EXE", ROOT / "build" / "release" / "bin" / "airlaunch"))
BASE = (ROOT / "input" / "airlaunch_paper.nml").read_text()
MILESTONES = ["edge_time_s", "separation_time_s", "edge_pull_time_s", "pitch_at_separation_deg",
              "pitch_rate_at_separation_deg_s", "pitch_max_time_s", "min_clearance_m", "peak_line_tension_N",
              "max_aircraft_pitch_excursion_deg", "max_load_factor_excursion"]
# the converged reference (N = 240, rtol 1e-9, atol 1e-10), rerun in the thirty-fourth session
# for the potential normal force at the ramp edge (docs/performance.md, "The paper scenario")
# (the load-factor excursion from the trimmed flight's cos(1.2174 deg) since the thirty-fifth session: + 2.2573e-4)
PAPER_REFERENCE = {"edge_time_s": 2.9952014, "separation_time_s": 3.8746231, "edge_pull_time_s": 3.6510727,
                   "pitch_at_separation_deg": 15.027764, "pitch_rate_at_separation_deg_s": 19.408748,
                   "pitch_max_time_s": 10.481423, "min_clearance_m": 8.7897492, "peak_line_tension_N": 78782.763,
                   "max_aircraft_pitch_excursion_deg": 1.0249325, "max_load_factor_excursion": 0.26624728}
SCENARIOS = {"paper": [], "snatch": [(r"^  deploy_time = -1.0 .*$", "  deploy_time = 1.0")]}
NAMES = {"d": "direct", "r": "rigidized"}


def variants():
    """Name -> &line assignments: the two couplings, the 16 splits, auto."""
    v = {"direct": [], "rigidized": ["  coupling = 'rigidized'"]}
    for split in itertools.product("dr", repeat=4):
        s = "".join(split)
        v[f"per_phase {s}"] = ["  coupling = 'per_phase'",
                               "  coupling_by_phase = " + ", ".join(f"'{NAMES[c]}'" for c in s)]
    v["auto"] = ["  coupling = 'auto'"]
    v["auto, line state only"] = ["  coupling = 'auto'", "  auto_min_steps = 0.0"]
    # the paper's method end to end: the rigidization with its marching line (§2.3)
    v["paper method"] = ["  coupling = 'rigidized'", "  inner_scheme = 'marching'"]
    return v


def scenario(edits, line, out=None, extra=(), run=()):
    text = BASE
    for old, new in list(edits) + list(extra):
        text, n = re.subn(old, new, text, flags=re.M)
        assert n == 1, old
    if run:
        text, n = re.subn(r"^(&run\b.*)$", lambda m: m.group(1) + "\n" + "\n".join(run), text, count=1, flags=re.M)
        assert n == 1
    if out is None:
        text = re.sub(r"^\s*output\s*=.*$", "  trajectory = .false.", text, flags=re.M)
    else:
        text = re.sub(r"^\s*output\s*=.*$", f"  output = '{out}'", text, flags=re.M)
    if line:
        text = re.sub(r"^(&line\b.*)$", lambda m: m.group(1) + "\n" + "\n".join(line), text, count=1, flags=re.M)
    return text


def milestones(nml, out):
    import xarray as xr
    res = subprocess.run([str(EXE), str(nml)], capture_output=True, text=True,
                         env=dict(os.environ, OPENBLAS_NUM_THREADS="1"))
    if res.returncode != 0:
        raise SystemExit(f"bench couplings: {nml} failed: {res.stderr.strip()}")
    with xr.open_dataset(out) as ds:
        m = {k: float(ds.attrs[k]) for k in MILESTONES}
        m["switches"] = int(ds.attrs.get("coupling_switches", 0))
    m["steps"] = int(re.search(r"(\d+) steps", res.stdout).group(1))
    return m


def error(m, ref):
    errs = {k: abs(m[k] - ref[k]) / abs(ref[k]) for k in MILESTONES}
    k = max(errs, key=errs.get)
    return errs[k], k


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--scenarios", default="paper,snatch")
    ap.add_argument("--core", default=os.environ.get("AIRLAUNCH_BENCH_CORE", "1"))
    args = ap.parse_args()
    pin = ["taskset", "-c", args.core] if shutil.which("taskset") else []
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
    result = {"bench": "couplings", "runs": args.runs}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        for sc in args.scenarios.split(","):
            edits = SCENARIOS[sc]
            if sc == "paper":
                ref = PAPER_REFERENCE
            else:
                out = tmp / f"{sc}_ref.nc"
                nml = tmp / f"{sc}_ref.nml"
                # no step limit: the reference takes more than the default max_steps (500 000)
                nml.write_text(scenario(edits, [], out, [(r"^  rtol = \S+.*$", "  rtol = 1.0e-9"),
                                                         (r"^  atol = \S+.*$", "  atol = 1.0e-10"),
                                                         (r"^  n_seg = \d+ .*$", "  n_seg = 60")],
                                        run=["  max_steps = 0"]))
                print(f"{sc}: reference run (N = 60, rtol 1e-9, max_steps = 0) ...", flush=True)
                t0 = time.perf_counter()
                ref = milestones(nml, out)
                print(f"{sc}: reference: {ref['steps']} steps, {time.perf_counter() - t0:.1f} s; "
                      + ", ".join(f"{k} {ref[k]:.8g}" for k in MILESTONES), flush=True)
                result[f"{sc}_reference"] = {k: ref[k] for k in MILESTONES + ["steps"]}
            rows = {}
            for name, line in variants().items():
                key = name.replace(" ", "_")
                out = tmp / f"{sc}_{key}.nc"
                nml = tmp / f"{sc}_{key}.nml"
                nml.write_text(scenario(edits, line, out))
                m = milestones(nml, out)
                timing = tmp / f"{sc}_{key}_t.nml"
                timing.write_text(scenario(edits, line))
                rows[name] = {"nml": timing, "walls": [], **m}
                rows[name]["error"], rows[name]["worst"] = error(m, ref)
            for _ in range(args.runs):          # interleaved rounds
                for r in rows.values():
                    t0 = time.perf_counter()
                    res = subprocess.run(pin + [str(EXE), str(r["nml"])], capture_output=True, text=True, env=env)
                    r["walls"].append(time.perf_counter() - t0)
                    if res.returncode != 0:
                        raise SystemExit(f"bench couplings: {r['nml']} failed: {res.stderr.strip()}")
            direct = statistics.median(rows["direct"]["walls"])
            print(f"\n{sc} scenario (median of {args.runs}, core {args.core}, trajectory off)")
            print(f"{'variant':22s} {'wall [s]':>9s} {'vs direct':>9s} {'steps':>7s} {'switches':>8s} "
                  f"{'error':>9s}  worst milestone")
            for name, r in rows.items():
                r["median"] = statistics.median(r["walls"])
                print(f"{name:22s} {r['median']:9.3f} {r['median'] / direct:9.2f} {r['steps']:7d} {r['switches']:8d} "
                      f"{r['error']:9.2e}  {r['worst']}")
            splits = {n: r for n, r in rows.items()
                      if n.startswith("per_phase") and {"d", "r"} <= set(n.split()[1])}
            best = min(splits, key=lambda n: splits[n]["median"])
            print(f"fastest mixed split: {best} ({splits[best]['median']:.3f} s, error {splits[best]['error']:.2e})")
            result[sc] = {n.replace(" ", "_"): {"median_wall_s": round(r["median"], 4), "steps": r["steps"],
                                                "switches": r["switches"], "error": float(f"{r['error']:.3e}")}
                          for n, r in rows.items()}
            result[sc]["fastest_mixed_split"] = best.replace(" ", "_")
    print("RESULT " + json.dumps(result))


if __name__ == "__main__":
    main()
