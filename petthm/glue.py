"""The algebra of the glued contact (physics.md section 3): which u unknowns
are the two copies of a closed fracture node, the normals, the lumped
weights of the weak opening and of the face load, and the basis Z of the
displacements that keep the closed nodes glued.  ``contactpc`` (the
null-space preconditioner of the {u, lam} block) and
``fieldsplit.split_block`` (the Schur terms of the flow and heat splits)
are built on it; the method is described in ``contactpc``'s docstring.

Everything is a parallel PETSc matrix or vector operation: the pairs are
listed once per problem in its global numbering (``ContactStructure``) and
restricted to the rows of an operator at every set-up (``glue_maps``); the
normals come from the weak opening B itself (the sum of a lam row's
+ face entries per component is the area-weighted normal around the node),
so every rank sees the same normal.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from petsc4py import PETSc

from . import compat, probes

#: a lam row with a diagonal D (the semismooth row of ``vinewtonssls``) is
#: glued when eliminating it would add a normal stiffness b c / D above this
#: multiple of the elasticity's own at its node (then it is a constraint to
#: within 1 %), and eliminated exactly otherwise (``glue_maps``)
STIFF_RATIO = 100.0


@dataclass
class ContactStructure:
    """The {u, lam} pairs of a problem in its global numbering: ``pairs``
    (N x N): row lam_i, columns u+-_i (each free component), value
    side * (component + 1), side = +1 on the + copy and -1 on the - copy;
    ``u``, ``lam``: this rank's (sorted) global unknowns of the two fields."""
    pairs: PETSc.Mat
    u: np.ndarray
    lam: np.ndarray

    def destroy(self) -> None:
        self.pairs.destroy()


def contact_structure(problem) -> ContactStructure:
    """List every (lam, u+, u-) of the fracture's lam nodes whose u is split
    (not the tip): the vertices, and the edge midpoints of a P2 lam.  A
    pair seen by several ranks (ghost cohesive cells) is entered by each of
    them and divided by the number of ranks that did."""
    from .model import Domain, Side, Trace
    disc = problem.disc
    g = disc.global_index
    d = disc.mesh.dim
    lam_dofs = disc.region_dofs(Domain.FRACTURE, "lam")                              # (nc, nb)
    nb = lam_dofs.shape[1]
    up, um = (disc.region_dofs(Domain.FRACTURE, Trace("u", side))[:, :nb * d].reshape(-1, d)
              for side in (Side.PLUS, Side.MINUS))
    local, first = np.unique(lam_dofs.ravel(), return_index=True)
    split = up[first, 0] != um[first, 0]
    lam = g[local[split]]
    u = np.concatenate([g[up[first[split]]], g[um[first[split]]]], axis=1)          # (n, 2d)
    comps = np.arange(d)
    code = np.concatenate([comps + 1, -(comps + 1)]).astype(float)
    rows = np.repeat(lam, 2 * d)
    ok = (rows >= 0) & (u.ravel() >= 0)
    comm = problem.dm.comm
    n, N = problem.X.getSizes()
    count = problem.X.duplicate()
    count.set(0.0)
    listed = lam[lam >= 0]
    count.setValues(listed.astype(compat.INT), np.ones(len(listed)), addv=PETSc.InsertMode.ADD_VALUES)
    count.assemble()
    pairs = _coo_matrix(rows[ok], u.ravel()[ok], np.tile(code, len(lam))[ok], (n, N), (n, N), comm)
    c = count.getArray()
    count.getArray()[:] = np.where(c > 0, 1.0 / np.maximum(c, 1.0), 1.0)
    pairs.diagonalScale(L=count)
    count.destroy()
    names, isets, _ = problem.dm.createFieldDecomposition()
    fields = {name: iset.getIndices().copy() for name, iset in zip(names, isets)}
    return ContactStructure(pairs, fields["u"], fields["lam"])


