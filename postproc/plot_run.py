#!/usr/bin/env python3
"""Draw the figure of one airlaunch run: plot_run.py OUTPUT.nc [FIGURE.png].

The figure depends on the scene recorded in the file's `scene` attribute
(airlaunch, line, drop); FIGURE.png defaults to OUTPUT.png beside the output.
A file it cannot draw, or a figure it cannot write (e.g. a full disk), is one
line on stderr and exit status 2; the figure appears under its name only when
written whole (an older figure of that name is then replaced, else left alone).
Scenes register a drawing function in PLOTTERS.
"""
import os
import pathlib
import re
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
    ground = f"ground ({ds.attrs.get('ground_body', '')} {ds.attrs.get('ground_point', '')})"
    for key, label in (("release_time_s", "release (Case 0->1)"), ("edge_time_s", "edge (Case 1->2)"),
                       ("separation_time_s", "separation (Case 2->3)"), ("ground_time_s", ground)):
        t = float(ds.attrs.get(key, -1.0))
        if t >= 0:
            ax.axvline(t, color="0.5", ls="--", lw=0.8)
            ax.text(t, ax.get_ylim()[1], " " + label, rotation=90, va="top", fontsize=7, color="0.3")


def _ground_altitude(ds):
    """&flight ground_altitude [m] of a run that ended on the ground (from the
    resolved input it records), else None."""
    if float(ds.attrs.get("ground_time_s", -1.0)) < 0:
        return None
    found = re.search(r"GROUND_ALTITUDE\s*=\s*([-+0-9.EeDd]+)", str(ds.attrs.get("input_namelist", "")), re.I)
    return float(found.group(1).replace("D", "E").replace("d", "e")) if found else None


def plot_airlaunch(ds, fig):
    """Analogues of the paper's Figs. 9-11: rocket pitch and pitch rate with the
    phase changes; 3-D track and 2-D (x-y) track of aircraft, rocket, parachute."""
    t = ds["time"]
    ax1 = fig.add_subplot(1, 3, 1)
    ax1.plot(t, ds["rocket_euler_deg"].sel(angle=1), label="Euler pitch [deg]")
    if "rocket_nose_elevation_deg" in ds:
        ax1.plot(t, ds["rocket_nose_elevation_deg"], ":", label="nose elevation [deg]")
    ax1.plot(t, ds["rocket_pitch_rate_deg_s"], label="pitch rate [deg/s]")
    t_max = float(ds.attrs.get("pitch_max_time_s", -1.0))
    if t_max >= 0 and "pitch_max_deg" in ds.attrs:
        # the milestone, an event of the integration: between two records
        p_max = float(ds.attrs["pitch_max_deg"])
        ax1.plot([t_max], [p_max], "kv", ms=6, label=f"first pitch maximum {p_max:.1f} deg at {t_max:.2f} s")
    ax1.set_xlabel("time [s]")
    ax1.set_ylabel("pitch [deg], pitch rate [deg/s]")
    ax1.set_title("rocket pitch (Fig. 9)")
    ax1.grid(True)
    lo, hi = ax1.get_ylim()
    ax1.set_ylim(lo, hi + 0.25 * (hi - lo))        # room for the legend above the curves
    ax1.legend(fontsize=7, loc="upper right")
    _phase_lines(ax1, ds)
    ax2 = fig.add_subplot(1, 3, 2, projection="3d")
    for name, style in (("aircraft", "-"), ("rocket", "-"), ("parachute", "--")):
        if f"{name}_position" not in ds:      # no parachute without a line (&line enabled = .false.)
            continue
        p = ds[f"{name}_position"]
        ax2.plot(p.sel(xyz=0), p.sel(xyz=2), p.sel(xyz=1), style, label=name)
    ax2.set_xlabel("x forward [m]")
    ax2.set_ylabel("z right [m]")
    ax2.set_zlabel("y up [m]")
    ax2.set_title("3-D track of the CGs (Fig. 10)")
    # equal-ish scaling of the lateral axis (the scenario is symmetric: z ~ 0),
    # reversed: the plot's axes (x, z, y) would otherwise draw the right-handed
    # frame (x forward, y up, z right) mirrored, a drift to the right on the left
    zr = max(1.0, float(abs(ds["rocket_position"].sel(xyz=2)).max()))
    ax2.set_ylim(max(zr, 50.0), -max(zr, 50.0))
    ax2.legend(fontsize=7)
    ax3 = fig.add_subplot(1, 3, 3)
    for name, style in (("aircraft", "-"), ("rocket", "-"), ("parachute", "--")):
        if f"{name}_position" not in ds:      # no parachute without a line (&line enabled = .false.)
            continue
        p = ds[f"{name}_position"]
        ax3.plot(p.sel(xyz=0), p.sel(xyz=1), style, label=name)
    ground = _ground_altitude(ds)
    if ground is not None:
        ax3.axhline(ground, color="0.4", lw=1.5)
        ax3.text(ax3.get_xlim()[0], ground, f" ground ({ground:g} m)", va="bottom", fontsize=7, color="0.3")
    ax3.set_xlabel("x forward [m]")
    ax3.set_ylabel("altitude y up [m]")
    ax3.set_title("2-D track of the CGs, side view (Fig. 11)")
    ax3.grid(True)
    ax3.legend(fontsize=7)


