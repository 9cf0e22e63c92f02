"""Reference simplices, quadrature rules and P1/P2 Lagrange bases.

Reference cells: the triangle (0,0),(1,0),(0,1) and the tetrahedron
(0,0,0),(1,0,0),(0,1,0),(0,0,1); their facets (facet ``f`` lies opposite
vertex ``f``) carry the boundary terms.  Barycentric coordinates
``L0 = 1 - sum(xi)``, ``Lk = xi_k``.

P1 basis ``phi_i = L_i``; P2 basis ``L_i (2 L_i - 1)`` at the vertices and
``4 L_a L_b`` at the edge midpoints.  Node order follows VTK/XDMF
(``Triangle_6``, ``Tetrahedron_10``): vertices, then the edges listed in
``EDGES[dim]``.

Quadrature: symmetric rules of Strang-Fix/Dunavant (triangle) and Keast
(tetrahedron) up to degree 5, collapsed Gauss-Jacobi (Stroud conical
product) rules for any higher degree.  Weights sum to the reference volume.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from petthm.mesh.reference import EDGES, REFERENCE_VERTICES, REFERENCE_VOLUME  # noqa: F401 - fe's names


def nodes_per_cell(dim: int, degree: int) -> int:
    """Number of Lagrange nodes of a P1/P2 simplex."""
    return dim + 1 + (len(EDGES[dim]) if degree == 2 else 0)


# --------------------------------------------------------------------------
# Quadrature
# --------------------------------------------------------------------------
@dataclass(frozen=True)
class Rule:
    """Quadrature points (nq, dim) on a reference simplex and weights (nq,)."""
    points: np.ndarray
    weights: np.ndarray
    degree: int


def _orbit(bary: tuple[float, ...]) -> np.ndarray:
    """All distinct permutations of barycentric coordinates -> ref points."""
    import itertools
    perms = sorted(set(itertools.permutations(bary)))
    return np.array([p[1:] for p in perms])


def _symmetric(dim: int, orbits) -> tuple[np.ndarray, np.ndarray]:
    pts, wts = [], []
    for bary, w in orbits:
        p = _orbit(bary)
        pts.append(p)
        wts.append(np.full(len(p), w))
    return np.vstack(pts), np.concatenate(wts)


def _gauss_jacobi01(n: int, alpha: float) -> tuple[np.ndarray, np.ndarray]:
    """n-point rule on [0,1] for the weight (1-u)^alpha (Gauss-Legendre from
    numpy for alpha = 0, the rules of edges; Gauss-Jacobi from scipy, whose
    import costs a small run's start-up 0.06 s, only where needed)."""
    if alpha == 0.0:
        t, w = np.polynomial.legendre.leggauss(n)
    else:
        from scipy.special import roots_jacobi
        t, w = roots_jacobi(n, alpha, 0.0)
    return (1.0 + t) / 2.0, w / 2.0 ** (alpha + 1.0)


def _collapsed(dim: int, degree: int) -> tuple[np.ndarray, np.ndarray]:
    """Stroud conical-product rule exact for total degree ``degree``."""
    n = max(1, math.ceil((degree + 1) / 2))
    if dim == 1:
        return _gauss_jacobi01(n, 0.0)[0][:, None], _gauss_jacobi01(n, 0.0)[1]
    u, wu = _gauss_jacobi01(n, dim - 1.0)
    if dim == 2:
        v, wv = _gauss_jacobi01(n, 0.0)
        U, V = np.meshgrid(u, v, indexing="ij")
        pts = np.column_stack([U.ravel(), (V * (1 - U)).ravel()])
        return pts, np.outer(wu, wv).ravel()
    v, wv = _gauss_jacobi01(n, 1.0)
    w, ww = _gauss_jacobi01(n, 0.0)
    U, V, W = np.meshgrid(u, v, w, indexing="ij")
    pts = np.column_stack([U.ravel(), (V * (1 - U)).ravel(), (W * (1 - U) * (1 - V)).ravel()])
    return pts, np.einsum("i,j,k->ijk", wu, wv, ww).ravel()


@functools.cache
def vertex_rule(dim: int) -> Rule:
    """The vertices of the reference simplex with equal weights (exact for
    P1; used for row-sum lumping of P1 mass-type terms)."""
    pts = np.vstack([np.zeros((1, dim)), np.eye(dim)])
    return Rule(pts, np.full(dim + 1, REFERENCE_VOLUME[dim] / (dim + 1)), 1)


def rule(dim: int, degree: int) -> Rule:
    """A quadrature rule on the reference simplex exact to ``degree``."""
    degree = max(int(degree), 1)
    if dim == 0:
        return Rule(np.zeros((1, 0)), np.ones(1), degree)
    if degree <= 1:
        pts, wts = np.full((1, dim), 1.0 / (dim + 1)), np.array([REFERENCE_VOLUME[dim]])
    elif dim == 2 and degree == 2:
        pts, wts = _symmetric(2, [((2 / 3, 1 / 6, 1 / 6), 1 / 6)])
    elif dim == 2 and degree <= 4:
        pts, wts = _symmetric(2, [
            ((1 - 2 * 0.445948490915965, 0.445948490915965, 0.445948490915965), 0.223381589678011 / 2),
            ((1 - 2 * 0.091576213509771, 0.091576213509771, 0.091576213509771), 0.109951743655322 / 2)])
    elif dim == 2 and degree == 5:
        a, b = 0.470142064105115, 0.101286507323456
        pts, wts = _symmetric(2, [((1 / 3, 1 / 3, 1 / 3), 0.1125),
                                  ((1 - 2 * a, a, a), 0.132394152788506 / 2),
                                  ((1 - 2 * b, b, b), 0.125939180544827 / 2)])
    elif dim == 3 and degree == 2:
        a, b = 0.5854101966249685, 0.1381966011250105
        pts, wts = _symmetric(3, [((a, b, b, b), 1 / 24)])
    elif dim == 3 and degree <= 5:
        a, b, c = 0.0455037041256496, 0.0927352503108912, 0.3108859192633006
        pts, wts = _symmetric(3, [((a, a, 0.5 - a, 0.5 - a), 0.00709100346284691),
                                  ((b, b, b, 1 - 3 * b), 0.0122488405193936),
                                  ((c, c, c, 1 - 3 * c), 0.0187813209530026)])
    else:
        pts, wts = _collapsed(dim, degree)
    return Rule(np.ascontiguousarray(pts), np.ascontiguousarray(wts), degree)


# --------------------------------------------------------------------------
# Lagrange bases
# --------------------------------------------------------------------------
def _barycentric(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Barycentric coordinates (nq, d+1) and their constant gradients (d+1, d)."""
    dim = points.shape[1]
    lam = np.column_stack([1.0 - points.sum(axis=1), points])
    dlam = np.vstack([-np.ones(dim), np.eye(dim)])
    return lam, dlam


@dataclass(frozen=True)
class Tabulation:
    """Basis values (nq, nb), reference gradients (nq, nb, d) and Hessians (nb, d, d)."""
    phi: np.ndarray
    dphi: np.ndarray
    hess: np.ndarray


def tabulate(dim: int, degree: int, points: np.ndarray) -> Tabulation:
    """P1 or P2 Lagrange basis on the reference simplex at ``points``."""
    if degree not in (1, 2):
        raise ValueError(f"element degree must be 1 or 2, got {degree}")
    lam, dlam = _barycentric(np.asarray(points, dtype=float).reshape(-1, dim))
    nq, nv = lam.shape[0], dim + 1
    if degree == 1:
        phi = lam
        dphi = np.broadcast_to(dlam, (nq, nv, dim)).copy()
        hess = np.zeros((nv, dim, dim))
        return Tabulation(phi, dphi, hess)
    edges = EDGES[dim]
    a, b = edges[:, 0], edges[:, 1]
    phi = np.hstack([lam * (2 * lam - 1), 4 * lam[:, a] * lam[:, b]])
    dv = (4 * lam - 1)[:, :, None] * dlam[None, :, :]
    de = 4 * (lam[:, a, None] * dlam[None, b, :] + lam[:, b, None] * dlam[None, a, :])
    dphi = np.concatenate([dv, de], axis=1)
    hv = 4 * np.einsum("ik,il->ikl", dlam, dlam)
    he = 4 * (np.einsum("ek,el->ekl", dlam[a], dlam[b]) + np.einsum("ek,el->ekl", dlam[b], dlam[a]))
    return Tabulation(phi, dphi, np.concatenate([hv, he], axis=0))


def reference_nodes(dim: int, degree: int) -> np.ndarray:
    """Coordinates of the Lagrange nodes on the reference simplex."""
    v = REFERENCE_VERTICES[dim]
    if degree == 1:
        return v.copy()
    e = EDGES[dim]
    return np.vstack([v, 0.5 * (v[e[:, 0]] + v[e[:, 1]])])


def facet_points(dim: int, facet: int, points: np.ndarray) -> np.ndarray:
    """Map points of the reference (dim-1)-simplex onto facet ``facet``
    (the facet opposite vertex ``facet``) of the reference ``dim``-simplex."""
    verts = [v for v in range(dim + 1) if v != facet]
    V = REFERENCE_VERTICES[dim][verts]
    return V[0] + points @ (V[1:] - V[0])


# --------------------------------------------------------------------------
# Dual (biorthogonal) multiplier bases
# --------------------------------------------------------------------------
#: weight of the edge functions added to a vertex function of a P2 triangle
#: in the modified basis of Popp, Wohlmuth, Gee & Wall (2012): the P2
#: vertex functions of a triangle integrate to zero, which would leave the
#: vertex multipliers without a pairing; alpha in (0, 1/2), 1/5 is theirs.
P2_TRIANGLE_ALPHA = 0.2


def modified_basis(dim: int, degree: int) -> np.ndarray:
    """T (nb, nb) with phi~ = T phi: the identity, except for P2 triangles,
    where phi~_v = phi_v + alpha sum_{edges e at v} phi_e and
    phi~_e = (1 - 2 alpha) phi_e (a partition of unity whose functions all
    have a positive integral)."""
    nb = nodes_per_cell(dim, degree)
    T = np.eye(nb)
    if dim == 2 and degree == 2:
        a = P2_TRIANGLE_ALPHA
        for k, (v0, v1) in enumerate(EDGES[2]):
            e = dim + 1 + k
            T[v0, e] = T[v1, e] = a
            T[e, e] = 1.0 - 2.0 * a
    return T


@functools.cache
def dual_coefficients(dim: int, degree: int) -> np.ndarray:
    """C (nb, nb) with the dual basis psi = C phi on the reference simplex:
    int psi_k phi~_j = delta_kj int phi~_k for the modified basis
    phi~ = T phi (``modified_basis``); psi = D M~^-1 T phi with M~ the mass
    matrix of phi~ and D = diag(int phi~).  The psi reproduce constants
    (sum_k psi_k = 1).  Used for contact multipliers: the weak opening
    int psi_k g is then D_k g~_k, a nodal quantity (manual, verification: contact)."""
    r = rule(dim, 2 * degree)
    phi = tabulate(dim, degree, r.points).phi
    M = phi.T @ (r.weights[:, None] * phi)
    T = modified_basis(dim, degree)
    Mt = T @ M @ T.T
    D = Mt.sum(axis=1)                     # int phi~_k (the phi~ sum to 1)
    return (D[:, None] * np.linalg.inv(Mt)) @ T


def tabulate_dual(dim: int, degree: int, points: np.ndarray) -> Tabulation:
    """The dual basis psi = C phi (``dual_coefficients``) at ``points``."""
    t = tabulate(dim, degree, points)
    C = dual_coefficients(dim, degree)
    return Tabulation(t.phi @ C.T, np.einsum("qjd,kj->qkd", t.dphi, C), np.einsum("kj,jab->kab", C, t.hess))


@functools.cache
def nodal_rule(dim: int, degree: int) -> Rule:
    """The Lagrange nodes with the weights int phi~_k of the modified basis
    (``modified_basis``): the rule under which a pointwise function of
    nodal values, tested with the Lagrange basis, gives the nodal rows
    D_k f(x_k) of the dual pairing (P1: the vertex rule; P2 segments:
    Simpson's rule; P2 triangles: weights 2 alpha/3 and (1 - 2 alpha)/3 of
    the area).  Used for the friction law (manual, verification: contact)."""
    r = rule(dim, 2 * degree)
    phi = tabulate(dim, degree, r.points).phi
    weights = modified_basis(dim, degree) @ (phi.T @ r.weights)
    return Rule(reference_nodes(dim, degree), weights, degree)


class ReferenceTable:
    """Reference tabulation of one element degree (Lagrange, or its dual
    basis) on one rule."""

    def __init__(self, dim, degree, points, dual=False):
        t = (tabulate_dual if dual else tabulate)(dim, degree, points)
        self.phi, self.dphi, self.hess = t.phi, t.dphi, t.hess
        nq, nb = t.phi.shape
        # D[q*d+k, i] = dphi[q, i, k]
        self.D = np.ascontiguousarray(t.dphi.transpose(0, 2, 1).reshape(nq * dim, nb))
        # P1 on a simplex: the gradients are the same at every point (an affine
        # cell's physical gradients are then constant over the cell)
        self.constant_grad = bool(np.allclose(t.dphi, t.dphi[:1], rtol=0.0, atol=1e-13))
