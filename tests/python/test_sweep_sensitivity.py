"""Which inputs drive each criterion (postproc/sweep/sensitivity.py), against
independent references: the partial rank correlation equals the one read off
the inverse of the rank correlation matrix (another algorithm), Spearman's
equals SciPy's, the rank regression's coefficients and R^2 equal the
correlation-matrix formulas and, on a grid whose response ranks are linear in
the inputs' ranks, their closed form; all are unchanged by strictly increasing
transforms (a property of ranks); and the 95 % interval covers the converged
value of a known model (one million cases) about 95 % of the time over 1000
repeated sweeps.  In the envelope, cases that did not compute are left out and
a NaN margin (the event never came) ranks below every finite one."""
import numpy as np
import pytest
import scipy.stats as st

from test_sweep_envelope import CRITERIA, synthetic_summary

from postproc.sweep.criteria import parse_criteria
from postproc.sweep.envelope import evaluate
from postproc.sweep.sensitivity import drivers_table, fisher_interval, rank_correlations, rank_regression


def model(rng, n, a, b, noise):
    """Three uniform inputs; the response is increasing in x0, decreasing in x1,
    independent of x2, with Gaussian noise."""
    x = rng.random((n, 3))
    return x, np.exp(a * x[:, 0]) - b * x[:, 1] ** 2 + noise * rng.standard_normal(n)


def precision_prcc(x, y):
    """Partial correlations of the ranks from the inverse of their correlation
    matrix: -P[j, y] / sqrt(P[j, j] P[y, y])."""
    ranks = np.column_stack([st.rankdata(c) for c in np.column_stack([x, y]).T])
    p = np.linalg.inv(np.corrcoef(ranks, rowvar=False))
    k = x.shape[1]
    return np.array([-p[j, k] / np.sqrt(p[j, j] * p[k, k]) for j in range(k)])


def test_prcc_and_spearman_equal_independent_computations():
    rng = np.random.default_rng(7)
    x = rng.random((300, 4))
    x[:, 3] = x[:, 0] + 0.5 * rng.random(300)      # a correlated input: partial and plain correlations differ
    y = np.sin(3 * x[:, 0]) + x[:, 1] ** 3 - x[:, 3] + 0.3 * rng.standard_normal(300)
    spearman, prcc = rank_correlations(x, y)
    np.testing.assert_allclose(prcc, precision_prcc(x, y), atol=1e-12)
    np.testing.assert_allclose(spearman, [st.spearmanr(x[:, j], y)[0] for j in range(4)], atol=1e-12)
    assert abs(prcc[3] - spearman[3]) > 0.1        # the comparison above is not trivial


def rank_matrix(x, y):
    return np.column_stack([st.rankdata(c) for c in np.column_stack([x, y]).T])


def test_rank_regression_equals_the_correlation_matrix_formulas():
    """Standardised coefficients R_xx^-1 r_xy and R^2 = r_xy' R_xx^-1 r_xy
    of the rank correlation matrix (normal equations, not least squares)."""
    rng = np.random.default_rng(9)
    x = rng.random((250, 3))
    x[:, 2] += 0.7 * x[:, 0]                        # correlated inputs
    y = np.exp(x[:, 0]) - 2 * x[:, 1] + x[:, 2] ** 2 + 0.2 * rng.standard_normal(250)
    c = np.corrcoef(rank_matrix(x, y), rowvar=False)
    beta = np.linalg.solve(c[:3, :3], c[:3, 3])
    srrc, r2 = rank_regression(x, y)
    np.testing.assert_allclose(srrc, beta, atol=1e-12)
    assert r2 == pytest.approx(c[:3, 3] @ beta, abs=1e-12)


def test_rank_regression_on_a_grid_has_its_closed_form():
    """y = 3 x0 + x1 on the grid x0 in {0..4}, x1 in {0, 1, 2}: the 15 values
    are distinct, so the ranks of y are y + 1, linear in the inputs' (tied)
    ranks: R^2 = 1 and SRRC = (3 s0, s1) / sqrt(9 s0^2 + s1^2), s0^2 = 2 and
    s1^2 = 2/3 the variances of the levels; the grid's inputs are uncorrelated,
    so the shares SRRC^2 add up to R^2 and each SRRC is Spearman's."""
    x0, x1 = (g.ravel().astype(float) for g in np.meshgrid(np.arange(5), np.arange(3)))
    y = 3 * x0 + x1
    srrc, r2 = rank_regression(np.column_stack([x0, x1]), y)
    want = np.array([3 * np.sqrt(2.0), np.sqrt(2.0 / 3.0)]) / np.sqrt(18.0 + 2.0 / 3.0)
    np.testing.assert_allclose(srrc, want, atol=1e-12)
    assert r2 == pytest.approx(1.0, abs=1e-12)
    assert np.sum(srrc**2) == pytest.approx(r2, abs=1e-12)
    spearman, _ = rank_correlations(np.column_stack([x0, x1]), y)
    np.testing.assert_allclose(srrc, spearman, atol=1e-12)


