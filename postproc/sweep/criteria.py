"""Separation safety criteria: a namelist file with one ``&criteria`` group.

Every criterion is optional; the ones the file sets are evaluated.  Each gives,
per case, a margin in its own units (positive: passes) and a relative margin
(the margin divided by the criterion's scale), so cases can be ranked across
criteria.  docs/sweep.md documents the variables.
"""
from __future__ import annotations

import dataclasses
import difflib
import math
import sys

import f90nml
import numpy as np

from .definition import DefinitionError, check_namelist_text, read_namelist_text, show, to_float

#: Variables of &criteria (what each limits is in docs/sweep.md).
CRITERIA_VARS = ("min_clearance_m", "min_line_clearance_m", "line_strength_n", "line_safety_factor",
                 "max_aircraft_pitch_excursion_deg", "max_load_factor_excursion",
                 "firing_pitch_min_deg", "firing_pitch_max_deg", "firing_time_max_s", "max_ground_speed_m_s")


#: The criteria's summary variables that a sweep of each scene other than the
#: air-launch has (an airlaunch-scene summary has every one; docs/sweep.md).
SCENE_CRITERION_METRICS = {"line": ("peak_line_tension_N", "ground_speed_m_s")}


def check_scene(criteria, scene, have, path):
    """Refuse a criterion whose summary variables a sweep of `scene` has not
    (`have`: the variables it has; None: every one) in one line."""
    for c in criteria:
        missing = [m for m in c.metrics if have is not None and m not in have]
        if missing:
            raise DefinitionError(f"{path}: &criteria: {', '.join(sorted(c.limits))} is not allowed for a sweep "
                                  f"of scene '{scene}': its summary has no {', '.join(missing)} (leave the "
                                  "criterion out; docs/sweep.md lists each scene's summary variables)")


#: Settings of a base scenario (or of its sweep's &fixed) under which a
#: criterion's metric is never computed, so that every case's margin would be
#: NaN and fail: (group, variable, the value, the criteria, why, the scene it
#: applies to (None: any) and whether a base that does not set it has it).
UNTRACKED = (
    ("line", "enabled", False, ("line_tension", "line_clearance"), "the scene has no line", None, False),
    ("line_scene", "peak_tension", False, ("line_tension",), "the peak tension is not tracked", None, False),
    ("line_scene", "ground", False, ("touchdown",), "the scene has no ground, the default", "line", True),
)


def _setting(defn, base, group, var):
    """(value, where it is set) of group%var for every case of a sweep: its
    &fixed, else the base (`base`: the parsed base, None if unreadable);
    value None where neither sets it."""
    name = f"{group}%{var}"
    for fixed_name, text in defn.fixed:
        if fixed_name == name:
            try:
                return f90nml.reads(f"&x v = {text} /\n")["x"]["v"], f"&fixed '{name}'"
            except Exception:   # noqa: BLE001 - airlaunch-sweep names an unreadable value
                return None, None
    group_vars = base.get(group) if base is not None else None
    return (group_vars.get(var) if hasattr(group_vars, "get") else None), f"the base scenario {defn.base}"


def check_tracked(criteria, defn, path):
    """Refuse in one line a criterion whose metric the sweep's base (with its
    &fixed) never computes: its margin would be NaN, and fail, in every case."""
    try:
        base = f90nml.reads(read_namelist_text(defn.base, "the base scenario"))
    except Exception:   # noqa: BLE001 - any unreadable base is airlaunch-sweep's to report
        base = None
    scene = str(base.get("run", {}).get("scene", "airlaunch")).strip().lower() if base is not None else None
    for group, var, off, names, why, only_scene, off_by_default in UNTRACKED:
        if only_scene is not None and scene != only_scene:
            continue
        value, source = _setting(defn, base, group, var)
        if value is None and off_by_default and base is not None:
            value, source = off, f"the base scenario {defn.base} (by default)"
        if isinstance(value, str):
            value = value.strip().lower()
        if value is None or value != off or isinstance(value, bool) != isinstance(off, bool):
            continue
        for c in criteria:
            if c.name in names:
                shown = show(off) if not isinstance(off, bool) else (".true." if off else ".false.")
                raise DefinitionError(f"{path}: &criteria: {', '.join(sorted(c.limits))} is not allowed for this "
                                      f"sweep: {source} sets &{group} {var} = {shown} ({why}: every case's "
                                      f"margin would be NaN, failing; leave the criterion out or change {var})")


