"""Foundation end to end: the demo scene runs, its output opens in xarray with
units on every variable and the resolved input echoed, and bad input gives one
clear line and a nonzero status without leaving an output file."""
import os
import pathlib
import re
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

from conftest import ROOT, assert_input_error, nml_variant, run_airlaunch

G0 = 9.80665


def write(path, text):
    path.write_text(text)
    return path


def drop_nml(tmp_path, store="mass = 28000.0, drag_area = 10.0", run_extra="", t_end=30.0):
    out = tmp_path / "drop.nc"
    nml = write(tmp_path / "drop.nml", f"""
&run scene = 'drop', t_end = {t_end}, output_dt = 0.05, output = '{out}' {run_extra} /
&store {store} /
""")
    return nml, out


def test_demo_output_opens_in_xarray_with_units(airlaunch_exe, tmp_path):
    nml, out = drop_nml(tmp_path)
    res = run_airlaunch(airlaunch_exe, nml)
    assert res.returncode == 0, res.stderr
    assert f"output: {out}" in res.stdout
    assert not (tmp_path / "drop.nc.part").exists()
    with xr.open_dataset(out) as ds:
        for name in list(ds.data_vars) + list(ds.coords):
            assert ds[name].attrs.get("units", "") != "", f"{name} has no units"
            assert ds[name].attrs.get("long_name", "") != "", f"{name} has no long_name"
        assert ds["store_position"].dims == ("time", "xyz")
        assert ds.attrs["status"] == "completed"
        assert ds.attrs["code_version"].startswith("airlaunch ")
        echo = ds.attrs["input_namelist"].upper()
        # resolved input: values written by the user and defaults alike
        assert "MASS=" in echo and "FALL_HEIGHT=" in echo and "RTOL=" in echo


def test_drop_without_drag_is_a_parabola(airlaunch_exe, tmp_path):
    """Independent reference: with Cd*A = 0 the store falls as x = v0 t,
    y = h - g t^2 / 2, and falls H metres at t = sqrt(2H/g)."""
    nml, out = drop_nml(tmp_path, store="mass = 500.0, drag_area = 0.0, fall_height = 500.0",
                        run_extra=", rtol = 1e-11, atol = 1e-9")
    res = run_airlaunch(airlaunch_exe, nml)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(out) as ds:
        t = ds["time"].values
        pos = ds["store_position"].values
        v0 = ds["store_velocity"].values[0, 0]
        # rtol 1e-11: the global error on a 1e4 m altitude is far below 1e-3 m
        np.testing.assert_allclose(pos[:, 1], 10000.0 - 0.5 * G0 * t**2, atol=1e-3)
        np.testing.assert_allclose(pos[:, 0], v0 * t, rtol=1e-6)
        # the event is located by root finding, not at an output sample
        assert ds.attrs["fall_time_s"] == pytest.approx(np.sqrt(2 * 500.0 / G0), abs=1e-6)
        # the run ends there and its last record is that instant, off the output grid (output.md)
        assert t[-1] == ds.attrs["fall_time_s"]


def test_drag_reaches_terminal_velocity(airlaunch_exe, tmp_path):
    """A light store with a large drag area approaches v_t = sqrt(2 m g / (rho Cd A))."""
    nml, out = drop_nml(tmp_path, store="mass = 10.0, drag_area = 5.0, altitude = 1000.0, "
                                         "mach = 0.05, fall_height = 900.0", t_end=400.0)
    res = run_airlaunch(airlaunch_exe, nml)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(out) as ds:
        vy = ds["store_velocity"].values[-1, 1]
        y = ds["store_position"].values[-1, 1]
    # ISA density at the final altitude (100 m): 1.2133 kg/m^3 (US Std Atm 1976 table)
    assert y == pytest.approx(100.0, abs=1e-3)
    vt = np.sqrt(2 * 10.0 * G0 / (1.2133 * 5.0))
    # the store lags the slowly changing terminal speed by less than 0.5 %
    assert -vy == pytest.approx(vt, rel=5e-3)


@pytest.mark.parametrize("store,fragment", [
    ("mas = 28000.0", "unknown variable 'mas' = 28000.0 (did you mean 'mass'?)"),
    # a name's first word ('cg' for &rocket cg_from_nose: no suggestion before the
    # thirty-third session, its edit distance being 10)
    ("mass = 28000.0, drag = 10.0", "unknown variable 'drag' = 10.0 (did you mean 'drag_area'?)"),
    ("mass = -5.0", "mass = -5.0 is not allowed (must be > 0 kg)"),
    ("mass = 'heavy'", "variable 'mass' = 'heavy' is not a real number"),
    ("drag_area = 1.0", "missing required value mass (kg)"),
    ("mass = 100.0, mach = 0.0", "mach = 0.0 is not allowed (must be in [0.001, 5.0])"),
    # NaN and Inf read as reals; variables without a range check (e.g. the tail's
    # position in the air-launch scene) accepted them before the ninth session
    ("mass = nan", "'mass' = nan is not allowed (not a finite number)"),
    # gfortran reads a lone sign as 0
    ("mass = -", "variable 'mass' = - is not a real number"),
    # a tab before a name hid the assignment from the checks (here: the second value)
    ("mass = 28000.0,\n\tmass = 2800.0", "'mass' = 2800.0 is assigned a second time (first at line 3: 28000.0)"),
    ("mass = 100.0, altitude = -Inf", "'altitude' = -Inf is not allowed (not a finite number)"),
    # a subnormal number passes "> 0"; as a stop time (deploy_time, break_time) it hung CVode
    # (test_line_airdrop.py)
    ("mass = 1.0e-310", "'mass' = 1.0e-310 is not allowed (a subnormal number, 0 < |x| < 2.2e-308"),
    # a three-digit exponent was printed without its E (es16.8): "-2.50000000-150", read as a difference
    ("mass = -2.5e-150", "mass = -2.50000000E-150 is not allowed (must be > 0 kg)"),
    # Fortran's namelist read would keep the second value without a word
    ("mass = 28000.0, drag_area = 10.0,\n mass = 2800.0",
     "'mass' = 2800.0 is assigned a second time (first at line 3: 28000.0)"),
])
def test_bad_input_gives_one_clear_line(airlaunch_exe, tmp_path, store, fragment):
    nml, out = drop_nml(tmp_path, store=store)
    res = run_airlaunch(airlaunch_exe, nml)
    assert res.returncode == 2
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1, res.stderr
    assert str(nml) in lines[0] and "&store" in lines[0]
    assert fragment in lines[0], lines[0]
    assert not out.exists() and not (tmp_path / "drop.nc.part").exists()


