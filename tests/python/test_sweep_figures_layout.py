"""The envelope figures' titles stay clear of their panels.  A sweep of six
inputs draws a pass/fail map of 15 panels in 5 rows (five: 10 in 4): tight_layout alone kept
the figure's title (fig.suptitle) a top margin that does not grow with the
figure's height, and the first row's panel titles were drawn over it (found by
a first-time user's six-input sweep; the margins figure's top tick labels
touched it the same way)."""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
import xarray as xr  # noqa: E402

from test_sweep_support import ROOT  # noqa: E402,F401  (puts the repository on sys.path)

from postproc.sweep import figures  # noqa: E402
from postproc.sweep.criteria import parse_criteria  # noqa: E402
from postproc.sweep.envelope import evaluate  # noqa: E402

INPUTS = ["flight%mach", "flight%altitude", "rocket%mass", "rocket%cg_from_nose", "gust%vertical"]


def five_input_envelope(n=40):
    rng = np.random.default_rng(11)
    x = {name: rng.uniform(0, 1, n) for name in INPUTS}
    data = {name: ("case", v, {"units": "1"}) for name, v in x.items()}
    data["status"] = ("case", np.zeros(n, dtype=np.int32))
    # passes where the CG input is large: a boundary in every pair with it
    data["min_clearance_m"] = ("case", 1.0 + 2.0 * (x["rocket%cg_from_nose"] - 0.5))
    data["min_line_clearance_m"] = ("case", 6.0 + x["flight%mach"])
    data["peak_line_tension_N"] = ("case", 1.2e5 + 1.0e4 * x["flight%altitude"])
    data["max_aircraft_pitch_excursion_deg"] = ("case", 1.0 + x["rocket%mass"])
    data["max_load_factor_excursion"] = ("case", 0.6 * x["gust%vertical"])
    data["pitch_max_deg"] = ("case", 60.0 + 30.0 * x["gust%vertical"])
    data["pitch_max_time_s"] = ("case", 9.0 + 4.0 * x["rocket%mass"])
    ds = xr.Dataset(data, coords={"case": np.arange(n)})
    ds.attrs.update(inputs=" ".join(INPUTS), sweep_name="layout")
    # the seven criteria of the paper's file: seven rows of margins
    return evaluate(ds, parse_criteria((ROOT / "input" / "criteria_paper.nml").read_text()))


def clearance_below_title(fig):
    """Pixels from the bottom of the figure's title down to the highest panel
    (its title, tick labels and colour bar included); < 0: they overlap."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    title = fig.get_suptitle()
    assert title, "the figure has a title"
    bottom = fig._suptitle.get_window_extent(renderer).y0
    return min(bottom - ax.get_tightbbox(renderer).y1 for ax in fig.axes if ax.get_visible() and ax.axison)


def captured(draw, env, monkeypatch):
    """The figure a drawer saves (it closes it afterwards)."""
    seen = {}

    def keep(self, *args, **kwargs):
        seen["gap"] = clearance_below_title(self)

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", keep)
    draw(env, "unused.png")
    return seen["gap"]


def test_pass_fail_map_of_five_inputs_keeps_its_title_clear():
    env = five_input_envelope()
    fig = figures.passfail_figure(env)
    try:
        assert len([ax for ax in fig.axes if ax.get_title()]) == 10
        gap = clearance_below_title(fig)
    finally:
        plt.close(fig)
    # > 0 px: nothing drawn under the title (it overlapped by about 5 px before the fix)
    assert gap > 0.0, f"the first row of panels reaches {-gap:.1f} px into the figure's title"


@pytest.mark.parametrize("name", ["margins"])
def test_tall_figures_keep_their_title_clear(name, monkeypatch):
    env = five_input_envelope()
    gap = captured(getattr(figures, name), env, monkeypatch)
    assert gap > 0.0, f"{name}: the first row of panels reaches {-gap:.1f} px into the figure's title"


def test_worst_case_table_headings_fit_their_columns(monkeypatch):
    """Each heading of worst_cases.png lies within its cell: the columns share
    the figure's width equally, and a margin's heading on one line
    ("aircraft_pitch margin [degree]") ran over its neighbours' by ~9 px."""
    env = five_input_envelope()
    over = {}

    def keep(self, *args, **kwargs):
        self.canvas.draw()
        renderer = self.canvas.get_renderer()
        (table,) = self.axes[0].tables
        for (row, col), cell in table.get_celld().items():
            box = cell.get_window_extent(renderer)
            text = cell.get_text().get_window_extent(renderer)
            if text.width > box.width or text.height > box.height:
                over[cell.get_text().get_text()] = (text.width - box.width, text.height - box.height)

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", keep)
    figures.worst_table(env, "unused.png", None)
    assert over == {}, f"text wider or taller than its cell (excess in px): {over}"


@pytest.mark.parametrize("n_inputs", [1, 2])
def test_narrow_margins_figure_keeps_its_title_inside(n_inputs, monkeypatch):
    """margins.png is 3.6 in wide per input: its one-line title (~10 in at
    the default size) was cut off at both sides for one or two inputs.  The
    title now breaks into lines: it lies within the figure's width, and
    still clear of the panels."""
    env = five_input_envelope()
    env.attrs["inputs"] = " ".join(INPUTS[:n_inputs])
    seen = {}

    def keep(self, *args, **kwargs):
        seen["gap"] = clearance_below_title(self)
        box = self._suptitle.get_window_extent(self.canvas.get_renderer())
        seen["left"], seen["right"] = box.x0, self.bbox.width - box.x1

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", keep)
    figures.margins(env, "unused.png")
    assert seen["left"] >= 0.0 and seen["right"] >= 0.0, f"the title runs {seen} px past the figure's sides"
    assert seen["gap"] > 0.0