def base_scene(base):
    """The &run scene of a base scenario ('airlaunch' when it sets none; None if
    the file cannot be read: airlaunch-sweep names that)."""
    try:
        nml = f90nml.reads(read_namelist_text(base, "the base scenario"))
        return str(nml.get("run", {}).get("scene", "airlaunch")).strip().lower()
    except Exception:   # noqa: BLE001 - any unreadable base is airlaunch-sweep's to report
        return None


@dataclasses.dataclass(frozen=True)
class Criterion:
    """One evaluated criterion: name, what it limits, and how to compute its margin."""

    name: str
    description: str
    units: str
    scale: float
    metrics: tuple
    limits: dict

    def margin(self, summary) -> np.ndarray:
        """Margin per case in the criterion's units (NaN where the metric is undefined)."""
        m = {k: np.asarray(summary[k].values, dtype=float) for k in self.metrics}
        lim = self.limits
        if self.name == "clearance":
            return m["min_clearance_m"] - lim["min_clearance_m"]
        if self.name == "line_clearance":
            return m["min_line_clearance_m"] - lim["min_line_clearance_m"]
        if self.name == "line_tension":
            return lim["line_strength_n"] / lim["line_safety_factor"] - m["peak_line_tension_N"]
        if self.name == "aircraft_pitch":
            return lim["max_aircraft_pitch_excursion_deg"] - m["max_aircraft_pitch_excursion_deg"]
        if self.name == "load_factor":
            return lim["max_load_factor_excursion"] - m["max_load_factor_excursion"]
        if self.name == "firing_attitude":
            p = m["pitch_max_deg"]
            lower = p - lim["firing_pitch_min_deg"]
            if lim["firing_pitch_max_deg"] >= 90.0:
                # the Euler pitch never exceeds 90 deg: a window ending at 90 has no upper side
                return lower
            return np.minimum(lower, lim["firing_pitch_max_deg"] - p)
        if self.name == "firing_time":
            return lim["firing_time_max_s"] - m["pitch_max_time_s"]
        if self.name == "touchdown":
            return lim["max_ground_speed_m_s"] - m["ground_speed_m_s"]
        raise DefinitionError(f"criterion {self.name} has no margin")


def _number(path, key, value):
    """A finite real number of normal magnitude: 0, or |x| in [2.2e-308, 1.8e308]
    (a subnormal limit would overflow the relative margins, margin / limit)."""
    number = None if isinstance(value, bool) or not isinstance(value, (int, float)) else to_float(value)
    if number is None or not math.isfinite(number):
        raise DefinitionError(f"{path}: &criteria: {key} = {show(value)} is not a finite real number "
                              f"(|x| <= {sys.float_info.max:.4g})")
    if number != 0 and abs(number) < sys.float_info.min:
        raise DefinitionError(f"{path}: &criteria: {key} = {number!r} is not allowed (a subnormal number, too "
                              f"small to compute with: give 0 or a magnitude >= {sys.float_info.min:.4g})")
    return number


