"""airlaunch-sweep's reading of a sweep definition at its limits (found by a fuzz
of the sweep inputs, ninth session): each case was accepted with a silently
changed value, or stopped with a message that named the wrong thing. Each now
stops before any case runs with one line naming the variable and what is
allowed (`--check`, exit 2); the valid forms next to them still pass."""
import pytest

from test_sweep_support import SMALL_INPUTS, SWEEP_EXE, make_table, run_sweep, small_definition


def _check(definition, tmp_path):
    if not SWEEP_EXE.exists():
        pytest.fail(f"{SWEEP_EXE} is missing: run scripts/setup release first")
    return run_sweep(definition, tmp_path, None, "--check")


def _one_line(res):
    lines = res.stderr.strip().splitlines()
    assert res.returncode == 2, res.stdout + res.stderr
    assert len(lines) == 1 and lines[0].startswith("airlaunch-sweep: error: "), res.stderr
    return lines[0]


@pytest.mark.parametrize("last", ["input", "fixed"])
def test_definition_without_final_newline(tmp_path, last):
    """The &input and &fixed groups are read in turn from one unit; with the
    last of them ending the file without a newline gfortran's read stopped with
    "End of file" (the table step, in Python, read it)."""
    definition = small_definition(tmp_path / "d.nml", n_cases=4)
    text = definition.read_text().strip()
    if last == "fixed":   # move the &fixed group to the end
        fixed = "&fixed name = 'line%n_seg', value = '10' /"
        text = text.replace(fixed, "").strip() + "\n" + fixed
    assert text.endswith("/") and text.splitlines()[-1].startswith(f"&{last}")
    definition.write_text(text)
    res = _check(definition, tmp_path)
    assert "End of file" not in res.stderr
    assert res.returncode == 0, res.stderr
    assert f"airlaunch-sweep: {definition}: ok: design lhs, 4 cases" in res.stdout, res.stdout


@pytest.mark.parametrize("change,words", [
    # strings longer than the reader's variable were cut off (a 300-character
    # output_dir became a 256-character one; a long &fixed value lost its end)
    (dict(output_dir="o" * 300), ["'output_dir' is 300 characters long; at most 256 are allowed"]),
    (dict(fixed="&fixed name = 'run%rtol', value = '" + "0" * 1100 + "1e-5' /"),
     ["'value' is 1104 characters long; at most 1024 are allowed"]),
    # an unquoted number for a string was taken as its text by Fortran (the table step refused it)
    (dict(extra_sweep="criteria = 1e30"), ["variable 'criteria' = 1e30 is not a quoted string"]),
    # lists longer than the reader's array: "Cannot match namelist object name 0.7"
    (dict(inputs="&input name = 'bay%release_time', distribution = 'list', values = 4500*0.7 /"),
     ["'values' has 4500 values; at most 4096 are allowed"]),
    (dict(extra_sweep="keep_ids = 5000*1"), ["'keep_ids' has 5000 values; at most 4096 are allowed"]),
    # a grid whose size overflowed a 32-bit integer (65536 x 65536 = 0 cases)
    (dict(design="grid", n_cases="", inputs=SMALL_INPUTS.replace("units = 's' /", "units = 's', levels = 65536 /")
          .replace("units = 'm2' /", "units = 'm2', levels = 65536 /").replace("std = 0.02 /", "std = 0.02, levels = 1 /")),
     ["design = 'grid' is not allowed with these levels", "more than 10000000 points"]),
    (dict(n_cases=2147483647), ["n_cases = 2147483647 is not allowed (at most 10000000)"]),
    (dict(n_cases=2147483648), ["variable 'n_cases' = 2147483648 is not an integer in [-2147483647, 2147483647]"]),
    # an empty output_dir meant the default here and the current directory in the table step
    (dict(output_dir=""), ["output_dir = '' is not allowed"]),
    # levels where nothing uses them (docs/sweep.md: a parameter a distribution does not use is an error)
    (dict(inputs=SMALL_INPUTS.replace("units = 's' /", "units = 's', levels = 3 /")),
     ["levels is not used with design = 'lhs' (only with 'grid')"]),
    (dict(design="grid", n_cases="", inputs="&input name = 'bay%release_time', distribution = 'list', "
          "values = 0.4, 0.6, levels = 2 /"),
     ["levels is not used by distribution = 'list'"]),
])
def test_definition_limits_are_one_line_errors(tmp_path, change, words):
    kw = dict(n_cases=4)
    kw.update(change)
    if kw.get("n_cases") == "":
        kw["n_cases"] = 1
        definition = small_definition(tmp_path / "d.nml", **kw)
        definition.write_text(definition.read_text().replace("  n_cases = 1\n", ""))
    else:
        definition = small_definition(tmp_path / "d.nml", **kw)
    line = _one_line(_check(definition, tmp_path))
    for w in words:
        assert w in line, (w, line)
    assert not (tmp_path / "out" / "journal").exists()


