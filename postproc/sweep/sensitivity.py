"""Which varied inputs drive each criterion: rank correlations of the margins.

For every criterion (and ``all``, by its smallest relative margin) and every
varied input, over the cases that computed (status 0):

- ``spearman``: Spearman's rank correlation of the margin with the input;
- ``prcc``: the partial rank correlation coefficient (PRCC): the correlation of
  the margin's ranks with the input's ranks once both are freed, by linear least
  squares, of the ranks of every other varied input (Iman & Conover 1980;
  Marino et al. 2008, J. Theor. Biol. 254:178).  It measures a monotone effect
  of the input with the others held fixed, and is unchanged by any strictly
  increasing transform of an input or of the margin.
- ``prcc_low``, ``prcc_high``: the PRCC's 95 % interval by Fisher's z with
  Bonett & Wright's variance for rank correlations (2000, Psychometrika 65:23):
  SE(atanh r) = sqrt((1 + r^2/2) / (n - 3 - p)), p = the number of inputs held
  fixed.  Measured coverage (tests/python/test_sweep_sensitivity.py,
  docs/sweep.md): 94-97 % for |PRCC| up to 0.9, about 90 % at 0.96.
- ``srrc`` and ``rank_r2``: the standardised coefficients of the margin's
  rank regression on the inputs' ranks, and its R^2: how much each input
  matters.  (The PRCC measures how cleanly an input acts once the others are
  fixed, not how much: a deterministic simulator's margins are nearly exact
  monotone functions of the inputs, so every input that acts at all has a
  PRCC near +-1; the SRRC ranks them.)

A computed case whose margin is NaN (the event never came: no separation, no
pitch maximum) fails its criterion; it ranks below every finite margin, as in
the envelope's ``all``.  Cases that did not compute carry no information about
the physics and are left out (``sensitivity_cases`` counts the cases used).
Where the margin or an input does not vary over those cases, or there are too
few of them (fewer than the inputs + 2; for the interval, the inputs + 3), the
values are NaN.
"""
from __future__ import annotations

import numpy as np
import scipy.stats as st
import xarray as xr

Z95 = st.norm.ppf(0.975)


def _ranks(values: np.ndarray) -> np.ndarray:
    """Ranks with ties averaged; NaN ranks below everything (-inf)."""
    v = np.where(np.isnan(values), -np.inf, values)
    return st.rankdata(v, method="average")


def _correlation(a: np.ndarray, b: np.ndarray) -> float:
    a = a - a.mean()
    b = b - b.mean()
    denom = np.sqrt((a @ a) * (b @ b))
    if denom == 0.0:   # one of them does not vary
        return np.nan
    return float(np.clip((a @ b) / denom, -1.0, 1.0))


def _residual(y: np.ndarray, basis: np.ndarray) -> np.ndarray:
    """y less its least-squares fit on the columns of basis (LAPACK gelsd);
    exactly zero where the fit leaves only rounding (y is a linear function of
    the basis: nothing is left to correlate)."""
    spread = np.linalg.norm(y - y.mean())
    coef, *_ = np.linalg.lstsq(basis, y, rcond=None)
    r = y - basis @ coef
    if spread == 0.0 or np.linalg.norm(r) <= 1e-9 * spread:
        return np.zeros_like(r)
    return r


