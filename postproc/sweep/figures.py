"""Figures of a separation safety envelope (matplotlib, Agg backend):

- ``passfail_map.png``: for every pair of varied inputs, the cases (pass / fail /
  not computed), the estimated probability of passing every criterion and its
  0.5 level, the boundary of the safe region;
- ``margins.png``: each criterion's margin against each input;
- ``probability.png``: probability of success per criterion with 95 % intervals;
- ``worst_cases.png`` (and ``worst_cases.md``): the table of the worst cases;
- ``sensitivity.png``: which inputs drive each criterion (standardised rank
  regression coefficients of the margins; sensitivity.py).
"""
from __future__ import annotations

import itertools
import math
import pathlib
import textwrap

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import PathCollection  # noqa: E402

from .envelope import envelope_name, pass_probability_map, worst_case_table  # noqa: E402
from .sensitivity import by_importance, significant  # noqa: E402
from .files import write_atomic  # noqa: E402
from .labels import input_label, margin_label  # noqa: E402
from .stamp import FIGURE_FILES  # noqa: E402

PASS_COLOUR, FAIL_COLOUR, NC_COLOUR = "#2a9d3a", "#d62728", "0.3"

#: Largest fraction of a panel that its markers may cover together (discs of
#: area pi/4 s): past it the points merge into one colour (20 000 cases hid the
#: P(pass) shading, and the failures, drawn last, looked many times as many as
#: they were).  Smaller sweeps keep the markers' own sizes.
MARKER_COVER = 0.3
#: The smallest marker size (points^2): still a dot at 110 dpi.
MIN_MARKER_SIZE = 0.25
#: Up to this many cases in a panel its legend goes where it hides the fewest
#: (matplotlib's loc="best": a search over every point, 0.8 s a panel at 50 000
#: cases); with more it goes to the upper right corner.
LEGEND_BEST_MAX_CASES = 5000


def fit_markers(fig):
    """After the layout: shrink each panel's scatter markers (by one factor)
    so that together, as discs of area pi/4 s, they cover at most
    MARKER_COVER of the panel, none below MIN_MARKER_SIZE.  The legends keep
    the markers' full sizes (their handles were made before)."""
    width, height = fig.get_size_inches() * 72.0
    for ax in fig.axes:
        dots = [c for c in ax.collections if isinstance(c, PathCollection) and len(c.get_offsets())]
        if not dots:
            continue
        pos = ax.get_position()
        area = pos.width * width * pos.height * height
        sizes = [np.broadcast_to(c.get_sizes(), (len(c.get_offsets()),)) for c in dots]
        total = math.pi / 4.0 * sum(float(np.sum(v)) for v in sizes)
        smallest = min(float(np.min(v)) for v in sizes)
        scale = min(1.0, max(MIN_MARKER_SIZE / smallest, MARKER_COVER * area / total))
        if scale < 1.0:
            for c in dots:
                c.set_sizes(c.get_sizes() * scale)


def case_legend(ax, n):
    """The panel's legend, placed by matplotlib's search up to
    LEGEND_BEST_MAX_CASES cases, else in the upper right corner."""
    ax.legend(fontsize=7, loc="best" if n <= LEGEND_BEST_MAX_CASES else "upper right")


def _label(env, name):
    """A varied input's axis label: its readable name and the unit docs/input.md
    gives it (labels.py); an input the table lacks keeps its raw name and the
    units its &input declared."""
    return input_label(name, env[name].attrs.get("units", "1"))


def _padded(v, frac=0.03):
    lo, hi = float(np.min(v)), float(np.max(v))
    pad = frac * (hi - lo) if hi > lo else 0.5
    return lo - pad, hi + pad


def fitted_suptitle(fig, text, **kwargs):
    """fig.suptitle(text), its lines broken at spaces where the figure is too
    narrow for them (a margins figure of one or two inputs is 3.6 or 7.2 in
    wide: its one-line title was cut off at both sides)."""
    title = fig.suptitle(text, **kwargs)
    renderer = fig.canvas.get_renderer()
    room = 0.96 * fig.bbox.width
    longest = max(len(line) for line in text.split("\n"))
    chars = longest
    while title.get_window_extent(renderer).width > room and chars > 12:
        chars = int(0.9 * chars)
        title.set_text("\n".join(textwrap.fill(line, chars) for line in text.split("\n")))
    return title


