"""Bad input to the Python steps of a sweep (table, table --check, envelope) is
exit status 2 and one line on stderr naming file, group, variable and value,
never a traceback, and leaves no output or .part file: bytes that are not
UTF-8, sizes too big to draw, an unusable output directory, files that are not
the netCDF file asked for, a variable assigned twice, blanks inside quotes, an
empty output_dir, levels where no grid uses them, subnormal limits and an
unterminated string."""
import pathlib

import numpy as np
import pytest
import xarray as xr

from test_sweep_support import PAPER, SWEEP_EXE, run_python, run_sweep, small_definition

ONE_INPUT = "&input name = 'bay%release_time', distribution = 'uniform', lower = 0.4, upper = 1.0 /\n"
BIG = "1" + "0" * 400


def definition(tmp_path, text=None, name="d.nml", **kw):
    """A small sweep definition (one uniform input, 6 cases) under tmp_path."""
    kw.setdefault("n_cases", 6)
    kw.setdefault("inputs", ONE_INPUT)
    path = small_definition(tmp_path / name, **kw)
    if text is not None:
        path.write_text(text(path.read_text()))
    return path


def assert_error(res, *words, tmp_path=None):
    """Exit status 2, exactly one line on stderr starting 'sweep: error:' with
    every word in it, no traceback, and no table, envelope or .part file."""
    assert res.returncode == 2, res.stdout + res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1, res.stderr
    assert lines[0].startswith("sweep: error: "), lines[0]
    for w in words:
        assert w in lines[0], (w, lines[0])
    if tmp_path is not None:
        left = [p for p in pathlib.Path(tmp_path).rglob("*")
                if p.name.endswith(".part") or p.name in ("table.nc", "envelope.nc")]
        assert not left, left
    return lines[0]


def table(tmp_path, path, *args):
    return run_python(["table", path, *args], tmp_path)


# 1. any byte in a namelist file --------------------------------------------

def test_latin1_comment_in_definition_and_criteria_just_works(tmp_path):
    d = definition(tmp_path)
    d.write_bytes("! caf\xe9: d\xe9finition\n".encode("latin-1") + d.read_bytes())
    res = table(tmp_path, d)
    assert res.returncode == 0 and not res.stderr, res.stderr
    assert (tmp_path / "out" / "table.nc").is_file()
    crit = tmp_path / "c.nml"
    crit.write_bytes("&criteria ! caf\xe9\n  min_clearance_m = 1.5 /\n".encode("latin-1"))
    res = run_python(["envelope", d, "--criteria", crit, "--summary", tmp_path / "none.nc"], tmp_path)
    # the criteria are read: the step goes on to the (missing) summary
    assert_error(res, "none.nc", "summary does not exist")


def test_binary_definition_is_one_line(tmp_path):
    d = definition(tmp_path)
    d.write_bytes(b"\x00\x01\xff" + d.read_bytes())
    assert_error(table(tmp_path, d), str(d), tmp_path=tmp_path)


# 2. sizes --------------------------------------------------------------------

@pytest.mark.parametrize("n", ["2147483648", "10000001", BIG])
def test_too_many_cases(tmp_path, n):
    d = definition(tmp_path, n_cases=n)
    assert_error(table(tmp_path, d), "&sweep", "n_cases = ", "is not allowed", "at most 10000000 cases",
                 tmp_path=tmp_path)


@pytest.mark.parametrize("levels,shown", [((1000, 1000, 1000), "1000 x 1000 x 1000"),
                                          ((65536, 65536, 1), "65536 x 65536 x 1")])
def test_too_big_grid(tmp_path, levels, shown):
    names = ("bay%release_time", "parachute%drag_area", "flight%mach")
    inputs = "".join(f"&input name = '{n}', distribution = 'uniform', lower = 0.5, upper = 0.7, levels = {k} /\n"
                     for n, k in zip(names, levels))
    d = definition(tmp_path, design="grid", inputs=inputs, text=lambda t: t.replace("n_cases = 6", ""))
    assert_error(table(tmp_path, d), "&input", f"levels = {shown}", "at most 10000000 cases", tmp_path=tmp_path)


def test_number_that_does_not_fit_a_float(tmp_path):
    d = definition(tmp_path, inputs=ONE_INPUT.replace("upper = 1.0", f"upper = {BIG}"))
    assert_error(table(tmp_path, d), "&input #1 'bay%release_time'", "upper = ", "(401 digits)",
                 "finite real number", tmp_path=tmp_path)
    crit = tmp_path / "c.nml"
    crit.write_text(f"&criteria line_strength_n = {'9' * 350} /\n")
    res = run_python(["envelope", definition(tmp_path, name="ok.nml"), "--criteria", crit], tmp_path)
    assert_error(res, str(crit), "&criteria", "line_strength_n = ", "(350 digits)", "finite real number")


# 3. unusable output_dir ---------------------------------------------------

def test_output_dir_is_a_file(tmp_path):
    (tmp_path / "afile").write_text("x")
    d = definition(tmp_path, output_dir="afile")
    assert_error(table(tmp_path, d), str(d), "&sweep", "output_dir = 'afile'", "not a directory",
                 tmp_path=tmp_path)


@pytest.mark.parametrize("out", ["/proc/x", "d" * 300], ids=["unwritable", "too long"])
def test_output_dir_cannot_be_made(tmp_path, out):
    d = definition(tmp_path, output_dir=out)
    assert_error(table(tmp_path, d), "&sweep", f"output_dir = '{out}'", "is not usable", tmp_path=tmp_path)


def test_table_nc_is_a_directory(tmp_path):
    (tmp_path / "out" / "table.nc").mkdir(parents=True)
    d = definition(tmp_path)
    res = table(tmp_path, d)
    assert_error(res, "&sweep", "output_dir = 'out'", "table.nc is a directory")
    assert not list((tmp_path / "out").glob("table.nc*.part"))


# 4. files that are not the netCDF file asked for ------------------------------