def _end_names(ds):
    """'end a (fixed)', 'end b (canopy)': each end with its kind from the resolved
    input the file records (`&line_scene a_kind`, `b_kind`), or without it."""
    names = []
    for end in "ab":
        found = re.search(rf"\b{end}_KIND\s*=\s*[\"']([^\"']*)", str(ds.attrs.get("input_namelist", "")), re.I)
        names.append(f"end {end} ({found.group(1).strip()})" if found else f"end {end}")
    return names


#: The zoom on a line's tension peak spans this many seconds either side of it.
PEAK_ZOOM_HALF_WIDTH = 2.0
#: A peak gets its zoom when the zoom's span is at most this fraction of the run
#: (on a shorter run the whole-run panel already shows the peak's shape) ...
PEAK_ZOOM_MAX_SPAN_FRACTION = 0.2
#: ... and the peak is at least this many times the median of the largest
#: tension outside the zoom (a sharp peak, not a plateau).
PEAK_ZOOM_MIN_RATIO = 2.0


def _largest_tension(ds):
    """The largest tension over the line at each record: every segment where the
    file has them (`line_tension`), else both ends."""
    ten = ds["line_tension"] if "line_tension" in ds else ds["line_end_tension"]
    return np.asarray(ten.max(ten.dims[-1]).values, dtype=float)


def tension_peak(ds):
    """(time [s], value [N]) of the run's largest line tension: the file's
    `peak_tension_N` / `peak_tension_time_s` (over every step, also between
    records) where it has them, else the largest recorded tension; None for a
    run without records."""
    t = np.asarray(ds["time"].values, dtype=float)
    largest = _largest_tension(ds)
    if t.size == 0 or not np.isfinite(largest).any():
        return None
    k = int(np.nanargmax(largest))
    t_peak, peak = float(t[k]), float(largest[k])
    if float(ds.attrs.get("peak_tension_time_s", -1.0)) >= 0 and "peak_tension_N" in ds.attrs \
            and float(ds.attrs["peak_tension_N"]) >= peak:
        t_peak, peak = float(ds.attrs["peak_tension_time_s"]), float(ds.attrs["peak_tension_N"])
    return t_peak, peak


def sharp_peak(ds):
    """The (time, value) of tension_peak when it deserves a zoom (a peak that
    the whole run's axis squeezes to a line: a heavy airdrop's opening shock,
    1.28 s into a 200 s descent), else None."""
    found = tension_peak(ds)
    if found is None:
        return None
    t_peak, peak = found
    t = np.asarray(ds["time"].values, dtype=float)
    if 2.0 * PEAK_ZOOM_HALF_WIDTH > PEAK_ZOOM_MAX_SPAN_FRACTION * (t[-1] - t[0]):
        return None
    outside = _largest_tension(ds)[np.abs(t - t_peak) > PEAK_ZOOM_HALF_WIDTH]
    outside = outside[np.isfinite(outside)]
    if outside.size == 0 or peak <= 0 or peak < PEAK_ZOOM_MIN_RATIO * max(float(np.median(np.abs(outside))), 0.0):
        return None
    return t_peak, peak


def _peak_zoom(ax, ds, ends, t_peak, peak):
    """The tensions of the records within PEAK_ZOOM_HALF_WIDTH of the peak
    (points marked: the shock's shape at the output cadence) and the peak,
    labelled with its value."""
    t = ds["time"]
    near = (np.abs(t - t_peak) <= PEAK_ZOOM_HALF_WIDTH).values
    ten = ds["line_end_tension"]
    for k in range(ten.shape[-1]):
        ax.plot(t[near], ten.isel({ten.dims[-1]: k})[near], ".-", ms=3,
                label=ends[k] if k < 2 else f"end {k}")
    if "line_tension" in ds:
        seg = ds["line_tension"]
        ax.plot(t[near], seg.max(seg.dims[-1])[near], ":", color="0.3", lw=0.8, label="largest segment")
    text = f"peak {peak / 1e3:.4g} kN at {t_peak:.4g} s"
    ax.plot([t_peak], [peak], "kv", ms=6)
    ax.annotate(text, (t_peak, peak), xytext=(6, -2), textcoords="offset points", fontsize=8, va="top",
                gid="peak_label")
    ax.set_xlim(max(t_peak - PEAK_ZOOM_HALF_WIDTH, float(t[0])), min(t_peak + PEAK_ZOOM_HALF_WIDTH, float(t[-1])))
    ax.set_ylim(0.0, 1.12 * peak)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("tension [N]")
    ax.set_title(f"zoom: \u00b1{PEAK_ZOOM_HALF_WIDTH:g} s around the peak tension")
    ax.set_label("tension_peak_zoom")
    ax.grid(True)
    ax.legend(fontsize=7, loc="lower right")


