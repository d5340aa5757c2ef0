#!/usr/bin/env python3
"""Work-precision of the cable pendulum of issue 7, for both line schemes: the
default (CVODE BDF <= 2, band) over a tolerance ladder (1-2-5 per decade, 1e-2 ...
1e-6, and 1e-7), the paper's explicit
marching (Eqs. (12)-(17)) over a step ladder, at N = 15 ... 240 segments.

    bench_workprecision_pendulum.py [--quick] [--cases undamped,material] [--mass lumped|mixed]
                                    [--figure output/workprecision_pendulum.png]

The pendulum (issue 7): a 60 m line, EA 2 MN, 0.5 kg/m, fixed at one end, a 50 kg
end mass, released horizontal from the straight, unstretched line, 6 s, gravity,
no air.  The issue gives no axial damping; two cases are run:
  undamped  c_d = 0 (the issue's words taken literally);
  material  5 % of critical on the first axial mode of the line with its end mass
            (c_d = 2 zeta EA / w1, w1 = 23.50 rad/s, as in bench_moordyn.py):
            a real line's damping, independent of N.
--mass: the default scheme's mass matrix (`&line mass`; lumped, the default, or
mixed); the marching scheme and the references always lump it.
Errors against a converged reference of each case (CVODE, N = 240, rtol = atol
= 1e-8, lumped mass; its own discretization error is printed as |N 120 - N 240|):
  end mass  the largest distance of the end mass from the reference's over the
            run (outputs every 0.01 s) [m] - the error the Pareto front uses;
  tension   the relative error of the peak end tension (over the same outputs).
Wall time: the whole process (start-up and output included; best of 3, one core,
one BLAS thread) and the integration alone (the program's own clock).  The
marching scheme runs at 0.9, 0.45, 0.225 and 0.1125 of its stability limit (it
cannot go cheaper).  Prints the table with the Pareto front (process wall
against end-mass error), whether the default tolerance (rtol 1e-5) is on it at
each N, the speed-up of the default scheme over the marching at equal end-mass
error (same N, and any N: the cheapest default run at least as accurate - the
verdict - and beside it the default scheme's wall read off its work-precision
front at the marching run's error, bench_workprecision.wall_at_error), and ends
with `RESULT {json}`."""
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

from bench_moordyn import C, EA, L, M, RHO, RTOLS_125, T_END, damping
from bench_workprecision import outside_legend, pareto, wall_at_error

ROOT = pathlib.Path(__file__).resolve().parents[1]
EXE = pathlib.Path(os.environ.get("AIRLAUNCH_EXE", ROOT / "build" / "release" / "bin" / "airlaunch"))
DT_OUT = 0.01                  # s, end-mass track and peak tension sampling
DEFAULT_RTOL = 1e-5            # the line scene's default tolerance (docs/input.md)
MARCHING_FRACTIONS = [0.9, 0.45, 0.225, 0.1125]
LADDER_BUDGET = 30.0           # s: a ladder at one N stops refining after a run this long
RUN_TIMEOUT = 60.0             # s: a run is abandoned (and reported) after this long
# the pendulum and its damping cases are bench_moordyn.py's (material: N-independent)
CASES = {case: damping(case, 1) for case in ("undamped", "material")}


def stable_step(n, cd):
    """The marching scheme's stability limit (airlaunch_line_model: model_stable_step)."""
    w = 2.0 * C / (L / n)
    zeta = w * cd / (2.0 * EA)
    return 2.0 / w * (math.sqrt(1.0 + zeta**2) - zeta)


def namelist(n, cd, scheme, rtol, dt, out, mass="lumped"):
    return f"""&run scene = 'line', t_end = {T_END}, output_dt = {DT_OUT}, output = '{out}',
  rtol = {rtol:.3e}, atol = {rtol:.3e}, max_steps = 0 /
&line length = {L}, n_seg = {n}, ea = {EA}, mass_per_length = {RHO}, damping = {cd!r},
  gravity = .true., air = .false., mass = '{mass}' /
&line_scene a_kind = 'fixed', a_position = 0.0, 0.0, 0.0,
  b_kind = 'point_mass', b_mass = {M}, b_position = {L}, 0.0, 0.0,
  scheme = '{scheme}', dt = {dt:.6e}, peak_tension = .false. /
"""