@pytest.mark.parametrize("content", ["empty", "text", "truncated"])
def test_check_of_a_table_that_is_not_netcdf(tmp_path, content):
    d = definition(tmp_path)
    assert table(tmp_path, d).returncode == 0
    t = tmp_path / "out" / "table.nc"
    data = {"empty": b"", "text": b"not a table\n", "truncated": t.read_bytes()[:3000]}[content]
    t.write_bytes(data)
    assert_error(table(tmp_path, d, "--check"), "table.nc", "cannot read the case table", "not a netCDF file")


def summary_file(path, table_path, drop=()):
    """A small summary-shaped file of the table at table_path (its one input,
    design, seed and case count: the envelope step checks that the summary is
    that of the current table)."""
    with xr.open_dataset(table_path) as t:
        n = t.sizes["case"]
        ds = xr.Dataset({"bay%release_time": ("case", t["bay%release_time"].values),
                         "status": ("case", np.zeros(n, dtype=np.int32)),
                         "min_clearance_m": ("case", np.full(n, 5.0))}, coords={"case": np.arange(n)})
        ds.attrs.update(inputs="bay%release_time", design=t.attrs["design"], seed=t.attrs["seed"],
                        n_cases=t.attrs["n_cases"])
    ds.drop_vars(list(drop)).to_netcdf(path)
    return path


@pytest.mark.parametrize("which", ["table", "envelope", "no metric", "text"])
def test_envelope_of_a_file_that_is_not_a_summary(tmp_path, which):
    d = definition(tmp_path)
    crit = tmp_path / "c.nml"
    crit.write_text("&criteria min_clearance_m = 1.5 /\n")
    assert table(tmp_path, d).returncode == 0
    if which == "table":
        summary, words = tmp_path / "out" / "table.nc", ["variable 'status' is missing"]
    elif which == "envelope":
        good = summary_file(tmp_path / "summary.nc", tmp_path / "out" / "table.nc")
        res = run_python(["envelope", d, "--criteria", crit, "--summary", good, "--no-figures"], tmp_path)
        assert res.returncode == 0, res.stderr
        summary = tmp_path / "env.nc"
        (tmp_path / "out" / "envelope.nc").rename(summary)
        words = ["variable 'min_clearance_m' is missing"]
    elif which == "no metric":
        summary = summary_file(tmp_path / "s.nc", tmp_path / "out" / "table.nc", drop=["min_clearance_m"])
        words = ["variable 'min_clearance_m' is missing"]
    else:
        summary = tmp_path / "s.txt"
        summary.write_text("status = 0\n")
        words = ["cannot read the summary", "not a netCDF file"]
    res = run_python(["envelope", d, "--criteria", crit, "--summary", summary, "--no-figures"], tmp_path)
    assert_error(res, str(summary), *words)
    assert not (tmp_path / "out" / "envelope.nc").exists()
    assert not list(tmp_path.rglob("*.part"))


@pytest.mark.parametrize("change,words", [
    (dict(n_cases=8, seed=9), ["seed is 5 in the summary, 9 in the definition"]),
    (dict(design="sobol", n_cases=8), ["design is 'lhs' in the summary, 'sobol' in the definition"]),
    (dict(inputs=ONE_INPUT.replace("upper = 1.0", "upper = 1.2")),
     ["its values of bay%release_time are not those of out/table.nc"]),
], ids=["seed and cases", "design", "input values"])
def test_envelope_refuses_the_summary_of_another_sweep(tmp_path, change, words):
    """A summary.nc left by an earlier sweep in the same output_dir (e.g. a rerun
    with another n_cases and seed killed before its own summary) was evaluated
    as the current sweep's: 12 cases reported, exit 0. It is refused with one
    line; the summary of the current table is accepted."""
    d = definition(tmp_path)
    crit = tmp_path / "c.nml"
    crit.write_text("&criteria min_clearance_m = 1.5 /\n")
    assert table(tmp_path, d).returncode == 0
    summary_file(tmp_path / "out" / "summary.nc", tmp_path / "out" / "table.nc")
    res = run_python(["envelope", d, "--criteria", crit, "--no-figures"], tmp_path)
    assert res.returncode == 0, res.stderr
    assert "over 6 cases" in res.stdout
    (tmp_path / "out" / "envelope.nc").unlink()
    d = definition(tmp_path, **change)             # the definition edited, its table drawn again
    assert table(tmp_path, d).returncode == 0
    res = run_python(["envelope", d, "--criteria", crit, "--no-figures"], tmp_path)
    assert_error(res, f"out/summary.nc: the summary is not that of {d}", *words,
                 "a summary left by an earlier sweep? run airlaunch-sweep")
    assert not (tmp_path / "out" / "envelope.nc").exists()


# 5. a variable assigned twice ------------------------------------------------

def test_variable_assigned_twice_in_sweep(tmp_path):
    d = definition(tmp_path, text=lambda t: t.replace("  n_cases = 6\n", "  n_cases = 1\n  n_cases = 6\n"))
    line = assert_error(table(tmp_path, d), "&sweep", "'n_cases' = 6 is assigned a second time",
                        "(first at line 6: 1)", tmp_path=tmp_path)
    assert line.startswith(f"sweep: error: {d}:7: ")


def test_variable_assigned_twice_in_input_and_criteria(tmp_path):
    d = definition(tmp_path, inputs=ONE_INPUT.replace("lower = 0.4,", "lower = 0.32, lower = 0.5,"))
    assert_error(table(tmp_path, d), "&input", "'lower' = 0.5 is assigned a second time", "(first at line",
                 ": 0.32)", tmp_path=tmp_path)
    d = definition(tmp_path, name="ok.nml")
    crit = tmp_path / "c.nml"
    crit.write_text("&criteria min_clearance_m = 1 min_clearance_m = 2 /\n")
    res = run_python(["envelope", d, "--criteria", crit], tmp_path)
    assert_error(res, f"{crit}:1: &criteria: 'min_clearance_m' = 2 is assigned a second time",
                 "(first at line 1: 1)")


