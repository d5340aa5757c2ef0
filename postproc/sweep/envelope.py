"""Separation safety envelopes from a sweep summary and a criteria file.

- ``evaluate``: pass/fail and margin per criterion and case (an xarray Dataset,
  written as OUTPUT_DIR/envelope.nc);
- ``success_probability``: the fraction of cases that pass, with a 95 % Wilson
  score interval and the exact Clopper-Pearson interval;
- ``pass_probability_map``: the probability of passing over a pair of inputs
  (Gaussian-kernel regression of the pass indicator, bandwidth by
  leave-one-out likelihood), whose 0.5 level is the boundary of the safe region;
- ``worst_cases``: the cases with the smallest relative margin;
- the rank sensitivities of every margin to every input (``sensitivity.py``:
  Spearman and partial rank correlations with 95 % intervals).

A case that failed numerically or whose input was invalid passes no criterion
(its margins are NaN): a sweep never counts what it could not compute as safe.
"""
from __future__ import annotations

import math

import numpy as np
import scipy.stats as st
import xarray as xr

from .criteria import Criterion
from .sensitivity import sensitivity

Z95 = st.norm.ppf(0.975)


def envelope_name(scene: str) -> str:
    """What the envelope of a sweep of `scene` is called (titles, figures)."""
    return "separation safety envelope" if scene == "airlaunch" else f"{scene} scene safety envelope"


def input_names(summary: xr.Dataset) -> list:
    """The varied inputs of a summary (its `inputs` attribute, in order)."""
    return summary.attrs["inputs"].split()


#: The attributes of a variable along `criterion` whose units are each criterion's
#: own (metres for one row, newtons for the next): no `units` attribute, which
#: one string cannot give and unit libraries (UDUNITS-2, pint-xarray's
#: `quantify`) would refuse, but `units_from` naming the variable that has them.
PER_CRITERION_UNITS = {"units_from": "criterion_units"}


