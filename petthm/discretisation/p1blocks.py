"""Jacobian terms of P1 functions summed over the cell before the basis
gradients are applied (no physics in here): an ``Assembler`` method
(``Assembler._constant_gradient_terms``), kept apart from the
reference-tensor path of ``assembly.py``; manual, performance, "The
Jacobian of a P2-displacement scene"."""
from __future__ import annotations

import numpy as np


def constant_gradient_terms(self, jb, ctx, cells, fast) -> np.ndarray:
    """The g1, g2, g3 terms (``fast``: which) of a block whose test (g2),
    trial (g1) or both (g3) functions have gradients constant over the
    cell (P1 on simplices, ``fe.ReferenceTable.constant_grad``), as (nc, m, n, nbF,
    nbG).  The same integrals as the reference-tensor path, summed in
    another order: the kernel over the quadrature points first, then the
    cell's physical basis gradients B (nc, nb, d) applied once,
    K = B_F (sum_q W g3) B_G^T for g3, and for g2 (g1) the kernel
    weighted by the trial (test) function's values.  No per-point
    J^-1 g J^-T and no product with the per-point reference tensors:
    the heat and flow blocks of a P2-displacement scene are integrated
    with the displacement's 14-point rule (manual, performance)."""
    fF, fG = self.disc.field(jb.test), self.disc.field(jb.trial)
    m, n, d = fF.ncomp, fG.ncomp, self.mesh.dim
    W = self.W[cells]
    nc, nq = W.shape
    K = np.zeros((nc, m, n, self.tab(jb.test).phi.shape[1], self.tab(jb.trial).phi.shape[1]))

    def weighted(raw, tail, phi):
        """sum_q W g phi_j (nc, prod(tail), nb): ``phi`` (nq, nb) or None (1)."""
        g, const = self._at_quadrature(raw, nc, nq, tail)
        if const:       # constant over the cell: the rule's sum of W (phi)
            g, w = g.reshape(nc, 1, -1), W.sum(axis=1, keepdims=True)
            w = w[:, :, None] if phi is None else w[:, :, None] * (self.rule.weights @ phi)[None, None] \
                / self.rule.weights.sum()
        else:
            g = g.reshape(nc, nq, -1)
            w = W[:, :, None] if phi is None else W[:, :, None] * phi[None]
        return np.swapaxes(g, 1, 2) @ w                                # (nc, prod(tail), nb or 1)

    if fast["g3"] and self.tab(jb.trial).constant_grad:
        S = weighted(jb.g3(ctx), (m, d, n, d), None).reshape(nc, m, d, n, d)
        BF, BG = self.basis_gradients(jb.test, cells), self.basis_gradients(jb.trial, cells)
        K += (BF[:, None, None] @ S.transpose(0, 1, 3, 2, 4)) @ np.swapaxes(BG, 1, 2)[:, None, None]
    elif fast["g3"]:     # P1 test, P2 trial: sum_q W (g3 J^-T) against the trial's reference gradients
        g = np.broadcast_to(jb.g3(ctx), (nc, nq, m, d, n, d)).reshape(nc, nq * m * d * n, d)
        r = ctx.Jinv.shape[1]
        G = (g @ np.swapaxes(ctx.Jinv, 1, 2)).reshape(nc, nq, m * d * n, r) * W[:, :, None, None]
        H = G.transpose(0, 2, 1, 3).reshape(nc * m * d * n, nq * r) @ self.tab(jb.trial).D
        K += self.basis_gradients(jb.test, cells)[:, None, None] @ \
            H.reshape(nc, m, d, n, -1).transpose(0, 1, 3, 2, 4)
    if fast["g2"]:       # test gradient . g2 . trial value
        T = weighted(jb.g2(ctx), (m, d, n), self.tab(jb.trial).phi).reshape(nc, m, d, n, -1)
        K += self.basis_gradients(jb.test, cells)[:, None, None] @ T.transpose(0, 1, 3, 2, 4)
    if fast["g1"]:       # test value . g1 . trial gradient
        T = weighted(jb.g1(ctx), (m, n, d), self.tab(jb.test).phi).reshape(nc, m, n, d, -1)
        BG = self.basis_gradients(jb.trial, cells)
        K += np.swapaxes(T, 3, 4) @ np.swapaxes(BG, 1, 2)[:, None, None]
    return K
