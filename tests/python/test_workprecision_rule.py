"""The equal-error rule of the benchmarks (postproc/bench_workprecision.py): the
work-precision front and the wall read off it at a given error.  Checked against
power laws, where log-log interpolation between two runs is exact."""
import math
import pathlib
import sys

import pytest

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "postproc"))
from bench_workprecision import pareto, wall_at_error  # noqa: E402


def test_front_drops_dominated_runs():
    pts = [(1.0, 1e-2), (2.0, 1e-3), (1.5, 2e-2), (3.0, 1e-3), (4.0, 1e-4)]
    # (1.5, 2e-2) is slower and less accurate than (1.0, 1e-2); (3.0, 1e-3) slower than (2.0, 1e-3)
    assert sorted(pareto(pts)) == [0, 1, 4]


@pytest.mark.parametrize("order", [1.0, 2.0, 4.0])
def test_power_law_is_read_exactly(order):
    # a scheme of order p: error = C h^p, wall = W / h  ->  wall = W (error/C)^(-1/p)
    c, w0 = 3.0, 0.01
    hs = [0.1 / 2**k for k in range(6)]
    pts = [(w0 / h, c * h**order) for h in hs]
    for h in (0.07, 0.02, 0.004):
        want = w0 / h
        got = wall_at_error(pts, c * h**order)
        assert got == pytest.approx(want, rel=1e-12)   # exact up to round-off


def test_ends_of_the_front():
    pts = [(1.0, 1e-2), (10.0, 1e-4)]
    assert wall_at_error(pts, 5e-2) == 1.0           # the cheapest run already suffices: no extrapolation
    assert wall_at_error(pts, 1e-5) is None          # below the most accurate run: out of reach
    assert wall_at_error(pts, 1e-3) == pytest.approx(math.sqrt(10.0), rel=1e-12)
    assert wall_at_error([], 1.0) is None


def test_a_dominated_run_does_not_bend_the_front():
    pts = [(1.0, 1e-2), (10.0, 1e-4), (3.0, 5e-2)]    # the third is worse than the first in both
    assert wall_at_error(pts, 1e-3) == pytest.approx(math.sqrt(10.0), rel=1e-12)