def evaluate(summary: xr.Dataset, criteria: list) -> xr.Dataset:
    """Pass/fail and margins of every case against every criterion (and 'all')."""
    ok = summary["status"].values == 0
    names = [c.name for c in criteria] + ["all"]
    n = summary.sizes["case"]
    margin = np.full((len(names), n), np.nan)
    relative = np.full((len(names), n), np.nan)
    for i, c in enumerate(criteria):
        m = np.where(ok, c.margin(summary), np.nan)
        margin[i] = m
        with np.errstate(over="ignore"):   # a tiny scale: the relative margin is +-inf, as it should
            relative[i] = m / c.scale
    # NaN (not computed, or the event never happened) counts as failing
    passed = np.where(np.isnan(margin), False, margin >= 0.0)
    passed[-1] = passed[:-1].all(axis=0) & ok
    rel = np.where(np.isnan(relative[:-1]), -np.inf, relative[:-1])
    relative[-1] = rel.min(axis=0)
    worst = np.where(ok, np.array(names[:-1])[rel.argmin(axis=0)], "not computed")
    ds = xr.Dataset(coords={"case": summary["case"],
                            "criterion": ("criterion", names,
                                          {"long_name": "criterion (the criteria file's, then 'all': every one)"})})
    for name in input_names(summary):
        ds[name] = summary[name]
    ds["status"] = summary["status"]
    ds["passed"] = (("criterion", "case"), passed.astype(np.int8),
                    {"long_name": "1 if the case meets the criterion ('all': every criterion)", "units": "1"})
    ds["margin"] = (("criterion", "case"), margin,
                    {"long_name": "margin in the criterion's units (>= 0 passes; NaN: not computed or event "
                                  "not reached)", **PER_CRITERION_UNITS})
    ds["relative_margin"] = (("criterion", "case"), relative,
                             {"long_name": "margin / criterion scale ('all': the smallest; -inf: not computed)",
                              "units": "1"})
    ds["worst_criterion"] = (("case",), worst.astype(str), {"long_name": "criterion with the smallest relative margin"})
    ds["criterion_units"] = (("criterion",), np.array([c.units for c in criteria] + ["1"]),
                             {"long_name": "units of each criterion's margins"})
    ds["criterion_scale"] = (("criterion",), np.array([c.scale for c in criteria] + [1.0]),
                             {"long_name": "scale of the criterion's margins (relative_margin = margin / scale)",
                              **PER_CRITERION_UNITS})
    ds["criterion_description"] = (("criterion",), np.array([c.description for c in criteria]
                                                           + ["every criterion above"]),
                                   {"long_name": "what the criterion asks"})
    k = passed.sum(axis=1)
    n_all = np.full(len(names), n)
    p = k / n_all
    wl, wh = wilson_interval(k, n_all)
    cl, ch = clopper_pearson_interval(k, n_all)
    ds["probability"] = (("criterion",), p, {"long_name": "fraction of cases that pass", "units": "1"})
    ds["wilson_low"] = (("criterion",), wl, {"long_name": "95% Wilson score interval, low", "units": "1"})
    ds["wilson_high"] = (("criterion",), wh, {"long_name": "95% Wilson score interval, high", "units": "1"})
    ds["clopper_pearson_low"] = (("criterion",), cl, {"long_name": "95% Clopper-Pearson interval, low", "units": "1"})
    ds["clopper_pearson_high"] = (("criterion",), ch, {"long_name": "95% Clopper-Pearson interval, high",
                                                       "units": "1"})
    for c in criteria:
        for key, value in c.limits.items():
            ds.attrs[f"limit_{key}"] = value
    scene = str(summary.attrs.get("scene", "airlaunch"))   # (summaries before line-scene sweeps: airlaunch)
    ds.attrs.update({"title": f"airlaunch {envelope_name(scene)}: {summary.attrs.get('sweep_name', '')}",
                     "scene": scene,
                     "inputs": summary.attrs["inputs"], "n_cases": np.int32(n),
                     "n_not_ok": np.int32((~ok).sum()),
                     "probability_note": "fraction of the table's cases that pass: an estimate of the "
                                         "probability of success under the table's input distributions; "
                                         "cases not computed count as failing"})
    ds.update(sensitivity(ds))
    return ds


#: Why a summary variable is NaN in a computed case (docs/sweep.md, "The summary").
UNDEFINED_WHY = {
    "ground_speed_m_s": "no run reached the ground, &flight ground_altitude or &line_scene ground, by its t_end",
    "pitch_max_deg": "no first pitch maximum after a separation by t_end",
    "pitch_max_time_s": "no first pitch maximum after a separation by t_end",
    "min_clearance_m": "no separation by t_end",
    "min_line_clearance_m": "no line",
    "peak_line_tension_N": "no line, or its peak tension not tracked",
}


def undefined_metrics(env: xr.Dataset, criteria: list) -> list:
    """The criteria whose metric is NaN in computed cases (they fail it, by
    rule): (criterion, its metrics, cases with a NaN metric, computed cases),
    one per such criterion, in the criteria's order."""
    ok = env["status"].values == 0
    out = []
    for c in criteria:
        margin = env["margin"].sel(criterion=c.name).values
        k = int(np.sum(ok & np.isnan(margin)))
        if k:
            out.append((c.name, c.metrics, k, int(ok.sum())))
    return out


def undefined_metric_lines(env: xr.Dataset, criteria: list) -> list:
    """Lines (for stdout, under the probabilities) on the criteria whose metric
    is NaN in computed cases: a warning when every computed case lacks it, so
    that a criterion no case can evaluate (the touchdown speed of a sweep that
    never lands) does not fail them all without a word; a note otherwise."""
    lines = []
    for name, metrics, k, n_ok in undefined_metrics(env, criteria):
        metric = ", ".join(metrics)
        why = UNDEFINED_WHY.get(metrics[0], "the event never came by t_end")
        if k == n_ok:
            lines.append(f"  warning: {name}: {metric} is NaN in every computed case ({k} of {k}): no case can pass "
                         f"this criterion ({why}); leave it out, or change the sweep so that the event happens")
        else:
            lines.append(f"  note: {name}: {metric} is NaN in {k} of {n_ok} computed cases ({why}): they fail it")
    return lines


