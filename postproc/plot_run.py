#!/usr/bin/env python3
"""Draw the figure of one airlaunch run: plot_run.py OUTPUT.nc [FIGURE.png].

The figure depends on the scene recorded in the file's `scene` attribute.
Scenes register a drawing function in PLOTTERS.
"""
import sys

import matplotlib

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


PLOTTERS = {"drop": plot_drop}


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
        fig = plt.figure(figsize=(11, 4.5))
        plotter(ds, fig)
        fig.suptitle(f"{ds.attrs.get('title', scene)} ({ds.attrs.get('status', '')})")
        fig.tight_layout()
        fig.savefig(out, dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
