#!/usr/bin/env python3
"""Draw the figure of one airlaunch run: plot_run.py OUTPUT.nc [FIGURE.png].

The figure depends on the scene recorded in the file's `scene` attribute.
Scenes register a drawing function in PLOTTERS.
"""
import sys

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import xarray as xr  # noqa: E402


def plot_drop(ds, fig):
    pos = ds["store_position"]
    ax1 = fig.add_subplot(1, 2, 1)
    ax1.plot(pos.sel(xyz=0), pos.sel(xyz=1))
    ax1.set_xlabel("x forward [m]")
    ax1.set_ylabel("altitude y [m]")
    ax1.set_title("store track")
    ax1.grid(True)
    ax2 = fig.add_subplot(1, 2, 2)
    ax2.plot(ds["time"], ds["store_mach"])
    ax2.set_xlabel("time [s]")
    ax2.set_ylabel("Mach")
    ax2.set_title("store Mach number")
    ax2.grid(True)


def _phase_lines(ax, ds):
    for key, label in (("release_time_s", "release"), ("edge_time_s", "Case 1->2"),
                       ("separation_time_s", "separation")):
        t = float(ds.attrs.get(key, -1.0))
        if t >= 0:
            ax.axvline(t, color="0.5", ls="--", lw=0.8)
            ax.text(t, ax.get_ylim()[1], " " + label, rotation=90, va="top", fontsize=7, color="0.3")


def plot_airlaunch(ds, fig):
    """Analogues of the paper's Figs. 9-11: rocket pitch and pitch rate with the
    phase changes; 3-D track and 2-D (x-y) track of aircraft, rocket, parachute."""
    t = ds["time"]
    ax1 = fig.add_subplot(1, 3, 1)
    ax1.plot(t, ds["rocket_euler_deg"].sel(angle=1), label="Euler pitch [deg]")
    if "rocket_nose_elevation_deg" in ds:
        ax1.plot(t, ds["rocket_nose_elevation_deg"], ":", label="nose elevation [deg]")
    ax1.plot(t, ds["rocket_pitch_rate_deg_s"], label="pitch rate [deg/s]")
    ax1.set_xlabel("time [s]")
    ax1.set_title("rocket pitch (Fig. 9)")
    ax1.grid(True)
    ax1.legend(fontsize=7)
    _phase_lines(ax1, ds)
    ax2 = fig.add_subplot(1, 3, 2, projection="3d")
    for name, style in (("aircraft", "-"), ("rocket", "-"), ("parachute", "--")):
        if f"{name}_position" not in ds:      # no parachute without a line (&line enabled = .false.)
            continue
        p = ds[f"{name}_position"]
        ax2.plot(p.sel(xyz=0), p.sel(xyz=2), p.sel(xyz=1), style, label=name)
    ax2.set_xlabel("x [m]")
    ax2.set_ylabel("z [m]")
    ax2.set_zlabel("y [m]")
    ax2.set_title("3-D track (Fig. 10)")
    # equal-ish scaling of the lateral axis (the scenario is symmetric: z ~ 0)
    zr = max(1.0, float(abs(ds["rocket_position"].sel(xyz=2)).max()))
    ax2.set_ylim(-max(zr, 50.0), max(zr, 50.0))
    ax2.legend(fontsize=7)
    ax3 = fig.add_subplot(1, 3, 3)
    for name, style in (("aircraft", "-"), ("rocket", "-"), ("parachute", "--")):
        if f"{name}_position" not in ds:      # no parachute without a line (&line enabled = .false.)
            continue
        p = ds[f"{name}_position"]
        ax3.plot(p.sel(xyz=0), p.sel(xyz=1), style, label=name)
    ax3.set_xlabel("x [m]")
    ax3.set_ylabel("altitude y [m]")
    ax3.set_title("2-D track (Fig. 11)")
    ax3.grid(True)
    ax3.legend(fontsize=7)


def plot_line(ds, fig):
    """Standalone line: the line's shape at a few times and its end tensions."""
    pos = ds["line_node_position"]
    ax1 = fig.add_subplot(1, 2, 1)
    for k in np.linspace(0, ds.sizes["time"] - 1, 6).astype(int):
        p = pos.isel(time=k)
        ax1.plot(p.sel(xyz=0), p.sel(xyz=1), ".-", ms=2, label=f"t = {float(ds['time'][k]):.2f} s")
    ax1.set_xlabel("x [m]")
    ax1.set_ylabel("y [m]")
    ax1.set_title("line shape")
    ax1.axis("equal")
    ax1.grid(True)
    ax1.legend(fontsize=7)
    ax2 = fig.add_subplot(1, 2, 2)
    ten = ds["line_end_tension"]
    for k in range(ten.shape[-1]):
        ax2.plot(ds["time"], ten.isel({ten.dims[-1]: k}), label=f"end {'ab'[k] if k < 2 else k}")
    ax2.set_xlabel("time [s]")
    ax2.set_ylabel("end tension [N]")
    ax2.grid(True)
    ax2.legend(fontsize=7)


PLOTTERS = {"drop": plot_drop, "airlaunch": plot_airlaunch, "line": plot_line}


def main(argv):
    if len(argv) < 2:
        print(__doc__.strip(), file=sys.stderr)
        return 2
    path = argv[1]
    out = argv[2] if len(argv) > 2 else path.rsplit(".", 1)[0] + ".png"
    with xr.open_dataset(path) as ds:
        scene = ds.attrs.get("scene", "")
        plotter = PLOTTERS.get(scene)
        if plotter is None:
            print(f"plot_run: no figure for scene '{scene}'", file=sys.stderr)
            return 0
        fig = plt.figure(figsize=(16, 5) if scene == "airlaunch" else (11, 4.5))
        plotter(ds, fig)
        fig.suptitle(f"{ds.attrs.get('title', scene)} ({ds.attrs.get('status', '')})")
        fig.tight_layout()
        fig.savefig(out, dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