def plot_line(ds, fig):
    """Standalone line: the line's shape at a few times, its end tensions, a
    zoom on a sharp tension peak (an airdrop's opening shock: sharp_peak) and,
    where the file has them (version 0.2.0 on), its ends' speeds - an airdrop's
    platform and canopy - with the touchdown marked."""
    pos = ds["line_node_position"]
    speeds = "line_end_velocity" in ds
    ends = _end_names(ds)
    zoom = sharp_peak(ds)
    npanel = 2 + (zoom is not None) + speeds
    nrow, ncol = (2, 2) if npanel == 4 else (1, npanel)
    if zoom is not None:
        width, height = fig.get_size_inches()
        # the panels keep their heights; four go on two rows (on one, each was 4.9 in wide)
        fig.set_size_inches(width * ncol / (npanel - 1) if nrow == 1 else width, height * nrow)
    ax1 = fig.add_subplot(nrow, ncol, 1)
    for k in np.linspace(0, ds.sizes["time"] - 1, 6).astype(int):
        p = pos.isel(time=k)
        ax1.plot(p.sel(xyz=0), p.sel(xyz=1), ".-", ms=2, label=f"t = {float(ds['time'][k]):.2f} s")
    ax1.set_xlabel("x forward [m]")
    ax1.set_ylabel("y up [m]")
    ax1.set_title("line shape (nodes) at six records")
    ax1.axis("equal")
    ax1.grid(True)
    ax1.legend(fontsize=7)
    ax2 = fig.add_subplot(nrow, ncol, 2)
    ten = ds["line_end_tension"]
    for k in range(ten.shape[-1]):
        ax2.plot(ds["time"], ten.isel({ten.dims[-1]: k}), label=ends[k] if k < 2 else f"end {k}")
    if "line_tension" in ds:
        # a snatch's largest load is often inside the line, not at an end
        seg = ds["line_tension"]
        ax2.plot(ds["time"], seg.max(seg.dims[-1]), ":", color="0.3", lw=0.8, label="largest segment")
    t_peak = float(ds.attrs.get("peak_tension_time_s", -1.0))
    if t_peak >= 0 and "peak_tension_N" in ds.attrs:
        # the peak over every step: between two records it can be far above them
        peak = float(ds.attrs["peak_tension_N"])
        ax2.plot([t_peak], [peak], "kv", ms=6, label=f"peak (every step) {peak / 1e3:.4g} kN at {t_peak:.4g} s")
    ax2.set_xlabel("time [s]")
    ax2.set_ylabel("tension [N]")
    ax2.set_title("end tensions (records) and the peak")
    ax2.grid(True)
    ax2.legend(fontsize=7)
    if zoom is not None:
        _peak_zoom(fig.add_subplot(nrow, ncol, 3), ds, ends, *zoom)
    if not speeds:
        return
    ax3 = fig.add_subplot(nrow, ncol, npanel)
    vel = ds["line_end_velocity"]
    for k in range(2):
        v = vel.isel(end=k)
        ax3.plot(ds["time"], np.sqrt((v ** 2).sum("xyz")), label=f"{ends[k]}: speed")
        ax3.plot(ds["time"], -v.sel(xyz=1), ":", label=f"{ends[k]}: descent rate")
    t_ground = float(ds.attrs.get("ground_time_s", -1.0))
    if t_ground >= 0:
        ax3.axvline(t_ground, color="0.5", ls="--", lw=0.8)
        ax3.text(t_ground, ax3.get_ylim()[1], f" touchdown {float(ds.attrs['ground_speed_m_s']):.2f} m/s",
                 rotation=90, va="top", fontsize=7, color="0.3")
    ax3.set_xlabel("time [s]")
    ax3.set_ylabel("speed, descent rate (-v_y) [m/s]")
    ax3.set_title("end speeds (earth frame)")
    ax3.grid(True)
    ax3.legend(fontsize=7)


PLOTTERS = {"drop": plot_drop, "airlaunch": plot_airlaunch, "line": plot_line}


def fail(message):
    """One line on stderr, exit status 2 (the project's rule for bad input)."""
    print(f"plot_run: error: {message}", file=sys.stderr)
    return 2


