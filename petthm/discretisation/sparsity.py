"""The Jacobian's nonzeros found at node level, and element matrices summed
into them (no physics in here).

Element matrices repeat a nonzero once for every cell that holds both of its
nodes: about 2.5 times for P2 tetrahedra, about 6 times for P1.  PETSc's COO
preallocation sorts every entry it is given; handed the element entries, it
cost 4-6 Jacobian assemblies at 1e4-2.3e4 P2 tetrahedra and 15 at a million
unknowns (manual, performance).  So each block of the Jacobian (a pair of
fields over one set of elements) is summed here first:

* once, at set-up, the node pairs of its element matrices are numbered
  (pairs of nodes, not of dofs: for a 3-component block one ninth of the
  element entries): from the simplices' topology (``simplexpairs``; it
  checks, node by node, that the nodes are one-to-one functions of the
  vertices and edges), else by ``np.unique``; then in key order
  (``radix.key_order``: numpy's SIMD sort where it has one, else a radix
  sort), the slots made in batches of cells;
* at every assembly the element values are summed into one entry per
  nonzero with ``np.bincount`` over that node-pair index (one pass per
  component pair).

PETSc then sees each nonzero once.  The index kept is one integer per node
pair of an element matrix, not per entry: 1/9 of the entries of a
displacement block.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from petthm import compat
from petthm.discretisation import radix, simplexpairs

SLOT_BATCH = 4096         # cells whose slots are made at once (~3 MB for P2 tetrahedra)


class NodePairs:
    """The nonzeros of one block: ``ne`` element matrices over the dofs
    ``rows`` (ne, nnF*m) and ``cols`` (ne, nnG*n) (local dofs, node-major,
    the components of a node consecutive: ``Discretisation``'s element
    tables), m and n components per node.  The nonzeros are ordered by
    component pair (a, b), then node pair (row node, column node): each
    component pair's sums are one contiguous ``np.bincount`` result."""

    def __init__(self, rows: np.ndarray, cols: np.ndarray, m: int, n: int, nlocal: int,
                 like: NodePairs | None = None, simplex_dim: int | None = None):
        """``like``: a block over the same element node tables (other fields
        of the same degree on the same elements): its node-pair index is
        shared (not made again, nor stored twice) when it reproduces this
        block's node pairs, which it does because a field's local dofs
        increase with the mesh point (checked, entry by entry).
        ``simplex_dim``: the elements are simplices of this dimension with
        P1 or P2 node tables (vertices, then edges), one cell each: the node
        pairs are numbered from their topology (``simplexpairs``), and
        ``np.unique`` is the fallback."""
        self.m, self.n, self.nlocal = m, n, int(nlocal)
        self.ne = rows.shape[0]
        self.nnF, self.nnG = rows.shape[1] // m, cols.shape[1] // n
        row_nodes, col_nodes = rows[:, ::m], cols[:, ::n]
        if like is not None and (like.ne, like.nnF, like.nnG) == (self.ne, self.nnF, self.nnG):
            self.inv, self.by_topology = like.inv, like.by_topology
            self._at = (like.pairs_at(), None)
            self.row_node, self.col_node = self._nodes_at(row_nodes, col_nodes)
            if not np.array_equal(self.keys[self.inv], self._element_keys(row_nodes, col_nodes)):
                like = None
        if like is None:
            found = self._numbered_by_topology(row_nodes, col_nodes, simplex_dim)
            self.by_topology = found is not None                        # numbered by ``simplexpairs``
            if found is None:
                keys, inv = np.unique(self._element_keys(row_nodes, col_nodes), return_inverse=True)
                self.row_node, self.col_node = np.divmod(keys, self.nlocal)
                entry = np.empty(keys.size, np.intp)                       # an element entry of each pair
                entry[inv] = np.arange(inv.size)
                cell, a, b = np.unravel_index(entry, (self.ne, self.nnF, self.nnG))
                self._at = ((cell * self.nnF + a, cell * self.nnG + b), None)
            else:
                self.row_node, self.col_node, inv, self._at = found
            self.inv = inv.reshape(-1).astype(np.intp, copy=False)       # one per node pair of an element
        self.npairs = self.row_node.size
        self.size = self.npairs * m * n
        self.values = self.ne * self.nnF * m * self.nnG * n           # element entries

    def pairs_at(self) -> tuple[np.ndarray, np.ndarray]:
        """Where one element entry of each node pair has its row node and its
        column node (flat indices into the node tables), in key order; put in
        that order when first asked for (when another block shares this
        one's index)."""
        at, order = self._at
        if order is not None:
            self._at = at, order = (at[0][order], at[1][order]), None
        return at

    def _nodes_at(self, row_nodes: np.ndarray, col_nodes: np.ndarray):
        """The row and the column node of each node pair in these tables."""
        row_at, col_at = self.pairs_at()
        return (np.ascontiguousarray(row_nodes).reshape(-1)[row_at],
                np.ascontiguousarray(col_nodes).reshape(-1)[col_at])

    @property
    def keys(self) -> np.ndarray:
        """The node pairs' keys, row node x nlocal + column node, ascending."""
        return self.row_node.astype(np.int64) * self.nlocal + self.col_node

    def _element_keys(self, row_nodes: np.ndarray, col_nodes: np.ndarray) -> np.ndarray:
        """The node-pair key (row node x nlocal + column node) of every element
        entry, flat."""
        return (row_nodes.astype(np.int64)[:, :, None] * self.nlocal + col_nodes[:, None, :]).reshape(-1)

    def _numbered_by_topology(self, row_nodes: np.ndarray, col_nodes: np.ndarray, dim: int | None):
        """The node pairs' row and column nodes in key order, each element
        pair's index into them (as ``np.unique(keys, return_inverse=True)``
        gives them) and where the tables hold each pair's nodes with the key
        order (``pairs_at``), from the simplices' topology; None where the tables are not simplex
        tables (``simplexpairs.numbered_slots``' check)."""
        if dim is None:
            return None
        found = simplexpairs.numbered_slots(row_nodes, col_nodes, dim)
        if found is None:
            return None
        row = np.ascontiguousarray(row_nodes).reshape(-1)[found.row_at]
        col = np.ascontiguousarray(col_nodes).reshape(-1)[found.col_at]
        keys = row.astype(np.int64)
        keys *= self.nlocal
        keys += col
        counting = np.arange(found.count)
        order = radix.key_order(keys, overwrite=True, counting=counting)   # in key order: PETSc's
        del keys
        rank = np.empty(found.count, np.intp)           # COO sort and the sums' writes run 3-4x and
        rank[order] = counting                          # 10-15 % faster (measured)
        del counting
        inv = np.empty((self.ne, self.nnF * self.nnG), np.intp)
        for s in range(0, self.ne, SLOT_BATCH):          # batches of cells: the slots stay in cache
            cells = slice(s, min(s + SLOT_BATCH, self.ne))
            np.take(rank, found.slots(cells).reshape(-1), out=inv[cells].reshape(-1), mode="clip")
        return row[order], col[order], inv.reshape(-1), ((found.row_at, found.col_at), order)

    def pattern(self, global_index: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> None:
        """Global rows and columns of the nonzeros (-1: constrained) written
        into ``rows`` and ``cols`` (``size`` entries each)."""
        R, C = rows.reshape(self.m, self.n, -1), cols.reshape(self.m, self.n, -1)
        for a in range(self.m):            # gathered straight into the pattern: no temporaries
            np.take(global_index, self.row_node + a if a else self.row_node, out=R[a, 0], mode="clip")
            R[a, 1:] = R[a, 0]
        for b in range(self.n):
            np.take(global_index, self.col_node + b if b else self.col_node, out=C[0, b], mode="clip")
            C[1:, b] = C[0, b]

    def element_view(self, values: np.ndarray) -> np.ndarray:
        """The element values of this block as (m, n, ne, nnF, nnG): the
        layout ``add`` reads (component pair, element, row node, column node)."""
        return values.reshape(self.m, self.n, self.ne, self.nnF, self.nnG)

    def add(self, values: np.ndarray, out: np.ndarray) -> None:
        """``out`` (``size`` entries, ``pattern``'s order) += the element
        values (``element_view``'s layout) summed per nonzero."""
        v = values.reshape(self.m * self.n, -1)
        o = out.reshape(self.m * self.n, self.npairs)
        for k in range(self.m * self.n):
            o[k] += np.bincount(self.inv, weights=v[k], minlength=self.npairs)


@dataclass(frozen=True, eq=False)
class Slab:
    """One term's element values: ``size`` entries (``NodePairs``'s element
    layout), summed into the block ``key`` (a pair of fields, or a facet
    term's field, boundary and batch); ``constant``: the term does not
    depend on the state (``model.CellJacobian.constant``).  Two terms of
    the same pair of fields are two slabs (compared by identity)."""
    key: tuple
    size: int
    constant: bool = False


class SummedBlocks:
    """An assembler's Jacobian: the element values of its terms (one
    ``Slab`` each) and the blocks they are summed into, in the order of
    their first slab.  ``make_block(key)`` makes a block's ``NodePairs``
    when the pattern is first asked for."""

    def __init__(self, slabs: list[Slab], make_block: Callable[[tuple], NodePairs]):
        self.slabs, self._make = slabs, make_block
        self.varying = {sl.key for sl in slabs if not sl.constant}   # blocks with a state-dependent term
        self._blocks = None
        self.values = {}               # slab -> its element values (of the last assembly)
        self.assembled = False         # the last call's sums hold the constant terms

    @property
    def blocks(self) -> dict:
        """{key: (``NodePairs``, offset in the sums)}, made once."""
        if self._blocks is None:
            self._blocks, pos = {}, 0
            for slab in self.slabs:
                if slab.key not in self._blocks:
                    b = self._make(slab.key)
                    self._blocks[slab.key] = (b, pos)
                    pos += b.size
        return self._blocks

    @property
    def nnz(self) -> int:
        """Number of sums (one per nonzero of each block)."""
        return sum(b.size for b, _ in self.blocks.values())

    def pattern(self, global_index, rows=None, cols=None):
        """Global rows and columns of the sums (-1: constrained), into
        ``rows`` and ``cols`` when given."""
        return concatenated_pattern([b for b, _ in self.blocks.values()], global_index, rows, cols)

    def store(self, slab: Slab, K: np.ndarray, rowfac: np.ndarray, cells) -> None:
        """Element matrices K (nc, m, n, nbF, nbG) of the elements ``cells``
        (a slice or an index array) of a slab, each row times ``rowfac`` (nc, nbF, m)."""
        if slab not in self.values:
            self.values[slab] = np.empty(slab.size)
        view = self.blocks[slab.key][0].element_view(self.values[slab])
        product = (K.transpose(1, 2, 0, 3, 4), rowfac.transpose(2, 0, 1)[:, None, :, :, None])
        if isinstance(cells, slice):
            np.multiply(*product, out=view[:, :, cells])
        else:                                      # index arrays (``Assembler.chunks``): no view
            view[:, :, cells] = np.multiply(*product)

    def skips(self, slab: Slab, keep_constant: bool) -> bool:
        """Whether a slab's element values need not be computed: a constant
        term, after an assembly whose sums the caller kept."""
        return keep_constant and self.assembled and slab.constant

    def sum(self, out: np.ndarray, keep_constant: bool) -> np.ndarray:
        """The element values summed into ``out`` (``nnz`` entries);
        ``keep_constant``: the blocks of constant terms only are left as
        they are in ``out`` (the caller's buffer of the last call).  The
        element values of those blocks are not kept: they are summed again
        only after the scaling changed, and computed again then (for linear
        elasticity, most of the element values)."""
        keep_constant = keep_constant and self.assembled
        blocks = self.blocks
        for key, (b, pos) in blocks.items():
            if not keep_constant or key in self.varying:
                out[pos:pos + b.size] = 0.0
        for slab in self.slabs:
            if slab.size and (not keep_constant or slab.key in self.varying):   # a rank may hold none
                b, pos = blocks[slab.key]
                b.add(self.values[slab], out[pos:pos + b.size])
            if slab.key not in self.varying:
                self.values.pop(slab, None)
        self.assembled = True
        return out


def concatenated_pattern(blocks, global_index, rows=None, cols=None):
    """Rows and columns of ``blocks`` one after another (into ``rows`` and
    ``cols`` when given)."""
    size = sum(b.size for b in blocks)
    if rows is None:
        rows, cols = np.empty(size, compat.INT), np.empty(size, compat.INT)
    pos = 0
    for b in blocks:
        b.pattern(global_index, rows[pos:pos + b.size], cols[pos:pos + b.size])
        pos += b.size
    return rows, cols
