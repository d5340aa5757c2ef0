#!/usr/bin/env python3
"""How each milestone of a scenario moves when each chosen (not given)
parameter spans its plausible range.

    sensitivity.py [--base input/airlaunch_paper.nml] [--exe build/release/bin/airlaunch] [--jobs 2]

Runs the base scenario and one variant per (parameter, value) with
trajectory output off, and prints a Markdown table of the milestones (the
base row first).  The ranges below are the plausible ranges stated in
docs/validation.md.
"""
import argparse
import concurrent.futures
import pathlib
import re
import subprocess
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[1]

# (group, variable, values, why this range)
RANGES = [
    ("bay", "release_time", [0.62, 0.82], "t0 +- 0.1 s"),
    ("bay", "l0", [9.5, 10.5], "tail 0.25-1.25 m inside the bay"),
    ("bay", "floor_y", [-2.5, -1.5], "floor 1.5-2.5 m below the aircraft CG"),
    ("line", "ea", [5.0e5, 2.0e6], "nylon, 3-4 x strength of 150-500 kN lines"),
    ("line", "mass_per_length", [0.2, 0.8], "1/2 to 1 inch nylon"),
    ("line", "damping", [3.0e2, 3.0e3], "loss factor 0.02-0.2"),
    ("rocket", "diameter", [1.4, 1.8], "28 t, 18.5 m solid rockets"),
    ("rocket", "cg_from_nose", [8.5, 10.0], "CG 46-54 % of the length"),
    ("rocket", "fin_semi_span", [1.30, 1.38], "fin size near the chosen 1.34 m"),
    ("rocket", "c_dn", [1.0, 1.4], "cylinder cross-flow drag, sub/supercritical"),
    ("aircraft", "k_theta", [4.0, 16.0], "attitude-hold gain / 2 and x 2"),
    ("parachute", "added_mass_factor", [0.5, 2.0], "apparent-mass coefficient"),
]

MILESTONES = [("edge (Case 1->2)", r"edge \(Case 1->2\):\s+t = (\S+)"),
              ("separation", r"separation \(Case 2->3\):\s+t = (\S+)"),
              ("pitch max t", r"maximum: t = (\S+) s"),
              ("pitch max", r"maximum: t = \S+ s, pitch (\S+)"),
              ("peak T [kN]", r"peak line tension: (\S+) kN"),
              ("aircraft dθ", r"pitch excursion: (\S+) deg")]


def variant_text(base, group, var, value):
    """The base namelist with `var` of `group` set to `value`."""
    pat = re.compile(rf"(&{group}\b.*?)(^\s*{var}\s*=\s*[^!\n]*)(.*?^/)", re.S | re.M | re.I)
    m = pat.search(base)
    if m:
        return base[:m.start(2)] + f"  {var} = {value}" + base[m.end(2):]
    gm = re.search(rf"^&{group}\b", base, re.M | re.I)
    if not gm:
        raise SystemExit(f"sensitivity: group &{group} not in the base file")
    return base[:gm.end()] + f"\n  {var} = {value}" + base[gm.end():]


def run(exe, text):
    with tempfile.NamedTemporaryFile("w", suffix=".nml", delete=False) as f:
        f.write(re.sub(r"^\s*output\s*=.*$", "  trajectory = .false.", text, flags=re.M))
        path = f.name
    res = subprocess.run([str(exe), path], capture_output=True, text=True)
    pathlib.Path(path).unlink()
    if res.returncode != 0:
        return {"error": res.stderr.strip().splitlines()[0] if res.stderr else "failed"}
    out = {}
    for name, pat in MILESTONES:
        m = re.search(pat, res.stdout)
        out[name] = m.group(1) if m else "-"
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", default=str(ROOT / "input" / "airlaunch_paper.nml"))
    ap.add_argument("--exe", default=str(ROOT / "build" / "release" / "bin" / "airlaunch"))
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()
    base = pathlib.Path(args.base).read_text()
    jobs = [("base", "", "", base)]
    for group, var, values, why in RANGES:
        for v in values:
            jobs.append((f"&{group} {var} = {v}", why, v, variant_text(base, group, var, v)))
    with concurrent.futures.ThreadPoolExecutor(args.jobs) as pool:
        results = list(pool.map(lambda j: run(args.exe, j[3]), jobs))
    names = [m[0] for m in MILESTONES]
    print("| variant | range reason | " + " | ".join(names) + " |")
    print("|" + "---|" * (len(names) + 2))
    for (label, why, _, _), r in zip(jobs, results):
        cells = [r.get("error", "")] if "error" in r else [r[n] for n in names]
        print(f"| {label} | {why} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