def test_unchanged_by_strictly_increasing_transforms():
    rng = np.random.default_rng(8)
    x, y = model(rng, 200, 2.0, 3.0, 0.8)
    x2 = np.column_stack([np.log1p(x[:, 0]), x[:, 1] ** 3, np.exp(5 * x[:, 2])])
    y2 = np.tanh(y / 10) + 2 * y
    for a, b in zip(rank_correlations(x, y) + rank_regression(x, y),
                    rank_correlations(x2, y2) + rank_regression(x2, y2)):
        np.testing.assert_allclose(b, a, atol=1e-12)


@pytest.mark.parametrize("a, b, noise", [(2.0, 3.0, 0.8), (0.5, 0.5, 1.0)])
@pytest.mark.parametrize("n", [30, 100])
def test_interval_covers_the_converged_value(a, b, noise, n):
    """Converged PRCCs (10^6 cases; their own sampling error ~2e-4, against
    half-widths of 0.05-0.4) of a strong (0.88, -0.68, 0) and a weak (0.18,
    -0.14, 0) model: 1000 sweeps of n cases cover each about 95 % of the time.
    The band [0.93, 0.975] is 95 % +- 3 binomial standard deviations (0.7 %)
    on the low side, wider on the high side: a conservative interval is safe."""
    rng = np.random.default_rng(11)
    _, converged = rank_correlations(*model(rng, 1_000_000, a, b, noise))
    covered = np.zeros(3)
    for _ in range(1000):
        _, prcc = rank_correlations(*model(rng, n, a, b, noise))
        low, high = fisher_interval(prcc, n, 2)
        covered += (low <= converged) & (converged <= high)
    coverage = covered / 1000
    print(f"converged PRCC {np.round(converged, 3)}, coverage at n = {n}: {coverage}")
    assert np.all((coverage >= 0.93) & (coverage <= 0.975)), coverage


def test_too_few_cases_give_no_interval():
    low, high = fisher_interval(np.array([0.5, -0.2]), 5, 2)
    assert np.isnan(low).all() and np.isnan(high).all()


def test_envelope_ranks_not_computed_out_and_nan_margins_lowest():
    """Clearance increasing in a only; the firing pitch increasing in a, the
    case of the smallest a never reaching a maximum (NaN: if it ranked anywhere
    but lowest, the PRCC would fall below 1); two cases not computed whose
    metrics would break the order if they counted."""
    rng = np.random.default_rng(3)
    n = 60
    a, b = rng.random(n), rng.random(n)
    clearance = 1.0 + 2.0 * a
    pitch = 60.0 + 30.0 * a
    pitch[np.argmin(a)] = np.nan                    # lowest a: no pitch maximum (fails, ranks lowest)
    status = np.zeros(n, dtype=np.int32)
    bad = np.argsort(a)[-2:]                        # the two largest a did not compute ...
    status[bad] = 1
    clearance[bad] = -5.0                           # ... and their metrics would invert the order
    pitch[bad] = 10.0
    env = evaluate(synthetic_summary(a, b, clearance, status=status, pitch=pitch), parse_criteria(CRITERIA))
    assert int(env["sensitivity_cases"].sel(criterion="clearance")) == n - 2
    for c in ("clearance", "firing_attitude"):
        prcc = env["prcc"].sel(criterion=c)
        assert float(prcc.sel(input="a")) == pytest.approx(1.0, abs=1e-12), c
        assert np.isnan(float(prcc.sel(input="b"))), c    # nothing left once a is held fixed
        assert float(env["prcc_low"].sel(criterion=c, input="a")) == pytest.approx(1.0, abs=1e-12)
    # the margin does not vary (the tension is the same in every case): no correlation
    assert np.isnan(env["prcc"].sel(criterion="line_tension").values).all()
    assert np.isnan(env["spearman"].sel(criterion="line_tension").values).all()
    assert np.isnan(env["srrc"].sel(criterion="line_tension").values).all()
    # a alone decides the clearance: the whole rank variance is a's
    assert float(env["srrc"].sel(criterion="clearance", input="a")) == pytest.approx(1.0, abs=1e-12)
    assert float(env["rank_r2"].sel(criterion="clearance")) == pytest.approx(1.0, abs=1e-12)
    text = drivers_table(env)
    assert "line_tension     (none: the margin does not vary" in text
    assert "clearance        R^2 1.00: a +1.00, b -0.00 (not significant)" in text or \
        "clearance        R^2 1.00: a +1.00, b +0.00 (not significant)" in text, text