def test_array_elements_are_different_variables(tmp_path):
    inputs = "&input name = 'flight%mach', distribution = 'list', values(1) = 0.6, values(2) = 0.7 /\n"
    d = definition(tmp_path, inputs=inputs)
    res = table(tmp_path, d)
    assert res.returncode == 0, res.stderr
    inputs = "&input name = 'flight%mach', distribution = 'list', values(1) = 0.6, values( 1 ) = 0.7 /\n"
    d = definition(tmp_path, inputs=inputs, output_dir="out2")
    assert_error(table(tmp_path, d), "'values(1)' = 0.7 is assigned a second time")


# 6. blanks inside quotes are part of the value --------------------------------

def test_leading_blank_in_a_string_is_kept(tmp_path):
    d = definition(tmp_path, extra_sweep="worst_by = ' min_clearance_m'")
    assert_error(table(tmp_path, d), "&sweep", "worst_by = ' min_clearance_m' is not allowed",
                 "one of: min_clearance_m", tmp_path=tmp_path)
    crit = tmp_path / "c.nml"
    crit.write_text("&criteria min_clearance_m = 1 /\n")
    d = definition(tmp_path, name="c_blank.nml", extra_sweep="criteria = ' c.nml'")
    res = run_python(["envelope", d], tmp_path)
    assert_error(res, "sweep: error:  c.nml: file does not exist")


def test_a_directory_given_as_a_file_is_named_as_such(tmp_path):
    """A directory given as the criteria file or the summary was reported as
    "file does not exist" (an audit, thirtieth session); the line now says what
    is there."""
    d = definition(tmp_path)
    (tmp_path / "crit.d").mkdir()
    (tmp_path / "summary.d").mkdir()
    res = run_python(["envelope", d, "--criteria", tmp_path / "crit.d"], tmp_path)
    assert_error(res, "crit.d: is a directory, not a file (give the path of")
    crit = tmp_path / "c.nml"
    crit.write_text("&criteria min_clearance_m = 1 /\n")
    assert table(tmp_path, d).returncode == 0
    res = run_python(["envelope", d, "--criteria", crit, "--summary", tmp_path / "summary.d"], tmp_path)
    assert_error(res, "summary.d: is a directory, not a file (run airlaunch-sweep first)")


# 7. empty output_dir ---------------------------------------------------------

def test_empty_output_dir(tmp_path):
    d = definition(tmp_path, output_dir="")
    assert_error(table(tmp_path, d), str(d), "&sweep", "output_dir = '' is not allowed",
                 "a directory, e.g. 'output/sweep_small'", tmp_path=tmp_path)


# 8. levels where no grid uses them ------------------------------------------

def test_levels_with_lhs(tmp_path):
    d = definition(tmp_path, inputs=ONE_INPUT.replace("upper = 1.0", "upper = 1.0, levels = 3"))
    assert_error(table(tmp_path, d), "&input #1 'bay%release_time'", "levels is not used by design = 'lhs'",
                 "only by design = 'grid'", tmp_path=tmp_path)


@pytest.mark.parametrize("levels", ["0", "3"])
def test_levels_with_lhs_refused_by_both_steps(tmp_path, levels):
    """levels = 0 given with design = 'lhs' is as much an error as 3 (sweep.md): the
    check step took 0 for 'not given' and accepted it while the table step refused."""
    d = definition(tmp_path, inputs=ONE_INPUT.replace("upper = 1.0", f"upper = 1.0, levels = {levels}"))
    assert_error(table(tmp_path, d), "levels is not used by design = 'lhs'", tmp_path=tmp_path)
    assert_check_refuses(tmp_path, d)


@pytest.mark.parametrize("where", ["input", "fixed"])
@pytest.mark.parametrize("name", ["run%scene", "run%output", "run%trajectory"])
def test_variables_the_sweep_sets_are_refused_by_both_steps(tmp_path, where, name):
    """sweep.md: the scene, the output and whether there is one are the sweep's; the
    check step refused them, the table step drew a table with them."""
    if where == "input":
        d = definition(tmp_path, inputs=f"&input name = '{name}', distribution = 'list', values = 1.0 /\n")
    else:
        d = definition(tmp_path, fixed=f"&fixed name = '{name}', value = \"'x'\" /")
    assert_error(table(tmp_path, d), f"name = '{name}' is not allowed: the sweep sets it", tmp_path=tmp_path)
    assert_check_refuses(tmp_path, d)


def test_empty_name_is_the_file_stem_in_both_steps(tmp_path):
    """sweep.md: name defaults to the definition's file name without extension, ''
    included - the check step did so and the table step wrote to output/sweep_."""
    d = definition(tmp_path, name="stemmed.nml", output_dir="",
                   text=lambda t: t.replace("name = 'small'", "name = ''").replace("  output_dir = ''\n", ""))
    res = table(tmp_path, d)
    assert res.returncode == 0, res.stderr
    assert (tmp_path / "output" / "sweep_stemmed" / "table.nc").is_file()
    if SWEEP_EXE.exists():
        res = run_sweep(d, tmp_path, None, "--check")
        assert res.returncode == 0, res.stderr


def test_levels_with_a_list(tmp_path):
    inputs = "&input name = 'flight%mach', distribution = 'list', values = 0.6, 0.7, levels = 2 /\n"
    d = definition(tmp_path, design="grid", inputs=inputs, text=lambda t: t.replace("n_cases = 6", ""))
    assert_error(table(tmp_path, d), "&input #1 'flight%mach'", "levels is not used by distribution = 'list'",
                 tmp_path=tmp_path)


# 9. subnormal limits ---------------------------------------------------------

