"""plot_run's figures are readable without the code: every panel has a title and
both axes a quantity with its unit ("time [s]", "x forward [m]"; a bare "[m/s]" or
no label at all is not enough), the line ends are named by their kind, the
rocket's first pitch maximum (a milestone) is marked where the file puts it, and
the figure's foot states the frame convention and the code version the file
records (before the thirty-fifth session the pitch panel had no y label, the
speeds panel a unit without a quantity, the ends were "end a" and "end b", the
pitch maximum was not marked and the figure had no foot).

Independent reference: the synthetic files' own attributes and the label rule
above, checked on the drawn matplotlib objects."""
import re

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

from postproc import plot_run  # noqa: E402
from postproc.plot_run import plot_airlaunch, plot_line  # noqa: E402

LABEL = re.compile(r"[A-Za-z].*\[[^\]]+\]")     # a quantity, then its unit in brackets
FRAMES = "earth: x forward, y up, z right"


def airlaunch_file():
    t = np.linspace(0.0, 12.0, 61)
    pos = np.stack([200 * t, 10000 - t ** 2, 0 * t], axis=1)
    pitch = np.stack([0 * t, 90 * np.sin(np.pi * t / 24), 0 * t], axis=1)
    ds = xr.Dataset({"rocket_euler_deg": (("time", "angle"), pitch),
                     "rocket_pitch_rate_deg_s": ("time", np.gradient(pitch[:, 1], t)),
                     "aircraft_position": (("time", "xyz"), pos + [0, 5, 0]),
                     "rocket_position": (("time", "xyz"), pos),
                     "parachute_position": (("time", "xyz"), pos - [50, 0, 0])},
                    coords={"time": t, "angle": [0, 1, 2], "xyz": [0, 1, 2]})
    ds.attrs.update(scene="airlaunch", status="completed", title="synthetic", frames=FRAMES + "; body ...",
                    code_version="airlaunch 9.9.9 (abcdef0)", pitch_max_time_s=11.97, pitch_max_deg=89.5,
                    release_time_s=0.7, edge_time_s=3.0, separation_time_s=3.9)
    return ds


def line_file():
    t = np.linspace(0.0, 1.0, 11)
    pos = np.zeros((t.size, 5, 3))
    pos[:, :, 1] = -np.linspace(0.0, 4.0, 5)
    ds = xr.Dataset({"line_node_position": (("time", "node", "xyz"), pos),
                     "line_tension": (("time", "segment"), np.ones((t.size, 4))),
                     "line_end_tension": (("time", "end"), np.ones((t.size, 2))),
                     "line_end_velocity": (("time", "end", "xyz"), np.zeros((t.size, 2, 3)))},
                    coords={"time": t})
    ds.attrs.update(scene="line", status="completed", title="synthetic line", frames=FRAMES,
                    code_version="airlaunch 9.9.9 (abcdef0)",
                    input_namelist="&LINE_SCENE A_KIND=\"fixed\", B_KIND=\"canopy\", /")
    return ds


def check_panels(fig):
    for ax in fig.axes:
        labels = [ax.get_xlabel(), ax.get_ylabel()] + ([ax.get_zlabel()] if ax.name == "3d" else [])
        assert ax.get_title(), f"a panel without a title (labels {labels})"
        for label in labels:
            assert LABEL.match(label), f"panel '{ax.get_title()}': axis label {label!r} lacks a quantity or a unit"


def test_airlaunch_panels_are_labelled_and_the_pitch_maximum_marked():
    fig = plt.figure(figsize=(16, 5))
    plot_airlaunch(airlaunch_file(), fig)
    check_panels(fig)
    pitch = fig.axes[0]
    marks = [np.column_stack(line.get_data()) for line in pitch.get_lines() if line.get_marker() == "v"]
    assert marks and np.any((marks[0][:, 0] == 11.97) & (marks[0][:, 1] == 89.5)), "first pitch maximum not marked"
    assert any("forward" in ax.get_xlabel() for ax in fig.axes[1:]), "no track names the x direction"
    plt.close(fig)


def test_line_panels_are_labelled_and_the_ends_named():
    fig = plt.figure(figsize=(16, 5))
    plot_line(line_file(), fig)
    check_panels(fig)
    legend = [t.get_text() for t in fig.axes[1].get_legend().get_texts()]
    assert "end a (fixed)" in legend and "end b (canopy)" in legend, legend
    plt.close(fig)


def test_the_figure_foot_names_the_frames_and_the_code(tmp_path, monkeypatch):
    """Through main(), which draws the foot: the texts of the figure it would save."""
    texts = []
    monkeypatch.setattr(plot_run, "save_figure", lambda fig, out: texts.extend(t.get_text() for t in fig.texts) or 0)
    for name, ds in (("a.nc", airlaunch_file()), ("l.nc", line_file())):
        path = tmp_path / name
        ds.to_netcdf(path)
        texts.clear()
        assert plot_run.main(["plot_run.py", str(path), str(path.with_suffix(".png"))]) == 0
        assert any(FRAMES in t and "airlaunch 9.9.9 (abcdef0)" in t for t in texts), texts
