"""The cell limit of mesh generation (-thm_max_cells): a size that would
make more cells than the limit is refused before gmsh meshes
(``generate``)."""
from __future__ import annotations

import contextlib
import contextvars

import numpy as np

#: the most cells a generated mesh may have (-thm_max_cells), for the meshing in the ``with
#: cell_limit(n)`` block that sets it
CELL_LIMIT: contextvars.ContextVar[int] = contextvars.ContextVar("cell_limit", default=5_000_000)


@contextlib.contextmanager
def cell_limit(cells: int):
    """Mesh generation in this block refuses more than ``cells`` cells."""
    token = CELL_LIMIT.set(int(cells))
    try:
        yield
    finally:
        CELL_LIMIT.reset(token)


def fewest_cells(volume: float, size: float, dim: int) -> float:
    """A lower bound on the cells of a mesh of ``volume`` (m^d, area in 2D)
    whose edges are at most 1.5 ``size``: the volume over that of the
    regular simplex of edge 1.5 size (h^3 / (6 sqrt 2), sqrt(3)/4 h^2)."""
    h = 1.5 * size
    simplex = h ** 3 / (6.0 * np.sqrt(2.0)) if dim == 3 else np.sqrt(3.0) / 4.0 * h ** 2 if dim == 2 else h
    return volume / simplex


def check_cell_limit(gmsh, dim: int) -> None:
    """Refuse, before meshing, a size that would make more than
    ``CELL_LIMIT`` cells even at the largest size (Mesh.MeshSizeMax, the
    generators' far-field size) everywhere: gmsh would work for hours, run
    out of memory, or clamp the size silently."""
    from petthm.errors import InputError
    size = gmsh.option.getNumber("Mesh.MeshSizeMax")
    if not 0.0 < size < 1e21:
        return
    try:
        volume = sum(gmsh.model.occ.getMass(d, t) for d, t in gmsh.model.getEntities(dim))
    except Exception:                          # a built-in (geo) model: the bounding box
        box = np.asarray(gmsh.model.getBoundingBox(-1, -1))
        volume = float(np.prod((box[3:] - box[:3])[:dim]))
    cells = fewest_cells(volume, size, dim)
    if cells > CELL_LIMIT.get():
        gmsh.finalize()
        raise InputError(f"mesh size {size:g} m would make at least {cells:.2g} cells on this domain, more "
                         f"than the limit {CELL_LIMIT.get():.3g} (-thm_max_cells): choose a larger "
                         "-thm_mesh_size (or raise -thm_max_cells on a machine with the memory)")
