"""Are a sweep's cheap settings accurate enough where it matters?  The cases
nearest the boundary of the safe region, rerun with more line segments and
tighter tolerances, against their summary rows.

A sweep runs at its base scenario's settings (the paper file: 15 segments,
rtol 1e-5), chosen for speed.  A case far from a limit does not care about the
numerical error; a case whose margin is within that error of zero may pass or
fail by it.  ``verify`` takes the K computed cases with the smallest |relative
margin| of 'all' (or the ids given), writes each one's namelist
(``airlaunch-sweep --case-namelist``), resolves it (``airlaunch --check``),
refines it (``refine_namelist``) and runs it with ``airlaunch``; the margins of
every criterion are computed from the run's milestone attributes exactly as the
sweep's summary computes them (``metrics_from_attributes``), and compared with
the summary's.  At factors 1 and 1 the rerun is the summary's row bit for bit
(tests/python/test_sweep_verify.py).
"""
from __future__ import annotations

import concurrent.futures
import math
import pathlib
import re
import subprocess
import threading

import numpy as np
import xarray as xr

from .envelope import PER_CRITERION_UNITS
from .definition import DefinitionError
from .files import write_text_atomic

#: The line's segment indices that must follow a change of n_seg, and whether
#: in a one-segment line each means the last end (refined_segment).
SEGMENT_INDEX_VARS = (("BREAK_SEGMENT", False), ("WEAK_LINK_SEGMENT", True))
#: The most segments a line may have (docs/input.md).
MAX_SEGMENTS = 1000


def nearest_the_boundary(env: xr.Dataset, k: int) -> np.ndarray:
    """Ids of the k computed cases with the smallest |relative margin| of 'all'
    (a case whose metric is NaN has none: it is left to --ids), ties by id."""
    rel = env["relative_margin"].sel(criterion="all").values
    ids = env["case"].values
    ok = (env["status"].values == 0) & np.isfinite(rel)
    order = np.lexsort((ids[ok], np.abs(rel[ok])))
    return ids[ok][order[:k]]


def _group_span(text: str, group: str):
    """(start, end) of the body of &GROUP ... / in a resolved namelist (None if absent)."""
    m = re.search(rf"^&{group}\s*$(.*?)^\s*/\s*$", text, flags=re.M | re.S | re.I)
    return (m.start(1), m.end(1)) if m else None


def _get(text: str, group: str, var: str):
    span = _group_span(text, group)
    if span is None:
        return None
    m = re.search(rf"^\s*{var}\s*=\s*([^,\n]+),?\s*$", text[span[0]:span[1]], flags=re.M | re.I)
    return m.group(1).strip() if m else None


def _set(text: str, group: str, var: str, value: str) -> str:
    span = _group_span(text, group)
    body = text[span[0]:span[1]]
    body, n = re.subn(rf"^(\s*{var}\s*=\s*)[^,\n]+(,?\s*)$", lambda m: f"{m.group(1)}{value}{m.group(2)}", body,
                      count=1, flags=re.M | re.I)
    if n != 1:
        raise DefinitionError(f"the resolved namelist has no {group}%{var} to refine")
    return text[:span[0]] + body + text[span[1]:]


def refined_segment(j: int, n: int, factor: int, at_last_end: bool = False) -> int:
    """Segment j of n after every segment is cut into `factor`: the first stays
    the first, the last becomes the last, another the middle one of its
    `factor` pieces.  A line of one segment has both ends in it: `at_last_end`
    says which the variable means (the weak link's default is the last
    segment, at the parachute; a scheduled cut's the first, at the rocket)."""
    if n == 1:
        return factor if at_last_end else 1
    if j <= 1:
        return 1
    if j >= n:
        return n * factor
    return (j - 1) * factor + (factor + 1) // 2