def test_vector_elements_once_each(airlaunch_exe, tmp_path):
    # Elements of a vector may be assigned one by one; the same element twice is an error.
    base = (ROOT / "input" / "line_catenary.nml").read_text()
    base = base.replace("output = 'output/line_catenary.nc'", f"output = '{tmp_path / 'c.nc'}'")
    base = base.replace("t_end = 60.0", "t_end = 0.5")
    ok = write(tmp_path / "ok.nml", base.replace("b_position = 80.0, 0.0, 0.0",
                                                 "b_position(1) = 80.0\n  b_position(2:3) = 0.0, 0.0"))
    res = run_airlaunch(airlaunch_exe, ok)
    assert res.returncode == 0, res.stderr
    bad = write(tmp_path / "bad.nml", base.replace("b_position = 80.0, 0.0, 0.0",
                                                   "b_position(1) = 80.0\n  b_position( 1 ) = 70.0"))
    res = run_airlaunch(airlaunch_exe, bad)
    assert res.returncode == 2
    assert len(res.stderr.strip().splitlines()) == 1, res.stderr
    assert f"{bad}:25: &line_scene: 'b_position(1)' = 70.0 is assigned a second time (first at line 24: 80.0)" \
        in res.stderr, res.stderr
    # an element the whole vector (or a range) sets too, in either order (before the twenty-sixth
    # session accepted: the later assignment won silently)
    for text, second, first in [
            ("b_position = 80.0, 0.0, 0.0\n  b_position(2) = -1.0", "'b_position(2)' = -1.0",
             "b_position = 80.0, 0.0, 0.0"),
            ("b_position(2) = -1.0\n  b_position = 80.0, 0.0, 0.0", "'b_position' = 80.0, 0.0, 0.0",
             "b_position(2) = -1.0"),
            ("b_position(1:2) = 80.0, 0.0\n  b_position(2:3) = -1.0, 0.0", "'b_position(2:3)' = -1.0, 0.0",
             "b_position(1:2) = 80.0, 0.0")]:
        bad = write(tmp_path / "overlap.nml", base.replace("b_position = 80.0, 0.0, 0.0", text))
        res = run_airlaunch(airlaunch_exe, bad)
        assert res.returncode == 2 and len(res.stderr.strip().splitlines()) == 1, res.stderr
        assert f"{bad}:25: &line_scene: {second} is assigned a second time (first at line 24: {first})" \
            in res.stderr, res.stderr


def test_an_unquoted_path_is_named_as_such(airlaunch_exe, tmp_path):
    """`output = /tmp/x.nc`: the / of an unquoted path would end the group; the
    error names the variable and the quoting (before the twenty-sixth session:
    'text outside a namelist group: tmp/x.nc ...')."""
    out = tmp_path / "drop.nc"
    nml = write(tmp_path / "unquoted.nml", f"&run scene = 'drop', t_end = 30.0, output = {out} /\n"
                                           "&store mass = 28000.0, drag_area = 10.0 /\n")
    res = run_airlaunch(airlaunch_exe, nml)
    assert_input_error(res, f"unquoted.nml:1: &run: 'output' = {out} is not allowed: a string must be quoted "
                            f"('{out}'); an unquoted / ends the group", out)


def test_a_byte_order_mark_is_read_as_blanks(airlaunch_exe, tmp_path):
    """A UTF-8 byte-order mark (some Windows editors write one) before the
    first group: the file runs as without it (before the twenty-sixth
    session: 'text outside a namelist group' quoting the invisible mark)."""
    nml, out = drop_nml(tmp_path, t_end=1.0)
    marked = tmp_path / "marked.nml"
    marked.write_bytes(b"\xef\xbb\xbf" + nml.read_bytes().lstrip())
    res = run_airlaunch(airlaunch_exe, marked)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(out) as ds:
        assert float(ds["time"].values[-1]) == 1.0


def test_a_fractional_integer_is_named_as_such(airlaunch_exe, tmp_path):
    """n_seg = 15.5: 'not an integer (a whole number ...)', not the range of
    32-bit integers, which is kept for a whole number beyond it."""
    for value, fragment in [("15.5", "is not an integer (a whole number: no decimal point or exponent)"),
                            ("1e3", "is not an integer (a whole number: no decimal point or exponent)"),
                            ("99999999999", "is not an integer in [-2147483647, 2147483647]")]:
        out = tmp_path / "l.nc"
        nml = write(tmp_path / "frac.nml", f"&run scene = 'line', t_end = 1.0, output = '{out}' /\n"
                                           f"&line length = 60.0, n_seg = {value}, ea = 2.0e6, "
                                           "mass_per_length = 0.5 /\n&line_scene a_kind = 'fixed' /\n")
        assert_input_error(run_airlaunch(airlaunch_exe, nml), f"&line: variable 'n_seg' = {value} {fragment}", out)


def test_a_missing_closing_quote_is_found_on_its_line(airlaunch_exe, tmp_path):
    """`scene = 'drop` without its closing quote: named at its own line, as the
    sweep definitions' reader does (before the twenty-sixth session the next
    quote, lines later, closed it and the error came from there)."""
    out = tmp_path / "x.nc"
    nml = write(tmp_path / "quote.nml", f"&run\n  scene = 'drop\n  t_end = 1.0\n  output = '{out}'\n/\n"
                                        "&store mass = 1.0, drag_area = 1.0 /\n")
    assert_input_error(run_airlaunch(airlaunch_exe, nml), "quote.nml:2: &run: unterminated string 'drop (a quoted "
                       "value must end with its ' on the same line)", out)


@pytest.mark.parametrize("program, file, hint", [
    ("airlaunch", "sweep_paper.nml", "unknown group &sweep (allowed: run, flight, aircraft, bay, rocket, parachute, "
     "line, gust): this is a sweep definition, run by scripts/sweep (docs/sweep.md)"),
    ("airlaunch", "criteria_paper.nml", "unknown group &criteria (allowed: run, flight, aircraft, bay, rocket, "
     "parachute, line, gust): this is a criteria file, named by a sweep's &sweep criteria (docs/sweep.md)"),
    ("airlaunch-sweep", "airlaunch_paper.nml", "unknown group &run (allowed: sweep, input, fixed): this looks like "
     "a scenario, run by airlaunch, or named as a sweep's &sweep base (docs/sweep.md)"),
    ("airlaunch-sweep", "line_airdrop.nml", "unknown group &run (allowed: sweep, input, fixed): this looks like "
     "a scenario"),
])
def test_another_kind_of_input_file_is_named(airlaunch_exe, tmp_path, program, file, hint):
    """The package's three kinds of input file (scenario, sweep definition,
    criteria) given to the wrong program: the one-line error says what the file
    is and where it goes."""
    res = subprocess.run([str(airlaunch_exe.parent / program), str(ROOT / "input" / file), "--check"],
                         capture_output=True, text=True, cwd=tmp_path, timeout=60)
    assert res.returncode == 2
    assert res.stderr.count("\n") == 1 and hint in res.stderr, res.stderr


def test_unknown_group_and_missing_file(airlaunch_exe, tmp_path):
    nml = write(tmp_path / "g.nml", "&run scene='drop' /\n&stor mass=1.0 /\n")
    res = run_airlaunch(airlaunch_exe, nml)
    assert res.returncode == 2 and "unknown group &stor" in res.stderr
    res = run_airlaunch(airlaunch_exe, tmp_path / "nope.nml")
    assert res.returncode == 2
    assert len(res.stderr.strip().splitlines()) == 1
    assert "nope.nml: file does not exist" in res.stderr