def run(n, cd, scheme, rtol=DEFAULT_RTOL, dt=1e-4, repeats=3, mass="lumped"):
    """End-mass track, peak end tension, walls (process, integration), steps; None on failure
    or after RUN_TIMEOUT.  `mass`: the mass matrix of a cvode run (marching: lumped)."""
    import xarray as xr
    with tempfile.TemporaryDirectory() as tmp:
        out = pathlib.Path(tmp) / "p.nc"
        nml = pathlib.Path(tmp) / "p.nml"
        nml.write_text(namelist(n, cd, scheme, rtol, dt, out, mass if scheme == "cvode" else "lumped"))
        cmd = [str(EXE), str(nml)]
        if shutil.which("taskset"):
            cmd = ["taskset", "-c", os.environ.get("AIRLAUNCH_BENCH_CORE", "0")] + cmd
        env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
        walls, inner = [], []
        for _ in range(repeats):
            t0 = time.perf_counter()
            try:
                res = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=RUN_TIMEOUT)
            except subprocess.TimeoutExpired:
                return None
            walls.append(time.perf_counter() - t0)
            if res.returncode != 0:
                return None
            inner.append(float(re.search(r"wall ([0-9.eE+-]+) s", res.stdout).group(1)))
            if walls[-1] > 1.0:
                break
        with xr.open_dataset(out) as ds:
            tip = ds["line_tip_position"].values.copy()
            tension = float(np.max(ds["line_end_tension"].values))
            steps = int(ds.attrs["steps"])
    return {"tip": tip, "peak_tension": tension, "wall": min(walls), "integration_wall": min(inner),
            "steps": steps}


def errors(r, ref):
    return (float(np.max(np.linalg.norm(r["tip"] - ref["tip"], axis=1))),
            abs(r["peak_tension"] - ref["peak_tension"]) / ref["peak_tension"])


def ladder(case, cd, ns, rtols, ref, mass="lumped"):
    rows = []
    for n in ns:
        settings = [("cvode", rtol, None) for rtol in rtols]
        settings += [("marching", None, f * stable_step(n, cd)) for f in MARCHING_FRACTIONS]
        over = set()
        for scheme, rtol, dt in settings:
            if scheme in over:
                continue
            r = run(n, cd, scheme, rtol or DEFAULT_RTOL, dt or 1e-4, mass=mass)
            if r is None:
                print(f"  {case:9s} {n:4d} {scheme:9s} {(rtol or dt):9.2e} failed or over {RUN_TIMEOUT:.0f} s",
                      flush=True)
                continue
            e_pos, e_ten = errors(r, ref)
            rows.append({"case": case, "n": n, "scheme": scheme, "rtol": rtol, "dt": dt, "steps": r["steps"],
                         "wall": r["wall"], "integration_wall": r["integration_wall"],
                         "error_m": e_pos, "tension_error": e_ten})
            print(f"  {case:9s} {n:4d} {scheme:9s} {(rtol or dt):9.2e} {r['steps']:8d} {r['wall']:9.4f} "
                  f"{r['integration_wall']:9.4f} {e_pos:10.3e} {e_ten:10.2e}", flush=True)
            # a slow loose-tolerance run (Newton failures, docs/performance.md) says
            # nothing about the tighter ones; a slow tight run or small step does
            if r["wall"] > LADDER_BUDGET and (scheme == "marching" or rtol <= 1e-4):
                over.add(scheme)
    return rows


def speedups(rows):
    """For each marching run: the cheapest default-scheme run (same N, and any N) at least
    as accurate in the end-mass position; the ratio of walls (process and integration)."""
    out = []
    cv = [r for r in rows if r["scheme"] == "cvode"]
    for m in (r for r in rows if r["scheme"] == "marching"):
        entry = {"n": m["n"], "dt": m["dt"], "marching_error_m": m["error_m"], "marching_wall": m["wall"]}
        for key, pool in (("same_n", [r for r in cv if r["n"] == m["n"]]), ("any_n", cv)):
            ok = [r for r in pool if r["error_m"] <= m["error_m"]]
            if ok:
                best = min(ok, key=lambda r: r["wall"])
                entry[key] = {"n": best["n"], "rtol": best["rtol"], "wall": best["wall"],
                              "speedup": m["wall"] / best["wall"],
                              "speedup_integration": m["integration_wall"] / best["integration_wall"]}
                # the same, read off the default scheme's work-precision front (log-log between runs)
                w = wall_at_error([(r["wall"], r["error_m"]) for r in pool], m["error_m"])
                entry[key]["speedup_interpolated"] = m["wall"] / w
            else:
                entry[key] = None
        out.append(entry)
    return out