def title_over_panels(fig, text, **kwargs):
    """The figure's title (fitted_suptitle) and a tight_layout with every panel
    (its title and tick labels included) below it.  tight_layout alone leaves
    the suptitle a top margin that does not grow with the figure's height: on a
    tall figure (a pass/fail map of 5 or more inputs, 10 or more panels) the
    first row's titles ran into it."""
    title = fitted_suptitle(fig, text, **kwargs)
    renderer = fig.canvas.get_renderer()   # the title stands where it is, whatever the panels' layout
    gap = 6.0 * fig.dpi / 72.0   # 6 points between the title and the panels
    top = (title.get_window_extent(renderer).y0 - gap) / fig.bbox.height
    title.set_in_layout(False)
    fig.tight_layout(rect=(0.0, 0.0, 1.0, top))


def clear_boundary(prob, contrast=0.15):
    """A boundary is drawn only where the map goes from clearly failing to
    clearly passing (P below 0.5 - contrast and above 0.5 + contrast): a map
    that hovers around 0.5 (the pair does not decide) has no boundary to show."""
    return prob.min() < 0.5 - contrast and prob.max() > 0.5 + contrast


def passfail_map(env, path, criterion="all"):
    """Pass/fail map with the boundary of the safe region for every pair of inputs."""
    fig = passfail_figure(env, criterion)
    try:
        fig.savefig(path, dpi=110, format="png")
    finally:
        plt.close(fig)