def test_plot_script_draws_the_demo_figure(airlaunch_exe, tmp_path):
    nml, out = drop_nml(tmp_path)
    assert run_airlaunch(airlaunch_exe, nml).returncode == 0
    fig = tmp_path / "drop.png"
    res = subprocess.run([sys.executable, str(ROOT / "postproc" / "plot_run.py"), str(out), str(fig)],
                         capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    assert fig.stat().st_size > 10000


def test_plot_script_names_what_it_cannot_draw_in_one_line(airlaunch_exe, tmp_path):
    """plot_run.py: a missing file, a file that is not netCDF, a netCDF file
    without a scene, an unwritable figure and bad arguments each give one line
    and exit 2 (before the twenty-sixth session: Python tracebacks of 15-41
    lines, exit 1, and exit 0 without a figure for an unknown scene); the
    default figure is OUTPUT.png beside the output, whatever dots the
    directories have."""
    nml, out = drop_nml(tmp_path)
    assert run_airlaunch(airlaunch_exe, nml).returncode == 0
    text = tmp_path / "text.nc"
    text.write_text("not netCDF\n")
    bare = tmp_path / "bare.nc"
    xr.Dataset({"x": ("t", np.zeros(2))}).to_netcdf(bare)
    # a sweep's summary (one row per case) handed to plot_run, and a line-scene file without its
    # node positions: before, the first failed in the second's way, and the message quoted xarray's
    # whole KeyError ("variable "No variable named 'line_node_position'. Variables on the dataset
    # include [...]" is missing"; a new user's walkthrough)
    summary = tmp_path / "summary.nc"
    xr.Dataset({"status": ("case", np.zeros(2, dtype=np.int32))},
               attrs={"scene": "line", "sweep_name": "s", "n_cases": 2, "inputs": "line%ea"}).to_netcdf(summary)
    partial = tmp_path / "partial.nc"
    xr.Dataset({"time": ("time", np.zeros(2))}, attrs={"scene": "line"}).to_netcdf(partial)
    dotted = tmp_path / "dir.x"
    dotted.mkdir()
    (dotted / "run").write_bytes(out.read_bytes())

    def plot(*args):
        return subprocess.run([sys.executable, str(ROOT / "postproc" / "plot_run.py"), *map(str, args)],
                              capture_output=True, text=True, timeout=120)
    for args, fragment in [((tmp_path / "missing.nc",), "missing.nc: no such file"),
                           ((text,), "text.nc: cannot read it as netCDF"),
                           ((bare,), "bare.nc: no figure for scene ''"),
                           ((summary,), "summary.nc: a sweep's file of 2 cases (its table, summary or envelope), "
                                        "not the output of one run"),
                           ((partial,), "partial.nc: variable 'line_node_position' is missing (an output written"),
                           ((out, tmp_path / "nodir" / "f.png"), "f.png: its directory"),
                           ((out, tmp_path / "f.xyz"), "f.xyz: no figure format 'xyz' (give a name ending in one of"),
                           ((), "usage: plot_run.py OUTPUT.nc [FIGURE.png]"),
                           ((out, "a.png", "b.png"), "usage: plot_run.py OUTPUT.nc [FIGURE.png]")]:
        res = plot(*args)
        assert res.returncode == 2, (args, res.stderr)
        assert res.stderr.count("\n") == 1 and fragment in res.stderr, (args, res.stderr)
    assert plot("--help").returncode == 0
    res = plot(dotted / "run")
    assert res.returncode == 0, res.stderr
    assert (dotted / "run.png").stat().st_size > 10000


@pytest.fixture
def small_disk(tmp_path):
    """A 64 KiB tmpfs at tmp_path/disk (mount needs root: skipped without it),
    unmounted at teardown."""
    disk = tmp_path / "disk"
    disk.mkdir()
    try:
        res = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(disk)],
                             capture_output=True, text=True, timeout=30)
    except OSError as exc:
        pytest.skip(f"no mount command ({exc.strerror})")
    if res.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here ({res.stderr.strip() or res.returncode})")
    try:
        yield disk
    finally:
        subprocess.run(["umount", str(disk)], check=True, timeout=30)


def fill_disk(disk, leave=0):
    """Fill `disk` with disk/fill until no block is left, then give `leave` bytes back."""
    with open(disk / "fill", "wb", buffering=0) as fh:
        try:
            while True:
                fh.write(b"\0" * 4096)
        except OSError:
            pass
    size = (disk / "fill").stat().st_size
    os.truncate(disk / "fill", max(size - leave, 0))


@pytest.mark.parametrize("leave", [0, 16384])
def test_plot_script_on_a_full_disk_leaves_no_figure(airlaunch_exe, tmp_path, small_disk, leave):
    """plot_run.py with no room for the figure (a 64 KiB tmpfs, completely full
    or with 16 KiB left for a figure of ~60 KiB): one line with the OS's reason,
    exit 2, and neither a figure under its name (QA found a 0-byte or a 16 KiB
    FIG.png left) nor the temporary it was written to; an
    older figure of that name is left as it was."""
    nml, out = drop_nml(tmp_path)
    assert run_airlaunch(airlaunch_exe, nml).returncode == 0
    old = small_disk / "old.png"
    old.write_bytes(b"an older figure")
    fill_disk(small_disk, leave)
    for fig in (small_disk / "fig.png", old):
        res = subprocess.run([sys.executable, str(ROOT / "postproc" / "plot_run.py"), str(out), str(fig)],
                             capture_output=True, text=True, timeout=120)
        assert res.returncode == 2, res.stderr
        assert res.stderr == f"plot_run: error: {fig}: cannot write the figure (No space left on device)\n"
    assert sorted(p.name for p in small_disk.iterdir()) == ["fill", "old.png"]
    assert old.read_bytes() == b"an older figure"


def test_missing_output_directory_is_an_input_error(airlaunch_exe, tmp_path):
    """The output directory is checked before the run (not found missing after
    it, with HDF5's error stack on stderr): one line naming the value and where
    it came from, exit 2, nothing written."""
    nml, _ = drop_nml(tmp_path)
    text = nml.read_text().replace(f"output = '{tmp_path / 'drop.nc'}'", f"output = '{tmp_path / 'no' / 'drop.nc'}'")
    nml.write_text(text)
    res = run_airlaunch(airlaunch_exe, nml)
    line = assert_input_error(res, f"its directory '{tmp_path / 'no'}' does not exist", tmp_path / "no" / "drop.nc")
    assert f"{nml}: &run: output" in line
    res = run_airlaunch(airlaunch_exe, nml, "--output", tmp_path / "none" / "x.nc")
    line = assert_input_error(res, "--output = ", tmp_path / "none" / "x.nc")
    assert "HDF5" not in res.stderr


@pytest.mark.parametrize("kind", ["empty", "too long", "trailing blank"])
def test_an_output_option_the_run_cannot_hold_is_an_input_error(airlaunch_exe, tmp_path, kind):
    """`--output ""` was ignored (the namelist's file written instead) and a path
    longer than the 256 characters &run output holds was cut silently (exit 0, a
    file under the first 256 characters); both are refused like the namelist's.
    So is a name ending in a blank, which Fortran's blank-padded name lost (an
    audit's `-o "out/trail.nc "` wrote and replaced out/trail.nc, exit 0)."""
    nml, _ = drop_nml(tmp_path)
    long = tmp_path / ("x" * (300 - len(str(tmp_path))) + ".nc")
    out, fragment = {"empty": ("", "--output needs a file name (it is empty)"),
                     "too long": (long, f"--output is {len(str(long))} characters long; at most 256 are allowed"),
                     "trailing blank": (f"{tmp_path / 'x.nc'} ", "ends with a blank, which the file name would lose")}[kind]
    res = run_airlaunch(airlaunch_exe, nml, "--output", out)
    assert_input_error(res, fragment, tmp_path / "drop.nc")
    assert not list(tmp_path.glob("x*"))