def wilson_interval(k, n, z=Z95):
    """Wilson score interval for k successes in n trials (arrays allowed)."""
    k = np.asarray(k, dtype=float)
    n = np.asarray(n, dtype=float)
    p = k / n
    denom = 1 + z**2 / n
    centre = (p + z**2 / (2 * n)) / denom
    half = z * np.sqrt(p * (1 - p) / n + z**2 / (4 * n**2)) / denom
    # the interval always contains p (k = 0 or n: an end at 0 or 1); keep it so
    # against rounding
    return np.minimum(np.clip(centre - half, 0, 1), p), np.maximum(np.clip(centre + half, 0, 1), p)


def clopper_pearson_interval(k, n, alpha=0.05):
    """Exact (Clopper-Pearson) interval from the beta distribution."""
    k = np.asarray(k, dtype=float)
    n = np.asarray(n, dtype=float)
    low = np.where(k > 0, st.beta.ppf(alpha / 2, k, n - k + 1), 0.0)
    high = np.where(k < n, st.beta.ppf(1 - alpha / 2, k + 1, n - k), 1.0)
    return low, high


def _normalise(v, lo, hi):
    return (v - lo) / (hi - lo) if hi > lo else np.zeros_like(v)


def bandwidth_subset(n, max_points=2000):
    """Indices (ascending) of the cases the bandwidth is chosen on: all n, or
    max_points of them drawn at random without replacement, with a fixed seed
    (the same sweep draws the same map).  Every k-th case instead aliased with
    the designs' own order: a scrambled Sobol sweep of 2^17 cases (k = 66) kept
    its second input in one half of its range, of 2^18 two inputs; a grid of
    4500 cases whose last input has 3 levels (k = 3), that input at one level."""
    if n <= max_points:
        return np.arange(n)
    return np.sort(np.random.default_rng(0).choice(n, size=max_points, replace=False))


def choose_bandwidth(points, passed, candidates=None, max_points=2000):
    """Bandwidth (in normalised units) maximising the leave-one-out Bernoulli
    likelihood (on a random subset of at most max_points points, bandwidth_subset)."""
    if candidates is None:
        # from about the mean spacing of the points (below it the estimate
        # follows single points) to half the box (nearly flat)
        candidates = np.geomspace(max(0.6 / math.sqrt(len(points)), 0.01), 0.5, 14)
    keep = bandwidth_subset(len(points), max_points)
    points, passed = points[keep], passed[keep]
    d2 = ((points[:, None, :] - points[None, :, :]) ** 2).sum(axis=2)
    y = passed.astype(float)
    best, best_ll = candidates[0], -np.inf
    for h in candidates:
        w = np.exp(-0.5 * d2 / h**2)
        np.fill_diagonal(w, 0.0)
        wsum = w.sum(axis=1)
        p = (w @ y + 0.5) / (wsum + 1.0)   # a weak prior keeps p inside (0, 1)
        ll = np.sum(y * np.log(p) + (1 - y) * np.log(1 - p))
        if ll > best_ll:
            best, best_ll = h, ll
    return best


#: Most kernel factors held at once by pass_probability_map: grid levels times
#: cases per chunk (two float64 arrays of this size: about 64 MB).
MAP_CHUNK_ELEMENTS = 4_000_000