def _coo_matrix(rows, cols, vals, row_sizes, col_sizes, comm) -> PETSc.Mat:
    """A parallel AIJ matrix from global (row, col, value) triplets, entries
    of other ranks' rows included; repeated entries are summed."""
    M = PETSc.Mat().create(comm=comm)
    M.setSizes((row_sizes, col_sizes))
    M.setType(PETSc.Mat.Type.AIJ)
    compat.coo_preallocate(M, np.asarray(rows, dtype=compat.INT), np.asarray(cols, dtype=compat.INT))
    compat.coo_set_values(M, np.asarray(vals, dtype=float))
    return M


def _index_set(idx: np.ndarray, comm) -> PETSc.IS:
    return PETSc.IS().createGeneral(np.ascontiguousarray(idx, dtype=compat.INT), comm=comm)


@dataclass
class GlueMaps:
    """The contact structure of one operator K (rows ``rows`` of the full
    system, in K's order): ``iu``, ``ilam`` the u and lam rows of K (in K's
    numbering), ``u_full`` the full-system index of each u row; ``pt``
    (lam x u): +n_i on u+_i, -n_i on u-_i (the transpose of the pair matrix
    P); ``glued`` (0/1), ``b``, ``c``, ``diag`` (D) lam vectors; ``code``
    (u vector): side * (component + 1) of a paired u row, 0 elsewhere."""
    iu: PETSc.IS
    ilam: PETSc.IS
    u_full: np.ndarray
    st: PETSc.Mat
    pt: PETSc.Mat
    glued: PETSc.Vec
    b: PETSc.Vec
    c: PETSc.Vec
    diag: PETSc.Vec
    code: PETSc.Vec

    def recovery(self, coupled: bool = False) -> PETSc.Mat:
        """G = diag(glued / c) P^T (lam x u): lam from the normal force the
        glue carries (step 3 of ``contactpc``'s docstring).  ``coupled``:
        every row with a weak opening (b != 0), glued or not: the Schur
        terms of ``fieldsplit.split_block`` take the contact traction of
        the rows the contact PC eliminates (the semismooth rows in
        transition) as if the glue carried the load too, so that a fracture
        pressure keeps the storage of the joint's compliance there."""
        G = self.pt.copy()
        mask = self.glued.duplicate()
        mask.getArray()[:] = (self.b.getArray(readonly=True) != 0.0) if coupled else \
            self.glued.getArray(readonly=True)
        c = _nonzero(self.c)
        mask.pointwiseDivide(mask, c)
        G.diagonalScale(L=mask)
        mask.destroy()
        c.destroy()
        return G

    def destroy(self) -> None:
        for obj in (self.iu, self.ilam, self.st, self.pt, self.glued, self.b, self.c, self.diag, self.code):
            obj.destroy()


def _nonzero(v: PETSc.Vec) -> PETSc.Vec:
    """A copy of ``v`` with its zeros replaced by ones (safe divisor)."""
    w = v.copy()
    a = w.getArray()
    a[a == 0.0] = 1.0
    return w


def glue_maps(K: PETSc.Mat, structure: ContactStructure, rows: np.ndarray) -> GlueMaps:
    """``GlueMaps`` of the operator K whose owned rows are the full-system
    unknowns ``rows`` (sorted)."""
    comm = K.getComm()
    r0 = K.getOwnershipRange()[0]
    is_u, is_lam = np.isin(rows, structure.u), np.isin(rows, structure.lam)
    iu = _index_set(np.flatnonzero(is_u) + r0, comm)
    ilam = _index_set(np.flatnonzero(is_lam) + r0, comm)
    st = structure.pairs.createSubMatrix(_index_set(rows[is_lam], comm), _index_set(rows[is_u], comm))
    B = K.createSubMatrix(ilam, iu)
    ones = st.createVecLeft()
    ones.set(1.0)
    code = st.createVecRight()
    st.multTranspose(ones, code)                               # side * (comp + 1) of each paired u row
    normal = _normals_from_opening(B, code)                    # (m, d) unit normals, from B
    pt = _signed_normals(st, normal)
    w = pt.createVecRight()
    pt.multTranspose(ones, w)                                  # side * n of each paired u row
    b = B.createVecLeft()
    B.mult(w, b)
    C = K.createSubMatrix(iu, ilam)
    c = C.createVecRight()
    C.multTranspose(w, c)
    D = K.createSubMatrix(ilam, ilam)
    diag = D.getDiagonal()
    glued = b.duplicate()
    glued.getArray()[:] = _glued_rows(K, iu, st, b, c, diag).astype(float)
    for obj in (B, C, D, ones, w):
        obj.destroy()
    return GlueMaps(iu, ilam, rows[is_u].copy(), st, pt, glued, b, c, diag, code)