def test_definition_that_is_not_a_regular_file(tmp_path):
    """/dev/zero was read for ever and a FIFO waited for a writer (hangs); a
    directory said 'no namelist group'. Each is one line at once, naming what
    it is (since the twenty-sixth session: 'not a regular file', where both
    said 'no namelist group in the file'); so is a base scenario that is a
    device or a FIFO."""
    import os
    fifo = tmp_path / "fifo.nml"
    os.mkfifo(fifo)
    regular = "not a regular file (a device, FIFO or socket: give the path of a namelist file)"
    for path, words in (("/dev/zero", f"/dev/zero: {regular}"),
                        (fifo, f"{fifo}: {regular}"),
                        (tmp_path, f"{tmp_path}: is a directory")):
        line = _one_line(run_sweep(path, tmp_path, None, "--check", timeout=30))
        assert words in line, line
    definition = small_definition(tmp_path / "d.nml", n_cases=4)
    text = definition.read_text()
    for base in ("/dev/zero", fifo):
        definition.write_text(text.replace("base = '", f"base = '{base}' ! '"))
        line = _one_line(_check(definition, tmp_path))
        assert f"{base}: {regular}" in line, line


@pytest.mark.parametrize("change,words", [
    # the cases ran the airlaunch scene whatever run%scene said; their printed
    # namelists then failed on their own (unknown group &flight)
    (dict(fixed="&fixed name = 'run%scene', value = \"'line'\" /"),
     ["name = 'run%scene' is not allowed: the sweep sets it for every case"]),
    (dict(fixed="&fixed name = 'run%output', value = \"'x.nc'\" /"), ["name = 'run%output' is not allowed"]),
    # a leading blank is part of the string in both steps (the table step refused it, Fortran dropped it)
    (dict(inputs=SMALL_INPUTS.replace("name = 'bay%release_time'", "name = ' bay%release_time'")),
     ["name = ' bay%release_time' is not allowed (write group%variable"]),
])
def test_names_the_sweep_cannot_take(tmp_path, change, words):
    definition = small_definition(tmp_path / "d.nml", n_cases=4, **change)
    line = _one_line(_check(definition, tmp_path))
    for w in words:
        assert w in line, (w, line)


def test_output_dir_with_a_file_in_the_way(tmp_path):
    (tmp_path / "blocker").write_text("a file, not a directory")
    definition = small_definition(tmp_path / "d.nml", n_cases=4, output_dir="blocker/out")
    line = _one_line(_check(definition, tmp_path))
    assert f"{definition}: &sweep: output_dir = 'blocker/out' is not usable" in line, line
    assert "(a file in the way, or no permission)" in line


@pytest.mark.parametrize("args,words", [
    (["--case-namelist", "1,2"], "--case-namelist 1,2 is not allowed (a case id: an integer in [0, 999999999])"),
    (["--case-namelist", "0 0"], "--case-namelist 0 0 is not allowed"),
    (["--case-namelist", "2147483648"], "--case-namelist 2147483648 is not allowed"),
    (["--case-namelist", "0", "--case-namelist", "1"], "--case-namelist given twice"),
])
def test_case_namelist_takes_one_case_id(tmp_path, args, words):
    definition = small_definition(tmp_path / "d.nml", n_cases=4)
    line = _one_line(run_sweep(definition, tmp_path, None, *args))
    assert words in line, line


def _long_dir(n):
    """A relative directory name of n characters (two levels: a name holds at most 255)."""
    first = min(n - 2, 120)
    return "o" * first + "/" + "r" * (n - first - 1)


@pytest.mark.parametrize("n_cases,length,allowed", [(4, 229, 228), (4, 256, 228), (2000000, 228, 227)])
def test_output_dir_too_long_for_the_trajectories(tmp_path, n_cases, length, allowed):
    """An output_dir of 229-256 characters was accepted, and the kept
    trajectories (written through the single run's 256-character output)
    went to names cut short (trajectories/case_000004.n) while the sweep said
    "3 of the cases kept end before their first output record", exit 0. Now
    the definition check refuses it: one line naming the longest file and the
    limit (a case id of 7 digits needs one character more)."""
    od = _long_dir(length)
    definition = small_definition(tmp_path / "d.nml", n_cases=n_cases, output_dir=od, extra_sweep="keep_worst = 1")
    line = _one_line(_check(definition, tmp_path))
    assert f"&sweep: output_dir = '{od}' is not allowed: it is {length} characters long" in line, line
    digits = f"{n_cases - 1:06d}"
    assert f"<output_dir>/trajectories/case_{digits}.nc, would be {length + 22 + len(digits)} characters" in line
    assert f"holds at most 256 (allowed: an output_dir of at most {allowed} characters for {n_cases} cases)" in line
    assert not (tmp_path / od).exists()


def test_output_dir_without_kept_trajectories_is_not_limited_so(tmp_path):
    """A sweep that keeps no trajectory (no keep_failed, keep_worst, keep_ids)
    writes none through a single run's output: its output_dir may take the
    whole 256 characters (the review of the limit above)."""
    od = _long_dir(256)
    definition = small_definition(tmp_path / "d.nml", n_cases=4, output_dir=od)
    res = _check(definition, tmp_path)
    assert res.returncode == 0, res.stderr


def test_output_dir_at_the_limit_keeps_its_trajectories(tmp_path):
    """The longest output_dir allowed (228 characters with case ids of 6
    digits): the kept trajectories are written under their full names."""
    od = _long_dir(228)
    definition = small_definition(tmp_path / "d.nml", n_cases=4, output_dir=od, extra_sweep="keep_ids = 1, 3")
    make_table(definition, tmp_path)
    res = run_sweep(definition, tmp_path, None)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "trajectories: 2 written" in res.stdout, res.stdout
    assert "before their first output record" not in res.stdout, res.stdout
    traj = tmp_path / od / "trajectories"
    assert sorted(p.name for p in traj.iterdir()) == ["case_000001.nc", "case_000003.nc"]
