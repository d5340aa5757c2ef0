"""plot_run's line figure zooms on a sharp tension peak.  The heavy airdrop
(input/line_airdrop.nml) has its opening shock, 46.9 kN, 1.28 s into a 200 s
run: on the whole run's axis the spike was a line at the left edge, its shape
and value unreadable (figure review, thirty-fifth session).  A run whose peak is
sharp (its ±2 s are at most a fifth of the run, and it is at least twice the
median tension outside them) gets a panel of the records within 2 s of the
peak, labelled with the peak's value.

Synthetic files, whose values are the data: a 100 s run with a 10 kN steady
tension and a 47 kN spike at 1.3 s.  The zoom's x-range must contain the peak
time and its label must give the file's largest tension (the `peak_tension_N`
attribute, over every step, or the records' largest without it) to the label's
printed 4 significant digits (half a unit in the last digit: the tolerance).
A 1 s run (the fishhook's kind) keeps its figure without a zoom."""
import re

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

from postproc.plot_run import plot_line  # noqa: E402


def spike_file(t_end=100.0, dt=0.05):
    t = np.arange(0.0, t_end + dt / 2, dt)
    n = 4
    pos = np.zeros((t.size, n + 1, 3))
    pos[:, :, 0] = np.linspace(0.0, 20.0, n + 1)
    pos[:, :, 1] = -5.7 * t[:, None]
    seg = np.repeat((10e3 + 37e3 * np.exp(-((t - 1.3) / 0.3) ** 2))[:, None], n, axis=1)
    ds = xr.Dataset({"line_node_position": (("time", "node", "xyz"), pos),
                     "line_tension": (("time", "segment"), seg),
                     "line_end_tension": (("time", "end"), seg[:, [0, n - 1]]),
                     "line_end_velocity": (("time", "end", "xyz"), np.zeros((t.size, 2, 3)))},
                    coords={"time": t})
    ds.attrs.update(scene="line", status="completed", peak_tension_N=47012.3, peak_tension_time_s=1.2764)
    return ds


def zoom_of(ds):
    fig = plt.figure(figsize=(16, 5))
    try:
        plot_line(ds, fig)
        zooms = [ax for ax in fig.axes if ax.get_label() == "tension_peak_zoom"]
        if not zooms:
            return None
        (ax,) = zooms
        labels = [t.get_text() for t in ax.texts if t.get_gid() == "peak_label"]
        return ax.get_xlim(), labels
    finally:
        plt.close(fig)


def label_newtons(text):
    value, = re.findall(r"peak ([0-9.]+) kN", text)
    return 1e3 * float(value), len(value.replace(".", "").lstrip("0"))


def test_sharp_peak_gets_a_zoom_labelled_with_the_files_largest_tension():
    ds = spike_file()
    found = zoom_of(ds)
    assert found is not None, "no zoom on the peak"
    (x0, x1), labels = found
    assert x0 <= 1.2764 <= x1 and x1 - x0 <= 4.0 + 1e-12, (x0, x1)
    assert len(labels) == 1, labels
    value, digits = label_newtons(labels[0])
    assert digits == 4
    assert abs(value - 47012.3) <= 0.5 * 10.0 ** (np.floor(np.log10(47012.3)) - 3), (labels[0], value)


def test_without_the_attribute_the_label_is_the_records_largest():
    ds = spike_file()
    del ds.attrs["peak_tension_N"], ds.attrs["peak_tension_time_s"]
    largest = float(ds["line_tension"].max())
    t_largest = float(ds["time"][int(np.argmax(ds["line_tension"].max("segment").values))])
    (x0, x1), (label,) = zoom_of(ds)
    assert x0 <= t_largest <= x1
    value, _ = label_newtons(label)
    assert abs(value - largest) <= 0.5 * 10.0 ** (np.floor(np.log10(largest)) - 3), (label, largest)


def test_a_short_run_keeps_its_figure_without_a_zoom():
    assert zoom_of(spike_file(t_end=1.0, dt=0.005)) is None
