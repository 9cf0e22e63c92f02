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
That a slot holds one pair and every slot is used follows when the nodes are
one-to-one functions of the vertices and edges they sit on; that is checked
per node (ne x 10 numbers for P2 tetrahedra), not per element entry (ne x
100).
This is how PETSc's DMPlex finds a matrix's adjacency (through the closure
and star of mesh points); here it is vectorised over cells.
"""
from __future__ import annotations

import itertools
from functools import cache

import numpy as np

from petthm.discretisation import fe, radix


def node_vertex_sets(dim: int, nnodes: int) -> list[tuple] | None:
    """The local vertices under each node of a ``dim``-simplex with
    ``nnodes`` nodes (P1: the vertices; P2: then the edges in ``fe.EDGES``'
    order), or None for another element."""
    nv = dim + 1
    if dim not in fe.EDGES or nnodes not in (nv, nv + len(fe.EDGES[dim])):
        return None
    return [(i,) for i in range(nv)] + [tuple(e) for e in fe.EDGES[dim]][:nnodes - nv]


def _roles(nv: int, sizes_rows: set, sizes_cols: set) -> tuple[np.ndarray, dict]:
    """The role number of each (row mask, column mask) over a carrier of k
    vertices (bit j: the j-th of its vertices in global order) whose union
    is the whole carrier, as a lookup array (k, row mask, column mask; -1:
    no role), and the number of roles per k."""
    lookup, count = np.full((nv + 1, 1 << nv, 1 << nv), -1, np.intp), {}
    for k in range(1, nv + 1):
        full = (1 << k) - 1
        rows = [a for a in range(1, full + 1) if bin(a).count("1") in sizes_rows]
        cols = [b for b in range(1, full + 1) if bin(b).count("1") in sizes_cols]
        pairs = [(a, b) for a in rows for b in cols if a | b == full]
        for i, (a, b) in enumerate(pairs):
            lookup[k, a, b] = i
        count[k] = len(pairs)
    return lookup, count


def _masks(sets) -> np.ndarray:
    """Bit masks of local vertex sets."""
    return np.array([sum(1 << i for i in s) for s in sets], np.intp)


@cache
def _tables(dim: int, nnr: int, nnc: int):
    """Per ordering of a cell's vertices (``code`` = sum_i rank_i nv^i,
    rank_i the position of local vertex i in global order): the carrier and
    the role of each local pair (code, row node, column node), the carrier
    given as a subset of *positions* (an index into ``subsets``, the subsets
    of 0 .. nv-1 by size, each ascending); the position subset each row and
    each column node sits on (code, node); the number of roles per size; and
    per ordering, carrier and role, the row node and the column node of that
    pair (2, code x len(subsets) + carrier, role; -1: none).  Vertex sets are
    bit masks throughout: ``at[p, M]`` is the positions' mask of the local
    mask M under ordering p, ``packed[P, M]`` the bits of M at P's positions
    packed (the carrier's own numbering)."""
    nv = dim + 1
    vr, vc = node_vertex_sets(dim, nnr), node_vertex_sets(dim, nnc)
    subsets = [s for k in range(1, nv + 1) for s in itertools.combinations(range(nv), k)]
    by_mask = np.full(1 << nv, -1, np.intp)                     # position mask -> subset
    by_mask[_masks(subsets)] = np.arange(len(subsets))
    lookup, nroles = _roles(nv, {len(s) for s in vr}, {len(s) for s in vc})
    rank = np.array([np.argsort(p) for p in itertools.permutations(range(nv))])   # (nperm, nv)
    codes = rank @ (nv ** np.arange(nv))
    M = np.arange(1 << nv)
    bits = (M[:, None] >> np.arange(nv)) & 1                    # (mask, vertex)
    at = (bits[None, :, :] << rank[:, None, :]).sum(axis=2)    # (nperm, local mask)
    packed = np.zeros((1 << nv, 1 << nv), np.intp)
    for P in M:
        for j, i in enumerate(np.flatnonzero(bits[P])):
            packed[P] |= bits[:, i] << j
    mr, mc = _masks(vr), _masks(vc)
    node_pos = (by_mask[at[:, mr]], by_mask[at[:, mc]])          # (nperm, node)
    where = at[:, mr[:, None] | mc[None, :]]                    # the carriers' position masks
    carrier = _by_code(by_mask[where], codes, nv)
    role = _by_code(lookup[bits[where].sum(axis=-1), packed[where, at[:, mr][:, :, None]],
                         packed[where, at[:, mc][:, None, :]]], codes, nv)
    node_pos = tuple(_by_code(t, codes, nv) for t in node_pos)
    pair_of = np.full((2, nv ** nv, len(subsets), max(nroles.values())), -1, np.intp)
    a, b = np.meshgrid(np.arange(nnr), np.arange(nnc), indexing="ij")
    pair_of[:, codes[:, None, None], carrier[codes], role[codes]] = np.stack([a, b])[:, None]
    pair_of = pair_of.reshape(2, nv ** nv * len(subsets), -1)     # rows: code x len(subsets) + carrier
    return subsets, carrier, role, node_pos, nroles, pair_of


def _by_code(table: np.ndarray, codes: np.ndarray, nv: int) -> np.ndarray:
    """A per-permutation table indexed by ordering code instead."""
    out = np.full((nv ** nv,) + table.shape[1:], -1, np.intp)
    out[codes] = table
    return out


def _ordered_vertices(v: np.ndarray):
    """Each cell's vertices in ascending order (ne, nv) and its ordering
    class ``code`` = sum_i rank_i nv^i (rank_i: the position of local vertex
    i, the number of the cell's vertices below it); None when a cell repeats
    a vertex (no simplex)."""
    ne, nv = v.shape
    below = v[:, :, None] > v[:, None, :]
    rank = below.sum(axis=2)
    if np.count_nonzero(below) != ne * nv * (nv - 1) // 2:     # a tie: a repeated vertex
        return None
    ordered = np.empty_like(v)
    np.put_along_axis(ordered, rank, v, axis=1)
    return ordered, rank @ (nv ** np.arange(nv))


def _of_size(subsets: list, k: int) -> list[int]:
    """The indices of the k-subsets in ``subsets``."""
    return [i for i, s in enumerate(subsets) if len(s) == k]


def _carrier_ids(ordered: np.ndarray, subsets: list) -> tuple[np.ndarray, dict]:
    """Each cell's id of each sub-simplex (ne, len(subsets)), a position
    subset of its ascending vertices ``ordered``; ids count from 0 per size,
    equal sub-simplices (equal global vertices) have equal ids; and the
    number of ids per size.  A k-subset's key is its first k-1 vertices' id
    and its last vertex, so no key overflows."""
    ne, nv = ordered.shape
    nverts = int(ordered.max()) + 1
    index = {s: i for i, s in enumerate(subsets)}
    ids = np.empty((ne, len(subsets)), np.int32 if ne * len(subsets) < 2**31 else np.int64)
    count = {1: nverts}
    for i, s in enumerate(subsets[:nv]):
        ids[:, i] = ordered[:, s[0]]
    for k in range(2, nv + 1):
        which = _of_size(subsets, k)
        prefix = [index[subsets[i][:-1]] for i in which]
        last = [subsets[i][-1] for i in which]
        key = ids[:, prefix].astype(np.int64) * nverts + ordered[:, last]
        found, count[k] = radix.unique_ids(key)
        ids[:, which] = found.reshape(ne, len(which))
    return ids, count


def _points_are_nodes(table: np.ndarray, point: np.ndarray, npoints: int) -> bool:
    """Whether the node numbers ``table`` (ne, nn) are a one-to-one function of
    the sub-simplices ``point`` (ne, nn) (global ids) they sit on: the same
    vertex or edge, the same node, in every cell; different ones, different
    nodes."""
    node = np.full(npoints, -1, np.int64)
    node[point] = table
    where = np.full(int(table.max()) + 1, -1, np.int64)
    where[table] = point
    return np.array_equal(node[point], table) and np.array_equal(where[table], point)


class SlotNumbering:
    """The node pairs of a block numbered from the topology
    (``numbered_slots``): ``count`` slots; ``row_at``, ``col_at``: where one
    element entry of each slot has its row node and its column node (flat
    indices into the node tables); ``slots(cells)``: the slot of every
    element entry of some cells, made on demand (a block's whole table of
    slots is as large as its element matrices: its users take it in
    batches)."""

    def __init__(self, base, code, carrier, role, count, row_at, col_at):
        self._base, self._code, self._carrier, self._role = base, code, carrier, role
        self._classes = np.unique(code)
        self.count, self.row_at, self.col_at = count, row_at, col_at

    def slots(self, cells: slice) -> np.ndarray:
        """The slots (nc, nnr, nnc) of the element entries of ``cells``:
        base[cell, carrier] + role, one gather per vertex ordering."""
        base, code = self._base[cells], self._code[cells]
        if self._classes.size == 1:                             # a mesh's own cells: one ordering
            c = self._classes[0]
            out = np.take(base, self._carrier[c], axis=1)
            out += self._role[c]
            return out
        out = np.empty((base.shape[0],) + self._role.shape[1:], np.intp)
        for c in self._classes:
            these = np.flatnonzero(code == c)
            out[these] = np.take(base[these], self._carrier[c], axis=1) + self._role[c]
        return out


def numbered_slots(row_nodes: np.ndarray, col_nodes: np.ndarray, dim: int,
                   checked: bool = True) -> SlotNumbering | None:
    """The node pairs of element tables of ``dim``-simplices with P1/P2 row
    and column nodes ``row_nodes`` (ne, nnr) and ``col_nodes`` (ne, nnc)
    (vertices first; the row nodes' vertex numbers are the vertices' ids),
    numbered (``SlotNumbering``).  None for tables that are not such
    simplices': a node count that is not P1/P2's, a cell that repeats a
    vertex, or (``checked``) node numbers that are not one-to-one functions
    of the vertices and edges they sit on; given that, each slot holds one
    node pair and every slot is used (the roles of a carrier are the node
    pairs of any cell that holds it)."""
    ne, nnr = row_nodes.shape
    nnc = col_nodes.shape[1]
    if node_vertex_sets(dim, nnr) is None or node_vertex_sets(dim, nnc) is None or not ne:
        return None
    subsets, carrier, role, node_pos, nroles, pair_of = _tables(dim, nnr, nnc)
    nv = dim + 1
    vertex_ids = row_nodes[:, :nv]
    present = np.zeros(int(vertex_ids.max()) + 1, bool)
    present[vertex_ids] = True
    dense = np.cumsum(present) - 1
    found = _ordered_vertices(dense[vertex_ids])                # vertex ids 0 .. nverts-1
    if found is None:
        return None
    ordered, code = found
    ids, count = _carrier_ids(ordered, subsets)
    first = np.cumsum([0] + [count[k] for k in range(1, nv + 1)])   # ids over all sizes, per size
    point = ids + first[[len(s) - 1 for s in subsets]]
    tables = [(row_nodes, node_pos[0])]
    if not (nnr == nnc and np.array_equal(row_nodes, col_nodes)):  # a field's own block: one check
        tables.append((col_nodes, node_pos[1]))
    if checked and not all(_points_are_nodes(table, np.take_along_axis(point, where[code], axis=1),
                                             int(first[-1])) for table, where in tables):
        return None
    total = sum(count[k] * nroles[k] for k in range(1, nv + 1))
    at_type = np.int32 if ne * max(nnr, nnc) < 2**31 else np.int64     # half the memory
    row_at, col_at = np.empty(total, at_type), np.empty(total, at_type)
    base = np.empty(ids.shape, np.int32 if total < 2**31 else np.int64)   # per carrier: its first slot
    offset = 0
    for k in range(1, nv + 1):
        which = _of_size(subsets, k)
        base[:, which] = offset + ids[:, which] * nroles[k]
        cell = np.empty(count[k], np.intp)                       # a cell holding each carrier ...
        sub = np.empty(count[k], np.intp)
        cell[ids[:, which]] = np.arange(ne)[:, None]
        sub[ids[:, which]] = np.array(which)[None, :]           # ... and the carrier's subset there
        where = code[cell] * len(subsets) + sub
        span = slice(offset, offset + count[k] * nroles[k])
        for at, pairs, nn in ((row_at, pair_of[0], nnr), (col_at, pair_of[1], nnc)):
            out = at[span].reshape(count[k], nroles[k])           # written in place: no temporaries
            np.take(np.ascontiguousarray(pairs[:, :nroles[k]], dtype=at_type), where, axis=0, out=out,
                    mode="clip")
            out += (cell * nn).astype(at_type)[:, None]
        offset += count[k] * nroles[k]
    return SlotNumbering(base, code, carrier, role, int(offset), row_at, col_at)
