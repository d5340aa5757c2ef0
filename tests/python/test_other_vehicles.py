"""Vehicles other than the paper's (generality audit, thirty-fifth session).

The code was built around one scenario (input/airlaunch_paper.nml); these
tests hold what a different carrier, payload, bay or canopy must get, each
against a reference independent of the code: a geometric construction, a
closed form, or the paper's own run where nothing should change."""
import math

import numpy as np
import pytest
import xarray as xr

from conftest import PAPER, ROOT, assert_input_error, nml_variant, run_airlaunch

LINE_OPENING = ROOT / "input" / "line_opening.nml"


# ---------------------------------------------------------------- a small canopy

def test_a_small_canopy_open_from_the_start_is_accepted(airlaunch_exe, tmp_path):
    """A drogue of 0.04 m^2 (a payload of a few hundred kilograms) open from the
    start never uses the packed drag area (`&parachute packed_drag_area`, the
    drag area before a deployment), so its default, 0.05 m^2, cannot make the
    canopy invalid.  Before, the air-launch scene and the line scene both
    refused it: 'packed_drag_area = 0.05 is not allowed (must be < drag_area =
    0.04 m^2)', a value the user never gave.  --check validates the input and
    the trim with the settled line (what a run starts from)."""
    nml = nml_variant(tmp_path, "drogue", edits=[(r"^  drag_area = 10.0 .*$", "  drag_area = 0.04")])
    res = run_airlaunch(airlaunch_exe, nml, "--check", "--output", tmp_path / "drogue.nc")
    assert res.returncode == 0, res.stderr
    # the line scene's canopy end, open from the start: a short run
    text = LINE_OPENING.read_text()
    for old, new in [("  t_end = 2.0 ", "  t_end = 0.02 "), ("  drag_area = 10.0 ", "  drag_area = 0.04 "),
                     ("  packed_drag_area = 0.1 ", "  ! packed_drag_area"), ("  deploy_time = 0.2 ", "  deploy_time = -1.0 ")]:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    line_nml = tmp_path / "line_drogue.nml"
    line_nml.write_text(text)
    res = run_airlaunch(airlaunch_exe, line_nml, "--output", tmp_path / "line_drogue.nc")
    assert res.returncode == 0, res.stderr


def test_a_small_canopy_that_deploys_needs_a_smaller_packed_area(airlaunch_exe, tmp_path):
    """The same drogue deployed during the run does use the packed drag area:
    the default 0.05 m^2 is refused there, and the message says it is the
    default (the user did not write it) and what to give."""
    nml = nml_variant(tmp_path, "drogue_deploys", edits=[(r"^  drag_area = 10.0 .*$", "  drag_area = 0.04"),
                                                          (r"^  deploy_time = -1.0 .*$", "  deploy_time = 1.0")])
    out = tmp_path / "x.nc"
    line = assert_input_error(run_airlaunch(airlaunch_exe, nml, "--output", out),
                              "&parachute: packed_drag_area = 0.05 (the default) is not allowed", out)
    assert "drag_area = 0.04" in line and "deploy_time" in line
