"""Integrals and error norms of a region's solution (no physics in here):
the functionals the scenes report, on the assembler's cells and scaling
(a mix-in of ``assembly.Assembler``)."""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from petthm.discretisation import fe
from petthm.discretisation.context import CellContext, physical_gradient


class Functionals:
    """Global integrals over an assembler's region (its ``W``, ``mesh``,
    ``disc``, ``chunks``, ``dofs`` and ``scale``)."""

    def integrate(self, xl, integrand: Callable, t: float = 0.0) -> float:
        """Global integral over this region of ``integrand(ctx)`` (nc, nq), SI."""
        acc = 0.0
        for cells in self.chunks():
            ctx = CellContext(self, cells, xl, xl, t)
            acc += float(np.sum(self.W[cells] * np.broadcast_to(integrand(ctx), self.W[cells].shape)))
        return self.mesh.dm.comm.tompi4py().allreduce(acc)

    def nodal_moments(self, xl, name: str, integrand: Callable, t: float = 0.0,
                      width: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """(int f psi_k, int psi_k) over this rank's cells for every local dof k
        of ``name`` (local arrays, SI; 0 elsewhere; the first (xl.size,
        width); a vector field's at the dofs of its first component),
        with f = ``integrand(ctx)`` (nc, nq) or (nc, nq, width) and psi the
        basis ``name`` is tested with here (the dual basis in a dual region)."""
        phi = self.tab(name).phi                                        # (nq, nb)
        dofs = self.dofs(name)[:, ::self.disc.field(name).ncomp]       # a vector's: its first component's
        num, den = np.zeros((xl.size, width)), np.zeros(xl.size)
        for cells in self.chunks():
            ctx = CellContext(self, cells, xl, xl, t)
            W = self.W[cells]
            idx = dofs[cells].ravel()
            f = np.broadcast_to(integrand(ctx), W.shape + ((width,) if width > 1 else ()))
            moments = np.einsum("cq,cqm,qk->ckm", W, f.reshape(W.shape + (width,)), phi)
            for m in range(width):
                num[:, m] += np.bincount(idx, weights=moments[..., m].ravel(), minlength=xl.size)
            den += np.bincount(idx, weights=(W @ phi).ravel(), minlength=xl.size)
        return num, den

    def error_norms(self, xl, name: str, exact: Callable, exact_grad: Callable, t: float,
                    degree: int = 6) -> dict[str, float]:
        """Global L2 and H1-seminorm errors and norms of the exact field (SI)."""
        m, f = self.mesh, self.disc.field(name)
        rule = fe.rule(m.rdim, max(degree, 2 * f.degree + 2))
        tab = fe.ReferenceTable(m.rdim, f.degree, rule.points)
        sc = self.scale(name)
        acc = np.zeros(4)
        for cells in self.chunks():
            X = xl[self.dofs(name)[cells]].reshape(-1, tab.phi.shape[1], f.ncomp) * sc.scale + sc.offset
            x = m.x0[cells][:, None, :] + np.einsum("cak,qk->cqa", m.J[cells], rule.points)
            W = np.abs(m.detJ[cells])[:, None] * rule.weights
            u = tab.phi @ X
            G = physical_gradient((tab.D @ X).reshape(len(X), -1, m.rdim, f.ncomp), m.Jinv[cells])
            ue = np.asarray(exact(x, t)).reshape(u.shape)
            ge = np.asarray(exact_grad(x, t)).reshape(G.shape)
            acc += [np.sum(W[:, :, None] * (u - ue) ** 2), np.sum(W[:, :, None] * ue ** 2),
                    np.sum(W[:, :, None, None] * (G - ge) ** 2), np.sum(W[:, :, None, None] * ge ** 2)]
        acc = m.dm.comm.tompi4py().allreduce(acc)
        return {"l2": float(np.sqrt(acc[0])), "l2_exact": float(np.sqrt(acc[1])),
                "h1": float(np.sqrt(acc[2])), "h1_exact": float(np.sqrt(acc[3])),
                "l2_rel": float(np.sqrt(acc[0] / max(acc[1], 1e-300))),
                "h1_rel": float(np.sqrt(acc[2] / max(acc[3], 1e-300)))}