def test_subnormal_line_strength(tmp_path):
    d = definition(tmp_path)
    crit = tmp_path / "c.nml"
    crit.write_text("&criteria line_strength_n = 1e-320 /\n")
    res = run_python(["envelope", d, "--criteria", crit], tmp_path)
    assert_error(res, str(crit), "&criteria", "line_strength_n = 1e-320 is not allowed", "subnormal")


def test_tiny_scale_gives_no_warning(tmp_path):
    d = definition(tmp_path)
    assert table(tmp_path, d).returncode == 0   # the summary must be that of the definition's table
    summary = summary_file(tmp_path / "s.nc", tmp_path / "out" / "table.nc")
    with xr.open_dataset(summary) as ds:
        ds = ds.load()
    ds["peak_line_tension_N"] = ("case", np.full(ds.sizes["case"], 1.0e5))
    ds.to_netcdf(tmp_path / "s2.nc")
    crit = tmp_path / "c.nml"
    crit.write_text("&criteria line_strength_n = 1e-300, line_safety_factor = 1e10 /\n")
    res = run_python(["envelope", d, "--criteria", crit, "--summary", tmp_path / "s2.nc", "--no-figures"],
                     tmp_path)
    assert res.returncode == 0 and not res.stderr, res.stderr


# 10. unterminated string ---------------------------------------------------

def test_unterminated_string(tmp_path):
    d = definition(tmp_path, text=lambda t: t.replace("name = 'small'", "name = 'small"))
    line = assert_error(table(tmp_path, d), "&sweep: unterminated string 'small", tmp_path=tmp_path)
    assert line.startswith(f"sweep: error: {d}:2: "), line
    assert "missing required value" not in line


# 11. what the Fortran reader refuses: the table step refuses it too ------------

def assert_check_refuses(tmp_path, path):
    """airlaunch-sweep --check refuses the same definition: exit 2, one line."""
    if not SWEEP_EXE.exists():
        return
    res = run_sweep(path, tmp_path, None, "--check")
    assert res.returncode == 2, res.stdout + res.stderr
    assert len(res.stderr.strip().splitlines()) == 1, res.stderr


LIST_INPUT = "&input name = 'flight%mach', distribution = 'list', values = {} /\n"


@pytest.mark.parametrize("group,var,edit,n,most", [
    ("sweep", "name", dict(text=lambda t: t.replace("name = 'small'", "name = '" + "s" * 257 + "'")), 257, 256),
    ("sweep", "criteria", dict(extra_sweep="criteria = '" + "c" * 300 + "'"), 300, 256),
    ("input", "name", dict(inputs=ONE_INPUT.replace("bay%release_time", "bay%" + "r" * 125)), 129, 128),
    # 'é' is two bytes of UTF-8: Fortran counts the bytes of the file
    ("input", "units", dict(inputs=ONE_INPUT.replace("/\n", ", units = '" + "é" * 65 + "' /\n")), 130, 128),
    ("input", "description", dict(inputs=ONE_INPUT.replace("/\n", ", description = '" + "d" * 1025 + "' /\n")),
     1025, 1024),
    ("fixed", "value", dict(fixed="&fixed name = 'line%n_seg', value = '" + "1" * 1025 + "' /"), 1025, 1024),
    ("fixed", "name", dict(fixed="&fixed name = 'line%" + "n" * 125 + "', value = '10' /"), 130, 128),
], ids=["sweep name", "criteria", "input name", "units utf-8", "description", "fixed value", "fixed name"])
def test_string_longer_than_the_fortran_variable(tmp_path, group, var, edit, n, most):
    d = definition(tmp_path, **edit)
    line = assert_error(table(tmp_path, d), f"&{group}: '{var}' is {n} characters long; at most {most} are allowed",
                        tmp_path=tmp_path)
    assert line.startswith(f"sweep: error: {d}:"), line
    assert_check_refuses(tmp_path, d)


def test_string_as_long_as_the_fortran_variable_is_accepted(tmp_path):
    d = definition(tmp_path, inputs=ONE_INPUT.replace("/\n", ", units = '" + "é" * 64 + "' /\n"))
    res = table(tmp_path, d)
    assert res.returncode == 0, res.stderr


@pytest.mark.parametrize("edit,var,n", [
    (dict(inputs=LIST_INPUT.format("0.6, 4096*0.7")), "values", 4097),
    (dict(inputs=LIST_INPUT.format("100000000*0.7")), "values", 100000000),
    (dict(extra_sweep="keep_ids = 4097*1"), "keep_ids", 4097),
], ids=["values", "values 1e8 (counted, not expanded)", "keep_ids"])
def test_list_longer_than_the_fortran_array(tmp_path, edit, var, n):
    d = definition(tmp_path, **edit)
    assert_error(table(tmp_path, d), f"'{var}' has {n} values; at most 4096 are allowed", tmp_path=tmp_path)
    assert_check_refuses(tmp_path, d)


@pytest.mark.parametrize("values,words", [
    ("4294967296*0.7", ["variable 'values' = 4294967296*0.7 is not a list of real numbers"]),
    ("0*0.7, 0.8", ["variable 'values' = 0*0.7, 0.8 is not a list of real numbers"]),
    ("0.7, +, 0.8", ["variable 'values' = 0.7, +, 0.8 is not a list of real numbers"]),
])
def test_list_with_a_bad_repeat_count_or_a_lone_sign(tmp_path, values, words):
    d = definition(tmp_path, inputs=LIST_INPUT.format(values))
    assert_error(table(tmp_path, d), "&input", *words, tmp_path=tmp_path)
    assert_check_refuses(tmp_path, d)


@pytest.mark.parametrize("index", ["0", "4097", "100000000"])
def test_list_index_beyond_the_fortran_array(tmp_path, index):
    inputs = f"&input name = 'flight%mach', distribution = 'list', values({index}) = 0.7 /\n"
    d = definition(tmp_path, inputs=inputs)
    assert_error(table(tmp_path, d), f"'values({index})' = 0.7 is not allowed", "at most 4096 values",
                 tmp_path=tmp_path)
    assert_check_refuses(tmp_path, d)