def test_the_longest_output_file_name_the_run_can_write(airlaunch_exe, tmp_path):
    """The run writes OUTPUT.part and holds OUTPUT.part.lock beside its output:
    a file name of 255 - 10 = 245 bytes (NAME_MAX of Linux's file systems) is
    the longest it can use, and it works, whole run; one of 246 is refused
    before the run, in one line giving the limit and why.  An audit found names
    from ~241 bytes refused with the reason cut off: the check's probe file,
    OUTPUT.probe-PID, was up to 14 bytes longer than the output."""
    nml, _ = drop_nml(tmp_path, t_end=1.0)
    ok = "b" * 242 + ".nc"
    res = run_airlaunch(airlaunch_exe, nml, "--output", ok, cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    assert (tmp_path / ok).is_file() and sorted(p.name for p in tmp_path.iterdir()) == sorted(["drop.nml", ok])
    bad = "b" * 243 + ".nc"
    res = run_airlaunch(airlaunch_exe, nml, "--output", bad, cwd=tmp_path)
    assert_input_error(res, "its file name is 246 bytes long; at most 245 are allowed (the run also writes it with "
                       "'.part' and '.part.lock' appended", tmp_path / bad)


@pytest.mark.parametrize("edit", [("edge_contact = 'bilateral'", "edge_contact = 'one_sided       bilateral'"),
                                  ("dynamics = 'free'", "dynamics = 'prescribed       junk'")])
def test_a_choice_longer_than_its_variable_is_an_input_error(airlaunch_exe, tmp_path, edit):
    """A choice longer than the 16 characters its variable holds was cut to its
    first 16 and then accepted ('one_sided       bilateral' ran as one_sided)."""
    old, new = edit
    nml = nml_variant(tmp_path, edits=[(r"^  " + re.escape(old) + ".*$", "  " + new)])
    name = old.split()[0]
    assert_input_error(run_airlaunch(airlaunch_exe, nml, "--output", tmp_path / "x.nc"),
                       f"'{name}' is {len(new.split(' = ')[1]) - 2} characters long; at most 16 are allowed",
                       tmp_path / "x.nc")


def test_a_listed_choice_longer_than_its_variable_is_an_input_error(airlaunch_exe, tmp_path):
    """Each item of &line coupling_by_phase holds 16 characters: a longer one was
    cut and accepted ('direct          rigidized' ran Case 0 as direct)."""
    nml = nml_variant(tmp_path, line=("  coupling = 'per_phase', coupling_by_phase = "
                                      "'direct          rigidized', 'direct', 'direct', 'direct'",))
    assert_input_error(run_airlaunch(airlaunch_exe, nml, "--output", tmp_path / "x.nc"),
                       "'coupling_by_phase' is 25 characters long; at most 16 are allowed", tmp_path / "x.nc")


def test_an_inflation_exponent_below_one_is_an_input_error(airlaunch_exe, tmp_path):
    """With j < 1 the filling rate d/dt ((t - t_d)/t_f)^j is infinite at the
    deployment, and so is the apparent mass's momentum force: the snatch run
    failed at t = 1.0 s with a step of 1e-16 s (j = 0.25, helper-36)."""
    nml = nml_variant(tmp_path, edits=[(r"^  inflation_exponent = .*$", "  inflation_exponent = 0.5"),
                                       (r"^  deploy_time = -1.0 .*$", "  deploy_time = 1.0")])
    assert_input_error(run_airlaunch(airlaunch_exe, nml, "--output", tmp_path / "x.nc"),
                       "inflation_exponent = 0.5 is not allowed (must be in [1.0, 8.0]", tmp_path / "x.nc")


@pytest.mark.parametrize("kind", ["directory", "directory/", "file as directory", "unwritable"])
def test_an_output_that_cannot_be_written_is_an_input_error(airlaunch_exe, tmp_path, kind):
    """An output naming a directory, inside a regular file or where no file can
    be created is refused before the run (exit 2, one line), not after the
    whole integration with exit 3, a vague HDF5 message and a stray .part file.
    /proc takes no new files even for root (CI runs as root, so a chmod'ed
    directory would not test this)."""
    nml, _ = drop_nml(tmp_path)
    out, fragment = {
        "directory": (tmp_path, "it names a directory"),
        "directory/": (f"{tmp_path}/", "it names a directory"),
        "file as directory": (nml / "x.nc", f"'{nml}' is not a directory"),
        "unwritable": ("/proc/airlaunch_test.nc", "no file can be written there"),
    }[kind]
    res = run_airlaunch(airlaunch_exe, nml, "--output", out)
    assert_input_error(res, fragment, tmp_path / "drop.nc")
    assert not list(tmp_path.glob("*.part")) and not list(tmp_path.glob(".part"))


@pytest.mark.parametrize("kind", ["device", "fifo", "the scenario file"])
def test_an_output_that_is_not_a_file_to_replace_is_an_input_error(airlaunch_exe, tmp_path, kind):
    """A device, a FIFO or the scenario file itself is refused before the run
    and left as it was: before the twenty-sixth session the program deleted
    /dev/null (as root) and wrote a regular HDF5 file in its place, blocked
    for good opening a FIFO, and replaced the scenario file by its output."""
    import os
    import stat
    nml, _ = drop_nml(tmp_path)
    text = nml.read_text()
    if kind == "device":
        out, fragment = "/dev/null", "it names a device, FIFO or socket, not a file"
    elif kind == "fifo":
        out, fragment = tmp_path / "fifo", "it names a device, FIFO or socket, not a file"
        os.mkfifo(out)
    else:
        out, fragment = nml, "it is the scenario file itself"
    res = subprocess.run([str(airlaunch_exe), str(nml), "--output", str(out)], capture_output=True, text=True,
                         timeout=60)
    assert_input_error(res, fragment, tmp_path / "drop.nc")
    if kind == "device":
        assert stat.S_ISCHR(os.stat("/dev/null").st_mode)
    elif kind == "fifo":
        assert stat.S_ISFIFO(os.stat(out).st_mode)
    assert nml.read_text() == text


def test_check_and_runs_leave_other_files_alone(airlaunch_exe, tmp_path):
    """The output's probe is a file of the process's own: --check removes no
    file ("No file is written or removed": it deleted an existing
    OUTPUT.part, another run's file in the making, before the twenty-sixth
    session) and a run leaves no probe behind; --output twice is refused."""
    nml, out = drop_nml(tmp_path)
    part = tmp_path / "drop.nc.part"
    part.write_text("another run's file\n")
    res = run_airlaunch(airlaunch_exe, nml, "--check")
    assert res.returncode == 0, res.stderr
    assert part.read_text() == "another run's file\n"
    part.unlink()
    res = run_airlaunch(airlaunch_exe, nml)
    assert res.returncode == 0, res.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["drop.nc", "drop.nml"]
    res = run_airlaunch(airlaunch_exe, nml, "-o", tmp_path / "a.nc", "--output", tmp_path / "b.nc")
    assert_input_error(res, "--output given more than once", tmp_path / "b.nc")


def test_an_older_output_that_cannot_be_removed_is_an_input_error(airlaunch_exe, tmp_path):
    """Another user's file under the output's name in a sticky directory
    cannot be removed: refused before the run.  Before the twenty-sixth
    session the run went on, lost its result at the rename and named the
    other user's file as its 'output so far'."""
    import os
    import shutil
    if os.geteuid() != 0 or shutil.which("setpriv") is None:
        pytest.skip("needs root and setpriv to run as another user")
    nobody = ["setpriv", "--reuid=65534", "--regid=65534", "--clear-groups"]
    if subprocess.run(nobody + [str(airlaunch_exe), "--version"], capture_output=True, timeout=60).returncode != 0:
        pytest.skip("the build is not reachable for another user (a clone in a private directory)")
    import tempfile
    # (pytest's tmp_path is under a directory only root may enter)
    with tempfile.TemporaryDirectory(dir="/tmp") as top:
        top = pathlib.Path(top)
        top.chmod(0o755)
        sticky = top / "sticky"
        sticky.mkdir()
        sticky.chmod(0o1777)
        old = sticky / "r.nc"
        old.write_text("root's file\n")
        old.chmod(0o600)
        nml, _ = drop_nml(top)
        nml.chmod(0o644)
        res = subprocess.run(nobody + [str(airlaunch_exe), str(nml), "--output", str(old)], capture_output=True,
                             text=True, timeout=60)
        assert res.returncode == 2, res.stderr
        assert len(res.stderr.strip().splitlines()) == 1
        assert "an older file of that name cannot be removed" in res.stderr
        assert old.read_text() == "root's file\n"
        assert sorted(p.name for p in sticky.iterdir()) == ["r.nc"]


@pytest.mark.parametrize("example, edits, records, limit_mb", [
    ("airlaunch_paper.nml", [(r"^  output_dt = 0.02 ", "  output_dt = 1.5e-6 ")], 10000002, 1024),
    ("line_pendulum.nml", [(r"^  output_dt = 0.005 ", "  output_dt = 1.0e-6 ")], 6000001, 1024),
    ("drop_demo.nml", [(r"^  output_dt = 0.1 ", "  output_dt = 6.1e-6 ")], 9836068, 300),
], ids=["airlaunch", "line", "drop"])
def test_more_records_than_memory_is_an_input_error(airlaunch_exe, tmp_path, example, edits, records, limit_mb):
    """An output cadence whose records (allocated before the run) do not fit
    in memory, here under an address-space limit (the records need 243 GB,
    5.6 GB and 630 MB; the program itself ~150 MB): one line naming
    output_dt, the record count and the memory, exit 2 (before the
    twenty-sixth session: exit 1 and a compiler backtrace)."""
    import resource
    nml = nml_variant(tmp_path, edits=edits, base=ROOT / "input" / example)
    out = tmp_path / "big.nc"

    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (limit_mb << 20, limit_mb << 20))
    res = subprocess.run([str(airlaunch_exe), str(nml), "--output", str(out)], capture_output=True, text=True,
                         timeout=120, preexec_fn=limit)
    line = assert_input_error(res, "&run: output_dt = ", out)
    assert f"is not allowed here: the trajectory's {records} records need " in line
    assert "more than can be allocated (raise output_dt, or set trajectory = .false.)" in line