def _glued_rows(K: PETSc.Mat, iu: PETSc.IS, st: PETSc.Mat, b: PETSc.Vec, c: PETSc.Vec,
                diag: PETSc.Vec) -> np.ndarray:
    """Which lam rows the glue holds: those with a weak opening (b != 0) and
    no diagonal, or one so small that eliminating the row would add a
    normal stiffness k = |b c / D| above ``STIFF_RATIO`` times the mean
    diagonal of the elasticity at the row's pair (``vinewtonssls``'s rows
    of closed nodes); the others (open nodes, and the nodes in transition
    of ``vinewtonssls``) are eliminated exactly by the contact PC."""
    dK = K.getDiagonal()
    dA = dK.getSubVector(iu)
    absd = dA.copy()
    absd.abs()
    dK.restoreSubVector(iu, dA)
    pat = pattern_of(st)
    total, count = b.duplicate(), b.duplicate()
    pat.mult(absd, total)
    ones = absd.duplicate()
    ones.set(1.0)
    pat.mult(ones, count)
    a = total.getArray(readonly=True) / np.maximum(count.getArray(readonly=True), 1.0)
    ba, ca, da = (np.abs(v.getArray(readonly=True)) for v in (b, c, diag))
    stiff = ba * ca > STIFF_RATIO * a * da
    out = (ba > 0) & ((da == 0) | stiff)
    for obj in (dK, absd, pat, total, count, ones):
        obj.destroy()
    return out


def _normals_from_opening(B: PETSc.Mat, code: PETSc.Vec) -> np.ndarray:
    """Unit normal at each lam row: the sum of the row's entries on the +
    copy's component k minus those on the - copy's, for each k (the weak
    opening int mu (u+ - u-) . n: its + entries are int mu phi n_k)."""
    cd = code.getArray(readonly=True)
    d = int(probes.global_max(B.getComm(), np.abs(cd), 0.0))
    ind = code.duplicate()
    out = B.createVecLeft()
    n = np.zeros((B.getLocalSize()[0], d))
    for k in range(d):
        ind.getArray()[:] = (cd == k + 1).astype(float) - (cd == -(k + 1)).astype(float)
        B.mult(ind, out)
        n[:, k] = out.getArray(readonly=True)
    ind.destroy()
    out.destroy()
    return n / np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-300)


def _signed_normals(st: PETSc.Mat, normal: np.ndarray) -> PETSc.Mat:
    """P^T: the pair listing with side * (comp + 1) replaced by side * n_comp."""
    ai, aj, av = st.getValuesCSR()
    row = np.repeat(np.arange(len(ai) - 1), np.diff(ai))
    comp = np.rint(np.abs(av)).astype(int) - 1
    vals = np.sign(av) * normal[row, comp] if len(av) else av
    pt = PETSc.Mat().createAIJ(st.getSizes(), csr=(ai, aj, vals), comm=st.getComm())
    pt.assemble()
    return pt


