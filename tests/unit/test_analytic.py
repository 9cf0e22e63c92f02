"""The numerical pieces of ``petthm.analytic`` that stand in for scipy on a
small run's start-up path: ``erfc`` (the C library's) and the vectorised
bisection ``increasing_root`` (Mandel's roots), each against scipy."""
import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.special import erfc as scipy_erfc

from petthm.analytic import erfc, increasing_root


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
    ref = np.array([brentq(f, a, b) for a, b in zip(lo, hi)])
    assert np.abs(roots - ref).max() < 3e-12
    # negative control: a bracket with no sign change gives its end, not a root
    assert abs(f(increasing_root(f, [0.5 * np.pi + 0.1], [0.5 * np.pi + 0.2])[0])) > 1.0
