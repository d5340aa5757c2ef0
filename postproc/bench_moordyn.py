#!/usr/bin/env python3
"""The cable pendulum of issue 7 with airlaunch and with MoorDyn, side by side,
for three axial-damping choices.

A 60 m line (EA 2 MN, 0.5 kg/m, no fluid) fixed at one end holds a 50 kg end
mass; released horizontal from MoorDyn's initial profile (its static catenary
between the end points, midspan sag ~1.14 m: MoorDyn cannot start from a
straight line; airlaunch starts from a parabola of the same sag) it swings for
6 s under gravity.

Damping cases (c_d [N s] = coefficient of the strain rate, T = EA eps + c_d epsdot;
the same number goes to airlaunch's `&line damping` and to MoorDyn's BA column,
which MoorDyn also reads as N-s times the strain rate):
  undamped  c_d = 0;
  segment   MoorDyn's recommended practice (BA = -1): the highest segment mode
            (w = 2c/l0, c = sqrt(EA/rho)) critically damped, c_d = l0 sqrt(EA rho):
            depends on N and goes to zero as N grows;
  material  5 % of critical on the first axial mode of the 50 kg / 60 m system
            (beta tan beta = rho L / M, w1 = beta c / L), c_d = 2 zeta EA / w1:
            independent of N.
The two codes' damping laws differ in one point: airlaunch's dashpot acts only
while a segment is taut and the tension never goes negative; MoorDyn's dashpot
acts whatever the strain (it pushes in a slack, shortening segment).  Hence each
damped case has a reference per code (its own converged track); the undamped
case (identical physics) has one.

MoorDyn (v2, PyPI) integrates with RK4 at dtM = 0.5 x the smaller of l0/c and its
damping limit 2/|lambda| (|lambda| = w (zeta + sqrt(zeta^2 - 1)) for zeta > 1), i.e.
h |lambda_max| = 1.  airlaunch runs its default scheme (CVODE BDF, band, order <= 2)
over an rtol ladder with atol = rtol (m, m/s).  Error of a run = the largest
distance over the run between its end-mass track (every 0.05 s) and the
reference.  MoorDyn is timed in-process, its stepping only (Create/Init
excluded); airlaunch both as a whole process (start-up, input, netCDF output:
charged to airlaunch alone) and by its own clock of the integration (timed
alike with MoorDyn).

Prints, per case, both ladders, the wall-time ratio at equal error - the cheapest
airlaunch run at least as accurate as MoorDyn's, by process wall (its start-up
charged), the same with the start-up of a tiny run subtracted, read off
airlaunch's work-precision front at MoorDyn's error
(bench_workprecision.wall_at_error), and with both codes timed alike - the cost
exponents in N, and ends with `RESULT {json}`.  --mass=mixed: airlaunch's ladder with
the mixed mass matrix (`&line mass`; its references stay lumped).  --quick: N up to 60, short
ladders, coarser references."""
import json
import math
import os
import pathlib
import re
import subprocess
import sys
import tempfile
import time

import numpy as np

from bench_workprecision import wall_at_error

ROOT = pathlib.Path(__file__).resolve().parents[1]
EXE = pathlib.Path(os.environ.get("AIRLAUNCH_EXE", ROOT / "build" / "release" / "bin" / "airlaunch"))
L, EA, RHO, M, T_END, DT_OUT = 60.0, 2.0e6, 0.5, 50.0, 6.0, 0.05
G = 9.80665
C = math.sqrt(EA / RHO)                     # axial wave speed [m/s]
ZETA_MATERIAL = 0.05
RUN_TIMEOUT = 300.0                          # s, one airlaunch run
#: airlaunch's tolerance ladder: 1-2-5 per decade, so that the cheapest run reaching
#: MoorDyn's error is found to within a factor 2.5 in rtol (a decade ladder made the
#: equal-error rule jump by up to 10x in cost when a run missed by millimetres)
RTOLS_125 = [1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5, 5e-6, 2e-6, 1e-6]
SAG = 0.0   # midspan sag of the initial line, set from MoorDyn's initial profile in main()
LINE_MASS = "lumped"   # airlaunch's `&line mass` for its ladder runs (--mass=mixed); references lumped