def parse_criteria(text, path="<criteria>"):
    """Validate a criteria namelist text; return the list of Criterion."""
    check_namelist_text(text, path, {"criteria": {k: ("real", 0) for k in CRITERIA_VARS}})
    try:
        nml = f90nml.reads(text)
    except Exception as exc:  # f90nml raises several exception types
        lines = str(exc).strip().splitlines() or [type(exc).__name__]
        raise DefinitionError(f"{path}: cannot read the namelist: {lines[0]}") from None
    for group in nml:
        if group != "criteria":
            raise DefinitionError(f"{path}: unknown group &{group} (allowed: criteria)")
    if "criteria" not in nml or isinstance(nml["criteria"], list):
        raise DefinitionError(f"{path}: the group &criteria must appear once")
    raw = nml["criteria"]
    for key in raw:
        if key not in CRITERIA_VARS:
            close = difflib.get_close_matches(key, CRITERIA_VARS, n=1, cutoff=0.6)
            hint = f" (did you mean '{close[0]}'?)" if close else ""
            raise DefinitionError(f"{path}: &criteria: unknown criterion '{key}'{hint} "
                                  f"(allowed: {', '.join(CRITERIA_VARS)})")
    v = {k: _number(path, k, raw[k]) for k in raw}
    where = f"{path}: &criteria: "
    out = []
    if "min_clearance_m" in v:
        if v["min_clearance_m"] < 0:
            raise DefinitionError(f"{where}min_clearance_m = {v['min_clearance_m']:g} is not allowed (must be >= 0 m)")
        out.append(Criterion("clearance", "minimum rocket-aircraft clearance after separation >= limit",
                             "m", max(v["min_clearance_m"], 1.0), ("min_clearance_m",),
                             {"min_clearance_m": v["min_clearance_m"]}))
    if "min_line_clearance_m" in v:
        if v["min_line_clearance_m"] < 0:
            raise DefinitionError(f"{where}min_line_clearance_m = {v['min_line_clearance_m']:g} is not allowed "
                                  "(must be >= 0 m)")
        out.append(Criterion("line_clearance", "minimum line-empennage clearance >= limit",
                             "m", max(v["min_line_clearance_m"], 1.0), ("min_line_clearance_m",),
                             {"min_line_clearance_m": v["min_line_clearance_m"]}))
    if "line_strength_n" in v or "line_safety_factor" in v:
        if "line_strength_n" not in v:
            raise DefinitionError(f"{where}line_safety_factor needs line_strength_n (the line's breaking strength, N)")
        strength = v["line_strength_n"]
        factor = v.get("line_safety_factor", 1.0)
        if not strength > 0:
            raise DefinitionError(f"{where}line_strength_n = {strength:g} is not allowed (must be > 0 N)")
        if not factor >= 1:
            raise DefinitionError(f"{where}line_safety_factor = {factor:g} is not allowed (must be >= 1)")
        out.append(Criterion("line_tension", "peak line tension <= strength / safety factor", "N",
                             strength / factor, ("peak_line_tension_N",),
                             {"line_strength_n": strength, "line_safety_factor": factor}))
    if "max_aircraft_pitch_excursion_deg" in v:
        lim = v["max_aircraft_pitch_excursion_deg"]
        if not lim > 0:
            raise DefinitionError(f"{where}max_aircraft_pitch_excursion_deg = {lim:g} is not allowed (must be > 0)")
        out.append(Criterion("aircraft_pitch", "largest aircraft pitch excursion from trim <= limit", "degree",
                             lim, ("max_aircraft_pitch_excursion_deg",),
                             {"max_aircraft_pitch_excursion_deg": lim}))
    if "max_load_factor_excursion" in v:
        lim = v["max_load_factor_excursion"]
        if not lim > 0:
            raise DefinitionError(f"{where}max_load_factor_excursion = {lim:g} is not allowed (must be > 0)")
        out.append(Criterion("load_factor", "largest aircraft load factor excursion from 1 g <= limit", "1",
                             lim, ("max_load_factor_excursion",), {"max_load_factor_excursion": lim}))
    if "firing_pitch_min_deg" in v or "firing_pitch_max_deg" in v:
        lo = v.get("firing_pitch_min_deg", -90.0)
        hi = v.get("firing_pitch_max_deg", 90.0)
        if not lo < 90:   # named before the window: with the default max, "reversed" blamed a value not set
            raise DefinitionError(f"{where}firing_pitch_min_deg = {lo:g} is not allowed (must be < 90 degrees: the "
                                  "rocket's Euler pitch never exceeds 90, so no case could reach it)")
        if not hi > lo:
            raise DefinitionError(f"{where}firing_pitch_max_deg = {hi:g} is not allowed (must be > "
                                  f"firing_pitch_min_deg = {lo:g}: reversed window)")
        # the scale: half the window the Euler pitch can reach (it never exceeds 90)
        out.append(Criterion("firing_attitude", "rocket Euler pitch at its first maximum (the firing moment) "
                             "inside [min, max]", "degree", (min(hi, 90.0) - lo) / 2, ("pitch_max_deg",),
                             {"firing_pitch_min_deg": lo, "firing_pitch_max_deg": hi}))
    if "firing_time_max_s" in v:
        lim = v["firing_time_max_s"]
        if not lim > 0:
            raise DefinitionError(f"{where}firing_time_max_s = {lim:g} is not allowed (must be > 0 s)")
        out.append(Criterion("firing_time", "the firing moment (first pitch maximum) comes by the limit", "s",
                             lim, ("pitch_max_time_s",), {"firing_time_max_s": lim}))
    if "max_ground_speed_m_s" in v:
        lim = v["max_ground_speed_m_s"]
        if not lim > 0:
            raise DefinitionError(f"{where}max_ground_speed_m_s = {lim:g} is not allowed (must be > 0 m/s)")
        out.append(Criterion("touchdown", "speed at the ground (the run's end: &flight ground_altitude, "
                             "&line_scene ground) <= limit; a case that ends above the ground fails", "m s-1",
                             lim, ("ground_speed_m_s",), {"max_ground_speed_m_s": lim}))
    if not out:
        raise DefinitionError(f"{path}: &criteria sets no criterion (allowed: {', '.join(CRITERIA_VARS)})")
    return out


def read_criteria(path):
    """Read and validate a criteria file."""
    return parse_criteria(read_namelist_text(path, "a criteria file"), str(path))