def default_figure(path):
    """OUTPUT.png beside OUTPUT.nc (the extension of the file name only)."""
    p = pathlib.Path(path)
    return str(p.with_suffix(".png")) if p.suffix else str(p) + ".png"


def main(argv):
    args = argv[1:]
    if any(a in ("-h", "--help") for a in args):
        print(__doc__.strip())
        return 0
    if not 1 <= len(args) <= 2 or any(a.startswith("-") for a in args):
        return fail("usage: plot_run.py OUTPUT.nc [FIGURE.png] (see --help)")
    path = args[0]
    out = args[1] if len(args) > 1 else default_figure(path)
    if not pathlib.Path(path).is_file():
        return fail(f"{path}: no such file (give the netCDF output of an airlaunch run)")
    out_dir = pathlib.Path(out).resolve().parent
    if not out_dir.is_dir():
        return fail(f"{out}: its directory {out_dir} does not exist")
    try:
        os.path.abspath(path).encode("utf-8")
    except UnicodeEncodeError:
        # netCDF takes UTF-8 paths only (its error named a 'utf-8' codec and called the file unreadable)
        shown = os.fsencode(os.path.abspath(path)).decode("utf-8", "backslashreplace")
        return fail(f"{shown}: cannot read it: its path is not UTF-8 text, which netCDF requires (copy or link it "
                    "to a path whose directory names are UTF-8)")
    try:
        ds = xr.open_dataset(path, engine="netcdf4")
    except Exception as exc:   # noqa: BLE001 - any unreadable file is the user's to hear about in one line
        text = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
        return fail(f"{path}: cannot read it as netCDF ({text})")
    with ds:
        if "n_cases" in ds.attrs and "inputs" in ds.attrs:
            # a sweep's table.nc, summary.nc or envelope.nc: one row per case, no time history
            return fail(f"{path}: a sweep's file of {ds.attrs['n_cases']} cases (its table, summary or envelope), "
                        "not the output of one run: the sweep's figures are drawn by `python -m postproc.sweep "
                        "envelope SWEEP.nml` into its figures/; plot a case's own run: its trajectories/case_ID.nc "
                        "(keep_ids, keep_worst), or airlaunch on the namelist `airlaunch-sweep SWEEP.nml "
                        "--case-namelist ID` prints")
        scene = ds.attrs.get("scene", "")
        plotter = PLOTTERS.get(scene)
        if plotter is None:
            return fail(f"{path}: no figure for scene '{scene}' (the file's 'scene' attribute must be one of "
                        f"{', '.join(PLOTTERS)}: is it an airlaunch output?)")
        fig = plt.figure(figsize=(16, 5) if scene == "airlaunch" or "line_end_velocity" in ds else (11, 4.5))
        try:
            plotter(ds, fig)
        except KeyError as exc:
            # xarray's KeyError reads "No variable named 'x'. Variables on the dataset include [...]"
            text = str(exc.args[0]) if exc.args else ""
            named = re.search(r"No variable named '([^']*)'", text)
            name = repr(named.group(1)) if named else repr(text)
            return fail(f"{path}: variable {name} is missing (an output written with trajectory = .false., or "
                        "not of this version of airlaunch?)")
        fig.suptitle(f"{ds.attrs.get('title', scene)} ({ds.attrs.get('status', '')})")
        footer = "; ".join(str(ds.attrs[k]) for k in ("frames", "code_version") if k in ds.attrs)
        if footer:
            # the axes' convention (a right-handed earth frame, y up) and the code that ran
            fig.text(0.5, 0.005, footer, ha="center", va="bottom", fontsize=7, color="0.3")
        fig.tight_layout(rect=(0, 0.03 if footer else 0, 1, 1))
        return save_figure(fig, out)


def save_figure(fig, out):
    """Write `fig` to `out` whole or not at all: to a temporary file beside it
    (.plot_run-PID.part), renamed to `out` once written and synced; on failure the
    temporary is removed, `out` is left as it was, and the OS's reason is one line."""
    target = pathlib.Path(out)
    fmt = target.suffix[1:].lower() or matplotlib.rcParams["savefig.format"]
    if fmt not in fig.canvas.get_supported_filetypes():
        return fail(f"{out}: no figure format '{fmt}' (give a name ending in one of "
                    f"{', '.join('.' + k for k in sorted(fig.canvas.get_supported_filetypes()))})")
    temp = target.with_name(f".plot_run-{os.getpid()}.part")
    try:
        fd = os.open(temp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        try:
            with os.fdopen(fd, "wb") as fh:
                fig.savefig(fh, format=fmt, dpi=110)
                fh.flush()
                os.fsync(fh.fileno())
            os.replace(temp, target)
        except BaseException:
            temp.unlink(missing_ok=True)
            raise
    except OSError as exc:
        return fail(f"{out}: cannot write the figure ({exc.strerror or exc})")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