def passfail_figure(env, criterion="all"):
    """The figure of passfail_map (the caller saves and closes it)."""
    inputs = env.attrs["inputs"].split()
    pairs = list(itertools.combinations(inputs, 2))
    ok = env["status"].values == 0
    passed = env["passed"].sel(criterion=criterion).values.astype(bool)
    if not pairs:
        pairs = [(inputs[0], None)]
    ncol = min(3, len(pairs))
    nrow = int(np.ceil(len(pairs) / ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(5.2 * ncol, 4.4 * nrow), squeeze=False)
    try:
        _draw_passfail(fig, axes, env, pairs, criterion, ok, passed)
    except BaseException:
        plt.close(fig)   # a figure that could not be drawn is not left open
        raise
    return fig


def _draw_passfail(fig, axes, env, pairs, criterion, ok, passed):
    """The panels of passfail_figure."""
    for ax, (a, b) in zip(axes.ravel(), pairs):
        x = env[a].values
        if b is None:   # one varied input: the cases along its axis
            ax.scatter(x[passed], np.zeros(passed.sum()), s=10, c=PASS_COLOUR, label="pass")
            ax.scatter(x[~passed & ok], np.zeros((~passed & ok).sum()), s=10, c=FAIL_COLOUR, label="fail")
            if (~ok).any():
                ax.scatter(x[~ok], np.zeros((~ok).sum()), s=22, c=NC_COLOUR, marker="x", label="not computed")
            ax.set_xlabel(_label(env, a))
            ax.set_xlim(*_padded(x))
            ax.set_yticks([])
            case_legend(ax, len(x))
            continue
        y = env[b].values
        if np.ptp(x) > 0 and np.ptp(y) > 0:
            gx, gy, prob, h = pass_probability_map(x, y, passed)
            levels = np.linspace(0, 1, 11)
            levels[-1] += 1e-9   # P = 1 exactly belongs to the top band
            cs = ax.contourf(gx, gy, np.clip(prob, 0, 1), levels=levels, cmap="RdYlGn", alpha=0.35)
            fig.colorbar(cs, ax=ax, label="P(pass)", ticks=np.linspace(0, 1, 6))
            if clear_boundary(prob):
                ax.contour(gx, gy, prob, levels=[0.5], colors="k", linewidths=1.6)
                ax.set_title(f"{criterion}: boundary P(pass) = 0.5 (kernel h = {h:.3f})", fontsize=9)
            else:
                ax.set_title(f"{criterion}: no boundary over this pair (P(pass) {prob.min():.2f}-{prob.max():.2f})",
                             fontsize=9)
        ax.scatter(x[passed], y[passed], s=9, c=PASS_COLOUR, edgecolors="none", label="pass")
        ax.scatter(x[~passed & ok], y[~passed & ok], s=9, c=FAIL_COLOUR, edgecolors="none", label="fail")
        if (~ok).any():
            ax.scatter(x[~ok], y[~ok], s=22, c=NC_COLOUR, marker="x", label="not computed")
        ax.set_xlabel(_label(env, a))
        ax.set_ylabel(_label(env, b))
        ax.set_xlim(*_padded(x))
        ax.set_ylim(*_padded(y))
        case_legend(ax, len(x))
    for ax in axes.ravel()[len(pairs):]:
        ax.axis("off")
    name = envelope_name(str(env.attrs.get("scene", "airlaunch")))
    title_over_panels(fig, f"{name} ({criterion}): {int(passed.sum())} of {passed.size} cases pass")
    fit_markers(fig)


def margins(env, path):
    """Margin of each criterion against each input (one panel per pair)."""
    inputs = env.attrs["inputs"].split()
    crit = [c for c in env["criterion"].values if c != "all"]
    units = dict(zip(env["criterion"].values, env["criterion_units"].values))
    fig, axes = plt.subplots(len(crit), len(inputs), figsize=(3.6 * len(inputs), 2.6 * len(crit)),
                             squeeze=False, sharex="col")
    try:
        for i, c in enumerate(crit):
            m = env["margin"].sel(criterion=c).values
            p = env["passed"].sel(criterion=c).values.astype(bool)
            for j, name in enumerate(inputs):
                ax = axes[i, j]
                x = env[name].values
                ax.scatter(x[p], m[p], s=6, c=PASS_COLOUR, edgecolors="none")
                ax.scatter(x[~p], m[~p], s=6, c=FAIL_COLOUR, edgecolors="none")
                ax.axhline(0.0, color="k", lw=0.8)
                if j == 0:
                    ax.set_ylabel(margin_label(c, str(units[c])), fontsize=8)
                if i == len(crit) - 1:
                    ax.set_xlabel(_label(env, name), fontsize=8)
                ax.tick_params(labelsize=7)
        title_over_panels(fig, "margins against each input (>= 0 passes; cases not computed, or whose metric "
                               "is NaN, have no margin and are not drawn)")
        fit_markers(fig)
        fig.savefig(path, dpi=110, format="png")
    finally:
        plt.close(fig)   # also when drawing or writing fails


def probability(env, path):
    """Probability of success per criterion with 95 % Wilson intervals."""
    names = list(env["criterion"].values)
    p = env["probability"].values
    lo = env["wilson_low"].values
    hi = env["wilson_high"].values
    fig, ax = plt.subplots(figsize=(7, 0.5 * len(names) + 1.5))
    try:
        yy = np.arange(len(names))[::-1]
        ax.barh(yy, p, color=[PASS_COLOUR if n != "all" else "#1f77b4" for n in names], alpha=0.6)
        ax.errorbar(p, yy, xerr=[p - lo, hi - p], fmt="none", ecolor="k", capsize=4)
        for y_, p_, l_, h_ in zip(yy, p, lo, hi):
            ax.text(1.01, y_, f"{p_:.3f} [{l_:.3f}, {h_:.3f}]", va="center", fontsize=8)
        ax.set_yticks(yy)
        ax.set_yticklabels(names)
        ax.set_xlim(0, 1.35)
        ax.set_xlabel(f"probability of success (95% Wilson interval), n = {env.sizes['case']} cases")
        fig.tight_layout()
        fig.savefig(path, dpi=110, format="png")
    finally:
        plt.close(fig)   # also when drawing or writing fails


def sensitivity(env, path):
    """One panel per criterion: the standardised rank regression coefficient of
    its margin on each input (largest on top; its square is the input's share
    of the margin's rank variance), pale where the partial rank correlation's
    95 % interval holds 0; the rank regression's R^2 in the title."""
    crit = list(env["criterion"].values)
    inputs = [str(v) for v in env["input"].values]
    ncol = min(3, len(crit))
    nrow = int(np.ceil(len(crit) / ncol))
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.8 * ncol, (0.45 * len(inputs) + 1.6) * nrow), squeeze=False)
    try:
        for ax, c in zip(axes.ravel(), crit):
            srrc = env["srrc"].sel(criterion=c).values
            sig = significant(env, c)
            order = by_importance(env, c)[::-1]   # the largest drawn on top
            yy = np.arange(len(order))
            for y_, j in zip(yy, order):
                if np.isnan(srrc[j]):
                    ax.text(0.0, y_, "n/a", ha="center", va="center", fontsize=7)
                    continue
                ax.barh(y_, srrc[j], color=PASS_COLOUR if srrc[j] > 0 else FAIL_COLOUR, alpha=0.8 if sig[j] else 0.25)
                ax.text(srrc[j], y_, f" {srrc[j]:+.2f} ", ha="left" if srrc[j] >= 0 else "right", va="center",
                        fontsize=7)
            ax.axvline(0.0, color="k", lw=0.8)
            ax.set_yticks(yy)
            ax.set_yticklabels([_label(env, inputs[j]) if inputs[j] in env else input_label(inputs[j])
                                for j in order], fontsize=7)
            ax.set_xlim(-1.3, 1.3)
            ax.set_title(f"{c} (rank R$^2$ = {float(env['rank_r2'].sel(criterion=c)):.2f})", fontsize=9)
            ax.tick_params(axis="x", labelsize=7)
        for ax in axes.ravel()[len(crit):]:
            ax.axis("off")
        n = int(env["sensitivity_cases"].values[0])
        title_over_panels(fig, "drivers: standardised rank regression coefficient of each margin on each "
                               f"input ({n} computed cases)\n> 0: a larger input gives a larger margin; pale: not "
                               "significant (the partial rank correlation's 95 % interval holds 0)", fontsize=9)
        fig.savefig(path, dpi=110, format="png")
    finally:
        plt.close(fig)   # also when drawing or writing fails