@pytest.mark.parametrize("edit,var,value", [
    (dict(extra_sweep="keep_worst = 4294967296"), "keep_worst", "4294967296"),
    (dict(text=lambda t: t.replace("seed = 5", "seed = 2147483648")), "seed", "2147483648"),
    (dict(inputs=ONE_INPUT.replace("/\n", ", levels = 4294967296 /\n")), "levels", "4294967296"),
    (dict(extra_sweep="keep_worst = " + BIG), "keep_worst", BIG),
])
def test_integer_beyond_32_bits(tmp_path, edit, var, value):
    d = definition(tmp_path, **edit)
    assert_error(table(tmp_path, d), f"variable '{var}' = {value} is not an integer in [-2147483647, 2147483647]",
                 tmp_path=tmp_path)
    assert_check_refuses(tmp_path, d)


def test_smallest_32_bit_integer_gets_the_range_message(tmp_path):
    d = definition(tmp_path, extra_sweep="keep_worst = -2147483648")
    assert_error(table(tmp_path, d), "keep_worst = -2147483648 is not allowed (must be >= 0)", tmp_path=tmp_path)
    assert_check_refuses(tmp_path, d)


@pytest.mark.parametrize("edit,shown", [
    (dict(inputs=ONE_INPUT.replace("release_time", "reléase_time")), "&input #1 'bay%reléase_time': "
                                                                        "name = 'bay%reléase_time'"),
    (dict(inputs=ONE_INPUT.replace("release_time", "release_\u212aime")), "name = 'bay%release_\u212aime'"),
    (dict(fixed="&fixed name = 'line%n_ség', value = '10' /"), "&fixed #1: name = 'line%n_ség'"),
], ids=["input é", "input Kelvin sign (lower() gives k)", "fixed é"])
def test_name_with_non_ascii_letters(tmp_path, edit, shown):
    d = definition(tmp_path, **edit)
    assert_error(table(tmp_path, d), shown, "is not allowed (write group%variable", tmp_path=tmp_path)
    assert_check_refuses(tmp_path, d)


@pytest.mark.parametrize("edit,line,shown", [
    (lambda t: "garbage text\n" + t, 1, "'garbage text &sweep'"),
    (lambda t: t.replace("/\n&fixed", "/\ngarbage text\n&fixed"), 12, "'garbage text &fixed n'"),
    (lambda t: t + "garbage text\n", 15, "'garbage text'"),
    (lambda t: t.replace("/\n&fixed", "/ garbage text ! a comment\n&fixed"), 11, "'garbage text &fixed n'"),
], ids=["before", "between", "after", "after / on its line"])
def test_text_outside_a_group(tmp_path, edit, line, shown):
    d = definition(tmp_path, text=edit)
    res_line = assert_error(table(tmp_path, d), f"{d}:{line}: text outside a namelist group: {shown} "
                            "(groups start with &name and end with /)", tmp_path=tmp_path)
    assert "!" not in res_line
    assert_check_refuses(tmp_path, d)


@pytest.mark.parametrize("edit,words", [
    (lambda t: t.replace("&sweep", "$sweep").replace("\n/\n&fixed", "\n$end\n&fixed"),
     [":12: group &sweep is not closed with / before the next group"]),
    (lambda t: t.replace("&", "$").replace("/\n", "$end\n"), [":1: group &sweep is not closed (end it with /)"]),
], ids=["$sweep $end", "all $ groups"])
def test_dollar_groups_are_not_closed(tmp_path, edit, words):
    d = definition(tmp_path, text=edit)
    assert_error(table(tmp_path, d), *words, tmp_path=tmp_path)
    assert_check_refuses(tmp_path, d)


def test_whole_definition_on_one_line_is_accepted(tmp_path):
    d = definition(tmp_path, text=lambda t: " ".join(t.split("\n")))
    assert "\n" not in d.read_text()
    res = table(tmp_path, d)
    assert res.returncode == 0 and not res.stderr, res.stderr
    if SWEEP_EXE.exists():
        res = run_sweep(d, tmp_path, None, "--check")
        assert res.returncode == 0, res.stderr


@pytest.mark.parametrize("old,new,words", [
    ("n_cases = 6", "n_cases = +", ["&sweep: variable 'n_cases' = + is not an integer"]),
    ("t_end = 4.0", "t_end = -", ["&sweep: variable 't_end' = - is not a real number"]),
    ("progress_interval = 0.5", "progress_interval = -", ["variable 'progress_interval' = - is not a real number"]),
    ("t_end = 4.0", "t_end = 2*4.0", ["variable 't_end' = 2*4.0 is not a real number"]),
])
def test_lone_sign_is_one_line(tmp_path, old, new, words):
    d = definition(tmp_path, text=lambda t: t.replace(old, new))
    assert_error(table(tmp_path, d), *words, tmp_path=tmp_path)
    if new == "n_cases = +":
        # airlaunch-sweep refuses it too (it reads '+' as no value: "missing
        # required value n_cases"); it accepts t_end = - and progress_interval = -
        assert_check_refuses(tmp_path, d)


def test_lone_sign_in_criteria_is_one_line(tmp_path):
    d = definition(tmp_path)
    crit = tmp_path / "c.nml"
    crit.write_text("&criteria min_clearance_m = +\n  line_strength_n = 1e5 /\n")
    res = run_python(["envelope", d, "--criteria", crit], tmp_path)
    assert_error(res, f"{crit}:1: &criteria: variable 'min_clearance_m' = + is not a real number")


def test_unquoted_string_and_control_character(tmp_path):
    d = definition(tmp_path, text=lambda t: t.replace("design = 'lhs'", "design = lhs"))
    assert_error(table(tmp_path, d), "&sweep: variable 'design' = lhs is not a quoted string", tmp_path=tmp_path)
    assert_check_refuses(tmp_path, d)
    d = definition(tmp_path, name="vt.nml", text=lambda t: t.replace("name = 'small'", "name = \v'small'"))
    assert_error(table(tmp_path, d), "&sweep: variable 'name' = \\x0b'small' is not a quoted string",
                 tmp_path=tmp_path)


