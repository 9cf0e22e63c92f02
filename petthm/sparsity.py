"""The Jacobian's nonzeros found at node level, and element matrices summed
into them (no physics in here).

Element matrices repeat a nonzero once for every cell that holds both of its
nodes: about 2.5 times for P2 tetrahedra, about 6 times for P1.  PETSc's COO
preallocation sorts every entry it is given; handed the element entries, it
cost 4-6 Jacobian assemblies at 1e4-2.3e4 P2 tetrahedra and 15 at a million
unknowns (docs/performance.md).  So each block of the Jacobian (a pair of
fields over one set of elements) is summed here first:

* once, at set-up, the node pairs of its element matrices are numbered
  (pairs of nodes, not of dofs: for a 3-component block one ninth of the
  element entries): from the simplices' topology (``simplexpairs``, checked
  entry by entry), else by ``np.unique``; then in key order;
* at every assembly the element values are summed into one entry per
  nonzero with ``np.bincount`` over that node-pair index (one pass per
  component pair).

PETSc then sees each nonzero once.  The index kept is one integer per node
pair of an element matrix, not per entry: 1/9 of the entries of a
displacement block.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from . import compat, simplexpairs


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
        keys = (rows[:, ::m].astype(np.int64)[:, :, None] * self.nlocal + cols[:, None, ::n]).reshape(-1)
        if like is not None and like.inv.size == keys.size:
            self.inv, self._any, self.by_topology = like.inv, like._any, like.by_topology
            self.keys = keys[self._any]
            if not np.array_equal(self.keys[self.inv], keys):
                like = None
        if like is None:
            found = self._numbered_by_topology(rows[:, ::m], keys, simplex_dim)
            self.by_topology = found is not None                        # numbered by ``simplexpairs``
            if found is None:
                found = np.unique(keys, return_inverse=True)
            self.keys, inv = found
            self.inv = inv.reshape(-1).astype(np.intp, copy=False)       # one per node pair of an element
            self._any = np.empty(self.keys.size, np.intp)                  # an element entry of each pair
            self._any[self.inv] = np.arange(keys.size)
        self.npairs = self.keys.size
        self.size = self.npairs * m * n
        self.values = self.ne * self.nnF * m * self.nnG * n           # element entries

    def _numbered_by_topology(self, row_nodes: np.ndarray, keys: np.ndarray, dim: int | None):
        """The unique node-pair keys in key order and each element pair's
        index into them, as ``np.unique(keys, return_inverse=True)`` gives
        them, from the simplices' topology; None where the tables are not
        simplex tables or the numbering does not reproduce the pairs
        (checked entry by entry: a slot holds one pair, every slot is used)."""
        if dim is None:
            return None
        found = simplexpairs.pair_slots(row_nodes[:, :dim + 1], dim, self.nnF, self.nnG)
        if found is None:
            return None
        slots, count = found
        inv = slots.reshape(-1)
        unique = np.full(count, -1, np.int64)
        unique[inv] = keys
        if not (np.array_equal(unique[inv], keys) and (unique >= 0).all()):
            return None
        order = np.argsort(unique, kind="stable")      # in key order: PETSc's COO sort and the sums'
        rank = np.empty(count, np.intp)                 # writes run 3-4x and 10-15 % faster (measured)
        rank[order] = np.arange(count)
        return unique[order], rank[inv]

    def pattern(self, global_index: np.ndarray, rows: np.ndarray, cols: np.ndarray) -> None:
        """Global rows and columns of the nonzeros (-1: constrained) written
        into ``rows`` and ``cols`` (``size`` entries each)."""
        r = global_index[(self.keys // self.nlocal)[None, None, :] + np.arange(self.m)[:, None, None]]
        c = global_index[(self.keys % self.nlocal)[None, None, :] + np.arange(self.n)[None, :, None]]
        r, c = np.broadcast_arrays(r, c)
        rows[...], cols[...] = r.reshape(-1), c.reshape(-1)

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
        (a slice) of a slab, each row times ``rowfac`` (nc, nbF, m)."""
        if slab not in self.values:
            self.values[slab] = np.empty(slab.size)
        view = self.blocks[slab.key][0].element_view(self.values[slab])
        np.multiply(K.transpose(1, 2, 0, 3, 4), rowfac.transpose(2, 0, 1)[:, None, :, :, None],
                    out=view[:, :, cells])

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
