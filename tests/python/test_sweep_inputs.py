"""Bad sweep input stops everything before any case runs, with one clear line
and a nonzero status: unknown group or variable (of the sweep file or of the
scenario), reversed bounds, a negative standard deviation, zero cases, a
variable that cannot be varied, a bad fixed value, a missing table, a table
that does not match its definition."""
import pytest

from test_sweep_support import SWEEP_EXE, make_table, run_python, run_sweep, small_definition

GOOD_INPUT = "&input name = 'bay%release_time', distribution = 'uniform', lower = 0.4, upper = 1.0 /"

# (case name, how to break the good definition, words the message must contain)
BAD = [
    ("unknown scenario group", dict(inputs=GOOD_INPUT.replace("bay%", "bya%")),
     ["'bya%release_time'", "unknown group &bya"]),
    ("unknown scenario variable", dict(inputs=GOOD_INPUT.replace("release_time", "relase_time")),
     ["unknown variable 'relase_time' in &bay", "did you mean 'release_time'"]),
    ("reversed bounds", dict(inputs=GOOD_INPUT.replace("lower = 0.4, upper = 1.0", "lower = 1.0, upper = 0.4")),
     ["upper = 0.4 is not allowed", "reversed"]),
    ("negative std", dict(inputs="&input name = 'flight%mach', distribution = 'normal', mean = 0.65, std = -0.02 /"),
     ["std = -0.02 is not allowed", "must be > 0"]),
    ("zero cases", dict(n_cases=0), ["n_cases = 0 is not allowed", "zero cases"]),
    ("string variable", dict(inputs="&input name = 'aircraft%control', distribution = 'list', values = 1, 2 /"),
     ["aircraft%control is a string variable"]),
    ("unknown sweep variable", dict(extra_sweep="n_case = 3"), ["unknown variable 'n_case'", "n_cases"]),
    ("bad fixed value", dict(fixed="&fixed name = 'flight%trim_mode', value = \"'glide'\" /"),
     ["trim_mode = 'glide' is not allowed"]),
]


def _one_line_error(res, prog):
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1, res.stderr
    assert lines[0].startswith(f"{prog}: error: "), lines[0]
    return lines[0]


@pytest.mark.parametrize("name,change,words", BAD, ids=[b[0] for b in BAD])
def test_bad_definition_stops_before_any_case(tmp_path, name, change, words):
    if not SWEEP_EXE.exists():
        pytest.fail(f"{SWEEP_EXE} is missing: run scripts/setup release first")
    kw = dict(n_cases=4)
    kw.update(change)
    definition = small_definition(tmp_path / "bad.nml", **kw)
    res = run_sweep(definition, tmp_path)
    assert res.returncode == 2, res.stdout + res.stderr
    line = _one_line_error(res, "airlaunch-sweep")
    for w in words:
        assert w in line, (w, line)
    assert not (tmp_path / "out" / "journal").exists(), "no case may have run"
    assert not (tmp_path / "out" / "summary.nc").exists()


@pytest.mark.parametrize("name,change,words", [b for b in BAD if b[0] in
                                               ("reversed bounds", "negative std", "zero cases",
                                                "unknown sweep variable")],
                         ids=["reversed bounds", "negative std", "zero cases", "unknown sweep variable"])
def test_bad_definition_stops_the_table_step(tmp_path, name, change, words):
    kw = dict(n_cases=4)
    kw.update(change)
    definition = small_definition(tmp_path / "bad.nml", **kw)
    res = run_python(["table", definition], tmp_path)
    assert res.returncode == 2, res.stdout + res.stderr
    line = _one_line_error(res, "sweep")
    assert words[0] in line, line
    assert not (tmp_path / "out" / "table.nc").exists()


def test_table_that_does_not_match_its_definition(tmp_path):
    definition = small_definition(tmp_path / "s.nml", n_cases=4, seed=5)
    make_table(definition, tmp_path)
    small_definition(tmp_path / "s.nml", n_cases=4, seed=6)      # edited after the table was made
    res = run_sweep(definition, tmp_path, 2)                    # under mpirun: rank 0 reports once
    assert res.returncode != 0
    errors = [x for x in res.stderr.splitlines() if x.startswith("airlaunch-sweep: error:")]
    assert len(errors) == 1, res.stderr
    assert "does not match" in errors[0] and "seed is 5 in the table, 6 in the definition" in errors[0]
    assert not (tmp_path / "out" / "journal").exists()


def test_missing_table(tmp_path):
    definition = small_definition(tmp_path / "s.nml", n_cases=4)
    res = run_sweep(definition, tmp_path)
    assert res.returncode == 2
    assert "case table does not exist" in _one_line_error(res, "airlaunch-sweep")


def test_check_reports_a_good_definition(tmp_path):
    definition = small_definition(tmp_path / "s.nml", n_cases=4)
    res = run_sweep(definition, tmp_path, None, "--check")
    assert res.returncode == 0, res.stderr
    assert "not made yet" in res.stdout
    make_table(definition, tmp_path)
    res = run_sweep(definition, tmp_path, None, "--check")
    assert res.returncode == 0 and "matches the definition" in res.stdout, res.stdout + res.stderr