def glued_basis(maps: GlueMaps, A: PETSc.Mat) -> PETSc.Mat:
    """Z (u x v, orthonormal columns): the displacements that keep every
    glued node glued.  A u row that no glued node holds is a column of its
    own; a glued pair with all 2d components free gets the tangential
    components of each copy and one shared normal component; a pair with
    fixed components (a symmetry plane) an orthonormal basis of the null
    space of its constraint n . (u+ - u-) over its free components."""
    comm = A.getComm()
    r0, r1 = A.getOwnershipRange()
    held = maps.code.duplicate()
    ones = pattern_of(maps.st)
    ones.multTranspose(maps.glued, held)                       # > 0 where a glued node holds the row
    free = np.flatnonzero(held.getArray(readonly=True) == 0.0) + r0
    ones.destroy()
    held.destroy()
    ai, aj, codes = maps.st.getValuesCSR()
    codes = np.rint(codes).astype(int)
    vals = maps.pt.getValuesCSR()[2]
    g = np.flatnonzero(maps.glued.getArray(readonly=True) > 0)
    rows, cols, out = [free], [np.arange(len(free))], [np.ones(len(free))]
    ncol = len(free)
    for sel, order in _patterns(ai, codes, g):
        idx = ai[sel][:, None] + order                         # (k, nf) CSR positions, + copy first
        signed = vals[idx]
        constrains = np.linalg.norm(signed, axis=1) > 1e-12
        for part in (constrains, ~constrains):
            if not part.any():
                continue
            v = _pair_basis(signed[part], codes[idx[0]]) if part is constrains else \
                np.broadcast_to(np.eye(idx.shape[1]), (int(part.sum()),) + (idx.shape[1],) * 2)
            k, nb, nf = v.shape
            c = ncol + np.arange(k * nb).reshape(k, nb)
            ncol += k * nb
            rows.append(np.broadcast_to(aj[idx[part]][:, None, :], v.shape).ravel())
            cols.append(np.broadcast_to(c[:, :, None], v.shape).ravel())
            out.append(v.ravel())
    start = comm.tompi4py().exscan(ncol) or 0
    r, c, v = (np.concatenate(a) for a in (rows, cols, out))
    keep = v != 0.0
    return _coo_matrix(r[keep], c[keep] + start, v[keep], (r1 - r0, PETSc.DECIDE), (ncol, PETSc.DECIDE), comm)


def pattern_of(M: PETSc.Mat) -> PETSc.Mat:
    """The nonzero pattern of M with ones."""
    ai, aj, _ = M.getValuesCSR()
    out = PETSc.Mat().createAIJ(M.getSizes(), csr=(ai, aj, np.ones(len(aj))), comm=M.getComm())
    out.assemble()
    return out


def _patterns(ai, codes, rows) -> list:
    """The glued lam rows grouped by the codes of their entries (which
    components of which copy are unknowns), each with the order of its
    entries that puts the + copy first, components ascending:
    [(rows, order (k, nf)), ...]."""
    out = []
    if not len(rows):
        return out
    lengths = np.diff(ai)[rows]
    for n in np.unique(lengths):
        sel = rows[lengths == n]
        mat = codes[ai[sel][:, None] + np.arange(n)]
        order = np.argsort(np.where(mat > 0, mat, 10 - mat), axis=1)
        keys = np.take_along_axis(mat, order, axis=1)
        _, inv = np.unique(keys, axis=0, return_inverse=True)
        inv = inv.ravel()
        for j in range(inv.max() + 1):
            out.append((sel[inv == j], order[inv == j]))
    return out


def _pair_basis(signed: np.ndarray, codes: np.ndarray) -> np.ndarray:
    """Orthonormal bases (k, nb, nf) of the glued displacements of k pairs
    whose entries (+ copy first) have the constraint coefficients
    ``signed`` (k, nf): side * n_comp."""
    k, nf = signed.shape
    d = int(np.abs(codes).max())
    if nf == 2 * d:                                            # a whole pair
        n = signed[:, :d]
        t = _tangents(n)                                       # (k, d-1, d)
        v = np.zeros((k, 2 * d - 1, nf))
        v[:, :d - 1, :d] = t
        v[:, d - 1:2 * d - 2, d:] = t
        v[:, -1, :d] = n / np.sqrt(2.0)
        v[:, -1, d:] = n / np.sqrt(2.0)
        return v
    # fixed components: the null space of the (nonzero) constraint row
    return np.linalg.svd(signed[:, None, :])[2][:, 1:]          # row 0 of V^T is along the constraint


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
