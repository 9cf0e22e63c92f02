"""The algebra of the glued contact (theory manual, "Contact and friction"): which u unknowns
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

from petthm import compat
from petthm.discretisation import probes
from petthm.solvers.nodeblocks import coo_matrix, slip_rotation

#: a lam row with a diagonal D (the semismooth row of ``vinewtonssls``) is
#: glued when eliminating it would add a normal stiffness b c / D above this
#: multiple of the elasticity's own at its node (then it is a constraint to
#: within 1 %), and eliminated exactly otherwise (``glue_maps``)
STIFF_RATIO = 100.0


@dataclass
class ContactStructure:
    """The contact pairs of a problem in its global numbering: ``pairs``
    (N x N): row r (a contact unknown: lam_i, or a component of the
    friction traction tau_i), columns u+-_i (each free component of the
    node's two copies), value side * (component + 1), side = +1 on the +
    copy and -1 on the - copy; ``u``, ``lam``, ``tau``: this rank's
    (sorted) global unknowns of the fields (``tau`` empty without
    friction); ``tangent``: for each owned unknown of the full system
    (from ``first``), the tangent t_k of a tau row as k + 1, 0 on every
    other row (the lam rows constrain the normal)."""
    pairs: PETSc.Mat
    u: np.ndarray
    lam: np.ndarray
    tau: np.ndarray
    tangent: np.ndarray
    first: int

    def constraints(self) -> np.ndarray:
        """The contact unknowns (lam and tau), this rank's, sorted."""
        return np.union1d(self.lam, self.tau)

    def destroy(self) -> None:
        self.pairs.destroy()


def contact_structure(problem) -> ContactStructure:
    """List every (lam, u+, u-) of the fracture's lam nodes whose u is split
    (not the tip): the vertices, and the edge midpoints of a P2 lam; and
    every (tau_k, u+, u-) of the same nodes with friction.  A pair seen by
    several ranks (ghost cohesive cells) is entered by each of them and
    divided by the number of ranks that did."""
    from petthm.discretisation.model import Domain, Side, Trace
    disc = problem.disc
    g = disc.global_index
    d = disc.mesh.dim
    names = [f.name for f in disc.fields]
    lam_dofs = disc.region_dofs(Domain.FRACTURE, "lam")                              # (nc, nb)
    nc, nb = lam_dofs.shape
    up, um = (disc.region_dofs(Domain.FRACTURE, Trace("u", side))[:, :nb * d].reshape(-1, d)
              for side in (Side.PLUS, Side.MINUS))
    local, first = np.unique(lam_dofs.ravel(), return_index=True)
    split = up[first, 0] != um[first, 0]
    node_rows = [g[local[split]][:, None]]                                           # (n, 1 + d - 1)
    kinds = [np.zeros(1, dtype=int)]
    if "tau" in names:
        tau_dofs = disc.region_dofs(Domain.FRACTURE, "tau").reshape(nc * nb, d - 1)   # same nodes as lam
        node_rows.append(g[tau_dofs[first[split]]])
        kinds.append(np.arange(1, d))
    rows_by_node = np.concatenate(node_rows, axis=1)                                  # (n, k)
    kind = np.concatenate(kinds)
    k = rows_by_node.shape[1]
    u = np.concatenate([g[up[first[split]]], g[um[first[split]]]], axis=1)          # (n, 2d)
    comps = np.arange(d)
    code = np.concatenate([comps + 1, -(comps + 1)]).astype(float)
    rows = np.repeat(rows_by_node.ravel(), 2 * d)
    cols = np.repeat(u, k, axis=0).ravel()
    ok = (rows >= 0) & (cols >= 0)
    comm = problem.dm.comm
    n, N = problem.X.getSizes()
    listed = rows_by_node.ravel()
    mine = listed >= 0
    count = _marked(problem.X, listed[mine], np.ones(int(mine.sum())), PETSc.InsertMode.ADD_VALUES)
    tangent = _marked(problem.X, listed[mine], np.tile(kind, len(rows_by_node))[mine],
                      PETSc.InsertMode.INSERT_VALUES)
    pairs = coo_matrix(rows[ok], cols[ok], np.tile(code, len(listed))[ok], (n, N), (n, N), comm)
    c = count.getArray()
    count.getArray()[:] = np.where(c > 0, 1.0 / np.maximum(c, 1.0), 1.0)
    pairs.diagonalScale(L=count)
    fields = {name: iset.getIndices().copy()
              for name, iset in zip(*problem.dm.createFieldDecomposition()[:2], strict=False)}
    none = np.zeros(0, dtype=compat.INT)
    tangent_of = np.rint(tangent.getArray(readonly=True)).astype(int)
    out = ContactStructure(pairs, fields["u"], fields["lam"], fields.get("tau", none), tangent_of,
                           tangent.getOwnershipRange()[0])
    count.destroy()
    tangent.destroy()
    return out


def _marked(like: PETSc.Vec, idx: np.ndarray, values: np.ndarray, mode) -> PETSc.Vec:
    """A vector of ``like``'s layout, zero but at the global ``idx`` (any
    rank's), which get ``values`` (added or inserted by ``mode``)."""
    out = like.duplicate()
    out.set(0.0)
    out.setValues(idx.astype(compat.INT), np.asarray(values, dtype=float), addv=mode)
    out.assemble()
    return out


def _index_set(idx: np.ndarray, comm) -> PETSc.IS:
    return PETSc.IS().createGeneral(np.ascontiguousarray(idx, dtype=compat.INT), comm=comm)


@dataclass
class GlueMaps:
    """The contact structure of one operator K (rows ``rows`` of the full
    system, in K's order): ``iu``, ``ilam`` the u rows and the contact rows
    (lam, and tau with friction) of K (in K's numbering), ``u_full`` the
    full-system index of each u row; ``pt`` (contact x u): +e on u+_i, -e on
    u-_i with e the row's direction (n_i for lam, t_k for tau_k; the
    transpose of the pair matrix P); ``glued`` (0/1), ``b``, ``c``,
    ``diag`` (D) contact-row vectors; ``code`` (u vector): side *
    (component + 1) of a paired u row, 0 elsewhere; ``kind`` (numpy, per
    contact row): 0 for lam, k for tau_k."""
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
    kind: np.ndarray
    rot: PETSc.Mat

    def contact_blocks(self, K: PETSc.Mat) -> tuple[PETSc.Mat, PETSc.Mat, PETSc.Mat]:
        """(B, C, D): the contact rows' weak jumps (contact x u), their face
        loads (u x contact) and their own block (contact x contact) of K,
        in the rotated contact rows of ``rot`` (``slip_rotation``): R B,
        C R^T, R D R^T."""
        return _rotated_blocks(K, self.iu, self.ilam, self.rot)

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
        mask.getArray()[:] = ((self.b.getArray(readonly=True) != 0.0) & (self.kind == 0)) if coupled else \
            self.glued.getArray(readonly=True)
        c = _nonzero(self.c)
        mask.pointwiseDivide(mask, c)
        G.diagonalScale(L=mask)
        mask.destroy()
        c.destroy()
        return G

    def destroy(self) -> None:
        for obj in (self.iu, self.ilam, self.st, self.pt, self.glued, self.b, self.c, self.diag, self.code,
                    self.rot):
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
    is_u, is_lam = np.isin(rows, structure.u), np.isin(rows, structure.constraints())
    iu = _index_set(np.flatnonzero(is_u) + r0, comm)
    ilam = _index_set(np.flatnonzero(is_lam) + r0, comm)
    kind = structure.tangent[rows[is_lam] - structure.first]                 # 0: lam, k: tau along t_k
    st = structure.pairs.createSubMatrix(_index_set(rows[is_lam], comm), _index_set(rows[is_u], comm))
    D0 = K.createSubMatrix(ilam, ilam)
    rot = slip_rotation(D0, kind > 0)
    D0.destroy()
    B, C, D = _rotated_blocks(K, iu, ilam, rot)
    ones = st.createVecLeft()
    ones.set(1.0)
    code = _pair_codes(st, ones)                               # side * (comp + 1) of each paired u row
    pt = _signed_normals(st, _normals_from_opening(B, code))   # each row's direction, from B
    b, c = _lumped_weights(pt, B, C, kind)
    diag = D.getDiagonal()
    glued = b.duplicate()
    glued.getArray()[:] = _glued_rows(K, iu, st, b, c, diag).astype(float)
    for obj in (B, C, D, ones):
        obj.destroy()
    return GlueMaps(iu, ilam, rows[is_u].copy(), st, pt, glued, b, c, diag, code, kind, rot)


def _rotated_blocks(K: PETSc.Mat, iu: PETSc.IS, ilam: PETSc.IS, rot: PETSc.Mat):
    """R B, C R^T, R D R^T of K's contact rows ``ilam`` (see ``GlueMaps.contact_blocks``)."""
    B0, C0, D0 = K.createSubMatrix(ilam, iu), K.createSubMatrix(iu, ilam), K.createSubMatrix(ilam, ilam)
    rt = rot.copy()
    rt.transpose()
    B, C = rot.matMult(B0), C0.matMult(rt)
    DR = D0.matMult(rt)
    D = rot.matMult(DR)
    for obj in (B0, C0, D0, DR, rt):
        obj.destroy()
    return B, C, D


def _pair_codes(st: PETSc.Mat, ones: PETSc.Vec) -> PETSc.Vec:
    """side * (component + 1) of each u row of the pairs ``st``, 0 on the
    other rows (the listing's column sums over the number of contact rows
    of the node: lam, and the tau components with friction)."""
    code, count = st.createVecRight(), st.createVecRight()
    st.multTranspose(ones, code)
    pattern = pattern_of(st)
    pattern.multTranspose(ones, count)
    code.pointwiseDivide(code, _nonzero(count))
    for obj in (count, pattern):
        obj.destroy()
    return code


def _lumped_weights(pt: PETSc.Mat, B: PETSc.Mat, C: PETSc.Mat, kind: np.ndarray):
    """b = B w and c = C^T w of each contact row, w = P 1 over the rows of
    its own kind (the normal, or the tangent t_k): the lumped weights of
    the row's weak jump and of its face load, with the other directions'
    rows of the same node left out (they are orthogonal to it)."""
    b, c = B.createVecLeft(), C.createVecRight()
    b.set(0.0)
    c.set(0.0)
    mask, w, bk, ck = b.duplicate(), pt.createVecRight(), b.duplicate(), c.duplicate()
    for k in range(int(probes.global_max(B.getComm(), kind, 0)) + 1):
        on = (kind == k).astype(float)
        mask.getArray()[:] = on
        pt.multTranspose(mask, w)                              # side * direction of each paired u row
        B.mult(w, bk)
        C.multTranspose(w, ck)
        b.getArray()[:] += on * bk.getArray(readonly=True)
        c.getArray()[:] += on * ck.getArray(readonly=True)
    for obj in (mask, w, bk, ck):
        obj.destroy()
    return b, c


def _glued_rows(K: PETSc.Mat, iu: PETSc.IS, st: PETSc.Mat, b: PETSc.Vec, c: PETSc.Vec,
                diag: PETSc.Vec) -> np.ndarray:
    """Which contact rows (rotated: ``slip_rotation``) the glue holds: those
    with a weak jump (b != 0) and no diagonal (a closed node's lam row; a
    sticking node's tau rows, C = c ds), and those with a diagonal so small
    that eliminating the row would add a stiffness k = |b c / D| above
    ``STIFF_RATIO`` times the mean diagonal of the elasticity at the row's
    pair (``vinewtonssls``'s rows of closed nodes; the row across the slip
    direction of a node that has just started to slip); the others (open
    nodes, the nodes in transition of ``vinewtonssls``, the slip direction
    of a slipping node) are eliminated exactly by the contact PC."""
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
    """Unit direction of each contact row (the normal of a lam row, the
    tangent of a sticking tau row): the sum of the row's entries on the +
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
    own; a pair glued along its normal only, with all 2d components free,
    gets the tangential components of each copy and one shared normal
    component; a pair with fixed components (a symmetry plane), or glued
    along several directions (a closed sticking node), an orthonormal basis
    of the null space of its constraints e . (u+ - u-) over its free
    components (``_pair_bases``)."""
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
    members = _rows_by_pair(ai, aj, np.flatnonzero(maps.glued.getArray(readonly=True) > 0))
    rows, cols, out = [free], [np.arange(len(free))], [np.ones(len(free))]
    ncol = len(free)
    for sel, order in _patterns(ai, codes, members[:, 0]):
        idx = ai[sel][:, None] + order                         # (k, nf) CSR positions, + copy first
        group = members[np.searchsorted(members[:, 0], sel)]  # the node's glued rows
        at = ai[np.maximum(group, 0)][:, :, None] + order[:, None, :]
        signed = np.where(group[:, :, None] >= 0, vals[at], 0.0)   # (k, rows of the node, nf)
        for part, v in _pair_bases(signed, codes[idx[0]]):
            k, nb, nf = v.shape
            c = ncol + np.arange(k * nb).reshape(k, nb)
            ncol += k * nb
            rows.append(np.broadcast_to(aj[idx[part]][:, None, :], v.shape).ravel())
            cols.append(np.broadcast_to(c[:, :, None], v.shape).ravel())
            out.append(v.ravel())
    start = comm.tompi4py().exscan(ncol) or 0
    r, c, v = (np.concatenate(a) for a in (rows, cols, out))
    keep = v != 0.0
    return coo_matrix(r[keep], c[keep] + start, v[keep], (r1 - r0, PETSc.DECIDE), (ncol, PETSc.DECIDE), comm)


def _rows_by_pair(ai, aj, rows) -> np.ndarray:
    """The glued contact rows grouped by the node pair they constrain
    (rows of one node list the same u columns): (pairs, d) local rows, the
    first column sorted, -1 where a node has fewer glued rows."""
    if not len(rows):
        return np.zeros((0, 1), dtype=int)
    key = aj[ai[rows]]                                         # the pair's first u column
    order = np.lexsort((rows, key))
    rows, key = rows[order], key[order]
    _, start, count = np.unique(key, return_index=True, return_counts=True)
    out = -np.ones((len(start), int(count.max())), dtype=int)
    rank = np.arange(len(rows)) - np.repeat(start, count)
    out[np.repeat(np.arange(len(start)), count), rank] = rows
    return out[np.argsort(out[:, 0])]


def _pair_bases(signed: np.ndarray, codes: np.ndarray):
    """Orthonormal bases of the glued displacements of k pairs with the
    constraint rows ``signed`` (k, rows, nf; zero rows: none): yields
    (mask of the pairs, bases (m, nb, nf)) per kind.  A pair with one
    constraint (the normal of a closed node) takes ``_pair_basis``; with
    none (its rows restricted to the free components vanish) every
    component is its own column; with several (a sticking closed node:
    the normal and the tangents) the null space of its constraints."""
    k, m, nf = signed.shape
    norms = np.linalg.norm(signed, axis=2)
    count = (norms > 1e-12).sum(axis=1)
    if (count == 1).any():
        part = count == 1
        one = signed[part, np.argmax(norms[part], axis=1)]
        yield part, _pair_basis(one, codes)
    if (count == 0).any():
        part = count == 0
        yield part, np.broadcast_to(np.eye(nf), (int(part.sum()), nf, nf))
    if (count > 1).any():
        part = np.flatnonzero(count > 1)
        _, sv, vt = np.linalg.svd(signed[part])
        rank = (sv > 1e-10 * sv[:, :1]).sum(axis=1)
        for r in np.unique(rank):
            mask = np.zeros(k, dtype=bool)
            mask[part[rank == r]] = True
            yield mask, vt[rank == r][:, r:, :]


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
