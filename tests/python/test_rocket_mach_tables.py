"""The rocket's optional Mach tables end to end (&rocket c_dn_mach/c_dn_table,
c_axial_mach/c_axial_table; docs/input.md, docs/model.md "Rocket"):

- the paper scenario with tables that are constant at the scalar coefficients
  (several points, so the interpolation runs) prints the paper's summary digit
  for digit: the tables take the scalars' place without changing the forces;
  a rising C_dn table changes the run (the tables reach the right-hand side);
- the resolved input holds the tables as given and reads back to itself;
- bad tables are one-line input errors naming file, group, variable, value and
  what is allowed;
- a sweep can vary one element of a table (`rocket%c_dn_table(2)`): the case's
  namelist reads back with that element and the base's others.
(Unit tests of the forces: tests/unit/test_rocket_mach.f90.)"""
import re
import subprocess

import pytest

from conftest import PAPER, ROOT, assert_input_error, nml_variant, run_airlaunch
from test_sweep_support import AIRLAUNCH_EXE, ENV, SWEEP_EXE, make_table

CONSTANT = ["  c_dn_mach = 0.0, 0.45, 0.9", "  c_dn_table = 3*1.2",
            "  c_axial_mach = 0.3, 0.9", "  c_axial_table = 0.35, 0.35"]


def with_rocket(tmp_path, name, lines):
    """The paper scenario with `lines` added to &rocket (after n_strips)."""
    return nml_variant(tmp_path, name, edits=[(r"^(  n_strips = 16)$", "\\1\n" + "\n".join(lines))])


def summary(res):
    """The printed summary without the output file's name."""
    assert res.returncode == 0, res.stderr
    return [l for l in res.stdout.splitlines() if not l.startswith("output:")]


def test_constant_tables_give_the_paper_summary(airlaunch_exe, tmp_path):
    paper = summary(run_airlaunch(airlaunch_exe, PAPER, "--output", tmp_path / "paper.nc"))
    const = summary(run_airlaunch(airlaunch_exe, with_rocket(tmp_path, "const", CONSTANT), "--output",
                                  tmp_path / "const.nc"))
    assert const == paper
    # C_dn rising with M_c (near 90 deg M_c is about the flight Mach number, 0.65): a different run
    rising = summary(run_airlaunch(airlaunch_exe, with_rocket(tmp_path, "rising", [
        "  c_dn_mach = 0.0, 0.5, 1.0", "  c_dn_table = 1.2, 1.5, 2.0"]), "--output", tmp_path / "rising.nc"))
    assert rising != paper


def test_resolved_input_holds_the_tables_and_reads_back(airlaunch_exe, tmp_path):
    nml = with_rocket(tmp_path, "t", ["  c_dn_mach = 0.0, 0.5, 1.0", "  c_dn_table = 1.2, 1.5, 2.0"])
    res = run_airlaunch(airlaunch_exe, nml, "--check", "--output", tmp_path / "x.nc")
    assert res.returncode == 0, res.stderr
    lines = res.stdout.splitlines()
    assert " C_DN_MACH= 0.0000000000000000E+000, 5.0000000000000000E-001, 1.0000000000000000E+000," in lines
    assert " C_DN_TABLE= 1.2000000000000000E+000, 1.5000000000000000E+000, 2.0000000000000000E+000," in lines
    assert not any("C_AXIAL_MACH" in l for l in lines)   # not given: not echoed
    again = tmp_path / "again.nml"
    again.write_text(res.stdout)
    res2 = run_airlaunch(airlaunch_exe, again, "--check", "--output", tmp_path / "x.nc")
    assert res2.returncode == 0, res2.stderr
    assert res2.stdout.splitlines()[1:] == lines[1:]
    # without tables the resolved &rocket has none of them (the paper's echo is unchanged)
    res = run_airlaunch(airlaunch_exe, PAPER, "--check", "--output", tmp_path / "x.nc")
    assert "C_DN_MACH" not in res.stdout and "C_AXIAL" in res.stdout