@pytest.mark.parametrize("value,words", [
    (",", ("&sweep", "'n_cases' has no value")),
    ("6,,", ("&sweep", "'n_cases' = 6, is not allowed: it has a null value")),
    ("2*", ("&sweep", "'n_cases' = 2* is not allowed: it has a null value")),
])
def test_null_value_in_the_definition(tmp_path, value, words):
    """A null value (`n_cases = ,`, `6,,`, `2*`) is skipped by a namelist read,
    which keeps the default without a word (tenth session); both steps refuse it
    with one line."""
    d = definition(tmp_path, text=lambda t: t.replace("  n_cases = 6\n", f"  n_cases = {value}\n"))
    assert_error(table(tmp_path, d), *words, tmp_path=tmp_path)
    assert_check_refuses(tmp_path, d)


def test_null_fixed_value_is_refused_by_the_check(tmp_path):
    """`&fixed value = ','` puts a null value into every case's namelist: the check
    step names it, reading the base scenario's variables (the table step asks
    it: section 14)."""
    d = definition(tmp_path, fixed="&fixed name = 'run%max_steps', value = ',' /")
    if not SWEEP_EXE.exists():
        pytest.skip("airlaunch-sweep not built")
    res = run_sweep(d, tmp_path, None, "--check")
    assert res.returncode == 2, res.stdout + res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "&run: 'max_steps' has no value" in lines[0], res.stderr


# 12. the base scenario: an existing regular file, for both steps -------------

@pytest.mark.parametrize("base,why", [("nope.nml", "does not exist"), ("adir", "is a directory")],
                         ids=["missing", "directory"])
def test_base_that_is_not_a_file(tmp_path, base, why):
    """A missing base or a directory passed the table step (exit 0, table.nc
    written) and the check step named neither the definition nor &sweep base.
    Both steps now refuse it with the same line; relative paths are taken from
    the current directory by both."""
    (tmp_path / "adir").mkdir()
    d = definition(tmp_path, text=lambda t: t.replace(f"base = '{PAPER}'", f"base = '{base}'"))
    assert f"base = '{base}'" in d.read_text()
    words = (f"{d}: &sweep: base = '{base}' is not allowed: the file {why} (allowed: an existing regular file, "
             "the base scenario; a relative path is taken from the current directory)")
    line = assert_error(table(tmp_path, d), words, tmp_path=tmp_path)
    assert line == "sweep: error: " + words
    if SWEEP_EXE.exists():
        res = run_sweep(d, tmp_path, None, "--check")
        assert res.returncode == 2, res.stdout + res.stderr
        assert res.stderr.strip().splitlines() == ["airlaunch-sweep: error: " + words], res.stderr


def test_relative_base_is_taken_from_the_current_directory(tmp_path):
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "b.nml").write_bytes(PAPER.read_bytes())
    d = definition(tmp_path, text=lambda t: t.replace(f"base = '{PAPER}'", "base = 'sub/b.nml'"))
    res = table(tmp_path, d)
    assert res.returncode == 0, res.stderr
    if SWEEP_EXE.exists():
        res = run_sweep(d, tmp_path, None, "--check")
        assert res.returncode == 0, res.stdout + res.stderr


# 13. indexed list elements: in order, one value each, no gaps (both steps) -----

ORDER_RULE = ("is not allowed: the elements of {v} are given one value each, in order and without gaps "
              "({v}({k}) is next), or as the whole list first ({v} = a, b, ...)")


def line_with(path, text):
    """The number of the (only) line of a file that contains text."""
    lines = [i + 1 for i, x in enumerate(pathlib.Path(path).read_text().splitlines()) if text in x]
    assert len(lines) == 1, lines
    return lines[0]


@pytest.mark.parametrize("values,shown,k", [
    ("values(2) = 0.5", "'values(2)' = 0.5", 1),                      # Python: 1 case; Fortran: "missing values"
    ("values(3) = 0.5, 0.7", "'values(3)' = 0.5, 0.7", 1),            # Python: 1 case, 0.7 dropped
    ("values(1) = 0.4, values(3) = 0.7", "'values(3)' = 0.7", 2),     # Python: error; Fortran: ok, 0.7 dropped
    ("values(2) = 0.7, values(1) = 0.6", "'values(2)' = 0.7", 1),     # out of order
    ("values(1) = 0.6, values = 0.7", "'values' = 0.7", 2),           # the whole list after an element
    ("values(1) = 2*0.6", "'values(1)' = 2*0.6", 1),                  # an element takes one value
], ids=["gap first", "element with two values", "gap", "out of order", "whole after element", "repeat"])
def test_indexed_list_elements_in_order_without_gaps(tmp_path, values, shown, k):
    """The table step (f90nml) and airlaunch-sweep read indexed list elements
    differently (values(2) = 0.5: one case here, 'missing required value values'
    there; values(1), values(3): the other way round, 0.7 dropped). Both now
    refuse a gap, an element out of order or an element given more than one
    value, with the same line."""
    d = definition(tmp_path, inputs=f"&input name = 'flight%mach', distribution = 'list', {values} /\n")
    want = f"{d}:{line_with(d, 'flight%mach')}: &input: {shown} " + ORDER_RULE.format(v="values", k=k)
    line = assert_error(table(tmp_path, d), tmp_path=tmp_path)
    assert line == "sweep: error: " + want
    if SWEEP_EXE.exists():
        res = run_sweep(d, tmp_path, None, "--check")
        assert res.returncode == 2, res.stdout + res.stderr
        assert res.stderr.strip().splitlines() == ["airlaunch-sweep: error: " + want], res.stderr