def figure(all_rows, path, mass="lumped"):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as exc:
        print(f"figure not drawn: {exc}")
        return
    cases = sorted({r["case"] for r in all_rows})
    fig, axes = plt.subplots(1, len(cases), figsize=(6.5 * len(cases), 5), squeeze=False)
    for ax, case in zip(axes[0], cases):
        rows = [r for r in all_rows if r["case"] == case]
        for scheme, style in (("cvode", "o-"), ("marching", "s--")):
            for n in sorted({r["n"] for r in rows}):
                pts = sorted((r["wall"], r["error_m"]) for r in rows if r["scheme"] == scheme and r["n"] == n)
                if pts:
                    ax.loglog(*zip(*pts), style, label=f"{'default (cvode)' if scheme == 'cvode' else 'marching'}, N = {n}")
        dflt = [(r["wall"], r["error_m"]) for r in rows if r["scheme"] == "cvode" and r["rtol"] == DEFAULT_RTOL]
        if dflt:
            ax.loglog(*zip(*dflt), "k*", ms=12, label="default rtol 1e-5")
        ax.set_title(f"cable pendulum, {case}" + (f" (default scheme: {mass} mass)" if mass != "lumped" else ""))
        ax.set_xlabel("wall time per run [s] (one core, whole process)")
        ax.set_ylabel("end-mass position error [m]")
        ax.grid(True, which="both", alpha=0.3)
        outside_legend(ax, ncol=2)
    pathlib.Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    print(f"figure: {path}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="N = 15, 30, 60, short ladders, reference N = 120")
    ap.add_argument("--cases", default="undamped,material")
    ap.add_argument("--mass", default="lumped", choices=["lumped", "mixed"],
                    help="the default scheme's mass matrix (marching and references: lumped)")
    ap.add_argument("--figure", default=str(ROOT / "output" / "workprecision_pendulum.png"))
    args = ap.parse_args()
    ns = [15, 30, 60] if args.quick else [15, 30, 60, 120, 240]
    rtols = [1e-2, 1e-3, 1e-4, 1e-5, 1e-6] if args.quick else RTOLS_125 + [1e-7]
    n_ref = 120 if args.quick else 240
    result = {"bench": "workprecision_pendulum", "quick": args.quick, "mass": args.mass, "cases": {}}
    all_rows = []
    for case in args.cases.split(","):
        cd = CASES[case]
        print(f"{case}: c_d = {cd:.1f} N s; default scheme with the {args.mass} mass; reference CVODE N = {n_ref}, "
              "rtol 1e-8, lumped ...", flush=True)
        ref = run(n_ref, cd, "cvode", 1e-8, repeats=1)
        coarse = run(n_ref // 2, cd, "cvode", 1e-8, repeats=1)
        if ref is None or coarse is None:
            sys.exit(f"bench workprecision_pendulum: the {case} reference run failed")
        ref_err = errors(coarse, ref)
        print(f"  reference: {ref['steps']} steps, {ref['wall']:.1f} s, peak tension {ref['peak_tension']:.1f} N; "
              f"|N {n_ref // 2} - N {n_ref}| = {ref_err[0]:.2e} m (end mass), {ref_err[1]:.1e} (peak tension)")
        print(f"  {'case':9s} {'N':>4s} {'scheme':9s} {'rtol|dt':>9s} {'steps':>8s} {'wall [s]':>9s} "
              f"{'integr [s]':>9s} {'end mass [m]':>10s} {'tension':>10s}")
        rows = ladder(case, cd, ns, rtols, ref, args.mass)
        front = set(pareto([(r["wall"], r["error_m"]) for r in rows]))
        for i, r in enumerate(rows):
            r["front"] = i in front
        print(f"  Pareto front (process wall, end-mass error): "
              + ", ".join(f"{r['scheme']} N={r['n']} {r['rtol'] or r['dt']:.1e}" for r in rows if r["front"]))
        default_on_front = {r["n"]: r["front"] for r in rows if r["scheme"] == "cvode" and r["rtol"] == DEFAULT_RTOL}
        print(f"  default (cvode, rtol 1e-5) on the front, by N: {default_on_front}")
        sp = speedups(rows)
        for s in sp:
            txt = [f"N = {s['n']:4d} marching dt {s['dt']:.2e} ({s['marching_error_m']:.2e} m, {s['marching_wall']:.4f} s):"]
            for key in ("same_n", "any_n"):
                b = s[key]
                txt.append(f"{key} " + ("none as accurate" if b is None else
                                        f"{b['speedup']:.2f}x (integration {b['speedup_integration']:.2f}x; "
                                        f"N = {b['n']}, rtol {b['rtol']:.0e}; on the front "
                                        f"{b['speedup_interpolated']:.2f}x)"))
            print("  " + "  ".join(txt))
        ratios = [s[k]["speedup"] for s in sp for k in ("same_n", "any_n") if s[k]]
        any_n = [s["any_n"]["speedup"] for s in sp if s["any_n"]]
        result["cases"][case] = {
            "damping_Ns": round(cd, 1), "reference_steps": ref["steps"], "reference_peak_tension_N": ref["peak_tension"],
            "reference_discretization_m": ref_err[0], "default_on_front_by_n": default_on_front,
            "marching_runs_without_equal_default": sum(1 for s in sp if s["any_n"] is None),
            "min_speedup_any_n": min(any_n) if any_n else None, "max_speedup_any_n": max(any_n) if any_n else None,
            "min_speedup": min(ratios) if ratios else None, "meets_30x": bool(any_n) and min(any_n) >= 30.0,
            "speedups_any_n": any_n,
            "speedups_any_n_interpolated": [s["any_n"]["speedup_interpolated"] for s in sp if s["any_n"]],
            "runs": [{k: (float(f"{v:.4g}") if isinstance(v, float) else v) for k, v in r.items()} for r in rows]}
        all_rows += rows
    figure(all_rows, args.figure, args.mass)
    print("RESULT " + json.dumps(result))


if __name__ == "__main__":
    main()
