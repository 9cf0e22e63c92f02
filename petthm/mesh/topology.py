"""Vectorised topology of a simplicial DMPlex (no Python loop over cells):
the vertex and edge closures of points from the cone arrays, the simplex
strata (after a cohesive split, the hybrid points follow the simplices),
the edges of simplices in the reference order (``reference.EDGES``), the
affine maps of simplices, and the names of boundary labels."""
from __future__ import annotations

import numpy as np
from petsc4py import PETSc

from petthm import compat
from petthm.mesh.reference import EDGES


def label_name(boundary: str) -> str:
    """DMLabel name of a named boundary part."""
    return f"thm_bc_{boundary}"


class VertexTopology:
    """Vertex closures of points of a given depth from the cone arrays."""

    def __init__(self, dm: PETSc.DMPlex):
        self.dm = dm
        self.dim = dm.getDimension()
        self.vstart, self.vend = dm.getDepthStratum(0)
        self.cones = {d: compat.plex_cone_array(dm, *simplex_stratum(dm, d), _cone_size(self.dim, d))
                      for d in range(1, self.dim + 1)}
        self.starts = {d: dm.getDepthStratum(d)[0] for d in range(0, self.dim + 1)}
        cdim = dm.getCoordinateDim()
        csec = dm.getCoordinateSection()
        nv = self.vend - self.vstart
        if nv and (csec.getOffset(self.vstart) != 0 or csec.getOffset(self.vend - 1) != (nv - 1) * cdim):
            raise RuntimeError("unexpected coordinate layout")
        self.coords = dm.getCoordinatesLocal().getArray().reshape(-1, cdim)[:, :self.dim].copy()

    def point_vertices(self, points: np.ndarray, depth: int) -> np.ndarray:
        """Sorted vertex indices (relative to vStart) of points of ``depth``: (n, depth+1)."""
        cur = np.asarray(points).reshape(-1, 1)
        for d in range(depth, 0, -1):
            cur = self.cones[d][(cur - self.starts[d]).ravel()].reshape(len(points), -1)
        return _unique_rows(cur, depth + 1) - self.vstart

    def point_edges(self, points: np.ndarray, depth: int) -> np.ndarray:
        """Sorted edge points of points of ``depth`` >= 2: (n, nedges)."""
        cur = np.asarray(points).reshape(-1, 1)
        for d in range(depth, 1, -1):
            cur = self.cones[d][(cur - self.starts[d]).ravel()].reshape(len(points), -1)
        return _unique_rows(cur, len(EDGES[depth]))


def simplex_stratum(dm: PETSc.DMPlex, depth: int) -> tuple[int, int]:
    """The simplex points of a depth stratum: after a cohesive split the hybrid
    (prism-tensor) points follow them at the end of each stratum."""
    if depth == 0:
        return dm.getDepthStratum(0)
    return compat.simplex_range(dm, dm.getDimension() - depth)


def _cone_size(dim: int, depth: int) -> int:
    """Cone size of a simplex point of ``depth`` in a simplicial mesh."""
    return 2 if depth == 1 else depth + 1


def _unique_rows(a: np.ndarray, k: int) -> np.ndarray:
    """Per row, the ``k`` distinct values (sorted)."""
    s = np.sort(a, axis=1)
    keep = np.ones_like(s, dtype=bool)
    keep[:, 1:] = s[:, 1:] != s[:, :-1]
    out = s[keep]
    if out.size != k * len(a):
        raise RuntimeError("non-simplicial cell found in the mesh")
    return out.reshape(len(a), k)


def ordered_edges(topo, points, depth, point_vertices, edge_vertices, estart) -> np.ndarray:
    """Edge points of simplices of ``depth`` (cells or facets) in the order of
    ``EDGES[depth]`` relative to their sorted vertices ``point_vertices``."""
    if depth == 1:                      # a segment is its own (only) edge
        return np.asarray(points, dtype=compat.INT)[:, None]
    edges = topo.cones[2][points - topo.starts[2]] if depth == 2 else topo.point_edges(points, depth)
    ev = edge_vertices[edges - estart]                                  # (n, ne, 2)
    local = np.argmax(ev[:, :, :, None] == point_vertices[:, None, None, :], axis=3)
    local.sort(axis=2)
    code = local[:, :, 0] * (depth + 1) + local[:, :, 1]
    slot = np.full((depth + 1) ** 2, -1)
    for k, (a, b) in enumerate(EDGES[depth]):
        slot[a * (depth + 1) + b] = k
    ordered = np.empty_like(edges)
    np.put_along_axis(ordered, slot[code], edges, axis=1)
    return ordered


def simplex_geometry(X: np.ndarray, rdim: int):
    """Affine maps x = x0 + J xi of simplices with vertex coordinates X (n, rdim+1, d).

    For rdim < d (fracture faces) ``detJ`` is the measure ratio sqrt(det(J^T J))
    and ``Jinv`` the left inverse (J^T J)^-1 J^T, which maps to tangential
    gradients.  Returns x0, J (n, d, rdim), detJ (n,), Jinv (n, rdim, d), h (n,).
    """
    n, d = X.shape[0], X.shape[2]
    x0 = X[:, 0, :]
    J = np.ascontiguousarray(np.swapaxes(X[:, 1:, :] - X[:, :1, :], 1, 2))
    if n == 0:
        return x0, J, np.zeros(0), np.zeros((0, rdim, d)), np.zeros(0)
    if rdim == d:
        detJ, Jinv = np.linalg.det(J), np.linalg.inv(J)
    else:
        G = np.swapaxes(J, 1, 2) @ J
        detJ = np.sqrt(np.linalg.det(G))
        Jinv = np.linalg.solve(G, np.swapaxes(J, 1, 2))
    a, b = EDGES[rdim][:, 0], EDGES[rdim][:, 1]
    h = np.linalg.norm(X[:, a] - X[:, b], axis=2).max(axis=1)
    return x0, J, detJ, Jinv, h


__all__ = ["VertexTopology", "label_name", "ordered_edges", "simplex_geometry", "simplex_stratum"]
