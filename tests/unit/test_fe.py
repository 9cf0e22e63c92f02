"""Reference elements: quadrature exactness and P1/P2 basis properties."""
import itertools
from math import factorial

import numpy as np
import pytest

from petthm import fe


@pytest.mark.parametrize("dim", [1, 2, 3])
@pytest.mark.parametrize("degree", range(1, 9))
def test_quadrature_integrates_monomials_exactly(dim, degree):
    r = fe.rule(dim, degree)
    for powers in itertools.product(range(degree + 1), repeat=dim):
        if sum(powers) > degree:
            continue
        exact = np.prod([factorial(p) for p in powers]) / factorial(sum(powers) + dim)
        num = np.sum(r.weights * np.prod(r.points ** np.array(powers), axis=1))
        assert abs(num - exact) <= 1e-13 * exact


def test_quadrature_is_not_exact_beyond_its_degree():
    r = fe.rule(2, 2)
    exact = factorial(3) / factorial(5)           # int x^3 over the triangle
    assert abs(np.sum(r.weights * r.points[:, 0] ** 3) - exact) > 1e-6


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("degree", [1, 2])
def test_basis_is_nodal_and_a_partition_of_unity(dim, degree):
    nodes = fe.reference_nodes(dim, degree)
    t = fe.tabulate(dim, degree, nodes)
    assert np.allclose(t.phi, np.eye(len(nodes)), atol=1e-14)
    pts = fe.rule(dim, 4).points
    t = fe.tabulate(dim, degree, pts)
    assert np.allclose(t.phi.sum(axis=1), 1.0)
    assert np.allclose(t.dphi.sum(axis=1), 0.0, atol=1e-13)


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("degree", [1, 2])
def test_gradients_and_hessians_match_finite_differences(dim, degree):
    x = np.full((1, dim), 0.21) + 0.03 * np.arange(dim)
    t = fe.tabulate(dim, degree, x)
    eps = 1e-6
    for k in range(dim):
        e = np.zeros((1, dim))
        e[0, k] = eps
        tp, tm = fe.tabulate(dim, degree, x + e), fe.tabulate(dim, degree, x - e)
        assert np.allclose((tp.phi - tm.phi) / (2 * eps), t.dphi[:, :, k], atol=1e-8)
        assert np.allclose((tp.dphi - tm.dphi)[0] / (2 * eps), t.hess[:, :, k], atol=1e-6)


def test_facet_points_lie_on_the_facet_opposite_the_vertex():
    pts = fe.rule(2, 3).points
    for f in range(4):
        x = fe.facet_points(3, f, pts)
        lam = np.column_stack([1 - x.sum(axis=1), x])
        assert np.allclose(lam[:, f], 0.0)
