"""Maps between reference and physical cells that the assembly needs
besides the cell's own Jacobian: the basis gradients of the rock cell next
to a fracture face, and a physical flux mapped to the reference cell."""
from __future__ import annotations

import numpy as np

from petthm.discretisation import fe


def adjacent_gradients(surface, side, degree: int, points: np.ndarray) -> np.ndarray:
    """Physical gradients of the basis (``degree``) of the rock cell next to
    each face of a fracture ``surface`` (``mesh.fracture.FractureSurface``)
    on ``side``, at the face's quadrature points (reference ``points`` of the
    face, (nq, rdim)): (nfaces, nq, nb, dim); nq = 1 for P1 (constant over
    the cell)."""
    m, rc = surface.mesh, surface.adjacent_cells(side)
    if degree == 1:
        points = points[:1]
    x = surface.x0[:, None, :] + np.einsum("cak,qk->cqa", surface.J, points)
    xi = np.einsum("cka,cqa->cqk", m.Jinv[rc], x - m.x0[rc][:, None, :])     # in the rock cell
    nc, nq = x.shape[:2]
    dim = surface.dim
    dphi = fe.tabulate(dim, degree, xi.reshape(-1, dim)).dphi.reshape(nc, nq, -1, dim)
    return np.einsum("cqjk,cka->cqja", dphi, m.Jinv[rc])


def reference_flux(f1, Jinv):
    """f1ref[c,q,k,m] = sum_a Jinv[c,k,a] f1[c,q,m,a] (a physical flux mapped to the reference cell)."""
    r, d = Jinv.shape[1], Jinv.shape[2]
    out = np.empty(f1.shape[:2] + (r, f1.shape[2]))
    for k in range(r):
        acc = f1[..., 0] * Jinv[:, None, None, k, 0]
        for a in range(1, d):
            acc += f1[..., a] * Jinv[:, None, None, k, a]
        out[:, :, k, :] = acc
    return out