def first_axial_frequency():
    """w1 [rad/s] of a fixed bar (rho, L, EA) carrying the end mass M: beta tan beta = rho L / M."""
    lo, hi = 1e-9, math.pi / 2 - 1e-12
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid * math.tan(mid) < RHO * L / M:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi) * C / L


W1 = first_axial_frequency()


def damping(case, n):
    """Axial damping coefficient c_d [N s] of `case` at N segments."""
    if case == "undamped":
        return 0.0
    if case == "segment":
        return (L / n) * math.sqrt(EA * RHO)          # zeta = 1 at w = 2c/l0
    if case == "material":
        return 2.0 * ZETA_MATERIAL * EA / W1          # zeta = 0.05 at w1
    raise ValueError(case)


def zeta_highest(cd, n):
    """Damping ratio of the highest segment mode w = 2c/l0."""
    return (2.0 * C / (L / n)) * cd / (2.0 * EA)


def moordyn_step(cd, n):
    """dtM = 0.5 x min(l0/c, 2/|lambda_max|) = 1/|lambda_max| of the highest segment mode."""
    w = 2.0 * C / (L / n)
    z = zeta_highest(cd, n)
    lam = w * (z + math.sqrt(z * z - 1.0)) if z > 1.0 else w
    return 0.5 * min((L / n) / C, 2.0 / lam)


def airlaunch_run(n, rtol, cd, tmp, reps=3, timeout=RUN_TIMEOUT, t_end=T_END, tag="", mass=None):
    """End-mass track (n_out, 3) in airlaunch's frame (y up), wall time [s] of the
    process (best of `reps` when below 1 s), steps, and the integration's own wall
    (the program's clock: no start-up, input or netCDF output; best of the same
    runs); (None, wall, reason, None) on failure or timeout."""
    import xarray as xr
    mass = mass or LINE_MASS
    name = f"al{tag}_{n}_{rtol:.0e}_{cd:.0f}_{mass}"
    out = tmp / f"{name}.nc"
    nml = tmp / f"{name}.nml"
    nml.write_text(f"""&run scene = 'line', t_end = {t_end}, output_dt = {DT_OUT}, output = '{out}',
  rtol = {rtol:.1e}, atol = {rtol:.1e}, max_steps = 0 /
&line length = {L}, n_seg = {n}, ea = {EA}, mass_per_length = {RHO}, damping = {cd!r},
  gravity = .true., air = .false., mass = '{mass}' /
&line_scene a_kind = 'fixed', a_position = 0.0, 0.0, 0.0,
  b_kind = 'point_mass', b_mass = {M}, b_position = {L}, 0.0, 0.0,
  initial_shape = '{"sag" if SAG > 0 else "straight"}', initial_sag = {SAG},
  record_tensions = .false., peak_tension = .false. /
""")
    best = inner = None
    for i in range(reps):
        t0 = time.perf_counter()
        try:
            res = subprocess.run([str(EXE), str(nml)], capture_output=True, text=True, timeout=timeout)
        except subprocess.TimeoutExpired:
            return None, time.perf_counter() - t0, "timeout", None
        wall = time.perf_counter() - t0
        if res.returncode != 0:
            return None, wall, "failed: " + res.stderr.strip()[-200:], None
        best = wall if best is None else min(best, wall)
        w_int = float(re.search(r"wall ([0-9.eE+-]+) s", res.stdout).group(1))
        inner = w_int if inner is None else min(inner, w_int)
        if best > 1.0:
            break
    with xr.open_dataset(out) as ds:
        tip = ds["line_tip_position"].values.copy()
        steps = int(ds.attrs.get("steps", -1))
    out.unlink()
    return tip, best, steps, inner