def _rank_columns(x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    return np.column_stack([_ranks(x[:, j]) for j in range(x.shape[1])])


def _basis_without(rx: np.ndarray, j: int) -> np.ndarray:
    """A constant and every rank column but column j."""
    return np.hstack([np.ones((rx.shape[0], 1)), np.delete(rx, j, axis=1)])


def rank_correlations(x: np.ndarray, y: np.ndarray):
    """Spearman and partial rank correlations of y with each column of x.

    x: (n, k) inputs; y: (n,) response (NaN ranks lowest).  Returns
    (spearman, prcc), each of length k."""
    rx = _rank_columns(x)
    ry = _ranks(np.asarray(y, dtype=float))
    k = rx.shape[1]
    spearman = np.array([_correlation(rx[:, j], ry) for j in range(k)])
    prcc = np.empty(k)
    for j in range(k):
        basis = _basis_without(rx, j)
        prcc[j] = _correlation(_residual(rx[:, j], basis), _residual(ry, basis))
    return spearman, prcc


def rank_regression(x: np.ndarray, y: np.ndarray):
    """Standardised rank regression coefficients of y on the columns of x, and
    the regression's R^2 (Saltelli et al. 2008, Global Sensitivity Analysis,
    §1.2.5).  With independent inputs SRRC_j^2 is the share of the response's
    rank variance that input j explains and their sum is R^2; a small R^2 says
    that no monotone, additive model explains the response (interactions or
    non-monotone effects).  Returns (srrc of length k, r2); NaN where y or an
    input does not vary, and for an input whose ranks are a linear combination
    of the others' (two inputs that move together over the cases): the fit
    cannot tell their shares apart, and least squares would return an
    arbitrary split of their sum (even of the wrong sign).  R^2 stays."""
    rx = _rank_columns(x)
    ry = _ranks(np.asarray(y, dtype=float))
    n, k = rx.shape
    sx, sy = rx.std(axis=0), ry.std()
    if sy == 0.0 or np.any(sx == 0.0):
        return np.full(k, np.nan), np.nan
    basis = np.hstack([np.ones((n, 1)), rx])
    coef, *_ = np.linalg.lstsq(basis, ry, rcond=None)
    residual = ry - basis @ coef
    r2 = 1.0 - (residual @ residual) / (n * sy**2)
    srrc = coef[1:] * sx / sy
    for j in range(k):
        # identifiable only if some of its ranks' variation is its own
        if not np.any(_residual(rx[:, j], _basis_without(rx, j))):
            srrc[j] = np.nan
    return srrc, float(r2)


def fisher_interval(r, n: int, p: int, z=Z95):
    """95 % interval of a (partial) rank correlation r from n cases with p
    variables held fixed (Fisher's z, Bonett & Wright's variance
    (1 + r^2/2) / (n - 3 - p)); NaN where n - 3 - p < 1."""
    r = np.asarray(r, dtype=float)
    dof = n - 3 - p
    if dof < 1:
        nan = np.full(r.shape, np.nan)
        return nan, nan.copy()
    half = z * np.sqrt((1.0 + r**2 / 2.0) / dof)
    with np.errstate(divide="ignore"):
        centre = np.arctanh(r)
    return np.tanh(centre - half), np.tanh(centre + half)


def sensitivity(env: xr.Dataset) -> xr.Dataset:
    """The rank sensitivities of every criterion's margin to every input, as
    variables over (criterion, input) to add to the envelope."""
    inputs = env.attrs["inputs"].split()
    criteria = [str(c) for c in env["criterion"].values]
    ok = env["status"].values == 0
    x = np.column_stack([np.asarray(env[name].values, dtype=float)[ok] for name in inputs])
    n = int(ok.sum())
    # an input constant over the computed cases (e.g. its other values all
    # invalid input) explains nothing: left out, its values NaN, the others kept
    varies = np.array([n > 0 and np.ptp(x[:, j]) > 0 for j in range(len(inputs))], dtype=bool)
    k = int(varies.sum())
    shape = (len(criteria), len(inputs))
    spearman, prcc, srrc = np.full(shape, np.nan), np.full(shape, np.nan), np.full(shape, np.nan)
    r2 = np.full(len(criteria), np.nan)
    for i, c in enumerate(criteria):
        # 'all': the smallest relative margin (-inf where a metric is NaN); the others: the margin
        var = "relative_margin" if c == "all" else "margin"
        y = np.asarray(env[var].sel(criterion=c).values, dtype=float)[ok]
        if _constant_to_roundoff(y):
            continue   # ranks of round-off would call noise a driver
        if k >= 1 and n >= k + 2:   # the regressions need a residual degree of freedom
            spearman[i, varies], prcc[i, varies] = rank_correlations(x[:, varies], y)
            srrc[i, varies], r2[i] = rank_regression(x[:, varies], y)
    low, high = fisher_interval(prcc, n, k - 1)
    ds = xr.Dataset(coords={"criterion": env["criterion"],
                            "input": ("input", np.array(inputs), {"long_name": "varied input (group%variable)"})})
    ds["spearman"] = (("criterion", "input"), spearman,
                      {"long_name": "Spearman rank correlation of the margin with the input (cases computed; "
                                    "'all': the smallest relative margin)", "units": "1"})
    ds["prcc"] = (("criterion", "input"), prcc,
                  {"long_name": "partial rank correlation of the margin with the input, the other inputs' "
                                "ranks held fixed (> 0: a larger input gives a larger margin)", "units": "1"})
    ds["prcc_low"] = (("criterion", "input"), low,
                      {"long_name": "95% interval of prcc, low (Fisher z, variance (1+r^2/2)/(n-3-p))", "units": "1"})
    ds["prcc_high"] = (("criterion", "input"), high,
                       {"long_name": "95% interval of prcc, high (Fisher z, variance (1+r^2/2)/(n-3-p))", "units": "1"})
    ds["srrc"] = (("criterion", "input"), srrc,
                  {"long_name": "standardised rank regression coefficient of the margin on the inputs (its square: "
                                "the input's share of the margin's rank variance, inputs independent)", "units": "1"})
    ds["rank_r2"] = (("criterion",), r2,
                     {"long_name": "R^2 of the margin's rank regression on the inputs' ranks (small: interactions or "
                                   "non-monotone effects that the coefficients do not describe)", "units": "1"})
    ds["sensitivity_cases"] = (("criterion",), np.full(len(criteria), n, dtype=np.int32),
                               {"long_name": "cases used by the rank correlations (those computed)", "units": "1"})
    return ds


#: A margin whose values differ by no more than this fraction of its size does
#: not vary: the differences are round-off and solver noise (far below any
#: sweep's tolerance), and their ranks would make any input look like a driver.
ROUNDOFF = 1e-9


def _constant_to_roundoff(y: np.ndarray) -> bool:
    """All finite and within ROUNDOFF of each other, relative to their size."""
    return bool(y.size and np.all(np.isfinite(y)) and np.ptp(y) <= ROUNDOFF * np.max(np.abs(y)))


def significant(env: xr.Dataset, criterion) -> np.ndarray:
    """Per input: the partial rank correlation's 95 % interval excludes 0."""
    low = env["prcc_low"].sel(criterion=criterion).values
    high = env["prcc_high"].sel(criterion=criterion).values
    return (low > 0) | (high < 0)


def by_importance(env: xr.Dataset, criterion) -> np.ndarray:
    """Indices of the inputs by |SRRC|, largest first (NaN last)."""
    srrc = env["srrc"].sel(criterion=criterion).values
    return np.argsort(-np.nan_to_num(np.abs(srrc), nan=-1.0), kind="stable")


def _why_none(env: xr.Dataset, j: int) -> str:
    """Why input j has no coefficient: it is constant over the computed cases,
    or it moves with the other inputs there (rank_regression)."""
    ok = env["status"].values == 0
    values = np.asarray(env[str(env["input"].values[j])].values, dtype=float)[ok]
    if values.size and np.ptp(values) > 0:
        return "(moves with the other inputs over the computed cases: its share cannot be told apart)"
    return "(constant over the computed cases)"


DRIVERS_HEADING = ("drivers (standardised rank regression coefficient of each margin on the inputs, largest first: "
                   "its square is the input's share of the margin's rank variance; R^2 of that regression; "
                   "'not significant': the partial rank correlation's 95% interval holds 0)")


def drivers_table(env: xr.Dataset) -> str:
    """Per criterion, one line: 'criterion R^2 0.97: input -0.85, input +0.50,
    input +0.01 (not significant)' (the coefficients, largest first)."""
    lines = []
    for c in env["criterion"].values:
        srrc = env["srrc"].sel(criterion=c).values
        if np.isnan(float(env["rank_r2"].sel(criterion=c))):
            lines.append(f"  {str(c):16s} (none: the margin does not vary over the computed cases (beyond "
                         f"{ROUNDOFF:.0e} of its size), or they are too few)")
            continue
        sig = significant(env, c)
        cells = [f"{env['input'].values[j]!s} " + (_why_none(env, j) if np.isnan(srrc[j]) else
                                                   f"{srrc[j]:+.2f}" + ("" if sig[j] else " (not significant)"))
                 for j in by_importance(env, c)]
        r2 = float(env["rank_r2"].sel(criterion=c))
        lines.append(f"  {str(c):16s} R^2 {r2:.2f}: " + ", ".join(cells))
    return "\n".join(lines) + "\n"