@pytest.mark.parametrize("lines,fragment", [
    (["  c_dn_mach = 0.0, 0.5, 0.5", "  c_dn_table = 1.2, 1.5, 2.0"],
     "&rocket: c_dn_mach = 0.0, 0.5, 0.5 is not allowed (the cross-flow Mach numbers must increase strictly: "
     "c_dn_mach(3) = 0.5 <= c_dn_mach(2) = 0.5)"),
    (["  c_axial_mach = 0.9, 0.3", "  c_axial_table = 0.35, 0.4"],
     "&rocket: c_axial_mach = 0.9, 0.3 is not allowed (the free-stream Mach numbers must increase strictly: "
     "c_axial_mach(2) = 0.3 <= c_axial_mach(1) = 0.9)"),
    (["  c_dn_mach = 0.0, 0.5", "  c_dn_table = 1.2, 1.5, 2.0"],
     "&rocket: c_dn_table = 1.2, 1.5, 2.0 is not allowed (3 values for the 2 points of c_dn_mach = 0.0, 0.5: "
     "one value per point)"),
    (["  c_dn_mach = 0.0, 0.5"],
     "&rocket: c_dn_mach = 0.0, 0.5 is not allowed without c_dn_table (give c_dn_table, one value per point, "
     "or neither)"),
    (["  c_dn_mach = 0.0, 0.5", "  c_dn_table = 1.2, -0.1"],
     "&rocket: c_dn_table(2) = -0.1 is not allowed (must be >= 0)"),
    (["  c_axial_mach = 0.3", "  c_axial_table = -0.35"],
     "&rocket: c_axial_table(1) = -0.35 is not allowed (must be >= 0)"),
    (["  c_dn_mach = -0.1, 0.5", "  c_dn_table = 1.2, 1.5"],
     "&rocket: c_dn_mach(1) = -0.1 is not allowed (must be >= 0: cross-flow Mach numbers)"),
    (["  c_dn_mach = 0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2, 1.3, 1.4, 1.5, 1.6",
      "  c_dn_table = 17*1.2"],
     "&rocket: c_dn_mach = 0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2, 1.3, 1.4, 1.5, 1.6 "
     "is not allowed (17 points; at most 16)"),
    (["  c_dn_mach(1) = 0.0, c_dn_mach(3) = 0.5", "  c_dn_table = 1.2, 1.5, 2.0"],
     "&rocket: c_dn_mach(2) is not set, but c_dn_mach(3) is (give the points in order without gaps)"),
])
def test_bad_tables_are_one_line_errors(airlaunch_exe, tmp_path, lines, fragment):
    nml = with_rocket(tmp_path, "bad", lines)
    out = tmp_path / "bad.nc"
    line = assert_input_error(run_airlaunch(airlaunch_exe, nml, "--output", out), fragment, out)
    assert line.startswith(f"airlaunch: error: {nml}: &rocket: ")


def test_a_read_failure_after_a_table_names_its_own_variable(airlaunch_exe, tmp_path):
    """A value the namelist read itself fails on (here an integer out of
    range) is looked for among the group's assignments to name it; a table's
    list of values is a valid array there, not "not a real number" (review of
    the thirty-fourth session: the tables, diagnosed as scalars, were blamed
    for an n_strips overflow after them: "variable 'c_dn_mach' = 0.0, 0.5 is
    not a real number")."""
    tables = "&rocket\n  c_dn_mach = 0.0, 0.5\n  c_dn_table = 1.2, 1.5"
    nml = nml_variant(tmp_path, "bad", edits=[(r"^&rocket$", tables), (r"^(  n_strips = )16$", "\\g<1>99999999999")])
    out = tmp_path / "bad.nc"
    assert_input_error(run_airlaunch(airlaunch_exe, nml, "--output", out),
                       "&rocket: variable 'n_strips' = 99999999999 is not an integer in [-2147483647, 2147483647]", out)


@pytest.mark.parametrize("base,edit,fragment", [
    (PAPER, (r"^(  n_strips = 16)$", "\\1\n  c_dn_mach = 0.0, 0.5\n  c_dn_table(0) = 1.2"),
     "&rocket: 'c_dn_table(0)' = 1.2 is not allowed (c_dn_table holds at most 16 values: indices 1 to 16)"),
    (PAPER, (r"^(  n_strips = 16)$", "\\1\n  c_dn_mach = 0.0, 0.5\n  c_dn_table(-1) = 1.2"),
     "&rocket: 'c_dn_table(-1)' = 1.2 is not allowed (c_dn_table holds at most 16 values: indices 1 to 16)"),
    (PAPER, (r"^(  n_strips = 16)$", "\\1\n  c_dn_mach = 0.0, 0.5\n  c_dn_table(5000) = 1.2"),
     "&rocket: 'c_dn_table(5000)' = 1.2 is not allowed (c_dn_table holds at most 16 values: indices 1 to 16)"),
    (PAPER, (r"^(  n_strips = 16)$", "\\1\n  c_axial_mach(16:17) = 0.3, 0.9"),
     "&rocket: 'c_axial_mach(16:17)' = 0.3, 0.9 is not allowed (c_axial_mach holds at most 16 values: "
     "indices 1 to 16)"),
    # an element given several values: the read stopped at the second ("Cannot match namelist object name 1.5")
    (PAPER, (r"^(  n_strips = 16)$", "\\1\n  c_dn_mach = 0.0, 0.5\n  c_dn_table(1) = 1.2, 1.5"),
     "&rocket: 'c_dn_table(1)' = 1.2, 1.5 is not allowed (one element takes one value: give c_dn_table(k:m) = "
     "... for several, or the whole c_dn_table = ...)"),
    # a 3-vector of another group alike
    (ROOT / "input" / "line_pendulum.nml", (r"^&line$", "&line\n  wind(4) = 1.0"),
     "&line: 'wind(4)' = 1.0 is not allowed (wind holds at most 3 values: indices 1 to 3)"),
])
def test_an_element_out_of_bounds_is_a_one_line_error(airlaunch_exe, tmp_path, base, edit, fragment):
    """An element the array does not have, or an element given several
    values, was the runtime's message ("cannot read the group: Index 1 out of
    range for namelist variable c_dn_table", "Cannot match namelist object
    name 1.5"), naming neither the value nor what is allowed (review of the
    thirty-fourth session); now the one-line error of every bad input."""
    nml = nml_variant(tmp_path, "bad", base=base, edits=[edit])
    out = tmp_path / "bad.nc"
    line = assert_input_error(run_airlaunch(airlaunch_exe, nml, "--output", out), fragment, out)
    assert line.startswith(f"airlaunch: error: {nml}:")


