"""p-multigrid for quadratic (P2) displacement: the elasticity solve of the
block preconditioner as two levels, P2 smoothed on the fine level and the
P1 (vertex) displacement as the coarse level, solved by algebraic multigrid.

Aggregation AMG (GAMG) converges about three times slower on P2 elasticity
than on P1 (manual, solver guide), so the coarse space of P2 is given by the
discretisation itself: the interpolation I from vertex values to P2 nodal
values (a vertex node keeps its value, an edge node takes the mean of its
two vertices).  PETSc's PCMG runs the cycle: Chebyshev/Jacobi smoothing of
the P2 operator, the Galerkin coarse operator I^T A I by GAMG with the
rigid-body modes (linear fields, exactly in the P1 space).

With the contact's glued basis Z (``contactpc``) the levels are the glued
spaces: the fine operator Z^T A Z, the interpolation Z^T I Z_v with Z_v the
columns of Z on vertex rows (a P1 field glued at the vertices interpolates
to a P2 field glued at the vertices: I Z_v lies in the range of Z).
"""
from __future__ import annotations

import numpy as np
from petsc4py import PETSc

from petthm import compat
from petthm.solvers.glue import pattern_of


def p1_interpolation(problem) -> tuple[PETSc.Mat, np.ndarray] | None:
    """(I, vertex rows): the interpolation of the u unknowns from their
    vertex values in the problem's global numbering (N x N; the columns of
    the vertex unknowns only), and this rank's vertex unknowns (sorted);
    None when u is not P2.  Constrained vertex values (Dirichlet) are not
    unknowns: their part of an edge value is dropped (the correction is 0
    there)."""
    disc = problem.disc
    if "u" not in disc.index or disc.field("u").degree != 2:
        return None
    mesh = disc.mesh
    pts = disc.node_points("u")
    g = disc.global_index[disc.field_local_dofs("u")]               # (n, d) global, -1: constrained
    d = g.shape[1]
    own = disc._owned(g)
    isv = (pts >= mesh.vstart) & (pts < mesh.vend)
    ise = (pts >= mesh.estart) & (pts < mesh.eend)
    ends = mesh.edge_vertices[pts[ise] - mesh.estart] + mesh.vstart   # (ne, 2) vertex points
    gv = disc.global_index[disc.offsets["u"][ends - disc.pstart][..., None] + np.arange(d)]  # (ne, 2, d)
    ok_v = own[isv] & (g[isv] >= 0)
    rows = [g[isv][ok_v], np.broadcast_to(g[ise][:, None, :], gv.shape).ravel()]
    cols = [g[isv][ok_v], gv.ravel()]
    vals = [np.ones(int(ok_v.sum())), np.full(gv.size, 0.5)]
    rows, cols, vals = (np.concatenate(a) for a in (rows, cols, vals))
    keep = (rows >= 0) & (cols >= 0) & disc._owned(rows)
    n, N = problem.X.getSizes()
    M = PETSc.Mat().create(comm=problem.dm.comm)
    M.setSizes(((n, N), (n, N)))
    M.setType(PETSc.Mat.Type.AIJ)
    compat.coo_preallocate(M, rows[keep], cols[keep])
    compat.coo_set_values(M, vals[keep])
    return M, np.unique(g[isv][ok_v])


def glued_interpolation(interp: tuple[PETSc.Mat, np.ndarray], u_full: np.ndarray,
                        Z: PETSc.Mat | None, comm):
    """The interpolation P between the P1 and P2 levels of an elasticity
    operator on the u unknowns ``u_full`` (full-system numbering, this
    rank's, sorted) in its glued basis Z (None: the unknowns themselves),
    and the map ``coarse(r)`` of a linear field r (a vector of the u
    unknowns) to the coarse coordinates c with P c = Z^T r."""
    I_full, vertex = interp
    u_is = PETSc.IS().createGeneral(np.asarray(u_full, dtype=compat.INT), comm=comm)
    I = I_full.createSubMatrix(u_is, u_is)                            # (u x u), vertex columns only
    u_is.destroy()
    r0 = I.getOwnershipRange()[0]
    on_vertex = np.isin(u_full, vertex)
    if Z is None:
        cols = PETSc.IS().createGeneral((np.flatnonzero(on_vertex) + r0).astype(compat.INT), comm=comm)
        P = _columns(I, cols)
        I.destroy()

        def coarse(r):
            sub = r.getSubVector(cols)
            out = sub.copy()
            r.restoreSubVector(cols, sub)
            return out
        return P, coarse
    # the columns of Z with no entry on an edge row: the glued P1 space
    edge = Z.createVecLeft()
    edge.getArray()[:] = (~on_vertex).astype(float)
    touch = Z.createVecRight()
    A = pattern_of(Z)
    A.multTranspose(edge, touch)
    c0 = touch.getOwnershipRange()[0]
    cols = PETSc.IS().createGeneral((np.flatnonzero(touch.getArray() == 0.0) + c0).astype(compat.INT),
                                    comm=comm)
    Zv = _columns(Z, cols)
    IZ = I.matMult(Zv)
    P = Z.transposeMatMult(IZ)
    for obj in (I, IZ, A, edge, touch, cols):
        obj.destroy()

    def coarse(r):
        out = Zv.createVecRight()
        Zv.multTranspose(r, out)
        return out
    return P, coarse


def _columns(M: PETSc.Mat, cols: PETSc.IS) -> PETSc.Mat:
    """M[:, cols] (all rows, in their distribution)."""
    r0, r1 = M.getOwnershipRange()
    rows = PETSc.IS().createStride(r1 - r0, r0, 1, comm=M.getComm())
    out = M.createSubMatrix(rows, cols)
    rows.destroy()
    return out


def set_two_level(ksp: PETSc.KSP, A: PETSc.Mat, P: PETSc.Mat, coarse_modes: list[PETSc.Vec]) -> PETSc.Mat:
    """Make ``ksp`` (operator A) a two-level PCMG: Chebyshev/Jacobi on A,
    the coarse operator P^T A P by GAMG with ``coarse_modes`` as its
    near-nullspace; the user's options (the KSP's prefix, ``mg_levels_``,
    ``mg_coarse_``) override.  Returns the coarse operator (the caller
    destroys it)."""
    from petthm.solvers.nullspace import orthonormal_nullspace
    pc = ksp.getPC()
    pc.setType("mg")
    pc.setMGLevels(2)
    pc.setMGInterpolation(1, P)
    Ac = compat.ptap(A, P)
    Ac.setNearNullSpace(orthonormal_nullspace(coarse_modes, A.getComm()))
    coarse = pc.getMGCoarseSolve()
    coarse.setOperators(Ac)
    coarse.setType("preonly")
    coarse.getPC().setType("gamg")
    smooth = pc.getMGSmoother(1)
    smooth.setType("chebyshev")
    smooth.getPC().setType("jacobi")
    return Ac
