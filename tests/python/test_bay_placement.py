"""&bay l0_from = 'tail': the rocket placed in the bay by its tail, so that a
rocket whose CG moves (a CG dispersion in a sweep) stays where it lies on the
rail.  With the default l0_from = 'cg' the same dispersion moved the whole
rocket aft and a forward CG put its tail outside the bay (a new user's
walkthrough of a CG sweep, thirty-third session).

References: the paper file's rocket (18.5 m, CG 9.25 m from the nose, CG 10 m
ahead of the ramp edge) has its tail 0.75 m ahead of the edge, so l0 = 0.75
from the tail is the same scenario, bit for bit; and at t = 0 (the rocket
locked in the bay) the distance between the rocket's and the aircraft's CGs is
|(ramp_edge_x + l0_cg, floor_y + diameter/2)| in the aircraft's axes, whatever
the attitude: a length, independent of the frames."""
import math

import numpy as np
import xarray as xr

from conftest import assert_input_error, nml_variant, run_airlaunch

RAMP_EDGE_X, FLOOR_Y, RADIUS, LENGTH = -13.0, -2.0, 0.8, 18.5
TAIL = [(r"^  l0 = 10.0 .*$", "  l0 = 0.75\n  l0_from = 'tail'")]


def cg_separation_at_release(path):
    with xr.open_dataset(path) as ds:
        return float(np.linalg.norm(ds["rocket_position"].values[0] - ds["aircraft_position"].values[0]))


def test_the_tail_placement_of_the_paper_rocket_is_the_paper_scenario(airlaunch_exe, tmp_path):
    cg = run_airlaunch(airlaunch_exe, nml_variant(tmp_path, "cg"), "--output", tmp_path / "cg.nc")
    tail = run_airlaunch(airlaunch_exe, nml_variant(tmp_path, "tail", edits=TAIL), "--output", tmp_path / "tail.nc")
    assert cg.returncode == 0 and tail.returncode == 0, cg.stderr + tail.stderr
    strip = lambda out: [ln for ln in out.splitlines() if "output" not in ln and "wall" not in ln]  # noqa: E731
    assert strip(tail.stdout) == strip(cg.stdout)
    assert math.isclose(cg_separation_at_release(tmp_path / "tail.nc"), math.hypot(-3.0, -1.2), rel_tol=1e-12)


def test_a_forward_cg_keeps_the_rocket_where_its_tail_lies(airlaunch_exe, tmp_path):
    forward = [(r"^  cg_from_nose = 9.25 .*$", "  cg_from_nose = 8.0")]
    # placed by its CG, the rocket moves 1.25 m aft: its tail would leave the bay
    out = tmp_path / "cg.nc"
    res = run_airlaunch(airlaunch_exe, nml_variant(tmp_path, "cg", edits=forward), "--output", out)
    assert_input_error(res, "&bay: l0 = 10.0 is not allowed (the rocket's tail, 10.5 m aft of its CG", out)
    # placed by its tail, it stays: its CG is 0.75 + 10.5 m ahead of the ramp edge
    res = run_airlaunch(airlaunch_exe, nml_variant(tmp_path, "tail", edits=forward + TAIL), "--output",
                        tmp_path / "tail.nc")
    assert res.returncode == 0, res.stderr
    expected = math.hypot(RAMP_EDGE_X + 0.75 + (LENGTH - 8.0), FLOOR_Y + RADIUS)
    assert math.isclose(cg_separation_at_release(tmp_path / "tail.nc"), expected, rel_tol=1e-12)


def test_a_rocket_placed_by_its_tail_must_fit_the_bay(airlaunch_exe, tmp_path):
    out = tmp_path / "run.nc"
    res = run_airlaunch(airlaunch_exe, nml_variant(tmp_path, edits=[(r"^  l0 = 10.0 .*$",
                                                                      "  l0 = 6.5\n  l0_from = 'tail'")]),
                        "--output", out)
    line = assert_input_error(res, "&bay: l0 = 6.5 is not allowed with l0_from = 'tail'", out)
    assert "need l0 <= 6.0 m" in line
    res = run_airlaunch(airlaunch_exe, nml_variant(tmp_path, edits=[(r"^  l0 = 10.0 .*$",
                                                                      "  l0 = 1.0\n  l0_from = 'nose'")]),
                        "--output", out)
    assert_input_error(res, "l0_from", out)