def startup_time(tmp):
    """Wall time of a tiny airlaunch line run (N = 2, 10 steps of output):
    process start-up, shared-library loading, input, netCDF output."""
    import xarray  # noqa: F401  (same conditions as the ladder)
    nml = tmp / "tiny.nml"
    nml.write_text(f"""&run scene = 'line', t_end = 0.05, output_dt = 0.005, output = '{tmp / "tiny.nc"}' /
&line length = 1.0, n_seg = 2, ea = 1.0e4, mass_per_length = 0.1 /
&line_scene b_kind = 'point_mass', b_mass = 1.0, b_position = 1.0, 0.0, 0.0, peak_tension = .false. /
""")
    walls = []
    for _ in range(7):
        t0 = time.perf_counter()
        subprocess.run([str(EXE), str(nml)], capture_output=True, check=True)
        walls.append(time.perf_counter() - t0)
    return float(np.median(walls)), float(min(walls))


def moordyn_run(n, cd, tmp, dtm=None, initial_sag_only=False):
    """End-mass track (converted to y up) and wall time of MoorDyn, RK4 at dtm
    (default: moordyn_step); or, with initial_sag_only, the midspan sag of
    MoorDyn's initial line."""
    import moordyn
    if dtm is None:
        dtm = moordyn_step(cd, n)
    f = tmp / f"md_{n}_{cd:.0f}_{dtm:.3e}.txt"
    f.write_text(f"""--------------------- MoorDyn Input File ------------------------------------
60 m cable pendulum in air (airlaunch benchmark)
----------------------- LINE TYPES ------------------------------------------
TypeName   Diam    Mass/m     EA     BA/-zeta    EI    Cd     Ca     CdAx    CaAx
(name)     (m)     (kg/m)     (N)    (N-s/-)    (N-m^2) (-)   (-)    (-)     (-)
cable      0.02    {RHO}       {EA}   {float(cd)!r}       0      0.0    0.0    0.0     0.0
---------------------- POINTS --------------------------------
ID  Attachment  X   Y   Z   Mass  Volume  CdA   Ca
(#)  (-)        (m) (m) (m) (kg)  (m^3)  (m^2)  (-)
1    Fixed      0   0   0   0     0      0      0
2    Free       {L}  0   0   {M}   0      0      0
---------------------- LINES --------------------------------
ID   LineType  AttachA  AttachB  UnstrLen  NumSegs  LineOutputs
(#)   (name)    (#)      (#)       (m)       (-)      (-)
1     cable     1        2        {L}       {n}       -
---------------------- OPTIONS -----------------------------------------
{dtm:.6e}   dtM
RK4      tScheme
{G}  g
1.0e-12  WtrDnsty
1.0e4    WtrDpth
0        TmaxIC
0        writeLog
-------------------------- OUTPUTS --------------------------------
END
------------------------------------------------------------------------
""")
    cwd = os.getcwd()
    os.chdir(tmp)
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        saved = os.dup(1)
        os.dup2(devnull, 1)          # MoorDyn prints its progress on stdout
        try:
            s = moordyn.Create(str(f))
            moordyn.Init(s, [], [])
            if initial_sag_only:
                ln = moordyn.GetLine(s, 1)
                k = moordyn.GetLineN(ln) // 2
                sag = -moordyn.GetLineNodePos(ln, k)[2]
                moordyn.Close(s)
                return sag, None
            pt = moordyn.GetPoint(s, 2)
            track = [moordyn.GetPointPos(pt)]
            t = 0.0
            t0 = time.perf_counter()
            for _ in range(int(round(T_END / DT_OUT))):
                moordyn.Step(s, [], [], t, DT_OUT)
                t += DT_OUT
                track.append(moordyn.GetPointPos(pt))
            wall = time.perf_counter() - t0
            moordyn.Close(s)
        finally:
            os.dup2(saved, 1)
            os.close(devnull)
    finally:
        os.chdir(cwd)
    xyz = np.array(track)
    if not np.all(np.isfinite(xyz)) or np.max(np.abs(xyz)) > 10 * L:
        return None, wall
    # MoorDyn's right-handed (x, y, z up) to ours (x, y up, z): a rotation about x,
    # y_ours = z_md, z_ours = -y_md ((x, z, y) would mirror a sideways motion)
    return np.stack([xyz[:, 0], xyz[:, 2], -xyz[:, 1]], axis=1), wall


