"""Re-running one case of a sweep that ran (docs/sweep.md, "How a case is
applied"): `airlaunch-sweep SWEEP.nml --case-namelist ID` prints the namelist
that `airlaunch` runs to the case's summary row (test_summary_mode.py checks
the row against the run).  That holds only while the base scenario and the
definition are what the sweep ran.  An audit edited the base's parachute mass
after a sweep: --case-namelist printed the edited case without a word, and its
run gave another separation time (3.2154030 s against the row's 3.2153708 s)
where the envelope step refused the same edit.  Now the query compares the
settings of the journal's fingerprint with those of the definition as it is
and refuses a difference in one line (exit 2); another build of the code
(another code digest) is a note on stderr: the namelist is the case's, the
run may differ in the last bits."""
import re

import pytest

from test_sweep_support import AIRLAUNCH_EXE, PAPER, SWEEP_EXE, make_table, run_sweep, small_definition


@pytest.fixture
def ran(tmp_path):
    """A two-case sweep of a copy of the paper base (2 s simulated), run on one
    rank; its namelist of case 1 then."""
    for exe in (SWEEP_EXE, AIRLAUNCH_EXE):
        assert exe.exists(), f"{exe} is missing: run scripts/setup release first"
    base = tmp_path / "base.nml"
    base.write_text(PAPER.read_text())
    definition = small_definition(tmp_path / "d.nml", n_cases=2, t_end=2.0)
    definition.write_text(definition.read_text().replace(f"base = '{PAPER}'", "base = 'base.nml'"))
    make_table(definition, tmp_path)
    res = run_sweep(definition, tmp_path, None)
    assert res.returncode == 0 and "2 cases: 2 ok" in res.stdout, res.stdout + res.stderr
    query = run_sweep(definition, tmp_path, None, "--case-namelist", 1)
    assert query.returncode == 0 and query.stderr == "", query.stderr
    return tmp_path, base, definition, query.stdout


def _refused(res, words):
    assert res.returncode == 2, res.stdout + res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and res.stdout == "", res.stdout + res.stderr
    assert "the sweep ran other settings than its definition gives now" in lines[0], lines[0]
    assert words in lines[0], lines[0]


def test_an_edited_base_is_refused(ran):
    cwd, base, definition, namelist = ran
    text = base.read_text()
    edited, n = re.subn(r"^  mass = 1\.798 ", "  mass = 3.0 ", text, flags=re.M)
    assert n == 1
    base.write_text(edited)
    _refused(run_sweep(definition, cwd, None, "--case-namelist", 1), "base_text_fnv1a")
    base.write_text(text)   # restored: the case's namelist again
    again = run_sweep(definition, cwd, None, "--case-namelist", 1)
    assert again.returncode == 0 and again.stdout == namelist, again.stderr


def test_an_edited_fixed_value_is_refused(ran):
    cwd, _, definition, _ = ran
    definition.write_text(definition.read_text().replace("value = '10'", "value = '12'"))
    _refused(run_sweep(definition, cwd, None, "--case-namelist", 1), "fixed line%n_seg = 12")


def test_another_build_is_a_note_and_the_same_namelist(ran):
    """The journal names the code by its digest: a sweep computed by another
    build gives the same namelist, with one note naming both digests."""
    cwd, _, definition, namelist = ran
    fingerprint = cwd / "out" / "journal" / "fingerprint.txt"
    text, n = re.subn(r"^code_digest = (\w+)$", "code_digest = 0123456789abcdef", fingerprint.read_text(),
                      flags=re.M)
    assert n == 1
    fingerprint.write_text(text)
    res = run_sweep(definition, cwd, None, "--case-namelist", 1)
    assert res.returncode == 0 and res.stdout == namelist, res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(
        "airlaunch-sweep: note: the sweep ran code digest 0123456789abcdef, this build is "), res.stderr
    assert "may differ from the case's summary row in the last bits" in lines[0]


def test_the_summary_names_the_build_of_its_rows(ran):
    """summary.nc carries the code digest its rows were computed with: the
    journal fingerprint's (which a resume and this query compare), which
    `airlaunch-sweep --version` prints."""
    import xarray as xr

    cwd, _, _, _ = ran
    journal = re.findall(r"^code_digest = (\w+)$", (cwd / "out" / "journal" / "fingerprint.txt").read_text(),
                         flags=re.M)
    version = run_sweep("--version", cwd, None)
    printed = re.findall(r"^code digest \(sources and build settings\): (\w+)$", version.stdout, flags=re.M)
    with xr.open_dataset(cwd / "out" / "summary.nc") as s:
        assert [s.attrs["code_digest"]] == journal == printed
