"""The line scene without its trajectory file prints the same milestones, to the
last printed digit, as with it.

Without the file (`&run trajectory = .false.`, and every sweep case) the line
scene takes the equivalent rigid body (Eqs. (18)-(32)) of its last record only,
the one the summary prints, from that record's state and piece kept aside,
instead of at every record (thirty-fourth session, docs/performance.md: 7 % of
the heavy airdrop's instructions).  Reference: the same input with the file,
which still takes it at every record.  Tolerance: none (the printed text, bit
for bit, less the wall time and the output file's name).  Cases: the heavy
airdrop (canopy), a run that fails (the step budget: its last record is
before the failure, and the state has moved on since), one that ends at the
ground, and the snap-back (the rigid body of the piece still holding an end)."""
import re

import pytest

from conftest import ROOT, nml_variant, run_airlaunch

AIRDROP = ROOT / "input" / "line_airdrop.nml"
SNAPBACK = ROOT / "input" / "line_snapback.nml"

CASES = {
    "airdrop": (AIRDROP, ((r"^\s*t_end\s*=.*$", "  t_end = 20.0"),)),
    "failed": (AIRDROP, ((r"^\s*t_end\s*=.*$", "  t_end = 20.0\n  max_steps = 2500"),)),
    "ground": (AIRDROP, ((r"^\s*t_end\s*=.*$", "  t_end = 60.0"),
                         (r"^&line_scene$", "&line_scene\n  ground = .true.\n  ground_altitude = 1400.0"))),
    "snapback": (SNAPBACK, ()),
}


def summary(res):
    """The printed milestones (a failed run prints them after its error, on stderr)."""
    return [ln for ln in (res.stdout + res.stderr).splitlines() if not re.match(r"^(airlaunch: )?output", ln)
            and "wall" not in ln]


@pytest.mark.parametrize("case", sorted(CASES))
def test_line_summary_without_trajectory_is_the_same(airlaunch_exe, tmp_path, case):
    base, edits = CASES[case]
    with_file = nml_variant(tmp_path, "with_file", base=base, edits=edits + (
        (r"^\s*output\s*=.*$", f"  output = '{tmp_path / 'out.nc'}'"),))
    without = nml_variant(tmp_path, "without", base=base, edits=edits + (
        (r"^\s*output\s*=.*$", "  trajectory = .false."),))
    a = run_airlaunch(airlaunch_exe, with_file)
    b = run_airlaunch(airlaunch_exe, without)
    assert a.returncode == b.returncode, (a.stderr, b.stderr)
    if case == "failed":
        assert a.returncode != 0 and "(failed; last record at" in a.stderr, a.stdout + a.stderr
    else:
        assert a.returncode == 0, a.stderr
    text = a.stdout + a.stderr
    assert "equivalent rigid body at the end" in text
    if case == "ground":
        assert "(the run ends there)" in text
    if case == "snapback":
        assert "the line has parted" in text
    assert summary(a) == summary(b)
