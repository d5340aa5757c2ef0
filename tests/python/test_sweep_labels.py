"""The sweep figures label their axes with a readable name and the unit, not the
raw namelist name (`parachute%drag_area`, no unit: a figure review, thirty-fifth
session).  The labels come from one table (postproc/sweep/labels.py); this test
checks it against an independent source, docs/input.md's own tables, parsed
here: every variable listed there that a sweep can vary (a real or integer of
one value, docs/sweep.md "&input") has a label whose unit is the unit the doc
gives it (exact string equality: no tolerance to state).  Then a tiny sweep's
figures, drawn from a synthetic envelope, carry the readable labels."""
import re

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

from test_sweep_support import ROOT  # noqa: E402,F401  (puts the repository on sys.path)

from postproc.sweep import figures, labels  # noqa: E402
from postproc.sweep.criteria import parse_criteria  # noqa: E402
from postproc.sweep.envelope import evaluate  # noqa: E402

#: groups of docs/input.md whose variables a sweep can vary (the drop scene's
#: &store is no sweep base: docs/sweep.md)
SWEPT_GROUPS = {"run", "flight", "aircraft", "bay", "rocket", "parachute", "line", "gust"}


def documented_units():
    """{group%variable: unit} of every sweepable row of docs/input.md's tables:
    strings and logicals (a quoted or logical default) and tables of values
    (`c_dn_mach`, `c_dn_table`, ...) and lists of choices without a default are left out; a row of several variables
    gives each its unit (`m², m, m`) or all the one unit."""
    group, out = None, {}
    for line in (ROOT / "docs" / "input.md").read_text().splitlines():
        head = re.match(r"#+ .*?`&(\w+)`", line)
        if head:
            group = head.group(1)
            continue
        if group not in SWEPT_GROUPS or not line.startswith("| `"):
            continue
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        names = [n.strip().strip("`") for n in cells[0].split(",")]
        units = [u.strip() for u in cells[2].split(",")]
        default = cells[3]
        if default.startswith("`'") or ".true." in default or ".false." in default or default == "–":
            # a string, a logical, or a list of choices without a default (`coupling_by_phase`)
            continue
        if len(units) == 1:
            units = units * len(names)
        assert len(units) == len(names), line
        for name, unit in zip(names, units):
            if name.endswith(("_mach", "_table")):
                continue
            out[f"{group}%{name}"] = unit
    return out


def test_every_documented_sweepable_input_has_the_documented_unit():
    doc = documented_units()
    # the parse found the tables (a doc rewritten into another form would pass vacuously)
    assert len(doc) > 90, len(doc)
    assert doc["parachute%drag_area"] == "m²" and doc["aircraft%span"] == "m" and doc["rocket%mass"] == "kg"
    wrong = {k: (labels.input_entry(k), u) for k, u in doc.items()
             if labels.input_entry(k) is None or labels.input_entry(k)[1] != u}
    assert not wrong, f"label missing or unit differing from docs/input.md: {wrong}"


def test_labels_read_as_names_with_units_and_fall_back_to_the_raw_name():
    assert labels.input_label("parachute%drag_area", "m2") == "parachute drag area [m²]"
    assert labels.input_label("flight%mach", "1") == "flight Mach number"   # dimensionless: no unit
    assert labels.input_label("line%wind(1)") == "wind x [m/s]"
    assert labels.input_label("line%wind(4)") == "line%wind(4)"   # no such component: the raw name
    assert labels.input_label("line%not_a_variable", "furlong") == "line%not_a_variable [furlong]"
    assert labels.input_label("line%not_a_variable") == "line%not_a_variable"
    assert labels.metric_label("min_clearance_m") == "min. rocket–empennage clearance [m]"
    assert labels.metric_label("no_such_metric") == "no_such_metric"


def tiny_envelope(n=40):
    rng = np.random.default_rng(3)
    area, mass = rng.uniform(520.0, 640.0, n), rng.normal(1000.0, 50.0, n)
    ds = xr.Dataset({"parachute%drag_area": ("case", area, {"units": "m2"}),
                     "line_scene%a_mass": ("case", mass, {"units": "kg"}),
                     "status": ("case", np.zeros(n, dtype=np.int32)),
                     "peak_line_tension_N": ("case", 47e3 + 60.0 * (mass - 1050.0) + 5.0 * (area - 580.0)),
                     "ground_speed_m_s": ("case", 5.6 + 0.01 * (mass - 1000.0))},
                    coords={"case": np.arange(n)})
    ds.attrs.update(inputs="parachute%drag_area line_scene%a_mass", sweep_name="labels", scene="line")
    return evaluate(ds, parse_criteria((ROOT / "input" / "criteria_airdrop.nml").read_text()))


def test_pass_fail_map_and_margins_axes_carry_the_readable_labels(tmp_path, monkeypatch):
    env = tiny_envelope()
    fig = figures.passfail_figure(env)
    try:
        axes = [a for a in fig.axes if a.get_xlabel() and a.get_ylabel() != "P(pass)"]
        got = {(a.get_xlabel(), a.get_ylabel()) for a in axes}
    finally:
        plt.close(fig)
    assert got == {("parachute drag area [m²]", "end a mass [kg]")}, got

    seen = {}
    savefig = plt.Figure.savefig

    def keep(fig, path, **kw):   # read the margins figure's labels as it is saved
        seen["x"] = [a.get_xlabel() for a in fig.axes if a.get_xlabel()]
        seen["y"] = [a.get_ylabel() for a in fig.axes if a.get_ylabel()]
        return savefig(fig, path, **kw)

    monkeypatch.setattr(plt.Figure, "savefig", keep)
    figures.margins(env, tmp_path / "margins.png")
    assert seen["x"] == ["parachute drag area [m²]", "end a mass [kg]"], seen
    assert "peak line tension\nmargin [N]" in seen["y"], seen
    assert not any("%" in t for t in seen["x"] + seen["y"]), seen