def test_indexed_keep_ids_follow_the_same_rule(tmp_path):
    d = definition(tmp_path, extra_sweep="keep_ids(2) = 1")
    want = f"{d}:{line_with(d, 'keep_ids')}: &sweep: 'keep_ids(2)' = 1 " + ORDER_RULE.format(v="keep_ids", k=1)
    assert assert_error(table(tmp_path, d), tmp_path=tmp_path) == "sweep: error: " + want
    if SWEEP_EXE.exists():
        res = run_sweep(d, tmp_path, None, "--check")
        assert res.stderr.strip().splitlines() == ["airlaunch-sweep: error: " + want], res.stderr


@pytest.mark.parametrize("values", ["values = 0.5, 0.6, values(3) = 0.7",
                                    "values(1) = 0.5, values(2) = 0.6, values(3) = 0.7"])
def test_indexed_list_elements_in_order_are_read_alike(tmp_path, values):
    """In order and without gaps, both steps take the same three values (the
    table holds exactly them; the check step accepts the table)."""
    d = definition(tmp_path, n_cases=9, inputs=f"&input name = 'flight%mach', distribution = 'list', {values} /\n")
    res = table(tmp_path, d)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(tmp_path / "out" / "table.nc") as t:
        assert sorted(set(t["flight%mach"].values)) == [0.5, 0.6, 0.7]
        np.testing.assert_array_equal(t["flight%mach"].attrs["values"], [0.5, 0.6, 0.7])
    if SWEEP_EXE.exists():
        res = run_sweep(d, tmp_path, None, "--check")
        assert res.returncode == 0 and "matches the definition" in res.stdout, res.stdout + res.stderr


@pytest.mark.parametrize("kind", ["input", "fixed"])
def test_t_end_of_the_sweep_and_of_an_input_or_fixed(tmp_path, kind):
    """&sweep t_end > 0 sets run%t_end in every case: an &input or &fixed of
    run%t_end beside it is refused by both steps before any case (before the
    twenty-sixth session --check passed it and every case was invalid input:
    't_end' assigned a second time)."""
    if kind == "input":
        d = definition(tmp_path, inputs=ONE_INPUT + "&input name = 'run%t_end', distribution = 'uniform', "
                                                    "lower = 3.0, upper = 6.0 /\n")
        words = ("&input #2 'run%t_end': run%t_end is also set by &sweep t_end", "leave &sweep t_end out")
    else:
        d = definition(tmp_path, fixed="&fixed name = 'run%t_end', value = '5.0' /")
        words = ("&fixed #1 'run%t_end': run%t_end is also set by &sweep t_end", "give it once")
    assert_error(table(tmp_path, d), *words, tmp_path=tmp_path)
    assert_check_refuses(tmp_path, d)
    res = run_sweep(d, tmp_path, None, "--check")
    assert words[0] in res.stderr, res.stderr


@pytest.mark.parametrize("edit,words", [
    ("fixed", ["its &fixed settings are not those the sweep ran: 'line%n_seg = 10' then, 'line%n_seg = 12' now"]),
    ("t_end", ["&sweep t_end = 5 s, the sweep ran 4 s"]),
    ("base", ["is not the text the sweep ran"]),
    ("distribution", ["out/table.nc: the values of bay%release_time are not those that",
                      "(definition changed since the table was made?)"]),
], ids=["fixed", "t_end", "base text", "distribution without a new table"])
def test_envelope_and_verify_refuse_a_summary_of_an_edited_definition(tmp_path, edit, words):
    """A finished sweep whose definition (or base scenario) was then edited:
    the envelope and verify steps refuse its summary in one line instead of
    evaluating (or verifying, against the new settings) the old cases (before
    the twenty-sixth session only the design, seed, case count and the input
    values against table.nc were compared)."""
    base = tmp_path / "base.nml"
    base.write_text(PAPER.read_text())
    d = definition(tmp_path, text=lambda t: t.replace(str(PAPER), str(base)))
    crit = tmp_path / "c.nml"
    crit.write_text("&criteria min_clearance_m = 1.5 /\n")
    assert table(tmp_path, d).returncode == 0
    res = run_sweep(d, tmp_path, None)
    assert res.returncode == 0, res.stderr
    res = run_python(["envelope", d, "--criteria", crit, "--no-figures"], tmp_path)
    assert res.returncode == 0, res.stderr
    text = d.read_text()
    if edit == "fixed":
        d.write_text(text.replace("value = '10'", "value = '12'"))
    elif edit == "t_end":
        d.write_text(text.replace("t_end = 4.0", "t_end = 5.0"))
    elif edit == "base":
        base.write_text(base.read_text() + "! edited after the sweep\n")
    else:
        d.write_text(text.replace("upper = 1.0", "upper = 1.2"))
    for step in (["envelope", d, "--criteria", crit, "--no-figures"], ["verify", d, "--criteria", crit]):
        res = run_python(step, tmp_path)
        assert_error(res, *words)


def test_keep_worst_ranks_a_clearance_never_reached_worst(tmp_path):
    """keep_worst by min_clearance_m: a computed case whose rocket never
    separated (clearance NaN, its margin failing in the envelope) is among the
    worst, before the smallest finite clearances, ties by id (before the
    twenty-sixth session it was skipped).  8 cases of 4 s with release times
    0.4-1.0 s: the late releases do not separate by 4 s."""
    d = definition(tmp_path, n_cases=8, extra_sweep="keep_worst = 4\n  worst_by = 'min_clearance_m'")
    assert table(tmp_path, d).returncode == 0
    res = run_sweep(d, tmp_path, None)
    assert res.returncode == 0, res.stderr
    with xr.open_dataset(tmp_path / "out" / "summary.nc") as s:
        ok = s["status"].values == 0
        clearance = s["min_clearance_m"].values
    never = [k for k in range(8) if ok[k] and np.isnan(clearance[k])]
    finite = sorted((clearance[k], k) for k in range(8) if ok[k] and not np.isnan(clearance[k]))
    assert 1 <= len(never) < 4 and finite, (never, finite)   # the test needs both kinds
    want = sorted(never + [k for _, k in finite[:4 - len(never)]])
    kept = sorted(int(p.stem.split("_")[1]) for p in (tmp_path / "out" / "trajectories").glob("case_*.nc"))
    assert kept == want


