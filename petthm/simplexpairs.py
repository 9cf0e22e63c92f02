"""The nonzeros of a Jacobian block over simplices numbered from the
elements' topology, without sorting the element entries (no physics here).

A node of a P1 or P2 simplex is a vertex or an edge's midpoint: a set of one
or two of the cell's vertices.  A pair of nodes (row node, column node) is
carried by the smallest sub-simplex that holds both: the union of their
vertex sets (a vertex, an edge, a face or the cell).  Within its carrier the
pair is one of a fixed set of *roles*: which of the carrier's vertices each
node sits on, the carrier's vertices taken in the order of their global
numbers.  The same pair seen from two cells has the same carrier and role, and
two different pairs differ in one or the other, so

    slot = offset(carrier's size) + carrier id * roles(size) + role

numbers the block's nonzeros once each.  The carriers' ids come from their
sorted vertex tuples (edges, faces, cells: a few entries per cell, against
the 100 entries of a P2 tetrahedron's element matrix that ``np.unique``
sorted before); the roles from a table per ordering of the cell's vertices.
This is how PETSc's DMPlex finds a matrix's adjacency (through the closure
and star of mesh points); here it is vectorised over cells.
"""
from __future__ import annotations

import itertools
from functools import lru_cache

import numpy as np

from . import fe


def node_vertex_sets(dim: int, nnodes: int) -> list[tuple] | None:
    """The local vertices under each node of a ``dim``-simplex with
    ``nnodes`` nodes (P1: the vertices; P2: then the edges in ``fe.EDGES``'
    order), or None for another element."""
    nv = dim + 1
    if dim not in fe.EDGES or nnodes not in (nv, nv + len(fe.EDGES[dim])):
        return None
    return [(i,) for i in range(nv)] + [tuple(e) for e in fe.EDGES[dim]][:nnodes - nv]


def _roles(nv: int, sizes_rows: set, sizes_cols: set) -> tuple[dict, dict]:
    """Per carrier size k: the role number of each (row mask, column mask)
    over the carrier's k vertices (bit j: the j-th vertex in global order)
    whose union is the whole carrier, as a lookup array (-1: no role), and
    the number of roles."""
    lookup, count = {}, {}
    for k in range(1, nv + 1):
        full = (1 << k) - 1
        rows = [a for a in range(1, full + 1) if bin(a).count("1") in sizes_rows]
        cols = [b for b in range(1, full + 1) if bin(b).count("1") in sizes_cols]
        pairs = [(a, b) for a in rows for b in cols if a | b == full]
        lookup[k] = np.full((1 << k, 1 << k), -1, np.intp)
        for i, (a, b) in enumerate(pairs):
            lookup[k][a, b] = i
        count[k] = len(pairs)
    return lookup, count


@lru_cache(maxsize=None)
def _tables(dim: int, nnr: int, nnc: int):
    """The carriers (local vertex subsets, by size), and per ordering of the
    cell's vertices (``code`` = sum_i rank_i nv^i) the carrier and role of each
    local pair (code, row node, column node); the number of roles per size."""
    nv = dim + 1
    vr, vc = node_vertex_sets(dim, nnr), node_vertex_sets(dim, nnc)
    subsets = [s for k in range(1, nv + 1) for s in itertools.combinations(range(nv), k)]
    index = {s: i for i, s in enumerate(subsets)}
    lookup, nroles = _roles(nv, {len(s) for s in vr}, {len(s) for s in vc})
    rank = np.array([np.argsort(p) for p in itertools.permutations(range(nv))])   # (nperm, nv)
    codes = rank @ (nv ** np.arange(nv))
    carrier = np.full((nv ** nv, nnr, nnc), -1, np.intp)
    role = np.full((nv ** nv, nnr, nnc), -1, np.intp)
    for (a, sa), (b, sb) in itertools.product(enumerate(vr), enumerate(vc)):
        S = tuple(sorted(set(sa) | set(sb)))
        rs = rank[:, S]                                          # position of S's vertices in order
        pos = (rs[:, :, None] > rs[:, None, :]).sum(axis=2)      # ... among S's own
        bit = 1 << pos
        ma = bit[:, [S.index(i) for i in sa]].sum(axis=1)
        mb = bit[:, [S.index(i) for i in sb]].sum(axis=1)
        carrier[codes, a, b] = index[S]
        role[codes, a, b] = lookup[len(S)][ma, mb]
    return subsets, carrier, role, nroles


def _tuple_ids(t: np.ndarray, nvals: int) -> tuple[np.ndarray, int]:
    """Ids 0 .. count-1 of the rows of ``t`` (n, k), each sorted, of values
    below ``nvals``: equal rows, equal ids."""
    k = t.shape[1]
    if float(nvals) ** k < 2.0 ** 62:
        key = t[:, 0].astype(np.int64)
        for j in range(1, k):
            key = key * nvals + t[:, j]
        u, ids = np.unique(key, return_inverse=True)
        return ids.reshape(-1), u.size
    ids, count = t[:, 0].astype(np.int64), nvals
    for j in range(1, k):                                   # pairwise, when k values overflow
        u, ids = np.unique(ids.reshape(-1) * nvals + t[:, j], return_inverse=True)
        count = u.size
    return ids.reshape(-1), count


def pair_slots(vertex_ids: np.ndarray, dim: int, nnr: int, nnc: int):
    """The slot of every element entry, (ne, nnr, nnc), and the number of
    slots (nonzeros), for element tables of ``dim``-simplices with ``nnr`` row
    and ``nnc`` column nodes whose vertices have the ids ``vertex_ids`` (ne,
    dim+1); None for tables that are not such simplices'."""
    if node_vertex_sets(dim, nnr) is None or node_vertex_sets(dim, nnc) is None or not vertex_ids.size:
        return None
    subsets, carrier, role, nroles = _tables(dim, nnr, nnc)
    ne, nv = vertex_ids.shape
    present = np.zeros(int(vertex_ids.max()) + 1, bool)
    present[vertex_ids] = True
    dense = np.cumsum(present) - 1
    v = dense[vertex_ids]                                   # 0 .. nverts-1
    nverts = int(dense[-1]) + 1
    rank = np.empty((ne, nv), np.intp)
    np.put_along_axis(rank, np.argsort(v, axis=1, kind="stable"), np.arange(nv)[None, :], axis=1)
    code = rank @ (nv ** np.arange(nv))
    base = np.empty((ne, len(subsets)), np.intp)              # per carrier: its first slot
    offset = 0
    for k in range(1, nv + 1):
        which = [i for i, s in enumerate(subsets) if len(s) == k]
        if k == 1:
            ids, count = v, nverts
        else:
            t = np.sort(v[:, np.array([subsets[i] for i in which])], axis=2).reshape(-1, k)
            ids, count = _tuple_ids(t, nverts)
        base[:, which] = offset + ids.reshape(ne, len(which)) * nroles[k]
        offset += count * nroles[k]
    slots = np.take_along_axis(base, carrier[code].reshape(ne, -1), axis=1)
    slots += role[code].reshape(ne, -1)
    return slots.reshape(ne, nnr, nnc), offset
