"""The wells of a deck's mesh (``../shared/docs/reservoir.md`` section 1): a
named physical group of dimension 1 in a 3D mesh (a polyline of mesh edges)
or of dimension 0 in a 2D mesh (points, a well normal to the plane).

PETSc's gmsh reader labels no group of dimension 1 in a 3D mesh, so rank 0
reads each well's elements from the file with gmsh and broadcasts, per
node of the well: its position, its share of the well's length (half of
each segment beside it; 1 in 2D), the well's direction there, the mean
length of the mesh edges at the node, and the fraction of the node's cells
in each region (what the well index needs: ``physics/linewells.py``).  The
whole file is read on rank 0 for that, once at set-up.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from petthm.errors import InputError


@dataclass(frozen=True)
class WellPath:
    name: str
    points: np.ndarray          # (n, dim)
    length: np.ndarray          # (n,) m (1 in 2D)
    direction: np.ndarray | None    # (n, 3) unit vectors along the well (3D), None in 2D
    edge: np.ndarray            # (n,) mean length of the mesh edges at the node (m)
    regions: np.ndarray         # (n, number of regions): fraction of the node's cells in each


def read_well_paths(path: str, dim: int, wells, regions, comm) -> list[WellPath]:
    """The ``WellPath`` of each well group of ``wells`` (``groups.Group``) in
    the mesh file ``path`` of dimension ``dim``, with ``regions`` (groups of
    the cells) in that order (collective; rank 0 reads)."""
    found, message = None, None
    if comm.rank == 0:
        try:
            found = _read(path, dim, list(wells), list(regions))
        except InputError as e:
            message = str(e)
    message = comm.bcast(message, root=0)
    if message:
        raise InputError(message)
    return comm.bcast(found, root=0)


def _read(path, dim, wells, regions) -> list[WellPath]:
    import gmsh
    if gmsh.isInitialized():
        gmsh.finalize()
    gmsh.initialize(["gmsh"], readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        gmsh.open(path)
        cells, cell_region = _cells(gmsh, dim, regions)
        tags, xyz, _ = gmsh.model.mesh.getNodes()
        coords = np.zeros((int(tags.max()) + 1, 3))
        coords[tags.astype(np.int64)] = xyz.reshape(-1, 3)
        return [_path(gmsh, dim, w, cells, cell_region, coords, len(regions)) for w in wells]
    finally:
        gmsh.finalize()


def _cells(gmsh, dim, regions):
    """(node tags of every cell (nc, dim + 1), the region index of each)."""
    nodes, region = [], []
    for index, g in enumerate(regions):
        for entity in gmsh.model.getEntitiesForPhysicalGroup(dim, g.tag):
            types, _, node_tags = gmsh.model.mesh.getElements(dim, entity)
            for t, n in zip(types, node_tags, strict=True):
                props = gmsh.model.mesh.getElementProperties(t)          # (.., number of nodes, .., corners)
                arr = np.asarray(n, dtype=np.int64).reshape(-1, props[3])[:, :props[5]]
                nodes.append(arr)
                region.append(np.full(len(arr), index))
    return np.concatenate(nodes), np.concatenate(region)


def _path(gmsh, dim, group, cells, cell_region, coords, nregions) -> WellPath:
    line = dim == 3
    want = 1 if line else 0
    if group.dim != want:
        raise InputError(f"well {group.name}: a physical group of dimension {want} in a {dim}D mesh "
                         f"({'a polyline of mesh edges' if line else 'points'}), not {group.dim}")
    segments = []
    for entity in gmsh.model.getEntitiesForPhysicalGroup(group.dim, group.tag):
        types, _, node_tags = gmsh.model.mesh.getElements(group.dim, entity)
        for t, n in zip(types, node_tags, strict=True):
            per = gmsh.model.mesh.getElementProperties(t)[3]
            segments.append(np.asarray(n, dtype=np.int64).reshape(-1, per)[:, :2 if line else 1])
    if not segments:
        raise InputError(f"well {group.name}: its physical group has no mesh elements")
    seg = np.concatenate(segments)
    tags = np.unique(seg)
    x = coords[tags]
    slot = {int(t): i for i, t in enumerate(tags)}
    length = np.ones(len(tags))
    direction = None
    if line:
        length = np.zeros(len(tags))
        tensor = np.zeros((len(tags), 3, 3))
        for a, b in seg:
            v = coords[b] - coords[a]
            L = float(np.linalg.norm(v))
            for t in (a, b):
                length[slot[int(t)]] += L / 2
                tensor[slot[int(t)]] += np.outer(v, v) / max(L, 1e-300)
        direction = np.array([np.linalg.eigh(T)[1][:, -1] for T in tensor])
    edge, fractions = _around(group.name, tags, x, cells, cell_region, coords, nregions)
    return WellPath(group.name, x[:, :dim], length, direction, edge, fractions)


def _around(name, tags, x, cells, cell_region, coords, nregions):
    """Per node: the mean length of the mesh edges at it, and the fraction
    of its cells in each region; an error for a node that no cell has."""
    touching = np.isin(cells, tags)
    rows = np.flatnonzero(touching.any(axis=1))
    edge = np.zeros(len(tags))
    fractions = np.zeros((len(tags), nregions))
    count = np.zeros(len(tags))
    position = {int(t): i for i, t in enumerate(tags)}
    for r in rows:
        c = cells[r]
        for j in np.flatnonzero(touching[r]):
            i = position[int(c[j])]
            others = coords[np.delete(c, j)]
            edge[i] += float(np.mean(np.linalg.norm(others - coords[c[j]], axis=1)))
            fractions[i, cell_region[r]] += 1
            count[i] += 1
    if np.any(count == 0):
        k = int(np.flatnonzero(count == 0)[0])
        raise InputError(f"well {name}: its node at ({', '.join(f'{v:.6g}' for v in x[k])}) is not a vertex "
                         "of the mesh's cells (embed the well's line or point in the geometry)")
    return edge / count, fractions / count[:, None]