@pytest.mark.parametrize("n_ok", [0, 1, 3])
def test_too_few_computed_cases_give_nan_not_an_error(n_ok):
    n = 8
    a, b = np.linspace(0, 1, n), np.linspace(1, 0, n) ** 2
    status = np.where(np.arange(n) < n_ok, 0, 1).astype(np.int32)
    env = evaluate(synthetic_summary(a, b, 1 + a, status=status), parse_criteria(CRITERIA))
    assert int(env["sensitivity_cases"].values[0]) == n_ok
    assert np.isnan(env["prcc_low"].values).all()       # n - 3 - p < 1: no interval
    for var in ("srrc", "prcc", "spearman", "rank_r2"):   # 2 inputs: 4 cases at least
        assert np.isnan(env[var].values).all(), var
    assert "(none: the margin does not vary" in drivers_table(env)


def test_an_input_constant_over_the_computed_cases_is_left_out():
    """b takes one value in every computed case (its other value only in cases
    that did not compute): it is left out, and a's coefficients are those of
    the one-input regression, whose SRRC is Spearman's correlation (SciPy) and
    whose R^2 its square (before the twenty-sixth session every input's
    values were NaN and the drivers line said the margin did not vary)."""
    rng = np.random.default_rng(11)
    n = 40
    a = rng.random(n)
    b = np.where(np.arange(n) % 4 == 0, 0.0, 11.0)
    status = np.where(b == 0.0, 2, 0).astype(np.int32)    # b = 0: invalid input, not computed
    clearance = 1.0 + 2.0 * a + 0.3 * rng.standard_normal(n)
    env = evaluate(synthetic_summary(a, b, clearance, status=status), parse_criteria(CRITERIA))
    ok = status == 0
    rho = st.spearmanr(a[ok], clearance[ok]).statistic
    srrc = env["srrc"].sel(criterion="clearance")
    assert float(srrc.sel(input="a")) == pytest.approx(rho, abs=1e-12)
    assert float(env["rank_r2"].sel(criterion="clearance")) == pytest.approx(rho**2, abs=1e-12)
    assert float(env["spearman"].sel(criterion="clearance", input="a")) == pytest.approx(rho, abs=1e-12)
    for var in ("srrc", "prcc", "spearman", "prcc_low"):
        assert np.isnan(float(env[var].sel(criterion="clearance", input="b"))), var
    assert "b (constant over the computed cases)" in drivers_table(env)


def test_inputs_that_move_together_have_no_coefficient():
    """b = -a over the computed cases (ranks reversed): the regression cannot
    tell their shares apart, and least squares returned an arbitrary split of
    the sum (an audit found SRRC +0.265 for an input whose Spearman
    correlation was -0.632).  Both get NaN, the drivers line says why, and the
    regression's R^2 is still the fit's: the response is a function of a alone,
    so R^2 equals the one-input regression's, Spearman's rho squared (SciPy)."""
    rng = np.random.default_rng(5)
    n = 40
    a = rng.random(n)
    b = -a
    clearance = 1.0 + 2.0 * a + 0.3 * rng.standard_normal(n)
    env = evaluate(synthetic_summary(a, b, clearance), parse_criteria(CRITERIA))
    srrc = env["srrc"].sel(criterion="clearance")
    assert np.isnan(srrc.values).all(), srrc.values
    rho = st.spearmanr(a, clearance).statistic
    assert float(env["rank_r2"].sel(criterion="clearance")) == pytest.approx(rho**2, abs=1e-12)
    assert float(env["spearman"].sel(criterion="clearance", input="b")) == pytest.approx(-rho, abs=1e-12)
    text = drivers_table(env)
    assert "a (moves with the other inputs over the computed cases: its share cannot be told apart)" in text, text
    # a third, independent input keeps its coefficient: the same as without the pair's twin
    x3 = np.column_stack([a, b, rng.random(n)])
    y = clearance + 0.5 * x3[:, 2]
    srrc3, r2 = rank_regression(x3, y)
    srrc2, r2_2 = rank_regression(x3[:, [0, 2]], y)
    assert np.isnan(srrc3[:2]).all() and srrc3[2] == pytest.approx(srrc2[1], abs=1e-12)
    assert r2 == pytest.approx(r2_2, abs=1e-12)


def test_a_margin_constant_to_roundoff_has_no_drivers():
    """The steady tow's peak tension moved by 3e-6 N out of 1e5 N with the
    release time (solver noise, below 1e-10 of it): its ranks made the release
    time a 'significant' driver with PRCC 1.000.  A margin within 1e-9 of its
    size is constant: NaN sensitivities and the drivers line says so; a
    variation of 1e-6 of it is kept."""
    n = 20
    rng = np.random.default_rng(3)
    a, b = rng.uniform(0.4, 1.0, n), rng.uniform(7.0, 13.0, n)
    for step, kept in ((1e-5, False), (1.0, True)):
        ds = synthetic_summary(a, b, 1.0 + a)
        ds["peak_line_tension_N"] = ("case", 1.0e5 + step * a)
        env = evaluate(ds, parse_criteria(CRITERIA))
        prcc = env["prcc"].sel(criterion="line_tension").values
        assert np.isfinite(prcc).any() == kept, (step, prcc)
        text = drivers_table(env)
        assert ("line_tension     (none: the margin does not vary" in text) != kept, text
