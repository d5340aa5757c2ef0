"""The case table: the same definition and seed give the same file bit for bit;
each design keeps the property that defines it (Latin hypercube: one point per
equal-probability stratum of every input; Sobol with 2^m points: one point per
dyadic interval; grid: the full product, first input slowest); the quantile
mapping gives the stated distributions; a changed definition no longer matches
its old table."""
import numpy as np
import pytest
import scipy.stats as st
import xarray as xr

from test_sweep_support import ROOT, run_python  # ROOT also puts the repository on sys.path

from postproc.sweep.definition import DefinitionError, parse_definition
from postproc.sweep.table import check_table, make_table, write_table

# the base must exist for the table step (it runs in tmp_path): an absolute path
BASE = "&sweep base = '" + str(ROOT / "input" / "airlaunch_paper.nml") + "', output_dir = '{out}', design = '{design}', n_cases = {n}, seed = {seed} /\n"


def definition(tmp_path, inputs, design="lhs", n=64, seed=11):
    text = BASE.format(out=tmp_path / "out", design=design, n=n, seed=seed) + inputs
    return parse_definition(text, str(tmp_path / "d.nml"))


THREE = """
&input name = 'bay%release_time', distribution = 'uniform', lower = 0.3, upper = 1.5 /
&input name = 'parachute%drag_area', distribution = 'truncnorm', mean = 10, std = 1.5, lower = 7, upper = 12 /
&input name = 'flight%mach', distribution = 'normal', mean = 0.65, std = 0.02 /
"""


def test_same_definition_and_seed_same_file_bit_for_bit(tmp_path):
    d = definition(tmp_path, THREE)
    a = write_table(d, tmp_path / "a.nc")
    b = write_table(d, tmp_path / "b.nc")
    assert a.read_bytes() == b.read_bytes()
    c = write_table(definition(tmp_path, THREE, seed=12), tmp_path / "c.nc")
    with xr.open_dataset(a) as ta, xr.open_dataset(c) as tc:
        assert not np.array_equal(ta["flight%mach"].values, tc["flight%mach"].values), "the seed matters"
        assert ta.attrs["design"] == "lhs" and int(ta.attrs["seed"]) == 11
        assert list(ta["case"].values) == list(range(64))


def test_cli_draws_the_table_and_checks_it(tmp_path):
    nml = tmp_path / "d.nml"
    nml.write_text(BASE.format(out=tmp_path / "out", design="sobol", n=16, seed=3) + THREE)
    res = run_python(["table", nml], tmp_path)
    assert res.returncode == 0, res.stderr
    assert (tmp_path / "out" / "table.nc").is_file()
    assert run_python(["table", nml, "--check"], tmp_path).returncode == 0


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_latin_hypercube_one_point_per_stratum(tmp_path, seed):
    """Map each value back through its own CDF: every input has exactly one
    case in each of the n equal-probability strata."""
    n = 50
    d = definition(tmp_path, THREE, n=n, seed=seed)
    t = make_table(d)
    u = {"bay%release_time": st.uniform(0.3, 1.2).cdf,
         "parachute%drag_area": st.truncnorm((7 - 10) / 1.5, (12 - 10) / 1.5, loc=10, scale=1.5).cdf,
         "flight%mach": st.norm(0.65, 0.02).cdf}
    for name, cdf in u.items():
        strata = np.floor(cdf(t[name].values) * n).astype(int)
        assert sorted(strata) == list(range(n)), name
    assert t["parachute%drag_area"].min() >= 7 and t["parachute%drag_area"].max() <= 12


def test_sobol_power_of_two_is_balanced(tmp_path):
    """2^m scrambled Sobol points: one point in each of the 2^m intervals of
    every coordinate (a (0, m, 1)-net in each dimension)."""
    n = 32
    inputs = "".join(f"&input name = 'g%x{k}', distribution = 'uniform', lower = 0, upper = 1 /\n"
                     for k in range(4))
    t = make_table(definition(tmp_path, inputs, design="sobol", n=n))
    for k in range(4):
        assert sorted(np.floor(t[f"g%x{k}"].values * n).astype(int)) == list(range(n))


def test_distributions_match_their_cdf(tmp_path):
    """With many cases the empirical distribution is the stated one
    (Kolmogorov-Smirnov distance below 3/n: LHS is far tighter than random)."""
    n = 2000
    t = make_table(definition(tmp_path, THREE, n=n))
    refs = {"bay%release_time": st.uniform(0.3, 1.2),
            "parachute%drag_area": st.truncnorm((7 - 10) / 1.5, (12 - 10) / 1.5, loc=10, scale=1.5),
            "flight%mach": st.norm(0.65, 0.02)}
    for name, dist in refs.items():
        assert st.kstest(t[name].values, dist.cdf).statistic < 3.0 / n, name


def test_list_values_drawn_evenly(tmp_path):
    inputs = "&input name = 'line%n_seg', distribution = 'list', values = 10, 20, 40 /\n"
    t = make_table(definition(tmp_path, inputs, n=30))
    values, counts = np.unique(t["line%n_seg"].values, return_counts=True)
    assert list(values) == [10, 20, 40] and list(counts) == [10, 10, 10]


def test_grid_is_the_full_product_first_input_slowest(tmp_path):
    inputs = """
&input name = 'flight%mach', distribution = 'list', values = 0.6, 0.7 /
&input name = 'bay%release_time', distribution = 'uniform', lower = 0.5, upper = 1.0, levels = 3 /
&input name = 'parachute%drag_area', distribution = 'normal', mean = 10, std = 1, levels = 2 /
"""
    text = "&sweep base = 'b.nml', design = 'grid' /\n" + inputs
    d = parse_definition(text, str(tmp_path / "g.nml"))
    assert d.n_cases == 12
    t = make_table(d)
    assert list(t["flight%mach"].values) == [0.6] * 6 + [0.7] * 6
    assert list(t["bay%release_time"].values[:6]) == [0.5, 0.5, 0.75, 0.75, 1.0, 1.0]
    # normal grid levels: the medians of two equal-probability halves
    q = st.norm(10, 1).ppf([0.25, 0.75])
    np.testing.assert_array_equal(t["parachute%drag_area"].values[:2], q)


def test_changed_definition_no_longer_matches_its_table(tmp_path):
    d = definition(tmp_path, THREE)
    path = write_table(d)
    check_table(d, path)
    changed = definition(tmp_path, THREE.replace("upper = 1.5", "upper = 1.6"))
    with pytest.raises(DefinitionError, match="not those that"):
        check_table(changed, path)
    with pytest.raises(DefinitionError, match="cases"):
        check_table(definition(tmp_path, THREE, n=65), path)


def test_grid_with_one_uniform_level_takes_the_midpoint(tmp_path):
    """docs/sweep.md: levels = 1 of a uniform input is (lower + upper)/2, not
    linspace's lower; more levels are linspace(lower, upper, levels)."""
    inputs = """
&input name = 'bay%release_time', distribution = 'uniform', lower = 0.4, upper = 1.0, levels = 1 /
&input name = 'flight%mach', distribution = 'uniform', lower = 0.6, upper = 0.7, levels = 3 /
"""
    t = make_table(parse_definition("&sweep base = 'b.nml', design = 'grid' /\n" + inputs, str(tmp_path / "g.nml")))
    assert list(t["bay%release_time"].values) == [0.7] * 3
    np.testing.assert_allclose(t["flight%mach"].values, [0.6, 0.65, 0.7], rtol=1e-15)
