"""A sweep varies one element of a vector (docs/sweep.md, "Varying an element
of a vector"): `&input name = 'line%wind(1)'` writes `wind(1) = v` into each
case's namelist and the vector's other elements keep the base's values.

What is checked: the heavy airdrop (input/line_airdrop.nml) swept over the
wind's x component, every row is a single `airlaunch` run of that case's
namelist (`airlaunch-sweep --case-namelist ID`), the run's resolved input holds
the drawn x and the base's y and z; the wind carries the canopy downwind by its
speed times the time (independent physics: a body hanging in the air mass
drifts with it); the envelope, its sensitivity and figures take the element's
name; an index out of range, an index on a scalar, an index 0, and one vector
set whole and by an element are refused in one line."""
import re
import subprocess

import numpy as np
import pytest
import xarray as xr

from conftest import run_airlaunch
from test_sweep_support import (AIRLAUNCH_EXE, ENV, ROOT, SWEEP_EXE, assert_line_row_is_the_run, make_table, run_python,
                                run_sweep)

WINDS = [-5.0, 0.0, 5.0]
T_END = 60.0


def wind_definition(tmp_path, inputs, extra_sweep="design = 'grid'", t_end=T_END):
    definition = tmp_path / "wind.nml"
    definition.write_text(f"""&sweep
  name = 'wind'
  base = '{ROOT / "input" / "line_airdrop.nml"}'
  output_dir = 'out'
  {extra_sweep}
  t_end = {t_end}
  criteria = '{ROOT / "input" / "criteria_airdrop.nml"}'
/
{inputs}
""")
    return definition


def case_run(definition, tmp_path, case):
    """The case's namelist (as airlaunch-sweep writes it) run by airlaunch: (namelist text, output file)."""
    res = subprocess.run([str(SWEEP_EXE), str(definition), "--case-namelist", str(case)], cwd=tmp_path,
                         capture_output=True, text=True, env=ENV, timeout=60)
    assert res.returncode == 0, res.stderr
    nml = tmp_path / f"case_{case}.nml"
    nml.write_text(res.stdout)
    out = tmp_path / f"case_{case}.nc"
    run = run_airlaunch(AIRLAUNCH_EXE, nml, "--output", out)
    assert run.returncode == 0, run.stderr
    return res.stdout, out


