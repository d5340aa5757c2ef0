"""The work-precision figures' legends are legible and hide no data (figure
review, thirty-fifth session: the legends were set in 6 pt type, too small to
read, and inside the axes).  Each figure is drawn from synthetic runs (the
benchmarks' own drawing functions, no benchmark run): every legend's type is at
least 8 pt, and no legend's box meets its axes' box (so it covers no curve; the
check is on the drawn pixels' boxes, exact, no tolerance), and the saved image
is saved with bbox_inches="tight", whose box holds the legend."""
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pytest  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "postproc"))
import bench_workprecision  # noqa: E402
import bench_workprecision_pendulum  # noqa: E402


def paper_rows():
    rows = []
    for c in ("direct", "rigidized", "paper"):
        for n in (15, 30, 60, 120, 240):
            for k, rtol in enumerate((1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8)):
                rows.append({"coupling": c, "n": n, "rtol": rtol, "wall": 0.01 * n ** 0.5 * 2 ** k,
                             "error": 1e-2 / (n * 4 ** k)})
    return rows


def pendulum_rows():
    rows = []
    for case in ("undamped", "material"):
        for n in (15, 60, 240):
            for k, rtol in enumerate((1e-3, 1e-4, 1e-5, 1e-6)):
                rows.append({"case": case, "scheme": "cvode", "n": n, "rtol": rtol, "dt": None,
                             "wall": 0.01 * n * 2 ** k, "error_m": 1e-2 / (n * 3 ** k)})
                rows.append({"case": case, "scheme": "marching", "n": n, "rtol": None, "dt": 1e-4 / 2 ** k,
                             "wall": 0.05 * n * 2 ** k, "error_m": 1e-2 / (n * 2 ** k)})
    return rows


def drawn_legends(monkeypatch, draw):
    """Draw with `draw(path)`, keeping each legend's font size and whether its
    box meets its axes' box, and the tight box the figure was saved with."""
    seen = {}

    def keep(fig, path, **kw):
        renderer = fig.canvas.get_renderer()
        fig.canvas.draw()
        seen["legends"] = [(min(t.get_fontsize() for t in ax.get_legend().get_texts()),
                            ax.get_legend().get_window_extent(renderer).overlaps(ax.get_window_extent(renderer)),
                            ax.get_legend().get_window_extent(renderer).transformed(fig.dpi_scale_trans.inverted()),
                            fig.get_tightbbox(renderer), kw.get("bbox_inches"))
                           for ax in fig.axes if ax.get_legend() is not None]
        # not written: the PNG encoding is most of the drawing's time, and the figure is checked above

    monkeypatch.setattr(plt.Figure, "savefig", keep)
    draw()
    return seen["legends"]


@pytest.mark.parametrize("which", ["paper", "pendulum"])
def test_work_precision_legends_are_legible_and_outside_the_data(which, tmp_path, monkeypatch):
    path = tmp_path / f"{which}.png"
    if which == "paper":
        rows = paper_rows()
        legends = drawn_legends(monkeypatch, lambda: bench_workprecision.draw(
            rows, ["direct", "rigidized", "paper"], [15, 30, 60, 120, 240], rows[14], path))
    else:
        legends = drawn_legends(monkeypatch, lambda: bench_workprecision_pendulum.figure(pendulum_rows(), path))
    assert len(legends) == (1 if which == "paper" else 2)
    for size, meets_axes, box, tight, bbox_inches in legends:
        assert size >= 8, f"legend type {size} pt"
        assert not meets_axes, "the legend lies over the axes (over the curves)"
        # saved with bbox_inches="tight", whose box (inches) holds the whole legend
        assert bbox_inches == "tight"
        assert tight.x0 <= box.x0 and box.x1 <= tight.x1 and tight.y0 <= box.y0 and box.y1 <= tight.y1, (box, tight)