def worst_table(env, path_png, path_md, k=10, text=None):
    """The worst cases as Markdown and as a picture of the table (`text`: the
    Markdown table if already made)."""
    if text is None:
        text = worst_case_table(env, k)
    if path_md is not None:
        pathlib.Path(path_md).write_text(text)
    rows = [line.strip("|").split("|") for line in text.strip().splitlines()]
    head, body = [c.strip() for c in rows[0]], [[c.strip() for c in r] for r in rows[2:]]
    fig, ax = plt.subplots(figsize=(min(2 + 1.3 * len(head), 24), 0.4 * len(body) + 1.2))
    try:
        ax.axis("off")
        if body:
            # a margin's heading on two lines ("aircraft_pitch" / "margin [degree]"): on one it
            # ran over its neighbours' (the columns share the figure's width equally)
            labels = [h.replace(" margin [", "\nmargin [") for h in head]
            table = ax.table(cellText=body, colLabels=labels, loc="center", cellLoc="center")
            table.auto_set_font_size(False)
            table.set_fontsize(7)
            table.scale(1, 1.3)
            for col in range(len(labels)):
                cell = table[0, col]
                cell.set_height(2 * cell.get_height())
        ax.set_title(f"the {len(body)} worst cases (smallest relative margin first)", fontsize=9)
        fig.tight_layout()
        fig.savefig(path_png, dpi=110, format="png")
    finally:
        plt.close(fig)   # also when drawing or writing fails
    return text


def _png(draw, *args):
    """A writer of write_atomic: draw(..., tmp) as PNG (tmp ends in .part, so
    matplotlib cannot tell the format from the name)."""
    def write(tmp):
        draw(*args, tmp)
    return write


def draw_all(env, figure_dir):
    """Every figure of the envelope into figure_dir; returns the paths.  Each
    is written under a temporary name ending in .part and renamed once whole."""
    d = pathlib.Path(figure_dir)
    d.mkdir(parents=True, exist_ok=True)
    paths = {key: d / name for key, name in FIGURE_FILES.items()}
    write_atomic(paths["passfail_map"], _png(passfail_map, env))
    write_atomic(paths["margins"], _png(margins, env))
    write_atomic(paths["probability"], _png(probability, env))
    text = worst_case_table(env, 10)
    write_atomic(paths["worst_cases_md"], lambda tmp: pathlib.Path(tmp).write_text(text))
    write_atomic(paths["worst_cases"], lambda tmp: worst_table(env, tmp, None, text=text))
    write_atomic(paths["sensitivity"], _png(sensitivity, env))
    return paths
