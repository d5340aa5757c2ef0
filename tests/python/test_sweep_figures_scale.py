"""The envelope figures of large sweeps stay legible.  At 20 000 cases the
pass/fail map's and the margins' markers, at their fixed sizes (9 and 6
points^2), covered their panels 2.8 and 4.4 times over: one solid colour that
hid the P(pass) shading, with the failures, drawn last, looking many times as
many as they were (docs/performance.md, "Sweeps at scale").  The markers now
shrink so that together they cover at most figures.MARKER_COVER of a panel
(sweeps of up to about 1900 cases keep their sizes, bit for bit), the legend
keeps full-size markers, and past LEGEND_BEST_MAX_CASES the legend goes to a
corner instead of matplotlib's search over every point (loc="best": 0.8 s a
panel at 50 000 cases)."""
import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import PathCollection  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
import xarray as xr  # noqa: E402

from test_sweep_support import ROOT  # noqa: E402,F401  (puts the repository on sys.path)

from postproc.sweep import figures  # noqa: E402
from postproc.sweep.criteria import parse_criteria  # noqa: E402
from postproc.sweep.envelope import evaluate  # noqa: E402

INPUTS = ["parachute%drag_area", "line_scene%a_mass"]


def line_envelope(n):
    """n cases of two inputs, the peak tension rising with the mass (a boundary
    across the map), judged by the airdrop's criteria (50 kN allowed)."""
    rng = np.random.default_rng(7)
    area, mass = rng.uniform(520.0, 640.0, n), rng.normal(1000.0, 50.0, n)
    ds = xr.Dataset({"parachute%drag_area": ("case", area, {"units": "m2"}),
                     "line_scene%a_mass": ("case", mass, {"units": "kg"}),
                     "status": ("case", np.zeros(n, dtype=np.int32)),
                     "peak_line_tension_N": ("case", 47e3 + 60.0 * (mass - 1050.0) + 5.0 * (area - 580.0))},
                    coords={"case": np.arange(n)})
    ds.attrs.update(inputs=" ".join(INPUTS), sweep_name="scale", scene="line")
    return evaluate(ds, parse_criteria((ROOT / "input" / "criteria_airdrop.nml").read_text()))


def covered(ax):
    """The area of the panel's markers (discs of pi/4 s points^2) over the axes' (both in points^2)."""
    fig = ax.figure
    box = ax.get_window_extent(fig.canvas.get_renderer())
    area = box.width * box.height * (72.0 / fig.dpi) ** 2
    return sum(math.pi / 4 * float(np.sum(np.broadcast_to(c.get_sizes(), (len(c.get_offsets()),))))
               for c in ax.collections if isinstance(c, PathCollection)) / area


def map_panel(env):
    fig = figures.passfail_figure(env)
    (ax,) = [a for a in fig.axes if a.get_legend() is not None]
    return fig, ax


def test_pass_fail_map_of_20000_cases_leaves_its_shading_visible():
    fig, ax = map_panel(line_envelope(20000))
    try:
        fig.canvas.draw()
        cover = covered(ax)
        legend = ax.get_legend()
        legend_sizes = [float(h.get_sizes()[0]) for h in legend.legend_handles]
        loc = legend._loc
    finally:
        plt.close(fig)
    # the sizes are chosen after the layout: the share holds to round-off
    assert cover <= figures.MARKER_COVER * (1 + 1e-9), f"the markers cover {cover:.2f} of the panel"
    assert cover >= 0.5 * figures.MARKER_COVER, f"the markers cover only {cover:.3f} of the panel"
    # the legend's markers at the full size, 9 points^2
    assert legend_sizes == [9.0, 9.0], legend_sizes
    assert loc == 1, f"legend location code {loc} (1: upper right; 0: matplotlib's search over 20 000 points)"


def test_margins_of_20000_cases_cover_at_most_their_share(monkeypatch):
    seen = {}

    def keep(self, *args, **kwargs):
        self.canvas.draw()
        seen["cover"] = [covered(ax) for ax in self.axes]

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", keep)
    figures.margins(line_envelope(20000), "unused.png")
    assert seen["cover"] and max(seen["cover"]) <= figures.MARKER_COVER * (1 + 1e-9), seen["cover"]


def test_small_sweeps_keep_their_marker_sizes_and_legend_search():
    fig, ax = map_panel(line_envelope(500))
    try:
        sizes = sorted({float(s) for c in ax.collections if isinstance(c, PathCollection) for s in c.get_sizes()})
        loc = ax.get_legend()._loc
    finally:
        plt.close(fig)
    assert sizes == [9.0], sizes
    assert loc == 0, f"legend location code {loc} (0: 'best')"