def segment_factor(n: int, segments: int) -> int:
    """The factor n_seg is multiplied by: `segments`, capped at MAX_SEGMENTS."""
    return max(1, min(segments, MAX_SEGMENTS // n))


def refine_namelist(resolved: str, segments: int, tolerance: float) -> tuple:
    """The resolved namelist of a case (``airlaunch --check``'s output) with
    `segments` times the line's segments (at most MAX_SEGMENTS) and the
    tolerances divided by `tolerance`: &run rtol and atol, &line inner_rtol
    (when set) and inner_dt (when set: divided by the segment factor, as the
    marching scheme's stability limit).  Returns (text, what changed, the
    segment factor applied: 1 without a line)."""
    text, changes, factor = resolved, [], 1
    for var in ("RTOL", "ATOL"):
        old = float(_get(text, "RUN", var).replace("D", "E").replace("d", "e"))
        text = _set(text, "RUN", var, repr(old / tolerance))
        changes.append(f"run%{var.lower()} {old:.3g} -> {old / tolerance:.3g}")
    n_text = _get(text, "LINE", "N_SEG")
    if n_text is not None and segments != 1:
        n = int(n_text)
        factor = segment_factor(n, segments)
        if factor > 1:
            text = _set(text, "LINE", "N_SEG", str(n * factor))
            changes.append(f"line%n_seg {n} -> {n * factor}")
            for var, at_last_end in SEGMENT_INDEX_VARS:
                j = _get(text, "LINE", var)
                if j is not None:
                    text = _set(text, "LINE", var, str(refined_segment(int(j), n, factor, at_last_end)))
            dt = _get(text, "LINE", "INNER_DT")
            if dt is not None and float(dt) > 0.0:
                text = _set(text, "LINE", "INNER_DT", repr(float(dt) / factor))
    inner = _get(text, "LINE", "INNER_RTOL")
    if inner is not None and float(inner) > 0.0:
        text = _set(text, "LINE", "INNER_RTOL", repr(float(inner) / tolerance))
    return text, changes, factor


#: Summary variables whose single-run attribute is −1 when the event did not
#: happen or the value was not tracked (docs/output.md); NaN in a summary.
SENTINEL_MINUS_ONE = ("min_clearance_m", "min_exit_clearance_m", "min_line_clearance_m", "pitch_max_time_s",
                      "peak_line_tension_time_s",
                      "line_break_time_s", "line_recoil_speed_m_s", "ground_time_s", "ground_speed_m_s")
#: A line-scene summary variable and the attribute of a single run it comes from.
LINE_SCENE_ATTRIBUTES = {"peak_line_tension_N": "peak_tension_N", "peak_line_tension_time_s": "peak_tension_time_s"}


def metrics_from_attributes(attrs: dict, scene: str, names) -> dict:
    """The summary variables `names` of a single run, from its global
    attributes, as airlaunch-sweep writes them (src/sweep/airlaunch_sweep_row.f90)."""
    out = {}
    for name in names:
        key = LINE_SCENE_ATTRIBUTES.get(name, name) if scene == "line" else name
        value = float(attrs[key]) if key in attrs else math.nan
        if name in SENTINEL_MINUS_ONE and value == -1.0:
            value = math.nan
        if scene == "line" and name == "peak_line_tension_N" and value < 0.0:   # peak_tension = .false.
            value = math.nan
        out[name] = value
    return out


def _run(cmd, cwd, timeout):
    return subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=timeout)


class Reruns:
    """The refined runs in flight (run from worker threads), so that an
    interrupt of the main thread ends them (stop) instead of waiting for
    them, and starts no other."""

    def __init__(self):
        self._lock = threading.Lock()
        self._procs = set()
        self._stopped = False

    def run(self, cmd, cwd, timeout):
        """subprocess.run(cmd) with its output captured, unless stopped."""
        with self._lock:
            if self._stopped:
                raise RuntimeError("the verification was interrupted")
            proc = subprocess.Popen(cmd, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            self._procs.add(proc)
        try:
            out, err = proc.communicate(timeout=timeout)
        except BaseException:
            proc.kill()
            proc.communicate()
            raise
        finally:
            with self._lock:
                self._procs.discard(proc)
        return subprocess.CompletedProcess(cmd, proc.returncode, out, err)

    def stop(self):
        """End the runs in flight (SIGTERM) and start no other."""
        with self._lock:
            self._stopped = True
            for proc in self._procs:
                proc.terminate()


def case_namelist(case_id, definition, sweep_exe, timeout):
    """The namelist of one case (airlaunch-sweep --case-namelist)."""
    res = _run([str(sweep_exe), str(definition), "--case-namelist", str(case_id)], None, timeout)
    if res.returncode != 0:
        raise DefinitionError(f"airlaunch-sweep --case-namelist {case_id}: {res.stderr.strip()}")
    return res.stdout


def _path_arg(path) -> str:
    """A path as a program argument: one starting with '-' (an output_dir '-x')
    would be taken for an option."""
    text = str(path)
    return "./" + text if text.startswith("-") else text


def rerun_case(case_id, text, exe, work: pathlib.Path, segments, tolerance, timeout, run=_run):
    """One case (its namelist `text`) at refined settings: (status, message,
    the output's path, changes)."""
    case_nml = write_text_atomic(work / f"case_{case_id:06d}.nml", text)
    out = work / f"case_{case_id:06d}.nc"
    res = run([str(exe), _path_arg(case_nml), "--check", "--output", _path_arg(out)], None, timeout)
    if res.returncode != 0:
        return "invalid_input", res.stderr.strip(), out, [], 1
    resolved = res.stdout.split("\n", 1)[1]   # without the leading comment line
    text, changes, factor = refine_namelist(resolved, segments, tolerance)
    refined = write_text_atomic(work / f"case_{case_id:06d}_refined.nml", text)
    res = run([str(exe), _path_arg(refined), "--output", _path_arg(out)], None, timeout)
    status = "ok" if res.returncode == 0 else ("failed" if res.returncode == 3 else "error")
    return status, res.stderr.strip().splitlines()[-1] if res.returncode else "", out, changes, factor


def attributes(path) -> dict:
    """The global attributes of a run's output (none if it wrote no file).
    Called from one thread only: the HDF5 library is not thread-safe."""
    if not pathlib.Path(path).is_file():
        return {}
    with xr.open_dataset(path) as ds:
        return dict(ds.attrs)


def verify(env, criteria, scene, ids, definition, sweep_exe, exe, work, segments=4, tolerance=100.0, jobs=2,
           timeout=3600):
    """Rerun the cases `ids` refined; the margins of each criterion at the
    sweep's settings and refined, as a Dataset over (case, criterion)."""
    work = pathlib.Path(work)
    work.mkdir(parents=True, exist_ok=True)
    texts = [case_namelist(int(i), definition, sweep_exe, timeout) for i in ids]
    reruns = Reruns()
    pool = concurrent.futures.ThreadPoolExecutor(max_workers=max(1, jobs))
    try:
        runs = list(pool.map(lambda a: rerun_case(int(a[0]), a[1], exe, work, segments, tolerance, timeout,
                                                  reruns.run), zip(ids, texts)))
    except BaseException:   # an interrupt: end the runs in flight, start no other
        reruns.stop()
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
    # a case the sweep computed whose rerun airlaunch refuses (its --check) is
    # verify's own failure (a path airlaunch cannot take, say), not a flip
    status = env["status"].sel(case=list(ids)).values
    for case_id, st, r in zip(ids, status, runs):
        if st == 0 and r[0] == "invalid_input":
            lines = r[1].splitlines() or ["no message"]
            raise DefinitionError(f"the rerun of case {int(case_id)} was refused: {lines[-1]}")
    names = [c.name for c in criteria]
    metrics = sorted({m for c in criteria for m in c.metrics})
    attrs = [attributes(r[2]) if r[0] == "ok" else {} for r in runs]
    rows = {m: np.array([metrics_from_attributes(a, scene, [m])[m] if r[0] == "ok" else math.nan
                         for a, r in zip(attrs, runs)]) for m in metrics}
    refined = xr.Dataset({m: ("case", v) for m, v in rows.items()})
    sel = env.sel(case=list(ids))
    margin_sweep = sel["margin"].sel(criterion=names).values
    margin_refined = np.array([c.margin(refined) for c in criteria])
    passed_sweep = sel["passed"].sel(criterion=names).values.astype(bool)
    passed_refined = np.where(np.isnan(margin_refined), False, margin_refined >= 0.0)
    scale = np.array([c.scale for c in criteria])[:, None]
    ds = xr.Dataset(coords={"case": ("case", np.asarray(ids)),
                            "criterion": ("criterion", names, {"long_name": "criterion (the criteria file's)"})})
    for name in env.attrs["inputs"].split():
        ds[name] = sel[name]
    ds["margin_sweep"] = (("criterion", "case"), margin_sweep,
                          {"long_name": "margin at the sweep's settings (the summary's)", **PER_CRITERION_UNITS})
    ds["margin_refined"] = (("criterion", "case"), margin_refined,
                            {"long_name": "margin at the refined settings (NaN: not computed or event not reached)",
                             **PER_CRITERION_UNITS})
    ds["difference"] = (("criterion", "case"), margin_sweep - margin_refined,
                        {"long_name": "margin at the sweep's settings less the refined one (the sweep's numerical "
                                      "error, in the criterion's units)", **PER_CRITERION_UNITS})
    ds["relative_difference"] = (("criterion", "case"), (margin_sweep - margin_refined) / scale,
                                 {"long_name": "difference / the criterion's scale", "units": "1"})
    ds["flipped"] = (("criterion", "case"), (passed_sweep != passed_refined).astype(np.int8),
                     {"long_name": "1 where the case passes at one setting and fails at the other", "units": "1"})
    ds["refined_status"] = (("case",), np.array([r[0] for r in runs]),
                            {"long_name": "status of the refined rerun (ok; failed: a numerical failure; invalid_input; error)"})
    ds["refined_message"] = (("case",), np.array([r[1] for r in runs]),
                             {"long_name": "the refined rerun's failure, if any (empty: none)"})
    ds["criterion_units"] = (("criterion",), np.array([c.units for c in criteria]),
                             {"long_name": "units of each criterion's margins"})
    ds["segments_factor"] = (("case",), np.array([r[4] for r in runs], dtype=np.int32),
                             {"long_name": "the factor n_seg was multiplied by (--segments, capped at "
                                           f"{MAX_SEGMENTS} segments; 1: no line)", "units": "1"})
    changes = next((r[3] for r in runs if r[3]), [])
    ds.attrs.update({"title": "airlaunch sweep verification: the cases nearest the boundary, refined",
                     "segments_factor_asked": np.int32(segments), "tolerance_factor": float(tolerance),
                     "refinement": "; ".join(changes)})
    return ds


def verification_table(ds: xr.Dataset) -> str:
    """Per case and criterion: the two margins, their difference, and a flip."""
    units = dict(zip(ds["criterion"].values, ds["criterion_units"].values))
    lines = ["| case | refined run | criterion | margin (sweep) | margin (refined) | difference | flips |",
             "|---|---|---|---|---|---|---|"]
    for cid in ds["case"].values:
        row = ds.sel(case=cid)
        for c in ds["criterion"].values:
            r = row.sel(criterion=c)
            cells = [str(int(cid)), str(row["refined_status"].values), str(c),
                     _fmt(r["margin_sweep"], units[c]), _fmt(r["margin_refined"], units[c]),
                     _fmt(r["difference"], units[c]), "**yes**" if int(r["flipped"]) else "no"]
            lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _fmt(v, units):
    """A margin with its units; a dimensionless one ("1") bare."""
    v = float(v)
    return "n/a" if math.isnan(v) else f"{v:.6g}" + ("" if units == "1" else f" {units}")