def test_a_distribution_beyond_double_precision_is_refused_by_the_table_step(tmp_path):
    """uniform over [-1.7e308, 1.7e308]: its width overflows and the draws are
    infinite; the table step refuses in one line and writes no table (before
    the twenty-sixth session it wrote Infinity values with a SciPy warning and
    exit 0, and airlaunch-sweep --check refused the table later)."""
    d = definition(tmp_path, inputs="&input name = 'bay%release_time', distribution = 'uniform', "
                                    "lower = -1.7e308, upper = 1.7e308 /\n")
    assert_error(table(tmp_path, d), "&input #1 'bay%release_time': the uniform distribution drew inf for case",
                 "beyond what double precision spans", tmp_path=tmp_path)


# 14. what airlaunch-sweep --check refuses, the table step refuses first ------

REAL_INPUT = "&input name = '{}', distribution = 'uniform', lower = 0.4, upper = 1.0 /\n"
CHECK_REFUSALS = {   # what the definition is given (small_definition's keywords), what the check says
    "unknown variable": ({"inputs": REAL_INPUT.format("bay%release_tme")}, "unknown variable 'release_tme'"),
    "unknown group": ({"inputs": REAL_INPUT.format("nosuch%release_time")}, "unknown group &nosuch"),
    "integer input drawn as reals": ({"inputs": "&input name = 'line%n_seg', distribution = 'uniform', "
                                                "lower = 8, upper = 12 /\n", "fixed": ""},
                                     "line%n_seg is an integer"),
    "fixed value of the wrong type": ({"fixed": "&fixed name = 'line%n_seg', value = \"'ten'\" /"},
                                      "'n_seg' = 'ten' is not an integer"),
    "null fixed value": ({"fixed": "&fixed name = 'run%max_steps', value = ',' /"}, "'max_steps' has no value"),
    "base of the drop scene": ({"base": "drop_demo.nml"}, "scene = 'drop' cannot be swept"),
}


def refused_definition(tmp_path, case, name="d.nml"):
    """The definition of CHECK_REFUSALS[case] (one uniform input, 6 cases, output_dir 'out')."""
    kw = dict(CHECK_REFUSALS[case][0])
    base = kw.pop("base", None)
    return definition(tmp_path, name=name, **kw,
                      text=base and (lambda t: t.replace(str(PAPER), str(PAPER.parent / base))))


def check_message(tmp_path, d, case):
    """The line airlaunch-sweep --check refuses d with (without its program's prefix)."""
    res = run_sweep(d, tmp_path, None, "--check")
    assert res.returncode == 2, res.stdout + res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("airlaunch-sweep: error: "), lines
    assert CHECK_REFUSALS[case][1] in lines[0], lines[0]
    return lines[0].removeprefix("airlaunch-sweep: error: ")


def files_under(path):
    return {str(p.relative_to(path)) for p in pathlib.Path(path).rglob("*") if p.is_file()}


@pytest.mark.parametrize("case", list(CHECK_REFUSALS))
def test_table_step_refuses_what_the_check_refuses(tmp_path, case):
    """Names the base scenario does not have, a value of the wrong type, a base
    the sweep cannot run: the table step wrote table.nc (exit 0) and only the
    check step refused the definition.  The table step now asks airlaunch-sweep
    --check before it writes: the check's line, exit 2, no table.nc and no
    file but the check's own scratch namelist (work/check_rank0.nml)."""
    d = refused_definition(tmp_path, case)
    line = assert_error(table(tmp_path, d), tmp_path=tmp_path)
    assert files_under(tmp_path / "out") <= {"work/check_rank0.nml"}, files_under(tmp_path / "out")
    assert line == "sweep: error: " + check_message(tmp_path, d, case)


@pytest.mark.parametrize("case", ["unknown variable", "fixed value of the wrong type"])
def test_a_refused_definition_keeps_no_earlier_table(tmp_path, case):
    """A valid definition's table, then a definition the check refuses with the
    same output_dir: the table step refuses it and leaves no table (the earlier
    one, which it replaces, goes first); table --check refuses the definition
    with the check's line even where the table is still the one it draws (the
    &fixed settings do not change the draw)."""
    d = refused_definition(tmp_path, case)
    message = check_message(tmp_path, d, case)
    assert table(tmp_path, definition(tmp_path, name="ok.nml")).returncode == 0
    assert (tmp_path / "out" / "table.nc").is_file()
    if case == "fixed value of the wrong type":
        line = assert_error(table(tmp_path, d, "--check"))   # before: "table: out/table.nc is the table of d.nml"
        assert line == "sweep: error: " + message
        assert (tmp_path / "out" / "table.nc").is_file()     # a check removes nothing
    line = assert_error(table(tmp_path, d), tmp_path=tmp_path)
    assert line == "sweep: error: " + message


def test_table_step_without_airlaunch_sweep_is_one_line(tmp_path):
    """One line naming the missing program; and an existing table stays: the
    step checks for the program before it removes the table it would replace
    (it removed it first, an audit found, thirtieth session)."""
    d = definition(tmp_path)
    assert_error(table(tmp_path, d, "--exe-dir", tmp_path / "nowhere"), "nowhere/airlaunch-sweep",
                 "no such program to check the definition with", "give --exe-dir", tmp_path=tmp_path)
    assert table(tmp_path, d).returncode == 0
    before = (tmp_path / "out" / "table.nc").read_bytes()
    assert_error(table(tmp_path, d, "--exe-dir", tmp_path / "nowhere"), "nowhere/airlaunch-sweep")
    assert (tmp_path / "out" / "table.nc").read_bytes() == before
