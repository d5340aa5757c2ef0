"""plot_run.py's 3-D track shows the model's right-handed frame (x forward,
y up, z right; model.md "Frames") as a right-handed frame, so a lateral drift
to the right is drawn on the right.

Independent reference: matplotlib's own 3-D axes with increasing limits draw
its (X, Y, Z) right-handed. The orientation of a drawn triad is the sign of
the determinant of the projection's Jacobian (view coordinates, depth
included) on the triad's unit vectors; the model's (x, y, z) on plot_run's
axes must have the sign of matplotlib's (X, Y, Z) on a default axes. Before the
thirty-fourth session the track plotted (x, z, y) on increasing limits: the
opposite sign (mirrored).
"""
import importlib.util

import matplotlib
import numpy as np
import xarray as xr

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from mpl_toolkits.mplot3d import proj3d  # noqa: E402

from conftest import ROOT


def _plot_run():
    spec = importlib.util.spec_from_file_location("plot_run", ROOT / "postproc" / "plot_run.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _orientation(ax, columns):
    """Sign of det of the projection's Jacobian at the axes' centre on the
    given data-space directions (one per column)."""
    fig = ax.figure
    fig.canvas.draw()
    m = ax.get_proj()
    c = np.array([np.mean(ax.get_xlim3d()), np.mean(ax.get_ylim3d()), np.mean(ax.get_zlim3d())])
    spans = np.array([np.ptp(ax.get_xlim3d()), np.ptp(ax.get_ylim3d()), np.ptp(ax.get_zlim3d())])
    p0 = np.array(proj3d.proj_transform(*c, m))
    jac = []
    for d in columns:
        step = 1e-4 * spans * np.asarray(d, float)
        jac.append((np.array(proj3d.proj_transform(*(c + step), m)) - p0) / 1e-4)
    return np.sign(np.linalg.det(np.array(jac).T))


def test_the_3d_track_is_right_handed():
    plot_run = _plot_run()
    t = np.linspace(0.0, 1.0, 5)
    pos = np.stack([100 * t, 1000 - 10 * t, 20 * t], axis=1)       # forward, down, drifting right
    ds = xr.Dataset({"rocket_euler_deg": (("time", "angle"), np.zeros((5, 3))),
                     "rocket_pitch_rate_deg_s": ("time", np.zeros(5)),
                     "aircraft_position": (("time", "xyz"), pos),
                     "rocket_position": (("time", "xyz"), pos)},
                    coords={"time": t, "angle": [0, 1, 2], "xyz": [0, 1, 2]})
    fig = plt.figure(figsize=(12, 4))
    plot_run.plot_airlaunch(ds, fig)
    track = [a for a in fig.axes if a.name == "3d"][0]
    # the model's x, y (up), z (right) in the plot's data space (X = x, Y = z, Z = y)
    model = _orientation(track, [(1, 0, 0), (0, 0, 1), (0, 1, 0)])
    ref_fig = plt.figure()
    ref = ref_fig.add_subplot(projection="3d")
    ref.set_xlim(0, 1), ref.set_ylim(0, 1), ref.set_zlim(0, 1)
    right_handed = _orientation(ref, [(1, 0, 0), (0, 1, 0), (0, 0, 1)])
    plt.close(fig), plt.close(ref_fig)
    assert right_handed != 0 and model == right_handed
