"""A heavy airdrop on the standalone line (input/line_airdrop.nml): a 1000 kg platform leaves
the aircraft at 70 m/s in still air, its 580 m^2 main canopy deploys from the pack at 0.5 s
(its filling time from the air speed it has then) and the two settle into the steady descent.

Independent references:
- The steady descent of platform, line and canopy: weight = drag,
  (m_platform + m_canopy + rho_l L) g = q (Cd S + (Cd A)_platform + Cd_t pi d L), the line
  hanging straight down (no cross-flow) - the apparent mass does not enter a steady state.
- The line is passive (point-mass ends, still air): its energy, with the canopy's apparent
  mass in the kinetic part, may only fall - the filling canopy in still air dissipates
  d/dt 1/2 (m + m_a) v^2 = v.F - 1/2 (dm_a/dt) v^2 (line.md section 4); the run reports the
  largest rise itself, which a wrong sign of the entrained air's momentum would make
  positive (+ (3/2) (dm_a/dt) v^2)."""
import math
import re
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr
from matplotlib import image

from conftest import ROOT, nml_scalar, run_airlaunch

AIRDROP = ROOT / "input" / "line_airdrop.nml"
G = 9.80665


def value(name):
    """A scalar set in the example file."""
    return nml_scalar(AIRDROP, name)


def steady_descent_rate():
    weight = (value("a_mass") + value("mass") + value("mass_per_length") * value("length")) * G
    drag_area = value("drag_area") + value("a_drag_area") + \
        value("cd_tangential") * math.pi * value("diameter") * value("length")
    return math.sqrt(2 * weight / (value("air_density") * drag_area))


def test_the_airdrop_opens_and_settles_into_the_steady_descent(airlaunch_exe, tmp_path):
    out = tmp_path / "airdrop.nc"
    res = run_airlaunch(airlaunch_exe, AIRDROP, "--output", out)
    assert res.returncode == 0, res.stderr
    v_t = steady_descent_rate()   # 5.684 m/s
    with xr.open_dataset(out) as ds:
        assert ds.attrs["status"] == "completed"
        t = ds["time"].values
        v = ds["line_tip_velocity"].values           # the canopy (node N)
        x = ds["line_node_position"].values
        tension = ds["line_end_tension"].values
        # the canopy deployed into the air speed it had (still air: its own speed), below the
        # exit speed: the packed canopy has slowed behind the platform
        deployed = np.flatnonzero(np.isclose(t, value("deploy_time"), rtol=0, atol=1e-12))[0]
        assert ds.attrs["canopy_deploy_air_speed_m_s"] == pytest.approx(
            np.linalg.norm(v[deployed]), rel=1e-12)
        assert ds.attrs["canopy_deploy_air_speed_m_s"] < value("a_velocity")
        # the steady descent after 200 s: what is left of the swing (the platform 0.16 m
        # aside of the canopy on the 20 m line, an angle of 8e-3 rad whose cosine moves the
        # balance by 3e-5) and CVODE's tolerance (rtol 1e-5 on a state that no longer
        # changes) within 1e-4; measured 1.9e-6 (0.3.0; 2.7e-6 when written)
        assert -v[-1, 1] == pytest.approx(v_t, rel=1e-4), (v[-1], v_t)
        # the end nodes' velocities: end b is the tip (node N) bit for bit; end a, the
        # platform, descends with the canopy at the same steady rate (the same 1e-4)
        ends = ds["line_end_velocity"].values        # (time, end, xyz)
        np.testing.assert_array_equal(ends[:, 1], v)
        assert -ends[-1, 0, 1] == pytest.approx(v_t, rel=1e-4), (ends[-1, 0], v_t)
        # and left the aircraft with its exit velocity (the record at t = 0)
        np.testing.assert_array_equal(ends[0, 0], [value("a_velocity"), 0.0, 0.0])
        # the forward motion is gone (70 m/s at the exit): what is left is the swing's, at most
        # 2 pi / 10 s x 0.16 m = 0.1 m/s at the platform and far less at the canopy, which
        # with its apparent mass (5.7 t) sits near the pivot: bound 1 % of v_t (0.057 m/s),
        # measured 1.3e-3 m/s
        assert abs(v[-1, 0]) < 0.01 * v_t
        # the platform hangs below the canopy, the line straight and stretched by the
        # platform's weight less its drag (EA eps = m g - q (Cd A)_p): the distance of the
        # ends is L (1 + eps) but for the line's own weight, which adds rho_l g L^2 / (2 EA)
        # = 0.2 mm, and what is left of the swing; bound 1 mm, measured +0.18 mm (the
        # vertical span alone is also shortened by the swing's L (1 - cos theta) = 0.6 mm)
        q = 0.5 * value("air_density") * v_t ** 2
        pull = value("a_mass") * G - q * value("a_drag_area")
        span = np.linalg.norm(x[-1, -1] - x[-1, 0])
        assert span == pytest.approx(value("length") * (1 + pull / value("ea")), abs=1e-3)
        # the opening shock comes while the canopy fills: the peak of the riser's tension
        i = int(tension[:, 0].argmax())
        t_fill = ds.attrs["canopy_fill_time_s"]
        assert value("deploy_time") < t[i] < value("deploy_time") + t_fill
        # passive line: the energy may only fall (the run's own invariant; 1e-6 of the
        # largest kinetic energy for the rounding of the recorded sums)
        assert 0.0 <= ds.attrs["max_energy_rise_J"] <= 1e-6 * float(ds["line_energy_kinetic"].max())