def test_a_sweep_varies_one_element_of_a_table(tmp_path):
    """Only the existing element machinery (docs/sweep.md): the case's namelist
    assigns c_dn_table(2) and the base's c_dn_table(1), (3); read back, the
    table is the base's with the drawn element."""
    base = with_rocket(tmp_path, "base", ["  c_dn_mach = 0.0, 0.5, 1.0", "  c_dn_table = 1.2, 1.5, 2.0"])
    definition = tmp_path / "cdn.nml"
    definition.write_text(f"""&sweep
  name = 'cdn'
  base = '{base}'
  output_dir = 'out'
  design = 'grid'
  t_end = 5.0
/
&input name = 'rocket%c_dn_table(2)', distribution = 'list', values = 1.3, 1.8 /
""")
    make_table(definition, tmp_path)
    res = subprocess.run([str(SWEEP_EXE), str(definition), "--case-namelist", "1"], cwd=tmp_path,
                         capture_output=True, text=True, env=ENV, timeout=60)
    assert res.returncode == 0, res.stderr
    assert re.search(r"^  c_dn_table\(2\) = 1\.8", res.stdout, flags=re.M), res.stdout
    case = tmp_path / "case_1.nml"
    case.write_text(res.stdout)
    check = run_airlaunch(AIRLAUNCH_EXE, case, "--check", "--output", tmp_path / "x.nc")
    assert check.returncode == 0, check.stderr
    assert (" C_DN_TABLE= 1.2000000000000000E+000, 1.8000000000000000E+000, 2.0000000000000000E+000,"
            in check.stdout.splitlines())


def test_a_sweep_may_not_set_a_coefficient_its_table_replaces(tmp_path):
    """Varying (or fixing) &rocket c_dn in a base that gives c_dn_table would
    change no case - its sensitivities would read "no effect" - so the sweep
    refuses it in one line naming the table to vary instead (c_axial alike).
    Without the table, c_dn varies as any real variable."""
    base = with_rocket(tmp_path, "base", ["  c_dn_mach = 0.0, 0.5, 1.0", "  c_dn_table = 1.2, 1.5, 2.0",
                                          "  c_axial_mach = 0.3, 0.9", "  c_axial_table = 0.35, 0.4"])
    plain = with_rocket(tmp_path, "plain", [])

    def check(name, base_path, body):
        definition = tmp_path / f"sweep_{name}.nml"
        definition.write_text(f"&sweep\n  name = '{name}'\n  base = '{base_path}'\n  output_dir = 'out_{name}'\n"
                              f"  design = 'grid'\n  t_end = 5.0\n/\n{body}")
        return subprocess.run([str(SWEEP_EXE), str(definition), "--check"], cwd=tmp_path,
                              capture_output=True, text=True, env=ENV, timeout=60), definition

    res, d = check("vary", base, "&input name = 'rocket%c_dn', distribution = 'list', values = 1.0, 1.4 /\n")
    assert res.returncode == 2, (res.returncode, res.stderr)
    assert res.stderr.splitlines() == [
        f"airlaunch-sweep: error: {d}:8: &input #1 'rocket%c_dn': rocket%c_dn has no effect: the base scenario "
        "gives c_dn_table, which replaces it (docs/input.md, &rocket); set the table's values instead, "
        "rocket%c_dn_table(k)"], res.stderr
    res, d = check("fixed", base, "&input name = 'rocket%c_dn_table(2)', distribution = 'list', values = 1.3 /\n"
                                  "&fixed name = 'rocket%c_axial', value = '0.5' /\n")
    assert res.returncode == 2 and "&fixed #1 'rocket%c_axial': rocket%c_axial has no effect" in res.stderr, \
        res.stderr
    res, _ = check("plain", plain, "&input name = 'rocket%c_dn', distribution = 'list', values = 1.0, 1.4 /\n")
    assert res.returncode == 0, res.stderr
    # a one-point table is one value (echoed so): the refusal names the whole variable
    single = with_rocket(tmp_path, "single", ["  c_dn_mach = 0.5", "  c_dn_table = 1.3"])
    res, _ = check("single", single, "&input name = 'rocket%c_dn', distribution = 'list', values = 1.0, 1.4 /\n")
    assert res.returncode == 2 and res.stderr.rstrip().endswith("set the table's values instead, rocket%c_dn_table"), \
        res.stderr
    res, _ = check("single_ok", single, "&input name = 'rocket%c_dn_table', distribution = 'list', values = 1.0, 1.4 /\n")
    assert res.returncode == 0, res.stderr
