"""Keep every cohesive cell on the rank of its two rock cells.

The fracture's terms that read the rock cell next to a face (the wall
conduction of the fracture heat's SUPG residual, kernels/wallflux.py) need
that cell on the face's rank.  PETSc's partitioner usually puts a cohesive
cell with its neighbours, but not always (2 of the 10 cohesive cells of a
coarse rigid_fracture mesh on 4 ranks with PETSc 3.18; all 10 with 3.26).
``repair`` checks the partition PETSc made and, where some cohesive cell is
apart from a rock neighbour, moves each group of cells joined through
cohesive cells (a rock cell, its cohesive cell, the rock cell on the other
side) to one rank and distributes the serial mesh
again with that partition (PETSc's shell partitioner).  Set-up only.
"""
from __future__ import annotations

import numpy as np
from petsc4py import PETSc

from petthm import compat


def cohesive_neighbours(dm: PETSc.DMPlex) -> tuple[np.ndarray, np.ndarray]:
    """Each local cohesive cell and the local rock cells next to its two faces:
    (cohesive cells (n,), rock cells (n, 2), -1 where that cell is not local)."""
    _, ce = dm.getHeightStratum(0)
    cs, se = compat.simplex_range(dm, 0)
    coh = np.arange(se, ce, dtype=compat.INT)
    rock = np.full((len(coh), 2), -1, dtype=compat.INT)
    for i, c in enumerate(coh):
        for k, face in enumerate(dm.getCone(int(c))[:2]):
            cells = [p for p in dm.getSupport(int(face)) if cs <= p < se]
            if cells:
                rock[i, k] = cells[0]
    return coh, rock


def split_count(dm: PETSc.DMPlex) -> int:
    """Number of cohesive cells (all ranks) whose rock neighbour is on another rank."""
    _, rock = cohesive_neighbours(dm)
    return dm.comm.tompi4py().allreduce(int((rock < 0).any(axis=1).sum()))


def _cell_owners(dm: PETSc.DMPlex, sf: PETSc.SF, ncells: int) -> np.ndarray | None:
    """On rank 0: the rank each cell of the serial mesh went to (None elsewhere)."""
    _, leaves, remote = sf.getGraph()
    cs, ce = dm.getHeightStratum(0)
    original = np.asarray(remote)[:, 1]
    local = np.arange(len(original)) if leaves is None else np.asarray(leaves)
    mine = original[(local >= cs) & (local < ce)]
    comm = dm.comm.tompi4py()
    parts = comm.gather(mine, root=0)
    if comm.rank:
        return None
    owner = np.full(ncells, -1, dtype=np.int64)
    for r, cells in enumerate(parts):
        owner[cells] = r                               # cells are the first points: 0 .. ncells - 1
    return owner


def _grouped_owners(serial: PETSc.DMPlex, owner: np.ndarray) -> np.ndarray:
    """``owner`` with each group of cells joined through cohesive cells on the
    rank of the group's first rock cell (the rock cells are the partitioner's
    balanced work; the cohesive cells, numbered last, may all sit on one
    rank, as PETSc's simple partitioner puts them)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    coh, rock = cohesive_neighbours(serial)
    n = len(owner)
    i = np.repeat(coh, 2)
    j = rock.ravel()
    graph = coo_matrix((np.ones(len(i)), (i, j)), shape=(n, n))
    _, label = connected_components(graph, directed=False)
    first = np.full(label.max() + 1, -1, dtype=np.int64)
    walls = np.unique(rock)
    first[label[walls[::-1]]] = walls[::-1]                # the smallest rock cell of each group
    grouped = owner.copy()
    joined = first[label] >= 0
    grouped[joined] = owner[first[label[joined]]]
    return grouped


def repair(serial: PETSc.DMPlex, dm: PETSc.DMPlex, sf: PETSc.SF):
    """(dm, sf) as they are when no cohesive cell is apart from its rock
    cells, else ``serial`` distributed again with each cohesive cell's group
    on one rank (``serial``: the mesh before ``dm = serial.distribute()``,
    all of it on rank 0)."""
    if sf is None or split_count(dm) == 0:
        return dm, sf
    comm = dm.comm.tompi4py()
    cs, ce = serial.getHeightStratum(0)
    owner = _cell_owners(dm, sf, ce - cs)
    sizes, points = np.zeros(comm.size, dtype=compat.INT), np.zeros(0, dtype=compat.INT)
    if comm.rank == 0:
        owner = _grouped_owners(serial, owner)
        sizes = np.bincount(owner, minlength=comm.size).astype(compat.INT)
        points = np.argsort(owner, kind="stable").astype(compat.INT) + cs
    part = serial.getPartitioner()
    part.setType(PETSc.Partitioner.Type.SHELL)
    part.setShellPartition(comm.size, sizes, points)
    sf = serial.distribute()
    return serial, sf
