"""plot_run's line figure shows the line's largest load, not only its end
tensions at the records. A winch-driven rope that goes slack and snatches
(60 m, EA 2 MN, 200 kg, the top moved 0.1 m at 1.5 Hz) had the peak segment
tension 59.0 kN at 1.141 s (the file's `peak_tension_N`, over every step),
inside the line and between two records, while the figure's end tensions
reached 24.2 kN: the figure showed less than half the snatch load.

The test draws a synthetic line file whose records are known exactly: the end
tensions stay at 1 kN, a middle segment carries 3 kN at one record, and the
attribute puts the peak at 5 kN between two records. The figure must reach
both (exact values: they are the data, drawn without arithmetic)."""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

from postproc.plot_run import plot_line  # noqa: E402


def line_file():
    t = np.linspace(0.0, 1.0, 11)
    n = 4
    x = np.linspace(0.0, 4.0, n + 1)
    pos = np.zeros((t.size, n + 1, 3))
    pos[:, :, 0] = x
    seg = np.full((t.size, n), 1000.0)
    seg[5, 2] = 3000.0                       # a load inside the line, at one record
    ends = seg[:, [0, n - 1]]
    ds = xr.Dataset({"line_node_position": (("time", "node", "xyz"), pos),
                     "line_tension": (("time", "segment"), seg),
                     "line_end_tension": (("time", "end"), ends),
                     "line_end_velocity": (("time", "end", "xyz"), np.zeros((t.size, 2, 3)))},
                    coords={"time": t})
    ds.attrs.update(scene="line", status="completed", peak_tension_N=5000.0, peak_tension_time_s=0.55)
    return ds


def drawn_points(ax):
    return np.concatenate([np.column_stack(line.get_data()) for line in ax.get_lines()])


def test_line_figure_shows_the_peak_and_the_largest_segment():
    fig = plt.figure()
    plot_line(line_file(), fig)
    ax = fig.axes[1]
    pts = drawn_points(ax)
    assert np.any((pts[:, 0] == 0.55) & (pts[:, 1] == 5000.0)), "the peak over every step is not drawn"
    assert np.any((pts[:, 0] == 0.5) & (pts[:, 1] == 3000.0)), "the largest segment tension is not drawn"
    assert ax.get_ylim()[1] >= 5000.0
    plt.close(fig)


def test_line_figure_without_a_peak_attribute():
    """`&line_scene peak_tension = .false.`: no attribute, no marker, the figure still drawn."""
    ds = line_file()
    del ds.attrs["peak_tension_N"], ds.attrs["peak_tension_time_s"]
    fig = plt.figure()
    plot_line(ds, fig)
    assert drawn_points(fig.axes[1])[:, 1].max() == 3000.0
    plt.close(fig)