def test_resolved_input_records_the_settings_used(airlaunch_exe, tmp_path):
    """The input echoed into the file is the one the run used: with --output
    the file's own name, and for the line scene the line scheme's default
    tolerances where &run does not set them (line.md section 4).  Run again
    from the echo, the line scene takes the same steps."""
    nml, _ = drop_nml(tmp_path, t_end=2.0)
    out = tmp_path / "elsewhere.nc"
    res = run_airlaunch(airlaunch_exe, nml, "--output", out)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(out) as ds:
        assert f'OUTPUT="{out}"' in ds.attrs["input_namelist"]
    line_nml = tmp_path / "line.nml"
    line_nml.write_text((ROOT / "input" / "line_catenary.nml").read_text().replace(
        "output = 'output/line_catenary.nc'", f"output = '{tmp_path / 'a.nc'}'"))
    assert "rtol" not in line_nml.read_text().split("&line")[0]
    res = run_airlaunch(airlaunch_exe, line_nml)
    assert res.returncode == 0, res.stderr
    steps = [l for l in res.stdout.splitlines() if l.startswith("end of run")][0].split(",")[1]
    with xr.open_dataset(tmp_path / "a.nc") as ds:
        echo = ds.attrs["input_namelist"]
    assert "RTOL=  1.0000000000000001E-005" in echo and "MAX_ORDER=2" in echo, echo[:400]
    again = tmp_path / "again.nml"
    again.write_text(echo.replace(str(tmp_path / "a.nc"), str(tmp_path / "b.nc")))
    res = run_airlaunch(airlaunch_exe, again)
    assert res.returncode == 0, res.stderr
    assert [l for l in res.stdout.splitlines() if l.startswith("end of run")][0].split(",")[1] == steps


@pytest.mark.parametrize("name", ["airlaunch_paper", "line_pendulum", "line_parachute", "line_fishhook",
                                  "line_opening", "line_airdrop", "line_snapback", "drop_demo",
                                  "airlaunch_gravity_drop"])
def test_check_prints_the_resolved_input_without_running(airlaunch_exe, tmp_path, name):
    """`--check` validates the input and prints it resolved (defaults included),
    exit 0, without running: no output file is written and an old one is left
    alone; for an air-launch scenario with the trim the run starts from.  The printed input is itself a valid scenario, and a fixed point: its
    own --check prints it again."""
    out = tmp_path / "x.nc"
    out.write_text("old")
    res = run_airlaunch(airlaunch_exe, ROOT / "input" / f"{name}.nml", "--check", "--output", out)
    assert res.returncode == 0, res.stderr
    assert res.stderr == ""
    assert res.stdout.startswith(f"! {ROOT / 'input' / name}.nml: valid input (airlaunch --check")
    if name.startswith("airlaunch"):   # the set-up's trim, as the run prints it
        run = run_airlaunch(airlaunch_exe, ROOT / "input" / f"{name}.nml", "--output", tmp_path / "run.nc")
        assert res.stdout.splitlines()[1] == "! " + run.stdout.splitlines()[0]
    assert f'OUTPUT="{out}"' in res.stdout and "&RUN" in res.stdout
    assert out.read_text() == "old" and not list(tmp_path.glob("*.part"))
    again = write(tmp_path / "resolved.nml", res.stdout)
    res2 = run_airlaunch(airlaunch_exe, again, "--check")
    assert res2.returncode == 0, res2.stderr
    assert res2.stdout.splitlines()[1:] == res.stdout.splitlines()[1:]


@pytest.mark.parametrize("value", ['a "b" c.nc', 'ünï\'cödé ""q"".nc', '  lead "x".nc', 'tail " .nc   ',
                                   '"q" ".nc', "it's a \"\" .nc"])