def test_the_platform_touches_down_at_the_steady_descent_rate(airlaunch_exe, tmp_path):
    """With `&line_scene ground = .true.` (sea level: 1500 m below the exit) and
    t_end = 400 s the run ends at the touchdown, the lowest integrated node's
    event: the platform (node 0), after ~260 s, at the steady descent rate
    (1e-4 as above; measured 8.6e-6); the last record is the event, the
    platform on the ground (1e-6 m: the event's own state), every earlier
    record above it; the sweep summary's names are in the file."""
    text = AIRDROP.read_text().replace("  t_end = 200.0", "  t_end = 400.0", 1)
    text = text.replace("&line_scene\n", "&line_scene\n  ground = .true., ground_altitude = 0.0\n", 1)
    nml = tmp_path / "touchdown.nml"
    nml.write_text(text)
    out = tmp_path / "touchdown.nc"
    res = run_airlaunch(airlaunch_exe, nml, "--output", out)
    assert res.returncode == 0, res.stderr
    v_t = steady_descent_rate()
    with xr.open_dataset(out) as ds:
        assert ds.attrs["status"] == "completed" and ds.attrs["ground_node"] == 0
        t_g = ds.attrs["ground_time_s"]
        assert 200.0 < t_g < 400.0 and ds["time"].values[-1] == t_g
        y0 = ds["line_node_position"].values[:, 0, 1]
        assert abs(y0[-1]) < 1e-6 and np.all(y0[:-1] > 0.0)
        assert ds.attrs["ground_speed_m_s"] == pytest.approx(v_t, rel=1e-4)
        # the touchdown speed is the platform's (node 0, end a) at the event, the last record
        # (Fortran's norm2 and numpy's norm may round the last bit apart)
        assert np.linalg.norm(ds["line_end_velocity"].values[-1, 0]) == pytest.approx(
            ds.attrs["ground_speed_m_s"], rel=1e-15)
    assert f"ground (0.0 m): reached by node 0 at t = " in res.stdout, res.stdout


def test_the_figure_draws_the_end_speeds(airlaunch_exe, tmp_path):
    """plot_run.py draws a line run's figure with the ends' speeds (a third panel,
    version 0.2.0's line_end_velocity), and a file of an earlier version without
    that variable with the first two panels alone."""
    text = AIRDROP.read_text().replace("  t_end = 200.0", "  t_end = 5.0", 1)
    nml = tmp_path / "short.nml"
    nml.write_text(text)
    out = tmp_path / "short.nc"
    assert run_airlaunch(airlaunch_exe, nml, "--output", out).returncode == 0
    old = tmp_path / "old.nc"
    with xr.open_dataset(out) as ds:
        ds.drop_vars("line_end_velocity").to_netcdf(old)
    for path, width in ((out, 16), (old, 11)):
        fig = path.with_suffix(".png")
        res = subprocess.run([sys.executable, str(ROOT / "postproc" / "plot_run.py"), str(path), str(fig)],
                             capture_output=True, text=True, timeout=120)
        assert res.returncode == 0, res.stderr
        # (the figure's width: 16 inches at plot_run's 110 dpi with three panels, 11 with two)
        assert image.imread(fig).shape[1] == width * 110