def pass_probability_map(x, y, passed, n_grid=81, bandwidth=None, chunk_elements=MAP_CHUNK_ELEMENTS):
    """P(pass) over the (x, y) box of the samples: Nadaraya-Watson regression of
    the pass indicator with a Gaussian kernel on inputs scaled to [0, 1].

    Returns (gx, gy, prob) with prob[j, i] at (gx[i], gy[j]), and the bandwidth.
    The 0.5 level of prob is the estimated boundary of the safe region; when
    other inputs vary too, it is the boundary of the probability averaged over them.

    The Gaussian kernel of the plane is the product of one per axis,
    exp(-(dx^2 + dy^2) / 2h^2) = exp(-dx^2 / 2h^2) exp(-dy^2 / 2h^2), so the
    sums over the cases at every grid point are two matrix products of the
    per-axis factors (n_grid x n each): 2 n_grid n exponentials, not
    n_grid^2 n (81 times fewer: 50 000 cases took 2.7 s per pair of inputs).
    The cases are taken in chunks of chunk_elements / n_grid, so the memory is
    about 2 x 8 x chunk_elements bytes whatever their number.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    passed = np.asarray(passed, dtype=bool)
    lo = np.array([x.min(), y.min()])
    hi = np.array([x.max(), y.max()])
    pts = np.stack([_normalise(x, lo[0], hi[0]), _normalise(y, lo[1], hi[1])], axis=1)
    h = bandwidth if bandwidth is not None else choose_bandwidth(pts, passed)
    u = np.linspace(0.0, 1.0, n_grid)
    yv = passed.astype(float)
    num = np.zeros((n_grid, n_grid))   # [j, i]: sum of kernel x pass at (u[i], u[j])
    den = np.zeros((n_grid, n_grid))   # [j, i]: sum of kernel
    step = max(1, int(chunk_elements) // n_grid)
    for start in range(0, len(pts), step):
        p = pts[start:start + step]
        kx = np.exp(-0.5 * (u[:, None] - p[None, :, 0]) ** 2 / h**2)   # [i, case]
        ky = np.exp(-0.5 * (u[:, None] - p[None, :, 1]) ** 2 / h**2)   # [j, case]
        num += (ky * yv[start:start + step]) @ kx.T
        den += ky @ kx.T
    prob = num / np.maximum(den, 1e-300)
    gx = lo[0] + u * (hi[0] - lo[0])
    gy = lo[1] + u * (hi[1] - lo[1])
    return gx, gy, prob, h


def worst_cases(env: xr.Dataset, k=10):
    """Case ids of the k cases with the smallest overall relative margin, worst
    first: the cases not computed first (by id), then the computed ones by
    relative margin (-inf: a metric NaN, the event never came), ties by id."""
    rel = env["relative_margin"].sel(criterion="all").values
    computed = env["status"].values == 0
    key = np.where(computed, rel, -np.inf)
    order = np.lexsort((env["case"].values, key, computed))
    return env["case"].values[order[:k]]


def worst_case_table(env: xr.Dataset, k=10) -> str:
    """The worst cases as a Markdown table: inputs, status, worst criterion, margins
    (each column says "margin": a touchdown column of 0.004 m s-1 is 0.004 m/s below
    the limit, not the speed)."""
    ids = worst_cases(env, k)
    inputs = env.attrs["inputs"].split()
    crit = [c for c in env["criterion"].values if c != "all"]
    units = dict(zip(env["criterion"].values, env["criterion_units"].values))
    head = ["case", "status"] + inputs + ["worst"] + [f"{c} margin [{units[c]}]" for c in crit]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    status_names = {0: "ok", 1: "failed", 2: "invalid input"}
    for cid in ids:
        row = env.sel(case=cid)
        cells = [str(int(cid)), status_names.get(int(row["status"]), "?")]
        cells += [f"{float(row[name]):.6g}" for name in inputs]
        cells.append(str(row["worst_criterion"].values) if int(row["status"]) == 0 else "-")
        cells += [_fmt(float(row["margin"].sel(criterion=c))) for c in crit]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _fmt(v):
    return "n/a" if math.isnan(v) else f"{v:.4g}"