def err(track, ref):
    if track is None or len(track) < len(ref):
        return float("inf")
    m = len(ref)
    return float(np.max(np.linalg.norm(track[:m] - ref[:m], axis=1)))


def exponent(points):
    """Least-squares slope of log(wall) against log(N) over (N, wall) pairs."""
    pts = [(n, w) for n, w in points if w is not None and w > 0]
    if len(pts) < 2:
        return None
    x = np.log([p[0] for p in pts])
    y = np.log([p[1] for p in pts])
    return float(np.polyfit(x, y, 1)[0])


def say(*a):
    print(*a, flush=True)


def run_case(case, cfg, tmp, startup):
    say(f"\n=== case '{case}' ===")
    ns, rtols = cfg["ns"], cfg["rtols"]
    for n in ns:
        cd = damping(case, n)
        say(f"  N = {n:4d}: c_d = {cd:9.1f} N s, zeta of the highest segment mode {zeta_highest(cd, n):6.3f}, "
            f"zeta at w1 = {W1:.2f} rad/s: {W1 * cd / (2 * EA):.2e}, MoorDyn dtM = {moordyn_step(cd, n):.3e} s")

    # ---- references
    refs = {}
    t0 = time.perf_counter()
    n_md = cfg["md_ref_n"][case]
    f_md = cfg["md_ref_step_factor"][case]
    md_ref, md_ref_wall = moordyn_run(n_md, damping(case, n_md), tmp, dtm=f_md * moordyn_step(damping(case, n_md), n_md))
    if md_ref is None:
        sys.exit(f"bench moordyn: MoorDyn's reference run ({case}) went unstable")
    refs["moordyn"] = {"code": "MoorDyn", "n": n_md, "step": f"{f_md} x dtM", "wall": md_ref_wall}
    say(f"  reference MoorDyn: N = {n_md}, RK4 at {f_md} x dtM: {md_ref_wall:.1f} s")
    al_ref = None
    if case != "undamped":
        n_al, r_al = cfg["al_ref_n"], cfg["al_ref_rtol"]
        al_ref, w, st, _ = airlaunch_run(n_al, r_al, damping(case, n_al), tmp, reps=1, timeout=3600, tag="ref",
                                         mass="lumped")
        if al_ref is None:
            sys.exit(f"bench moordyn: airlaunch's reference run ({case}) failed: {st}")
        refs["airlaunch"] = {"code": "airlaunch", "n": n_al, "rtol": r_al, "wall": w, "steps": st}
        say(f"  reference airlaunch: N = {n_al}, rtol = atol = {r_al:.0e}: {w:.1f} s, {st} steps")
        refs["distance_between_references"] = err(al_ref, md_ref)
        say(f"  distance between the two references (the two damping laws): {refs['distance_between_references']:.3e} m")
    else:
        say("  (one reference for both codes: identical physics; airlaunch is too slow undamped to give it)")
    ref_for = {"MoorDyn": md_ref, "airlaunch": al_ref if al_ref is not None else md_ref}

    # ---- does the reference converge?  the same settings at N_ref/2 and N_ref/4:
    # the distance between successive N must shrink
    conv = {}
    tr_md = {n_md: md_ref}
    for k in (2, 4):
        n = n_md // k
        tr_md[n], _ = moordyn_run(n, damping(case, n), tmp, dtm=f_md * moordyn_step(damping(case, n), n))
    conv["moordyn"] = [{"n_fine": n, "n_coarse": n // 2, "distance": err(tr_md[n // 2], tr_md[n])}
                       for n in (n_md, n_md // 2)]
    if al_ref is not None:
        tr_al = {n_al: al_ref}
        for k in (2, 4):
            n = n_al // k
            tr_al[n], _, _, _ = airlaunch_run(n, r_al, damping(case, n), tmp, reps=1, timeout=3600, tag="ref",
                                              mass="lumped")
        conv["airlaunch"] = [{"n_fine": n, "n_coarse": n // 2, "distance": err(tr_al[n // 2], tr_al[n])}
                             for n in (n_al, n_al // 2)]
    for code, rows in conv.items():
        say(f"  reference convergence ({code}, same step or tolerance): " + ", ".join(
            f"|N {r['n_coarse']} - N {r['n_fine']}| = {r['distance']:.3e} m" for r in rows))
    refs["convergence"] = conv

    # ---- MoorDyn ladder
    md, md_tracks = [], {}
    for n in cfg["md_ns"][case]:
        cd = damping(case, n)
        tr, wall = moordyn_run(n, cd, tmp)
        row = {"n": n, "c_d": cd, "dtm": moordyn_step(cd, n), "wall": wall, "error": err(tr, ref_for["MoorDyn"]),
               "stable": tr is not None}
        if n <= cfg["md_halving_max_n"]:
            tr2, _ = moordyn_run(n, cd, tmp, dtm=0.5 * moordyn_step(cd, n))
            row["time_error"] = err(tr, tr2)      # dtM against dtM/2
        if case != "undamped":
            row["error_vs_airlaunch_reference"] = err(tr, al_ref)
        md.append(row)
        md_tracks[n] = tr
        say(f"  MoorDyn   N = {n:4d}  {wall:8.3f} s  error {row['error']:.3e} m"
            + (f"  (time error dtM vs dtM/2 {row['time_error']:.1e} m)" if "time_error" in row else ""))

    # ---- airlaunch ladder
    al, al_best = [], {}
    for n in [k for k in ns if k in cfg["al_ns"][case]]:
        cd = damping(case, n)
        for rtol in rtols:
            tr, wall, st, inner = airlaunch_run(n, rtol, cd, tmp)
            row = {"n": n, "rtol": rtol, "wall": wall, "integration_wall": inner}
            if tr is None:
                row["failure"] = st
                al.append(row)
                say(f"  airlaunch N = {n:4d} rtol {rtol:.0e}: {st} after {wall:.1f} s; tighter tolerances skipped")
                break
            row.update({"steps": st, "error": err(tr, ref_for["airlaunch"])})
            if case != "undamped":
                row["error_vs_moordyn_reference"] = err(tr, md_ref)
            al.append(row)
            al_best[n] = (rtol, tr)
            say(f"  airlaunch N = {n:4d} rtol {rtol:.0e}  {wall:8.3f} s  {st:7d} steps  error {row['error']:.3e} m")
            if wall > cfg["al_budget"]:
                say(f"    ({wall:.0f} s > {cfg['al_budget']:.0f} s: tighter tolerances at this N skipped)")
                break

    # ---- both codes at equal N (airlaunch at its tightest rtol run)
    same_n = []
    for n, (rtol, tr) in sorted(al_best.items()):
        if n in md_tracks and md_tracks[n] is not None:
            same_n.append({"n": n, "airlaunch_rtol": rtol, "distance": err(tr, md_tracks[n])})

    # ---- equal error
    ratios = []
    for r in md:
        ok = [a for a in al if "error" in a and a["error"] <= r["error"]]
        if not ok:
            ratios.append({"moordyn_n": r["n"], "moordyn_error": r["error"], "moordyn_wall": r["wall"],
                           "airlaunch": None})
            continue
        best = min(ok, key=lambda a: a["wall"])
        ratios.append({"moordyn_n": r["n"], "moordyn_error": r["error"], "moordyn_wall": r["wall"],
                       "airlaunch_n": best["n"], "airlaunch_rtol": best["rtol"], "airlaunch_wall": best["wall"],
                       "airlaunch_error": best["error"], "ratio": r["wall"] / best["wall"],
                       "ratio_without_startup": r["wall"] / max(best["wall"] - startup, 1e-9)})
        # both codes timed alike: MoorDyn's stepping against airlaunch's integration
        # (neither's start-up, input or set-up), the cheapest run by that clock
        best_i = min(ok, key=lambda a: a["integration_wall"])
        ratios[-1].update({"airlaunch_n_integration": best_i["n"], "airlaunch_rtol_integration": best_i["rtol"],
                           "airlaunch_integration_wall": best_i["integration_wall"],
                           "ratio_integration": r["wall"] / best_i["integration_wall"]})
        # the same comparison read off airlaunch's work-precision front (log-log between runs)
        w = wall_at_error([(a["wall"], a["error"]) for a in al if "error" in a], r["error"])
        if w is not None:
            ratios[-1]["airlaunch_wall_interpolated"] = w
            ratios[-1]["ratio_interpolated"] = r["wall"] / w

    # ---- cost exponents
    exp_md = exponent([(r["n"], r["wall"]) for r in md])
    exp_al = {}
    for rtol in rtols:
        pts = [(a["n"], a["wall"]) for a in al if a["rtol"] == rtol and "error" in a]
        if len(pts) >= 2:
            exp_al[f"{rtol:.0e}"] = {"exponent": exponent(pts), "exponent_without_startup":
                                     exponent([(n, w - startup) for n, w in pts]), "ns": [p[0] for p in pts]}

    # ---- print
    say(f"\n  {'code':10s} {'N':>4s} {'rtol':>7s} {'c_d [N s]':>10s} {'wall [s]':>9s} {'steps':>8s} {'error [m]':>10s}")
    for r in md:
        say(f"  {'MoorDyn':10s} {r['n']:4d} {'RK4':>7s} {r['c_d']:10.1f} {r['wall']:9.3f} {'':>8s} {r['error']:10.3e}")
    for a in al:
        if "error" in a:
            say(f"  {'airlaunch':10s} {a['n']:4d} {a['rtol']:7.0e} {damping(case, a['n']):10.1f} {a['wall']:9.3f} "
                f"{a['steps']:8d} {a['error']:10.3e}")
        else:
            say(f"  {'airlaunch':10s} {a['n']:4d} {a['rtol']:7.0e} {damping(case, a['n']):10.1f} {a['wall']:9.1f} "
                f"{'':>8s} {a['failure']}")
    say("\n  both codes at equal N (airlaunch at its tightest run):")
    for s in same_n:
        say(f"    N = {s['n']:4d}: end-mass tracks {s['distance']:.3e} m apart (airlaunch rtol {s['airlaunch_rtol']:.0e})")
    say("\n  at equal end-mass error (cheapest airlaunch run, any N and rtol, at least as accurate):")
    for q in ratios:
        if "ratio" not in q:
            say(f"    MoorDyn N = {q['moordyn_n']:4d} ({q['moordyn_error']:.2e} m, {q['moordyn_wall']:.3f} s): "
                "no airlaunch run as accurate")
        else:
            say(f"    MoorDyn N = {q['moordyn_n']:4d} ({q['moordyn_error']:.2e} m, {q['moordyn_wall']:.3f} s)  vs  "
                f"airlaunch N = {q['airlaunch_n']}, rtol {q['airlaunch_rtol']:.0e} ({q['airlaunch_error']:.2e} m, "
                f"{q['airlaunch_wall']:.3f} s): {q['ratio']:.2f}x ({q['ratio_without_startup']:.2f}x without "
                f"start-up; on airlaunch's front at MoorDyn's error: {q['airlaunch_wall_interpolated']:.3f} s, "
                f"{q['ratio_interpolated']:.2f}x)\n        both timed alike (MoorDyn's stepping, airlaunch's "
                f"integration): airlaunch N = {q['airlaunch_n_integration']}, rtol {q['airlaunch_rtol_integration']:.0e}, "
                f"{q['airlaunch_integration_wall']:.4f} s: {q['ratio_integration']:.2f}x")
    say(f"\n  cost exponent in N (fit of log wall on log N): MoorDyn {exp_md:.2f}" if exp_md is not None else "")
    for k, v in exp_al.items():
        say(f"    airlaunch rtol {k}: {v['exponent']:.2f} ({v['exponent_without_startup']:.2f} without start-up), "
            f"N = {v['ns']}")
    return {"case": case, "references": refs, "moordyn": md, "airlaunch": al, "same_n": same_n,
            "equal_error": ratios, "exponent_moordyn": exp_md, "exponent_airlaunch": exp_al}


def main():
    global LINE_MASS
    quick = "--quick" in sys.argv
    LINE_MASS = next((a.split("=", 1)[1] for a in sys.argv[1:] if a.startswith("--mass=")), "lumped")
    cases = [a.split("=", 1)[1] for a in sys.argv[1:] if a.startswith("--case=")] or \
        ["undamped", "segment", "material"]
    if quick:
        cfg = {"ns": [15, 30, 60], "rtols": [1e-2, 1e-3, 1e-4],
               "md_ns": {"undamped": [15, 30, 60], "segment": [15, 30, 60], "material": [15, 30]},
               "al_ns": {"undamped": [15, 30], "segment": [15, 30, 60], "material": [15, 30, 60]},
               "md_ref_n": {"undamped": 120, "segment": 120, "material": 60},
               "md_ref_step_factor": {"undamped": 0.5, "segment": 1.0, "material": 1.0},
               "al_ref_n": 120, "al_ref_rtol": 1e-6, "al_budget": 10.0, "md_halving_max_n": 30}
    else:
        cfg = {"ns": [15, 30, 60, 120, 240], "rtols": RTOLS_125,
               "md_ns": {"undamped": [15, 30, 60, 120, 240], "segment": [15, 30, 60, 120, 240],
                         "material": [15, 30, 60]},
               "al_ns": {"undamped": [15, 30, 60, 120], "segment": [15, 30, 60, 120, 240],
                         "material": [15, 30, 60, 120, 240]},
               "md_ref_n": {"undamped": 480, "segment": 480, "material": 120},
               "md_ref_step_factor": {"undamped": 0.5, "segment": 1.0, "material": 1.0},
               "al_ref_n": 480, "al_ref_rtol": 1e-7, "al_budget": 30.0, "md_halving_max_n": 60}
    global SAG
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        SAG, _ = moordyn_run(120, 0.0, tmp, initial_sag_only=True)
        say(f"initial line: MoorDyn's profile, midspan sag {SAG:.4f} m (used for both codes); airlaunch's "
            f"ladder with the {LINE_MASS} mass matrix, its references lumped")
        say(f"first axial mode (fixed bar + end mass): w1 = {W1:.3f} rad/s; material c_d = "
            f"{damping('material', 1):.1f} N s")
        startup, startup_min = startup_time(tmp)
        say(f"airlaunch start-up (tiny run N = 2, process + netCDF output): median {startup * 1e3:.1f} ms, "
            f"min {startup_min * 1e3:.1f} ms; airlaunch walls below include it, MoorDyn's are in-process")
        results = [run_case(c, cfg, tmp, startup) for c in cases]
    summary = {}
    for r in results:
        rat = [q for q in r["equal_error"] if "ratio" in q]
        summary[r["case"]] = {
            "min_ratio": min((q["ratio"] for q in rat), default=None),
            "max_ratio": max((q["ratio"] for q in rat), default=None),
            "ratios": [q["ratio"] for q in rat],
            "ratios_interpolated": [q["ratio_interpolated"] for q in rat],
            "ratios_integration": [q["ratio_integration"] for q in rat],
            "target_3x_met_timed_alike": bool(rat) and len(rat) == len(r["equal_error"])
            and min(q["ratio_integration"] for q in rat) >= 3.0,
            "moordyn_runs_without_equal_airlaunch": sum(1 for q in r["equal_error"] if "ratio" not in q),
            "target_3x_met": bool(rat) and len(rat) == len(r["equal_error"]) and min(q["ratio"] for q in rat) >= 3.0,
            "exponent_moordyn": r["exponent_moordyn"],
            "exponent_airlaunch": {k: v["exponent"] for k, v in r["exponent_airlaunch"].items()}}
    say("\nsummary: " + "; ".join(f"{k}: ratio {v['min_ratio']}..{v['max_ratio']}, 3x met {v['target_3x_met']} "
                                 f"(timed alike: {min(v['ratios_integration'], default=None)}.."
                                 f"{max(v['ratios_integration'], default=None)}, 3x met "
                                 f"{v['target_3x_met_timed_alike']})" for k, v in summary.items()))
    say("RESULT " + json.dumps({"bench": "moordyn_pendulum", "quick": quick, "mass": LINE_MASS, "startup_s": startup,
                                "w1": W1, "sag": SAG, "summary": summary, "cases": results}))


if __name__ == "__main__":
    main()