@pytest.fixture(scope="module")
def wind_sweep(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("wind")
    values = ", ".join(str(v) for v in WINDS)
    definition = wind_definition(tmp, f"&input name = 'line%wind(1)', distribution = 'list', values = {values}, "
                                      "units = 'm s-1' /")
    make_table(definition, tmp)
    for args in (("--check",), ()):
        res = run_sweep(definition, tmp, None, *args)
        assert res.returncode == 0, res.stderr
    return tmp, definition, tmp / "out" / "summary.nc"


def test_rows_are_the_single_runs_and_the_wind_carries_the_canopy(wind_sweep):
    tmp, definition, summary = wind_sweep
    drift = []
    with xr.open_dataset(summary) as s:
        assert s.attrs["inputs"] == "line%wind(1)"
        np.testing.assert_array_equal(s["line%wind(1)"].values, WINDS)
        assert s["line%wind(1)"].attrs["units"] == "m s-1"
        assert (s["status"].values == 0).all() and (s["completed"].values == 1).all()
        for case, wind in enumerate(WINDS):
            text, out = case_run(definition, tmp, case)
            # the element is assigned alone; the base's whole vector is taken out and its
            # other elements are written from its resolved values
            assert re.search(rf"^\s*wind\(1\) = {wind:g}\s+! sweep wind, case {case}$", text, flags=re.M), text
            assert re.search(r"^! \(set by the sweep below\)\s+wind = 0\.0, 0\.0, 0\.0", text, flags=re.M), text
            row = {k: s[k].values[case] for k in s.variables if s[k].dims == ("case",)}
            with xr.open_dataset(out) as ds:
                resolved = re.search(r"^ WIND=(.*)$", ds.attrs["input_namelist"], flags=re.M).group(1)
                values = [float(v) for v in re.findall(r"[-+0-9.Ee]+(?:\*[-+0-9.Ee]+)?", resolved)
                          for v in ([v.split("*")[1]] * int(v.split("*")[0]) if "*" in v else [v])]
                assert values == [wind, 0.0, 0.0]
                assert_line_row_is_the_run(row, ds, T_END)
                # the canopy (end b, the line's last node) at the end
                drift.append(ds["line_node_position"].values[-1, -1, 0])
        # the canopy deploys into its air speed: a tail wind (+x, the exit's direction) lowers it
        deploy = s["canopy_deploy_air_speed_m_s"].values
        assert deploy[0] > deploy[1] > deploy[2]
    # Downwind by the wind's speed times the time: once open (by ~3 s of the 60) the system
    # hangs in the air mass and moves with it.  2 % for the opening, when the canopy is not
    # yet carried (its 70 m/s exit speed is braked against air moving at the wind's speed):
    # measured 296.6 and 296.7 m of 300 m, 1.1 %.
    step = np.diff(drift)
    assert (step > 0).all()
    np.testing.assert_allclose(step, 5.0 * T_END, rtol=0.02)


def test_the_envelope_and_its_sensitivity_take_the_element(tmp_path):
    """A Latin hypercube over the wind's x with the wind's z fixed (&fixed of an
    element): the envelope, its rank correlations and its figures name the
    input line%wind(1); every case's namelist carries wind(3) = 1.5 and the
    base's y."""
    definition = wind_definition(tmp_path, "&input name = 'line%wind(1)', distribution = 'uniform', lower = -5.0, "
                                           "upper = 5.0, units = 'm s-1' /\n"
                                           "&input name = 'parachute%drag_area', distribution = 'uniform', "
                                           "lower = 520.0, upper = 640.0, units = 'm2' /\n"
                                           "&fixed name = 'line%wind(3)', value = '1.5' /",
                                 "design = 'lhs'\n  n_cases = 8\n  seed = 7", t_end=3.0)
    make_table(definition, tmp_path)
    res = run_sweep(definition, tmp_path, None)
    assert res.returncode == 0, res.stderr
    text, out = case_run(definition, tmp_path, 4)
    assert re.search(r"^\s*wind\(3\) = 1\.5\s+! sweep wind, fixed$", text, flags=re.M), text
    assert re.search(r"^\s*wind\(2\) = 0\.0+\s+! the base's value", text, flags=re.M), text
    res = run_python(["envelope", definition], tmp_path)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(tmp_path / "out" / "summary.nc") as s, xr.open_dataset(tmp_path / "out" / "envelope.nc") as e:
        np.testing.assert_array_equal(e["line%wind(1)"].values, s["line%wind(1)"].values)
        assert e.attrs["inputs"] == "line%wind(1) parachute%drag_area"
        assert s.attrs["fixed"] == "line%wind(3) = 1.5"
        w = s["line%wind(1)"].values
        assert ((w >= -5.0) & (w <= 5.0)).all() and np.ptp(w) > 5.0
        # the rank correlations of the margins with the inputs, by the inputs' names
        assert list(e["input"].values) == ["line%wind(1)", "parachute%drag_area"]
        assert np.isfinite(e["spearman"].sel(input="line%wind(1)").values).all()
    assert "figures: " in res.stdout and sorted((tmp_path / "out").rglob("*.png")), res.stdout


def airdrop_with(tmp_path, extra):
    text = re.sub(r"^(\s*(?:base|criteria)\s*=\s*')input/", lambda m: f"{m.group(1)}{ROOT / 'input'}/",
                  (ROOT / "input" / "sweep_airdrop.nml").read_text(), flags=re.M)
    definition = tmp_path / "sweep_airdrop.nml"
    definition.write_text(text + extra + "\n")
    return definition


def check_refused(tmp_path, definition, message):
    """Refused by airlaunch-sweep --check and by the table step (which runs it), one line, exit 2."""
    for res in (run_sweep(definition, tmp_path, None, "--check"), run_python(["table", definition], tmp_path)):
        assert res.returncode == 2 and res.stderr.strip().count("\n") == 0, res.stdout + res.stderr
        assert message in res.stderr, res.stderr
    assert not (tmp_path / "output").exists()


@pytest.mark.parametrize("extra, message", [
    ("&input name = 'line%wind(4)', distribution = 'uniform', lower = -5.0, upper = 5.0 /",
     "&input #5 'line%wind(4)': line%wind(4) is not allowed: index 4 is out of range (line%wind has 3 elements: "
     "allowed line%wind(1) to line%wind(3))"),
    ("&input name = 'line%damping(1)', distribution = 'uniform', lower = 900.0, upper = 1100.0 /",
     "&input #5 'line%damping(1)': line%damping is a real of one value, not a vector: it has no element 1 (allowed: "
     "line%damping, without an index)"),
    ("&fixed name = 'line_scene%a_position(7)', value = '1400.0' /",
     "&fixed #1 'line_scene%a_position(7)': line_scene%a_position(7) is not allowed: index 7 is out of range "
     "(line_scene%a_position has 3 elements: allowed line_scene%a_position(1) to line_scene%a_position(3))"),
    ("&input name = 'line%wind', distribution = 'uniform', lower = -5.0, upper = 5.0 /",
     "&input #5 'line%wind': line%wind is a vector of 3 values; a sweep varies one value: vary its elements one "
     "by one (allowed: line%wind(1) to line%wind(3), each an &input)"),
    ("&fixed name = 'line%wind(2)', value = '1.0, 2.0' /",
     "&fixed #1 'line%wind(2)': value = '1.0, 2.0' is not allowed: line%wind(2) is one element (allowed: one "
     "number; the whole vector is &fixed name = 'line%wind', value = 'x, y, z')"),
], ids=["index-out-of-range", "scalar-with-index", "fixed-out-of-range", "whole-vector", "fixed-element-of-two"])
def test_bad_elements_are_refused_against_the_base(tmp_path, extra, message):
    check_refused(tmp_path, airdrop_with(tmp_path, extra), message)


@pytest.mark.parametrize("extra, message", [
    ("&input name = 'line%wind(0)', distribution = 'uniform', lower = -5.0, upper = 5.0 /",
     "&input #5 'line%wind(0)': name = 'line%wind(0)' is not allowed (an element index starts at 1"),
    ("&input name = 'line%wind(1)', distribution = 'uniform', lower = -5.0, upper = 5.0 /\n"
     "&input name = 'line%wind(01)', distribution = 'uniform', lower = -5.0, upper = 5.0 /",
     "&input #6 'line%wind(1)': the input is varied twice"),
    ("&input name = 'line%wind', distribution = 'uniform', lower = -5.0, upper = 5.0 /\n"
     "&input name = 'line%wind(2)', distribution = 'uniform', lower = -5.0, upper = 5.0 /",
     "&input #5 'line%wind': line%wind is a vector of 3 values; a sweep varies one value"),
    ("&input name = 'line%wind(1)', distribution = 'uniform', lower = -5.0, upper = 5.0 /\n"
     "&fixed name = 'line%wind', value = '0.0, 2.0, 0.0' /",
     "line%wind and the varied input line%wind(1) (&input #5) both set line%wind, whole and one element"),
    ("&fixed name = 'line%wind(2)', value = '1.0' /\n&fixed name = 'line%wind', value = '0.0, 2.0, 0.0' /",
     "line%wind and line%wind(2) (&fixed #1) both set line%wind, whole and one element"),
    ("&input name = 'line%wind(1)', distribution = 'uniform', lower = -5.0, upper = 5.0 /\n"
     "&fixed name = 'line%wind(1)', value = '1.0' /",
     "line%wind(1) is also a varied input"),
], ids=["index-zero", "same-element-twice", "whole-and-element", "fixed-whole-and-varied-element",
        "fixed-element-and-whole", "fixed-and-varied-element"])
def test_an_element_set_twice_is_refused(tmp_path, extra, message):
    """Refused in one line: an index 0 and the same element twice by the
    definition readers themselves (airlaunch-sweep's and the table step's), a
    vector set both whole and by an element by airlaunch-sweep --check (which
    the table step runs), as each case's namelist would assign an element the
    whole vector also assigns, which the scenario readers refuse."""
    check_refused(tmp_path, airdrop_with(tmp_path, extra), message)
