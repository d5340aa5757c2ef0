"""The stress cases of the air-launch scene (issue 7 item 4), shared by
tests/python/test_stress.py and postproc/stress_table.py."""
import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parents[1]
PAPER = (ROOT / "input" / "airlaunch_paper.nml").read_text()


def variant(tmp_path, edits, t_end=6.0):
    text = re.sub(r"^  t_end = 15.0 .*$", f"  t_end = {t_end}", PAPER, flags=re.M)
    for old, new in edits:
        text, n = re.subn(old, new, text, flags=re.M)
        assert n == 1, old
    p = tmp_path / "stress.nml"
    p.write_text(text)
    return p


#: the paper's method end to end: the rigidized coupling with its line marched (§2.3)
PAPER_METHOD = (r"^(  cd_tangential = 0.01 .*)$", r"\1\n  coupling = 'rigidized'\n  inner_scheme = 'marching'")

CASES = {
    # name: (edits, t_end)
    "EA 1e4 N (soft line)": ([(r"^  ea = 1.0e6 .*$", "  ea = 1.0e4")], 6.0),
    "EA 1e9 N (stiff line)": ([(r"^  ea = 1.0e6 .*$", "  ea = 1.0e9")], 6.0),
    "N = 1 segment": ([(r"^  n_seg = \d+ .*$", "  n_seg = 1")], 6.0),
    "N = 1000 segments": ([(r"^  n_seg = \d+ .*$", "  n_seg = 1000")], 4.2),
    "rtol 1e-2": ([(r"^  rtol = \S+.*$", "  rtol = 1.0e-2"), (r"^  atol = \S+.*$", "  atol = 1.0e-3")], 6.0),
    "rtol 1e-12": ([(r"^  rtol = \S+.*$", "  rtol = 1.0e-12"), (r"^  atol = \S+.*$", "  atol = 1.0e-12")], 4.2),
    "light line 1e-3 kg/m": ([(r"^  mass_per_length = 0.4 .*$", "  mass_per_length = 1.0e-3")], 6.0),
    "heavy line 5 kg/m": ([(r"^  mass_per_length = 0.4 .*$", "  mass_per_length = 5.0")], 6.0),
    "parachute 0.28 kg (rocket/parachute 1e5)": ([(r"^  mass = 1.798 .*$", "  mass = 0.28"),
                                                  (r"^  added_mass_factor = 1.0 .*$", "  added_mass_factor = 0.0")], 6.0),
    # the release at sea level falls below it: the ground (default 0 m) goes to
    # its lowest allowed altitude, so that the run keeps the dense air for 6 s
    "sea level": ([(r"^  altitude = 10000.0 .*$", "  altitude = 0.0\n  ground_altitude = -1000.0")], 6.0),
    "20 km": ([(r"^  altitude = 10000.0 .*$", "  altitude = 20000.0")], 6.0),
    "Mach 0.3": ([(r"^  mach = 0.65 .*$", "  mach = 0.3")], 8.0),
    "Mach 0.9": ([(r"^  mach = 0.65 .*$", "  mach = 0.9")], 6.0),
    "tumbling rocket (no fins)": ([(r"^  fin_count = 4$", "  fin_count = 0")], 15.0),
    "early separation (one-sided edge)": ([(r"^  edge_contact = 'bilateral'.*$", "  edge_contact = 'one_sided'")], 6.0),
    "stick-fixed aircraft": ([(r"^  control = 'attitude_hold'.*$", "  control = 'stick_fixed'")], 6.0),
    "slack then snatch (canopy inflates at 1 s)": ([(r"^  deploy_time = -1.0 .*$", "  deploy_time = 1.0")], 6.0),
    # the paper's marching line inside the rigidized coupling, at its stability limit
    "paper method: EA 1e9 N (stiff line)": ([PAPER_METHOD, (r"^  ea = 1.0e6 .*$", "  ea = 1.0e9")], 6.0),
    "paper method: light line 1e-3 kg/m": ([PAPER_METHOD, (r"^  mass_per_length = 0.4 .*$",
                                                             "  mass_per_length = 1.0e-3")], 6.0),
    "paper method: N = 1 segment": ([PAPER_METHOD, (r"^  n_seg = \d+ .*$", "  n_seg = 1")], 6.0),
    "paper method: slack then snatch": ([PAPER_METHOD, (r"^  deploy_time = -1.0 .*$", "  deploy_time = 1.0")], 6.0),
}


