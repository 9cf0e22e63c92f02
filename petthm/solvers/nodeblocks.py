"""Per-node block algebra of the contact rows (theory manual, "Contact and friction"): the
rows of one fracture node (lam and the tau components of its friction law)
couple only to each other, so their block of the operator is block
diagonal.  ``node_blocks`` finds the blocks, ``block_inverse`` inverts them
(the rows the contact preconditioner eliminates), ``slip_rotation`` turns a
slipping node's tau rows to the slip direction (``glue.glue_maps``,
``contactpc``; manual, solver guide "Friction")."""
from __future__ import annotations

import numpy as np
from petsc4py import PETSc

from petthm import compat
from petthm.discretisation import probes


def coo_matrix(rows, cols, vals, row_sizes, col_sizes, comm) -> PETSc.Mat:
    """A parallel AIJ matrix from global (row, col, value) triplets, entries
    of other ranks' rows included; repeated entries are summed."""
    M = PETSc.Mat().create(comm=comm)
    M.setSizes((row_sizes, col_sizes))
    M.setType(PETSc.Mat.Type.AIJ)
    compat.coo_preallocate(M, np.asarray(rows, dtype=compat.INT), np.asarray(cols, dtype=compat.INT))
    compat.coo_set_values(M, np.asarray(vals, dtype=float))
    return M


def node_blocks(D: PETSc.Mat, keep: np.ndarray):
    """The diagonal blocks of D over its owned rows ``keep`` (bool per owned
    row) for a D whose nonzeros couple only small groups of rows of one
    rank (the contact rows of one node: lam and the tau components of its
    friction law, theory manual, "Contact and friction"): yields (rows (k, m), blocks
    (k, m, m)) per block size m, rows local, in the order of D."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    r0, r1 = D.getOwnershipRange()
    n = r1 - r0
    ai, aj, av = D.getValuesCSR()
    row = np.repeat(np.arange(n), np.diff(ai))
    col = aj - r0
    big = np.abs(av) > 1e-14 * probes.global_max(D.getComm(), np.abs(av), 0.0)
    sel = (col >= 0) & (col < n) & big
    sel[sel] &= keep[row[sel]] & keep[col[sel]]
    row, col, val = row[sel], col[sel], av[sel]
    _, label = connected_components(coo_matrix((np.ones(len(row)), (row, col)), shape=(n, n)), directed=False)
    kept = np.flatnonzero(keep)
    order = kept[np.argsort(label[kept], kind="stable")]
    _, start, size = np.unique(label[order], return_index=True, return_counts=True)
    position = np.zeros(n, dtype=int)
    position[order] = np.arange(len(order)) - np.repeat(start, size)
    group_of = -np.ones(n, dtype=int)
    group_of[order] = np.repeat(np.arange(len(start)), size)
    for m in np.unique(size):
        which = np.flatnonzero(size == m)
        slot = -np.ones(len(start), dtype=int)
        slot[which] = np.arange(len(which))
        on = slot[group_of[row]] >= 0
        blocks = np.zeros((len(which), m, m))
        blocks[slot[group_of[row[on]]], position[row[on]], position[col[on]]] = val[on]
        yield order[start[which][:, None] + np.arange(m)], blocks


def _block_diagonal(D: PETSc.Mat, parts) -> PETSc.Mat:
    """A matrix of D's layout from diagonal blocks [(rows (k, m), blocks (k, m, m)), ...]."""
    r0 = D.getOwnershipRange()[0]
    out_r, out_c, out_v = [np.zeros(0, dtype=int)], [np.zeros(0, dtype=int)], [np.zeros(0)]
    for rows, blocks in parts:
        m = rows.shape[1]
        out_r.append(np.repeat(rows, m, axis=1).ravel() + r0)
        out_c.append(np.tile(rows, (1, m)).ravel() + r0)
        out_v.append(blocks.ravel())
    r, c, v = (np.concatenate(a) for a in (out_r, out_c, out_v))
    return coo_matrix(r, c, v, D.getSizes()[0], D.getSizes()[1], D.getComm())


def block_inverse(D: PETSc.Mat, keep: np.ndarray) -> PETSc.Mat:
    """The inverse of D restricted to its owned rows and columns ``keep``,
    zero elsewhere (``node_blocks``).  A zero 1 x 1 block is taken as 1 (a
    row with no diagonal that is not glued couples to nothing); larger
    singular blocks take the pseudo-inverse."""
    def inverse(blocks):
        if blocks.shape[1] == 1:
            return 1.0 / np.where(blocks == 0.0, 1.0, blocks)
        return np.linalg.pinv(blocks)
    return _block_diagonal(D, [(rows, inverse(blocks)) for rows, blocks in node_blocks(D, keep)])


def slip_rotation(D: PETSc.Mat, tau: np.ndarray) -> PETSc.Mat:
    """R (contact x contact, orthogonal): the identity, except on the tau rows
    ``tau`` of a slipping node in 3D, whose law's block D_k (I - r (I - zz))
    (r = b/|z| < 1, z the trial traction) couples the two tangents: there R
    takes them to the eigenvectors of the block, the slip direction z (row
    D_k: tau along z is the bound, eliminated) and the direction across it
    (row D_k (1 - r), with the stiffness c r of the slip across the slip
    direction: a constraint as r -> 1).  R D R^T is diagonal per node, so
    each rotated row can be glued or eliminated on its own."""
    r0, r1 = D.getOwnershipRange()
    parts = [(np.arange(r1 - r0)[~tau][:, None], np.ones((int((~tau).sum()), 1, 1)))]
    for rows, blocks in node_blocks(D, tau):
        if rows.shape[1] == 1:
            parts.append((rows, np.ones_like(blocks)))
        else:
            _, vectors = np.linalg.eigh(0.5 * (blocks + np.swapaxes(blocks, 1, 2)))
            parts.append((rows, np.swapaxes(vectors, 1, 2)))            # rows of R: the eigenvectors
    return _block_diagonal(D, parts)
