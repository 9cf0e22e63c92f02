"""Reference elements: quadrature exactness and P1/P2 basis properties."""
import itertools
from math import factorial

import numpy as np
import pytest

from petthm.discretisation import fe


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


@pytest.mark.parametrize("dim", [1, 2])
@pytest.mark.parametrize("degree", [1, 2])
def test_dual_basis_is_biorthogonal_to_the_modified_basis(dim, degree):
    """int psi_k phi~_j = delta_kj int phi~_j with every int phi~_j > 0
    (the P2 triangle's vertex functions need the modified basis), and the
    dual basis reproduces constants."""
    r = fe.rule(dim, 2 * degree + 2)
    phi = fe.tabulate(dim, degree, r.points).phi
    psi = fe.tabulate_dual(dim, degree, r.points).phi
    mod = phi @ fe.modified_basis(dim, degree).T
    E = psi.T @ (r.weights[:, None] * mod)
    D = mod.T @ r.weights
    assert np.all(0.05 * fe.REFERENCE_VOLUME[dim] / len(D) < D)
    assert np.allclose(E, np.diag(D), atol=1e-14)
    assert np.allclose(psi.sum(axis=1), 1.0)
    assert np.allclose(mod.sum(axis=1), 1.0)


def test_p2_triangle_pairing_is_nodal_at_the_vertices():
    """int psi_k phi_j of the P2 triangle (area A = 1/2): A/3 [[2a I, 0],
    [-a adj, I]], a = P2_TRIANGLE_ALPHA: a vertex row of the weak opening
    sees its own node only, an edge row its node and the edge's two ends;
    the columns give the consistent load of a uniform traction (0 at the
    vertices, A/3 at the edges)."""
    r = fe.rule(2, 6)
    phi = fe.tabulate(2, 2, r.points).phi
    psi = fe.tabulate_dual(2, 2, r.points).phi
    E = psi.T @ (r.weights[:, None] * phi) / (0.5 / 3)
    a = fe.P2_TRIANGLE_ALPHA
    expect = np.zeros((6, 6))
    expect[:3, :3] = 2 * a * np.eye(3)
    expect[3:, 3:] = np.eye(3)
    for k, (v0, v1) in enumerate(fe.EDGES[2]):
        expect[3 + k, [v0, v1]] = -a
    assert np.allclose(E, expect, atol=1e-13)
    assert np.allclose(E.sum(axis=0), [0, 0, 0, 1, 1, 1], atol=1e-13)
