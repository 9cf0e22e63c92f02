"""A null-space preconditioner for frictionless contact: the {u, lam} block

    K = [ A  C ]      A: elasticity (u rows), C: the face loads of lam,
        [ B  0 ]      B: the weak opening of the closed nodes (lam rows)

of the VI reduced system (physics.md section 3; kernels/contact.py).

A closed node i holds the normal opening at zero: the constraint glues the
normal displacement of its two copies u+_i, u-_i.  With the lumped
(nodal) weights b_i+ = sum_k B[i, u+_k . n], b_i- (and c_i+-, the same
sums of the lam column of C), the preconditioner solves

    1. u_p: the normal jump that B u = r_lam asks for, split evenly
       between the faces (u_p+- = +- r_lam,i / (b_i+ - b_i-) n);
    2. A_Z v = Z^T (r_u - A u_p), with Z the orthonormal basis of the
       displacements that keep every closed node glued (the tangential
       components of each copy, and one shared normal component): A_Z =
       Z^T A Z is the elasticity of the body glued along its closed
       fracture parts, for algebraic multigrid (GAMG, the rigid-body modes
       Z^T r) like any elasticity matrix; u = Z v + u_p;
    3. lam_i from the normal force the glue carries:
       lam_i = [(r_u - A u)_i+ - (r_u - A u)_i-] . n / (c_i+ - c_i-).

With B and C exact nodal (lumped) operators and an exact A_Z solve this is
the null-space method, an exact solve; with the consistent weak opening it
is spectrally equivalent to it with constants independent of the mesh
(lumped against consistent mass), so the outer Krylov count does not grow
under refinement.  Rows of lam that do not couple to u (an open node on the
full space of ``vinewtonssls``: its semismooth row is nearly lam = 0) are
solved by their diagonal and not glued.

The PC gets its structure (which rows are lam, which u rows are the two
copies of a fracture vertex, the normals) from ``layout``: a ``ContactLayout``
in the numbering of the operator it preconditions.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from petsc4py import PETSc

from . import compat
from .fieldsplit import orthonormal_nullspace, rigid_modes


@dataclass
class ContactLayout:
    """The {u, lam} structure of an operator, in its row numbering (this
    rank's rows; serial for now).  ``lam``: rows of the lam unknowns (n,);
    ``plus``, ``minus``: the u rows of the two copies of the same vertex
    (n, d); ``normal``: its unit normal (n, d); ``u``: every u row (sorted),
    ``u_coords`` its node's coordinates and ``u_comp`` its component (for
    the rigid-body modes)."""
    lam: np.ndarray
    plus: np.ndarray
    minus: np.ndarray
    normal: np.ndarray
    u: np.ndarray
    u_coords: np.ndarray
    u_comp: np.ndarray


def layout_of(problem, space: np.ndarray | None = None) -> ContactLayout:
    """The contact layout of a problem's (reduced) system: global rows, or
    positions in ``space`` (the sorted unknowns of a VI reduced system);
    vertices whose lam is not an unknown there (tip, open nodes of RSLS)
    are left out."""
    from .model import Domain
    disc = problem.disc
    surf = disc.regions[Domain.FRACTURE]
    g = disc.global_index
    pairs = np.unique(np.column_stack([surf.cell_vertices.ravel(), surf.plus_vertices.ravel()]), axis=0)
    pairs = pairs[pairs[:, 0] != pairs[:, 1]]                       # tip vertices are not split
    pts = pairs + surf.vstart - disc.pstart
    lam = g[disc.offsets["lam"][pts[:, 0]]]
    d = disc.mesh.dim
    minus = g[disc.offsets["u"][pts[:, 0]][:, None] + np.arange(d)]
    plus = g[disc.offsets["u"][pts[:, 1]][:, None] + np.arange(d)]
    normal = _vertex_normals(surf, pairs[:, 0])
    keep = lam >= 0
    udofs = disc.field_local_dofs("u")                                # (nodes, d)
    ug = g[udofs]
    xyz = np.broadcast_to(disc.field_node_coordinates("u")[:, None, :], udofs.shape + (d,))
    comp = np.broadcast_to(np.arange(d), udofs.shape)
    ok = ug >= 0
    u, first = np.unique(ug[ok], return_index=True)
    u_coords, u_comp = xyz[ok][first], comp[ok][first]
    lam, minus, plus, normal = lam[keep], minus[keep], plus[keep], normal[keep]
    if space is not None:
        inside = np.isin(lam, space)
        lam, minus, plus, normal = lam[inside], minus[inside], plus[inside], normal[inside]
        lam = np.searchsorted(space, lam)
        minus, plus = (np.where(a >= 0, np.searchsorted(space, a), -1) for a in (minus, plus))
        inu = np.isin(u, space)
        u, u_coords, u_comp = np.searchsorted(space, u[inu]), u_coords[inu], u_comp[inu]
    return ContactLayout(lam.astype(compat.INT), plus.astype(compat.INT), minus.astype(compat.INT), normal,
                         u.astype(compat.INT), u_coords, u_comp)


def _vertex_normals(surf, verts: np.ndarray) -> np.ndarray:
    """The mean unit normal of the faces around each - vertex."""
    n = np.zeros((len(verts), surf.dim))
    pos = {int(v): k for k, v in enumerate(verts)}
    for f, cv in enumerate(surf.cell_vertices):
        for v in cv:
            k = pos.get(int(v))
            if k is not None:
                n[k] += surf.normals[f]
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)


def _tangents(n: np.ndarray) -> np.ndarray:
    """An orthonormal basis of the plane normal to each n: (m, d - 1, d)."""
    m, d = n.shape
    if d == 2:
        return np.stack([-n[:, 1], n[:, 0]], axis=1)[:, None, :]
    a = np.where(np.abs(n[:, [0]]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    t1 = a - np.sum(a * n, axis=1, keepdims=True) * n
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(n, t1)
    return np.stack([t1, t2], axis=1)


class ContactNullspacePC:
    """``-pc_type python -pc_python_type petthm.contactpc.ContactNullspacePC``
    with the layout set by ``serve`` (see the module docstring).  The A_Z
    solve takes the options prefix ``contact_`` (default: one GAMG V-cycle:
    ``-contact_ksp_type preonly -contact_pc_type gamg``)."""

    def __init__(self, layout: ContactLayout | None = None):
        self.layout = layout
        self.ksp = None

    def setUp(self, pc):
        K, _ = pc.getOperators()
        if K.getComm().getSize() > 1:
            raise NotImplementedError("ContactNullspacePC runs on one rank so far (docs/solvers.md)")
        lay = self.layout if self.layout is not None else pc.getAttr("petthm_contact_layout")
        if lay is None:
            raise RuntimeError("ContactNullspacePC needs a ContactLayout")
        n = K.getSize()[0]
        is_lam = np.zeros(n, dtype=bool)
        is_lam[lay.lam] = True
        urows = np.flatnonzero(~is_lam).astype(compat.INT)
        self.urows, self.lamrows = urows, lay.lam
        u_is = PETSc.IS().createGeneral(urows, comm=PETSc.COMM_SELF)
        lam_is = PETSc.IS().createGeneral(lay.lam, comm=PETSc.COMM_SELF)
        self.A = K.createSubMatrix(u_is, u_is)
        B = K.createSubMatrix(lam_is, u_is)
        C = K.createSubMatrix(u_is, lam_is)
        D = K.createSubMatrix(lam_is, lam_is).getDiagonal().getArray().copy()
        pos = np.full(n, -1, dtype=compat.INT)
        pos[urows] = np.arange(len(urows))
        # (m, d) in the u numbering; -1: a fixed component (not an unknown)
        plus = np.where(lay.plus >= 0, pos[np.maximum(lay.plus, 0)], -1)
        minus = np.where(lay.minus >= 0, pos[np.maximum(lay.minus, 0)], -1)
        self.plus, self.minus, self.normal = plus, minus, lay.normal
        m = len(lay.lam)
        side = np.zeros(len(urows))
        nrm = np.zeros(len(urows))
        for rows, sign in ((plus, 1.0), (minus, -1.0)):
            ok = rows >= 0
            side[rows[ok]] = sign
            nrm[rows[ok]] = lay.normal[ok]
        # lumped weights: B's + and - columns along n (row sums), C's rows (column sums)
        ai, aj, av = B.getValuesCSR()
        rows = np.repeat(np.arange(m), np.diff(ai))
        w = av * nrm[aj]
        self.b_plus = np.bincount(rows, weights=w * (side[aj] > 0), minlength=m)
        self.b_minus = np.bincount(rows, weights=w * (side[aj] < 0), minlength=m)
        ci, cj, cv = C.getValuesCSR()
        crow = np.repeat(np.arange(len(urows)), np.diff(ci))
        wc = cv * nrm[crow]
        self.c_plus = np.bincount(cj, weights=wc * (side[crow] > 0), minlength=m)
        self.c_minus = np.bincount(cj, weights=wc * (side[crow] < 0), minlength=m)
        scale = np.maximum(np.abs(self.b_plus - self.b_minus), 1e-300)
        self.glued = np.abs(self.b_plus - self.b_minus) > 1e-8 * max(np.abs(D).max(initial=0.0), 1e-300) \
            if m else np.zeros(0, dtype=bool)
        self.glued |= np.abs(D) <= 1e-12 * scale
        self.diag = np.where(D != 0.0, D, 1.0)
        self.Z = self._basis(len(urows))
        AZ = compat.ptap(self.A, self.Z)
        AZ.setNearNullSpace(self._rigid_modes(lay, urows))
        self._set_inner(pc, AZ)
        self.r_u = self.A.createVecLeft()
        self.work = self.A.createVecLeft()
        self.v = self.Z.createVecRight()
        self.zr = self.Z.createVecRight()

    def _basis(self, nu: int) -> PETSc.Mat:
        """Z: the glued displacements (orthonormal columns), (nu, nv).  A
        glued pair with all 2d components free gets the tangential
        components of each copy and one shared normal component; a pair
        with fixed components (a symmetry plane) the null space of its
        constraint n . (u+ - u-) over its free components."""
        d = self.normal.shape[1] if len(self.normal) else 0
        g = np.flatnonzero(self.glued)
        plus, minus, n = self.plus[g], self.minus[g], self.normal[g]
        special = np.zeros(nu, dtype=bool)
        for side in (plus, minus):
            special[side[side >= 0]] = True
        free = np.flatnonzero(~special)
        rows, cols, vals = [free], [np.arange(len(free))], [np.ones(len(free))]
        col = len(free)
        whole = np.all(plus >= 0, axis=1) & np.all(minus >= 0, axis=1)
        if whole.any():
            p, m, nw = plus[whole], minus[whole], n[whole]
            t = _tangents(nw)                                          # (k, d-1, d)
            for side in (p, m):                                        # tangential components of each copy
                for k in range(d - 1):
                    c = col + np.arange(len(nw))
                    col += len(nw)
                    rows.append(side.ravel())
                    cols.append(np.repeat(c, d))
                    vals.append(t[:, k, :].ravel())
            c = col + np.arange(len(nw))                               # the shared normal component
            col += len(nw)
            for side in (p, m):
                rows.append(side.ravel())
                cols.append(np.repeat(c, d))
                vals.append(nw.ravel() / np.sqrt(2.0))
        for k in np.flatnonzero(~whole):                               # few: fixed components
            dofs = np.concatenate([plus[k], minus[k]])
            cvec = np.concatenate([n[k], -n[k]])[dofs >= 0]
            dofs = dofs[dofs >= 0]
            basis = np.linalg.svd(cvec[None, :])[2][1:] if np.linalg.norm(cvec) > 1e-12 else np.eye(len(dofs))
            for vec in basis:
                rows.append(dofs)
                cols.append(np.full(len(dofs), col))
                vals.append(vec)
                col += 1
        r, c, v = (np.concatenate(a) for a in (rows, cols, vals))
        keep = np.abs(v) > 0.0
        r, c, v = r[keep], c[keep], v[keep]
        order = np.lexsort((c, r))
        r, c, v = r[order], c[order], v[order]
        ai = np.concatenate([[0], np.cumsum(np.bincount(r, minlength=nu))]).astype(compat.INT)
        Z = PETSc.Mat().createAIJ([nu, col], csr=(ai, c.astype(compat.INT), v), comm=PETSc.COMM_SELF)
        Z.assemble()
        return Z

    def _rigid_modes(self, lay: ContactLayout, urows: np.ndarray) -> PETSc.NullSpace:
        """The rigid-body modes of the glued body: Z^T r for the translations
        and rotations r of the u rows (they are glued displacements)."""
        pos = np.searchsorted(lay.u, urows)
        x = lay.u_coords[pos] - lay.u_coords.mean(axis=0)
        comp = lay.u_comp[pos]
        r, vecs = self.Z.createVecLeft(), []
        for m in rigid_modes(comp, x):
            r.getArray()[:] = m
            v = self.Z.createVecRight()
            self.Z.multTranspose(r, v)
            vecs.append(v)
        return orthonormal_nullspace(vecs, PETSc.COMM_SELF)

    def _set_inner(self, pc, AZ):
        if self.ksp is None:
            self.ksp = PETSc.KSP().create(comm=PETSc.COMM_SELF)
            self.ksp.setOptionsPrefix((pc.getOptionsPrefix() or "") + "contact_")
            self.ksp.setType("preonly")
            self.ksp.getPC().setType("gamg")
        self.ksp.setOperators(AZ)
        self.ksp.setFromOptions()
        self.ksp.setUp()

    def _normal_part(self, f: np.ndarray, side: np.ndarray) -> np.ndarray:
        """sum over the free components of f[side] . n (fixed components: 0)."""
        vals = np.where(side >= 0, f[np.maximum(side, 0)], 0.0)
        return np.einsum("md,md->m", vals, self.normal)

    def apply(self, pc, x, y):
        xa = x.getArray(readonly=True)
        r_u, r_lam = xa[self.urows], xa[self.lamrows]
        g = self.glued
        u = np.zeros(len(self.urows))
        jump = np.where(g, r_lam / np.where(g, self.b_plus - self.b_minus, 1.0), 0.0)
        for side, sign in ((self.plus, 1.0), (self.minus, -1.0)):
            ok = side >= 0
            u[side[ok]] += (sign * jump[:, None] * self.normal)[ok]
        self.work.getArray()[:] = u
        self.A.mult(self.work, self.r_u)                              # A u_p
        self.r_u.getArray()[:] = r_u - self.r_u.getArray(readonly=True)
        self.Z.multTranspose(self.r_u, self.zr)
        self.ksp.solve(self.zr, self.v)
        self.Z.mult(self.v, self.work)
        u = u + self.work.getArray(readonly=True)
        self.work.getArray()[:] = u
        self.A.mult(self.work, self.r_u)
        f = r_u - self.r_u.getArray(readonly=True)                    # the force the glue carries
        fn = np.zeros(len(self.lamrows))
        if len(fn):
            den = self.c_plus - self.c_minus
            glue = (self._normal_part(f, self.plus) - self._normal_part(f, self.minus)) / \
                np.where(g & (den != 0), den, 1.0)
            fn = np.where(g, glue, r_lam / self.diag)
        ya = y.getArray()
        ya[self.urows] = u
        ya[self.lamrows] = fn