def test_a_line_below_the_atmosphere_model_stops_the_run(airlaunch_exe, tmp_path):
    """The airdrop from 100 m in the standard atmosphere (&line air_density = 0)
    without a ground falls through the model's floor (-2 km) after ~400 s: a
    numerical failure, exit 3, one line naming the time, the node and its
    altitude, the output so far readable with status "failed" and its last
    record above the floor.  Before, the ISA was held at its floor's density
    there and the run went on to t_end (-9.9 km at 2000 s, "completed")."""
    text = AIRDROP.read_text().replace("  t_end = 200.0", "  t_end = 2000.0", 1)
    for old, new in [("  air_density = 1.1117", "  air_density = 0.0"),
                     ("a_position = 0.0, 1500.0, 0.0", "a_position = 0.0, 100.0, 0.0"),
                     ("b_position = -20.0, 1500.0, 0.0", "b_position = -20.0, 100.0, 0.0")]:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    nml = tmp_path / "deep.nml"
    nml.write_text(text)
    out = tmp_path / "deep.nc"
    res = run_airlaunch(airlaunch_exe, nml, "--output", out)
    assert res.returncode == 3, res.stderr
    first = res.stderr.strip().splitlines()[0]
    assert re.search(r"t = [0-9.]+ s: right-hand side failed: line node \d+ altitude -2[0-9.]+ m is outside the "
                     r"atmosphere model \(ISA, -2000.0 to 47000.0 m; &line air_density = 0\)", first), first
    with xr.open_dataset(out) as ds:
        assert ds.attrs["status"] == "failed" and "outside the atmosphere model" in ds.attrs["failure"]
        assert ds["line_node_position"].values[-1, :, 1].min() >= -2000.0
        assert ds["time"].values[-1] > 300.0


@pytest.mark.parametrize("group,edit", [
    ("&parachute", ("  deploy_time = 0.5 ", "  deploy_time = 1.0e-310 ")),
    ("&line", ("  n_seg = 10\n", "  n_seg = 10\n  break_time = 1.0e-310\n")),
])
def test_a_subnormal_stop_time_is_refused_not_hung(airlaunch_exe, tmp_path, group, edit):
    """A stop time a subnormal distance after t = 0 (`deploy_time`, `break_time`
    = 1e-310: > 0, so allowed by their ranges) made CVODE's first step
    subnormal, 1/h overflowed, and CVode never returned (found by an audit: the
    line scene spun inside CVode, where SIGTERM is not looked at; the air-launch
    scene's deployment at 4.9e-324 failed with an aircraft altitude of NaN).  A
    subnormal input is now refused when read, one line naming file, group,
    variable and value, exit 2, as a non-finite one is; the timeout turns the
    hang into a failure here."""
    text = AIRDROP.read_text()
    assert text.count(edit[0]) == 1, edit[0]
    nml = tmp_path / "subnormal.nml"
    nml.write_text(text.replace(edit[0], edit[1]))
    out = tmp_path / "subnormal.nc"
    try:
        res = subprocess.run([str(airlaunch_exe), str(nml), "--output", str(out)], capture_output=True, text=True,
                             timeout=60)
    except subprocess.TimeoutExpired:
        pytest.fail("the run did not end within 60 s (a run of the example takes 0.06 s)")
    assert res.returncode == 2, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1, res.stderr
    assert f"{nml}:" in lines[0] and f"{group}: " in lines[0], lines[0]
    assert "= 1.0e-310 is not allowed (a subnormal number" in lines[0], lines[0]
    assert not out.exists()
