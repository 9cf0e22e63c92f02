"""The numerical pieces of ``petthm.verification.analytic`` that stand in for scipy on a
small run's start-up path: ``erfc`` (the C library's) and the vectorised
bisection ``increasing_root`` (Mandel's roots), each against scipy."""
import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.special import erfc as scipy_erfc

from petthm.verification.analytic import erfc, increasing_root, series_sum


def test_erfc_is_scipys_to_round_off():
    x = np.linspace(-3.0, 6.0, 9000).reshape(3, -1)
    assert erfc(x).shape == x.shape
    assert np.max(np.abs(erfc(x) - scipy_erfc(x)) / scipy_erfc(x)) < 1e-14


@pytest.mark.parametrize("k", [1.05, 1.5, 30.0])
def test_increasing_root_finds_the_roots_of_tan_x_equals_k_x(k):
    """One root of tan x = k x (k > 1) in each (i pi, i pi + pi/2), as
    Mandel's solution needs; brentq's to its tolerance (2e-12)."""
    def f(x):
        return np.tan(x) - k * x
    i = np.arange(50)
    lo, hi = np.where(i > 0, i * np.pi + 1e-12, 1e-9), i * np.pi + np.pi / 2 - 1e-12
    roots = increasing_root(f, lo, hi)
    ref = np.array([brentq(f, a, b) for a, b in zip(lo, hi, strict=False)])
    assert np.abs(roots - ref).max() < 3e-12
    # negative control: a bracket with no sign change gives its end, not a root
    assert abs(f(increasing_root(f, [0.5 * np.pi + 0.1], [0.5 * np.pi + 0.2])[0])) > 1.0


def test_series_sum_equals_the_outer_product_sum_and_skips_decayed_terms():
    """series_sum: term by term, the same sum as the points x terms product;
    decayed terms (exp(-lam^2 T) at a late time) are left out without changing it."""
    x = np.random.default_rng(0).uniform(0, 1, (50, 7))
    lam = (2 * np.arange(400) + 1) * np.pi / 2
    for T in (0.0, 1e-3, 0.5):
        c = np.exp(-lam ** 2 * T) * 2 / lam
        ref = np.sum(np.sin(np.multiply.outer(x, lam)) * c, axis=-1)
        assert np.max(np.abs(series_sum(x, lam, c, np.sin) - ref)) <= 1e-13 * np.max(np.abs(ref))
    calls = []
    series_sum(x, lam, np.exp(-lam ** 2 * 0.5), lambda y: calls.append(1) or np.sin(y))
    assert 0 < len(calls) < 10                      # at T = 0.5 a handful of terms remain
