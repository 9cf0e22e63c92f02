"""``NodeSetTerm``s located on the distributed mesh (``model.NodeSetTerm``):
each node of a term is found among the mesh points that carry its first
field, on the rank that owns the point (the point SF's root, whether or not
a Dirichlet condition holds the node's value), and the term's residual and
Jacobian are added to the rows of the owned nodes.  The Jacobian's columns
may be any node of the set, on any rank: their global numbers are summed
over the ranks once, at set-up."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from petthm import compat
from petthm.discretisation.fields import Discretisation
from petthm.discretisation.model import NodeSetTerm
from petthm.errors import InputError


@dataclass
class _Context:
    """``model.NodeSetContext``."""
    values: dict
    owned: np.ndarray
    t: float
    comm: object

    def total(self, a) -> np.ndarray:
        return np.asarray(self.comm.allreduce(np.asarray(a, dtype=float)))


def owned_points(dm, points: np.ndarray) -> np.ndarray:
    """Mask of the mesh ``points`` this rank owns (not leaves of the point SF)."""
    if dm.comm.getSize() == 1:                      # (a serial mesh's point SF has no graph)
        return np.ones(len(points), dtype=bool)
    _, leaves, _ = dm.getPointSF().getGraph()
    if leaves is None or len(leaves) == 0:
        return np.ones(len(points), dtype=bool)
    return ~np.isin(points, leaves)


class NodeSetDofs:
    """A ``NodeSetTerm`` located: the local dofs of its fields at the nodes
    this rank owns, and every node's global numbers (collective)."""

    def __init__(self, disc: Discretisation, term: NodeSetTerm):
        from scipy.spatial import cKDTree
        self.term, self.disc = term, disc
        mesh = disc.mesh
        self.comm = mesh.dm.comm.tompi4py()
        f0 = term.fields[0]
        pts = disc.support[f0]
        n = len(term.points)
        found = np.full(n, -1)
        if len(pts):
            X = mesh.point_coordinates(pts)
            tol = 1e-9 * max(float(mesh.h.max()) if mesh.ncells else 1.0, 1e-300)
            dist, idx = cKDTree(X).query(np.asarray(term.points, dtype=float)[:, :mesh.dim],
                                         distance_upper_bound=tol)
            hit = np.isfinite(dist)
            mine = np.zeros(n, dtype=bool)
            mine[hit] = owned_points(mesh.dm, pts[idx[hit]])
            found[mine] = pts[idx[mine]]
        owners = self.comm.allreduce((found >= 0).astype(np.int64))
        if np.any(owners != 1):
            k = int(np.flatnonzero(owners != 1)[0])
            at = ", ".join(f"{c:.6g}" for c in term.points[k])
            raise InputError(f"well {term.name}: its node at ({at}) is not a vertex of the mesh")
        self.owned = np.flatnonzero(found >= 0)
        self.local = {f: np.asarray([int(disc.offsets[f][p - disc.pstart]) for p in found[self.owned]],
                                    dtype=np.int64) for f in term.fields}
        self.global_numbers = {}
        for f in term.fields:
            g = np.zeros(n, dtype=np.int64)
            g[self.owned] = disc.global_index[self.local[f]] + 1        # 0: not here (constrained: -1 + 1)
            self.global_numbers[f] = self.comm.allreduce(g) - 1
        self.coo_rows, self.coo_cols = self._pattern()

    def _pattern(self) -> tuple[np.ndarray, np.ndarray]:
        rows, cols = [], []
        m, n = len(self.owned), len(self.term.points)
        for test, trial, kind in self.term.blocks:
            r = self.global_numbers[test][self.owned]
            if kind == "diagonal":
                rows.append(r)
                cols.append(self.global_numbers[trial][self.owned])
            else:
                rows.append(np.repeat(r, n))
                cols.append(np.tile(self.global_numbers[trial], m))
        return (np.concatenate(rows).astype(compat.INT) if rows else np.zeros(0, compat.INT),
                np.concatenate(cols).astype(compat.INT) if cols else np.zeros(0, compat.INT))

    def context(self, xl, t, scales) -> _Context:
        values = {f: xl[d] * scales[f].scale + scales[f].offset for f, d in self.local.items()}
        return _Context(values, self.owned, t, self.comm)

    def add_residual(self, r, xl, t, scales, inv_rscale) -> None:
        for f, v in self.term.residual(self.context(xl, t, scales)).items():
            d = self.local[f]
            r[d] += np.asarray(v) * inv_rscale[d]

    def jacobian_values(self, xl, t, scales, inv_rscale) -> np.ndarray:
        jac = self.term.jacobian(self.context(xl, t, scales))
        out = []
        for test, trial, kind in self.term.blocks:
            v = np.asarray(jac[(test, trial)], dtype=float)
            row = inv_rscale[self.local[test]] * scales[trial].scale
            out.append((v * (row if kind == "diagonal" else row[:, None])).ravel())
        return np.concatenate(out) if out else np.zeros(0)

    def inflow(self, xl, t, scales, field: str) -> tuple[float, float]:
        """(net, sum of |.|) of what the term brings into ``field``'s rows on
        this rank (SI), e.g. a well's volume rate."""
        if field not in self.local:                  # the same on every rank
            return 0.0, 0.0
        q = -np.asarray(self.term.residual(self.context(xl, t, scales))[field])
        return float(q.sum()), float(np.abs(q).sum())