def test_a_string_value_round_trips_through_the_resolved_input(airlaunch_exe, tmp_path, value):
    """A string value with blanks next to its quotes, apostrophes, non-ASCII
    letters or leading blanks is echoed as it was given (QA found the echo
    dropping the blank before a doubled quote:
    output 'a "b" c.nc' was echoed "a""b"" c.nc", and the echo, run again,
    wrote another file).  Trailing blanks are padding to Fortran, in the
    value as in the file name.  The --check print run again prints the same,
    the run writes the file named, and its input_namelist holds the value."""
    quoted = '"' + value.rstrip().replace('"', '""') + '"'
    nml = write(tmp_path / "s.nml", f"&run scene = 'drop', t_end = 0.5, output_dt = 0.05,\n"
                                    f"  output = {quoted.ljust(len(quoted) + len(value) - len(value.rstrip()))} /\n"
                                    "&store mass = 28000.0 /\n")
    res = run_airlaunch(airlaunch_exe, nml, "--check", cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    assert f" OUTPUT={quoted}," in res.stdout.splitlines(), res.stdout
    again = write(tmp_path / "resolved.nml", res.stdout)
    res2 = run_airlaunch(airlaunch_exe, again, "--check", cwd=tmp_path)
    assert res2.returncode == 0, res2.stderr
    assert res2.stdout.splitlines()[1:] == res.stdout.splitlines()[1:]
    run = run_airlaunch(airlaunch_exe, again, cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["s.nml", "resolved.nml", value.rstrip()])
    with xr.open_dataset(tmp_path / value.rstrip()) as ds:
        assert f" OUTPUT={quoted}," in ds.attrs["input_namelist"].splitlines()


def test_an_output_option_with_quotes_is_echoed_as_given(airlaunch_exe, tmp_path):
    """QA's case: --output 'a "b" c.nc' on the command line; the --check print,
    run, writes `a "b" c.nc` (it wrote `a"b" c.nc`)."""
    res = run_airlaunch(airlaunch_exe, ROOT / "input" / "drop_demo.nml", "-o", 'a "b" c.nc', "--check",
                        cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    assert ' OUTPUT="a ""b"" c.nc",' in res.stdout.splitlines()
    echo = write(tmp_path / "echo1.nml", res.stdout.replace("T_END=  60.", "T_END=  0.5"))
    assert run_airlaunch(airlaunch_exe, echo, cwd=tmp_path).returncode == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ['a "b" c.nc', "echo1.nml"]


def test_check_reports_bad_input_like_a_run(airlaunch_exe, tmp_path):
    """Bad input under --check: the same one line and exit 2 as a run."""
    nml, out = drop_nml(tmp_path, store="mass = -5.0, drag_area = 10.0")
    res = run_airlaunch(airlaunch_exe, nml, "--check")
    assert_input_error(res, "&store: mass = -5.0 is not allowed", out)
    nml, out = drop_nml(tmp_path)
    res = run_airlaunch(airlaunch_exe, nml, "--check", "--output", tmp_path / "no" / "x.nc")
    assert_input_error(res, "its directory", out)


def test_resolved_paper_input_gives_the_same_run(airlaunch_exe, tmp_path):
    """The paper file and its --check print, run with trajectory output off, print
    the same milestones and step counts."""
    res = run_airlaunch(airlaunch_exe, ROOT / "input" / "airlaunch_paper.nml", "--check", "--output",
                        tmp_path / "p.nc")
    assert res.returncode == 0, res.stderr
    resolved = write(tmp_path / "resolved.nml", res.stdout.replace("TRAJECTORY=T", "TRAJECTORY=F"))
    original = nml_variant(tmp_path, "orig", edits=[(r"^(  output_dt = .*)$", r"\1\n  trajectory = .false.")])
    a = run_airlaunch(airlaunch_exe, original)
    b = run_airlaunch(airlaunch_exe, resolved)
    assert a.returncode == 0 and b.returncode == 0, (a.stderr, b.stderr)
    assert a.stdout == b.stdout


def test_file_without_final_newline_reads_like_one_with_it(airlaunch_exe, tmp_path):
    """gfortran's namelist read meets the end of the file at a last group's '/'
    with no newline after it (iostat -1, "End of file") although every value
    was read; editors write such files. Reference: the same file with the
    newline, whose result must be identical to the last printed digit."""
    nml, out = drop_nml(tmp_path, t_end=5.0)
    text = nml.read_text().strip()
    assert not text.endswith("\n")
    res_nl = run_airlaunch(airlaunch_exe, write(tmp_path / "nl.nml", text + "\n"))
    assert res_nl.returncode == 0, res_nl.stderr
    bare = write(tmp_path / "bare.nml", text)
    assert bare.read_bytes()[-1:] == b"/"
    res = run_airlaunch(airlaunch_exe, bare)
    assert res.returncode == 0, res.stderr
    assert res.stdout == res_nl.stdout
    # the error messages still point at the user's file and its lines
    bad = write(tmp_path / "bad.nml", text.replace("mass = 28000.0", "mass = -1.0"))
    res = run_airlaunch(airlaunch_exe, bad)
    assert res.returncode == 2 and f"{bad}: &store: mass = -1.0 is not allowed" in res.stderr, res.stderr


@pytest.mark.parametrize("old,new,fragment", [
    # 1e30 s / 0.05 s output times overflowed the record count (a crash, not a message)
    ("t_end = 30.0", "t_end = 1.0e30", "&run: t_end / output_dt = 1.00000000E+30 s / 0.05 s is not allowed"),
    ("output_dt = 0.05", "output_dt = 1.0e-30", "output times; at most 10000000: raise output_dt or shorten t_end"),
    ("t_end = 30.0", "t_end = 30.0, max_steps = -1",
     "&run: max_steps = -1 is not allowed (must be an integer in [0, 2147483647])"),
])
def test_run_limits_are_input_errors(airlaunch_exe, tmp_path, old, new, fragment):
    nml, out = drop_nml(tmp_path)
    text = nml.read_text()
    assert old in text
    nml.write_text(text.replace(old, new))
    assert_input_error(run_airlaunch(airlaunch_exe, nml), fragment, out)


def failed_paper_run(exe, tmp_path, name, edit, output_line):
    """The paper scenario with one edit and its output line replaced: it must
    fail numerically (exit 3); returns the input, the result, stderr's first line."""
    nml = nml_variant(tmp_path, name, edits=[edit, (r"^  output = .*$", output_line)])
    res = run_airlaunch(exe, nml)
    assert res.returncode == 3, res.stderr
    return nml, res, res.stderr.strip().splitlines()[0]


def test_step_budget_stops_a_run_that_cannot_progress(airlaunch_exe, tmp_path):
    """An infinitely stiff elevator loop (k_q = 1e30 rad per rad/s) chatters at
    the deflection limit: CVODE steps at ~5e-7 s and the 15 s run would take
    about two hours. With a step budget the run stops with one line naming the
    phase, the time, the step size and the state the integrator could not
    follow (the aircraft's pitch rate: body axis z), exit 3, and the output so
    far stays readable with status 'failed'."""
    out = tmp_path / "kq.nc"
    nml, res, first = failed_paper_run(airlaunch_exe, tmp_path, "kq", (r"^  k_q = .*$", "  k_q = 1.0e30"),
                                       f"  output = '{out}'\n  max_steps = 3000")
    # the loop is at rest in the trimmed Case 0 and starts chattering at the release
    # (with CVODE's own difference-quotient Jacobian, which lost the line's dashpot
    # at rest, it chattered from t = 0.17 s)
    assert first.startswith("airlaunch: error: phase 1 (extraction on the rail), t = 0.72") or \
        first.startswith("airlaunch: error: phase 1 (extraction on the rail): integration failed at t = 0.72"), first
    assert "the step budget is spent (3000 steps in total, &run max_steps)" in first, first
    assert "largest local error estimate in aircraft angular velocity z (body axes)" in first, first
    assert "step size " in first
    assert "separation (Case 2->3):     not reached" in res.stderr
    with xr.open_dataset(out) as ds:
        assert ds.attrs.get("status") == "failed"
        assert np.isfinite(ds["time"].values).all()
    # scripts/run passes the status on and draws the output so far
    out.unlink()
    run = subprocess.run([str(ROOT / "scripts" / "run"), str(nml)], capture_output=True, text=True, timeout=600)
    assert run.returncode == 3, run.stderr
    assert f"figure (of the output so far): {tmp_path / 'kq.png'}" in run.stdout, run.stdout
    assert (tmp_path / "kq.png").stat().st_size > 10000


def test_marching_step_count_is_checked_before_the_run(airlaunch_exe, tmp_path):
    """The paper's marching scheme takes t_end/dt fixed steps: more than the
    run's step budget is an input error naming dt, not hours of stepping."""
    out = tmp_path / "m.nc"
    nml = nml_variant(tmp_path, "m", base=ROOT / "input" / "line_pendulum.nml",
                      edits=[(r"^  output = .*$", f"  output = '{out}'"),
                             (r"^  b_kind = 'point_mass'$", "  b_kind = 'point_mass'\n  scheme = 'marching', dt = 1.0e-9")])
    assert_input_error(run_airlaunch(airlaunch_exe, nml),
                       "&line_scene: dt = 1.00000000E-09 s is not allowed with t_end = 6.0 s", out)


@pytest.mark.parametrize("value,count", [("80.0, 0.0", 2), ("80.0, 0.0, 0.0, 1.0", 4), ("2*80.0", 2)])
def test_a_whole_vector_takes_three_values(airlaunch_exe, tmp_path, value, count):
    """Fortran's read keeps the old z of `b_position = 80.0, 0.0` without a word,
    and stops at a fourth value with "Cannot match namelist object name"; both
    are one line naming the vector and the count. Repeat counts count
    (`3*0.0` is three values: the catenary input below runs with it)."""
    base = (ROOT / "input" / "line_catenary.nml").read_text()
    base = base.replace("output = 'output/line_catenary.nc'", f"output = '{tmp_path / 'c.nc'}'")
    base = base.replace("t_end = 60.0", "t_end = 0.5")
    assert "a_position = 0.0, 0.0, 0.0" in base and "b_position = 80.0, 0.0, 0.0" in base
    ok = write(tmp_path / "ok.nml", base.replace("a_position = 0.0, 0.0, 0.0", "a_position = 3*0.0"))
    res = run_airlaunch(airlaunch_exe, ok)
    assert res.returncode == 0, res.stderr
    bad = write(tmp_path / "bad.nml", base.replace("b_position = 80.0, 0.0, 0.0", f"b_position = {value}")
                .replace(str(tmp_path / "c.nc"), str(tmp_path / "bad.nc")))
    line = assert_input_error(run_airlaunch(airlaunch_exe, bad),
                              f"&line_scene: 'b_position' = {value} has {count} values; a vector of 3 (x, y, z) "
                              "is expected", tmp_path / "bad.nc")
    assert line.startswith(f"airlaunch: error: {bad}:")


def test_a_file_without_groups_is_named_as_such(airlaunch_exe, tmp_path):
    """An empty file (or one of comments) was read as all defaults and failed on
    the default output directory; now the message says what is wrong."""
    for text in ("", "! only a comment\n"):
        nml = write(tmp_path / "empty.nml", text)
        res = run_airlaunch(airlaunch_exe, nml)
        assert res.returncode == 2
        assert res.stderr.strip() == f"airlaunch: error: {nml}: no namelist group in the file (a group starts " \
            "with &name and ends with /, e.g. &run ... /)", res.stderr
    # a device was read for ever (/dev/zero), a directory said 'no namelist group'; since the
    # twenty-sixth session a device says what it is (it said 'no namelist group')
    res = run_airlaunch(airlaunch_exe, "/dev/zero")
    assert res.returncode == 2 and res.stderr.strip() == "airlaunch: error: /dev/zero: not a regular file (a " \
        "device, FIFO or socket: give the path of a namelist file)", res.stderr
    res = run_airlaunch(airlaunch_exe, tmp_path)
    assert res.returncode == 2 and res.stderr.strip() == f"airlaunch: error: {tmp_path}: is a directory (give the " \
        "path of a namelist scenario file)", res.stderr


def test_an_output_that_cannot_be_renamed_is_kept_as_part(airlaunch_exe, tmp_path):
    """A directory appears under the output's name during the run (after the
    checks): the final rename fails, and the complete output is kept as
    OUTPUT.part, named on stderr (before the twenty-sixth session it was
    deleted, and the program said 'no output written').  The line pendulum
    over 60 s: 2-4 s of integration, the directory made after 0.5 s."""
    import time
    nml = nml_variant(tmp_path, edits=[(r"^  t_end = 6.0 ", "  t_end = 60.0 ")], base=ROOT / "input" /
                      "line_pendulum.nml")
    out = tmp_path / "p.nc"
    proc = subprocess.Popen([str(airlaunch_exe), str(nml), "--output", str(out)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    time.sleep(0.5)
    if proc.poll() is not None:
        pytest.skip("the run ended within 0.5 s: no time to make the directory")
    out.mkdir()
    stdout, stderr = proc.communicate(timeout=300)
    assert proc.returncode == 3, stderr
    lines = stderr.strip().splitlines()
    assert f"cannot rename {out}.part to it; the complete output is kept as {out}.part" in lines[0], stderr
    assert lines[-1] == f"airlaunch: output kept as {out}.part (it could not be renamed)"
    with xr.open_dataset(f"{out}.part") as ds:
        assert ds.attrs["status"] == "completed" and float(ds["time"].values[-1]) == 60.0


def test_a_run_failing_before_its_first_record_leaves_no_old_file(airlaunch_exe, tmp_path):
    """An aircraft of 1e30 kg cannot be trimmed (Case 0): the run fails before
    writing anything. An older file under the same name (here a placeholder)
    must not survive to pass for this run's output, and the program must not
    point at it as 'output so far'."""
    out = tmp_path / "trim.nc"
    out.write_text("an older result")
    _, res, first = failed_paper_run(airlaunch_exe, tmp_path, "trim", (r"^  mass = 89000.0 .*$", "  mass = 1.0e30"),
                                     f"  output = '{out}'")
    assert first.startswith("airlaunch: error: Case 0 trim (t = 0 s): trim: no equilibrium found"), first
    assert "airlaunch: no output written (the run failed before its first record)" in res.stderr
    assert "output so far" not in res.stderr
    assert not out.exists()


@pytest.mark.parametrize("value,fragment", [
    (",", "'t_end' has no value (a namelist read would keep its default silently)"),
    ("1.0,,", "'t_end' = 1.0, is not allowed: it has a null value"),
    (", 1.0", "'t_end' = , 1.0 is not allowed: it has a null value"),
    ("2*", "'t_end' = 2* is not allowed: it has a null value"),
])
def test_a_null_value_is_an_input_error(airlaunch_exe, tmp_path, value, fragment):
    """Fortran's namelist read skips a null value (`t_end = ,`, `1.0,,`, `2*`) and
    keeps the variable's default without a word (tenth session: `t_end = ,` ran the
    scene's default end time); each is one line naming the variable. One separator after the
    last value is not a null value: `t_end = 0.5,` runs (0.5 s)."""
    out = tmp_path / "drop.nc"
    text = f"&run scene = 'drop', output_dt = 0.05, output = '{out}'\n  t_end = VALUE\n/\n&store mass = 28000.0 /\n"
    nml = write(tmp_path / "null.nml", text.replace("VALUE", value))
    assert_input_error(run_airlaunch(airlaunch_exe, nml), fragment, out)
    nml.write_text(text.replace("VALUE", "0.5,"))
    res = run_airlaunch(airlaunch_exe, nml)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(out) as ds:
        assert float(ds["time"].values[-1]) == pytest.approx(0.5)


def test_a_failed_drop_prints_its_summary_so_far(airlaunch_exe, tmp_path):
    """output.md: a failed run prints the summary so far after its error line (the
    drop scene printed none): the release and the last record, whose time and
    altitude are the file's last."""
    nml, out = drop_nml(tmp_path, run_extra=", max_steps = 20")
    res = run_airlaunch(airlaunch_exe, nml)
    assert res.returncode == 3, res.stderr
    lines = res.stderr.strip().splitlines()
    assert "step budget" in lines[0] and lines[1].startswith("release: altitude")
    last = re.search(r"last record at t = ([0-9.]+) s, altitude ([0-9.]+) m", res.stderr)
    with xr.open_dataset(out) as ds:
        assert ds.attrs["status"] == "failed"
        assert float(last.group(1)) == pytest.approx(float(ds["time"].values[-1]), abs=1e-9)
        assert float(last.group(2)) == pytest.approx(float(ds["store_position"].values[-1, 1]), rel=1e-9)


def test_drop_honours_trajectory_and_max_order(airlaunch_exe, tmp_path):
    """input.md: trajectory = .false. writes no file (the drop scene wrote one), and
    max_order is honoured (the drop scene ignored it)."""
    nml, out = drop_nml(tmp_path, run_extra=", trajectory = .false.")
    res = run_airlaunch(airlaunch_exe, nml)
    assert res.returncode == 0, res.stderr
    assert not out.exists() and "output:" not in res.stdout
    tracks = {}
    for order in (0, 1):
        nml, out = drop_nml(tmp_path, run_extra=f", max_order = {order}")
        res = run_airlaunch(airlaunch_exe, nml)
        assert res.returncode == 0, res.stderr
        with xr.open_dataset(out) as ds:
            tracks[order] = ds["store_position"].values.copy()
    # another integrator order: another numerical solution of the same fall (ignored,
    # the two runs were bit for bit the same), within 1e-3 of the 2.6 km travel (BDF
    # order 1 at rtol 1e-6 is the cruder one: measured 1.2 m, at the impact event)
    assert not np.array_equal(tracks[0], tracks[1])
    travel = np.abs(tracks[0][-1] - tracks[0][0]).max()
    assert np.abs(tracks[0] - tracks[1]).max() < 1e-3 * travel


@pytest.mark.parametrize("altitude,ok", [(46000.0, True), (46000.5, False)])
def test_store_altitude_stays_inside_the_atmosphere(airlaunch_exe, tmp_path, altitude, ok):
    """input.md: altitude in [0, 46000] m; 47 000 m (the atmosphere model's top) was
    accepted and every run failed at t = 0."""
    nml, out = drop_nml(tmp_path, store=f"mass = 28000.0, drag_area = 10.0, altitude = {altitude}", t_end=2.0)
    res = run_airlaunch(airlaunch_exe, nml)
    if ok:
        assert res.returncode == 0, res.stderr
    else:
        assert_input_error(res, f"altitude = {altitude}", out)


def test_help_names_every_documented_option(airlaunch_exe):
    """`airlaunch --help` names every option of the command line that
    docs/input.md documents ("The command line is ..."): the reference is the
    documentation, read here, not a copy of the usage text.  It once showed
    `--output FILE` and `--check` only."""
    text = (ROOT / "docs" / "input.md").read_text()
    m = re.search(r"The command line is (.*?)both print to stdout", text, re.S)
    assert m, "docs/input.md lost its command-line sentence"
    options = set(re.findall(r"(?<![\w-])(--?[a-zA-Z][\w-]*)", m.group(1)))
    assert {"-o", "--output", "--check", "-h", "--help", "-V", "--version"} <= options, options
    res = subprocess.run([str(airlaunch_exe), "--help"], capture_output=True, text=True, timeout=60)
    assert res.returncode == 0 and res.stderr == ""
    shown = set(re.findall(r"(?<![\w-])(--?[a-zA-Z][\w-]*)", res.stdout))
    assert options <= shown, f"--help does not name {sorted(options - shown)}"


def test_a_scenario_named_like_an_option_runs_after_a_double_dash(airlaunch_exe, tmp_path):
    """POSIX's `--` ends the options: a scenario file named `-drop.nml` is
    refused as an unknown option (the message says how to give it) and runs
    after `--`, with `-o` before it.  The run is checked against the
    parabola of a drop without drag, so the file read is the one named."""
    nml, _ = drop_nml(tmp_path, store="mass = 500.0, drag_area = 0.0", t_end=2.0,
                      run_extra=", rtol = 1e-11, atol = 1e-9")
    dashed = tmp_path / "-drop.nml"
    nml.rename(dashed)
    out = tmp_path / "dashed.nc"
    res = subprocess.run([str(airlaunch_exe), "-drop.nml"], capture_output=True, text=True, cwd=tmp_path,
                         timeout=60)
    assert res.returncode == 2 and res.stdout == "", res.stdout + res.stderr
    assert res.stderr.count("\n") == 1 and "unknown option -drop.nml" in res.stderr and " -- " not in res.stderr
    assert "goes after --" in res.stderr
    res = subprocess.run([str(airlaunch_exe), "-o", str(out), "--", "-drop.nml"], capture_output=True,
                         text=True, cwd=tmp_path, timeout=60)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(out) as ds:
        # as test_drop_without_drag_is_a_parabola: rtol 1e-11 on 1e4 m is far below 1e-3 m
        np.testing.assert_allclose(ds["store_position"].values[:, 1], 10000.0 - 0.5*G0*ds["time"].values**2,
                                   atol=1e-3)
    # after "--" an option is a file name: two scenario files
    res = subprocess.run([str(airlaunch_exe), "--", "-drop.nml", "--check"], capture_output=True, text=True,
                         cwd=tmp_path, timeout=60)
    assert res.returncode == 2 and "more than one scenario file given" in res.stderr


def test_a_line_break_in_a_name_keeps_messages_and_the_check_print_whole(airlaunch_exe, tmp_path):
    """A newline in a file name (legal on Linux) split the one-line error in
    two and made --check's print, whose first comment names the scenario,
    a file that does not read back; an --output name with a newline was
    echoed into a string no scenario can hold.  Now messages write it as \\n,
    the print reads back as a valid scenario, and such an --output is
    refused in one line (exit 2) before anything is written."""
    nml, out = drop_nml(tmp_path, t_end=1.0)
    odd = tmp_path / "drop\nfile.nml"
    nml.rename(odd)
    res = subprocess.run([str(airlaunch_exe), str(odd), "--check"], capture_output=True, text=True, timeout=60)
    assert res.returncode == 0, res.stderr
    assert res.stdout.splitlines()[0] == f"! {tmp_path}/drop\\nfile.nml: valid input (airlaunch --check; " \
        "resolved, defaults included; the run was not started)"
    printed = write(tmp_path / "printed.nml", res.stdout)
    res = subprocess.run([str(airlaunch_exe), str(printed), "--check"], capture_output=True, text=True, timeout=60)
    assert res.returncode == 0, res.stderr
    bad = tmp_path / "bad\nscene.nml"
    write(bad, "&run scene = 'bogus' /\n")
    res = subprocess.run([str(airlaunch_exe), str(bad)], capture_output=True, text=True, timeout=60)
    assert res.returncode == 2 and res.stderr.count("\n") == 1, res.stderr
    assert res.stderr.startswith(f"airlaunch: error: {tmp_path}/bad\\nscene.nml: &run: scene = 'bogus'"), res.stderr
    res = subprocess.run([str(airlaunch_exe), str(odd), "-o", str(tmp_path / "a\nb.nc")], capture_output=True,
                         text=True, timeout=60)
    assert res.returncode == 2 and res.stderr.count("\n") == 1, res.stderr
    assert "holds a line break" in res.stderr and "a\\nb.nc" in res.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["drop\nfile.nml", "printed.nml", "bad\nscene.nml"])


@pytest.mark.parametrize("old, new, hint", [
    ("cg_from_nose = 9.25", "cg = 9.25", "(did you mean 'cg_from_nose'?)"),
    ("fin_root_chord = ", "fin_root = ", "(did you mean one of 'fin_root_chord', 'fin_root_le_from_nose'?)"),
])
def test_a_name_cut_short_is_suggested_whole(airlaunch_exe, tmp_path, old, new, hint):
    """An unknown name that is the first word(s) of known ones suggests them
    (up to four): 'cg' for cg_from_nose had no suggestion, its edit distance
    being 10 (a new user's CG sweep, thirty-third session)."""
    nml = nml_variant(tmp_path, edits=[(r"^  " + re.escape(old), "  " + new)])
    assert_input_error(run_airlaunch(airlaunch_exe, nml, "--output", tmp_path / "x.nc"), hint, tmp_path / "x.nc")
