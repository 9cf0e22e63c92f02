"""gmsh file -> distributed DMPlex, boundary labels and vectorised topology.

The mesh is read on rank 0, boundary facets are labelled there (labels made
before ``distribute()`` migrate consistently with the points), then the DM is
distributed and ``-dm_*`` options (``-dm_refine K``, ``-dm_view``) are
applied.  After that, the cell->vertex, cell->edge and facet arrays every
assembly needs are built once, without a Python loop over cells.
"""
from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np
from petsc4py import PETSc

from petthm import compat
from petthm.errors import InputError
from petthm.mesh.fracture import MINUS_LABEL, FractureSurface
from petthm.mesh.topology import VertexTopology, label_name, ordered_edges, simplex_geometry, simplex_stratum

#: A boundary predicate receives facet centroids (n, dim) and returns a mask.
BoundaryPredicate = Callable[[np.ndarray], np.ndarray]


class Interior:
    """A named part inside the domain (a matrix well's perforated interval):
    the vertices where ``predicate(x)`` holds for their coordinates (n, dim)
    and the edges between two of them.  Used in a scene's ``boundaries()``
    in place of a facet predicate, for Dirichlet data on lines of the mesh."""

    def __init__(self, predicate: BoundaryPredicate):
        self.predicate = predicate


def _mpi_max():
    from mpi4py import MPI
    return MPI.MAX


def read_plex(path: str, comm: PETSc.Comm) -> PETSc.DMPlex:
    """Read a gmsh file (serially on rank 0, as PETSc does) into an interpolated DMPlex."""
    ok = comm.tompi4py().bcast(os.path.isfile(path) if comm.rank == 0 else None, root=0)
    if not ok:
        raise InputError(f"mesh file '{path}' does not exist (-thm_mesh_file)")
    dm = PETSc.DMPlex().createFromFile(path, interpolate=True, comm=comm)
    dm.setName("mesh")
    return dm


def bounding_box(dm: PETSc.DMPlex) -> tuple[np.ndarray, np.ndarray]:
    """The (lower, upper) corners of the mesh's coordinates over every rank (collective)."""
    from mpi4py import MPI
    comm = dm.comm.tompi4py()
    cdim = dm.getCoordinateDim()
    x = dm.getCoordinatesLocal().getArray(readonly=True).reshape(-1, cdim)
    lo = x.min(axis=0) if len(x) else np.full(cdim, np.inf)
    hi = x.max(axis=0) if len(x) else np.full(cdim, -np.inf)
    lower, upper = np.empty(cdim), np.empty(cdim)
    comm.Allreduce(lo, lower, op=MPI.MIN)
    comm.Allreduce(hi, upper, op=MPI.MAX)
    return lower, upper


def check_every_rank_has_cells(dm: PETSc.DMPlex) -> None:
    """A distributed mesh with a rank without cells (more ranks than the mesh
    can feed) is an ``InputError`` (collective)."""
    start, end = dm.getHeightStratum(0)
    counts = dm.comm.tompi4py().allgather(end - start)
    if min(counts) == 0:
        raise InputError(f"the mesh's {sum(counts)} cells cannot feed {len(counts)} ranks (rank "
                         f"{counts.index(0)} has none): run on fewer ranks, or refine the mesh "
                         "(-thm_mesh_size, -dm_refine)")


def label_boundaries(dm: PETSc.DMPlex, parts: Mapping[str, BoundaryPredicate]) -> None:
    """Create one label per named boundary part, with the closure of its facets.

    Must be called before distribution; predicates see the facet centroids.
    """
    dim = dm.getDimension()
    dm.createLabel("thm_boundary_all")
    dm.markBoundaryFaces("thm_boundary_all", 1)
    facets = np.asarray(dm.getStratumIS("thm_boundary_all", 1).getIndices(), dtype=compat.INT) \
        if dm.getStratumSize("thm_boundary_all", 1) > 0 else np.zeros(0, dtype=compat.INT)
    topo = VertexTopology(dm)
    centroids = topo.coords[topo.point_vertices(facets, dim - 1)].mean(axis=1) \
        if facets.size else np.zeros((0, dim))
    for name, predicate in parts.items():
        dm.createLabel(label_name(name))
        label = dm.getLabel(label_name(name))
        if isinstance(predicate, Interior):
            _label_interior(label, topo, predicate.predicate)
            continue
        for p in facets[np.asarray(predicate(centroids), dtype=bool)]:
            label.setValue(int(p), 1)
        dm.labelComplete(label)
    dm.removeLabel("thm_boundary_all")


def _label_interior(label, topo: VertexTopology, predicate: BoundaryPredicate) -> None:
    """The vertices on which ``predicate`` holds and the edges joining two of them."""
    on = np.asarray(predicate(topo.coords), dtype=bool)
    for v in np.flatnonzero(on):
        label.setValue(int(v + topo.vstart), 1)
    if on.any():
        ends = topo.cones[1] - topo.vstart                      # (nedges, 2)
        for e in np.flatnonzero(on[ends].all(axis=1)):
            label.setValue(int(e + topo.starts[1]), 1)


#: the attribute of a distributed DM that holds each local point's number in
#: the serial mesh it was distributed from (``original_points``)
ORIGINAL_POINTS = "petthm_original_points"


def distribute(dm: PETSc.DMPlex) -> PETSc.DMPlex:
    """Distribute over the communicator (no overlap) and apply -dm_* options.
    Each local point's number in the serial mesh is kept on the DM
    (``original_points``): a checkpoint keys its values by it, so that a
    restart does not depend on the partition (the partitioners are not
    deterministic from run to run) nor on the rank count."""
    from petthm.errors import petsc_option_errors
    from petthm.mesh.partition import repair
    original = np.arange(*dm.getChart())
    if dm.comm.size > 1:
        serial = dm.clone()
        sf = dm.distribute()
        dm, sf = repair(serial, dm, sf)
        if sf is not None:
            _, leaves, remote = sf.getGraph()
            original = np.full(dm.getChart()[1] - dm.getChart()[0], -1, dtype=np.int64)
            original[np.arange(len(remote)) if leaves is None else leaves] = np.asarray(remote)[:, 1]
    chart = dm.getChart()
    opts = PETSc.Options()
    ours = not opts.hasName("dm_distribute")
    if ours:                                      # PETSc 3.18 would distribute the distributed mesh again
        opts.setValue("dm_distribute", "0")
    with petsc_option_errors("the mesh options (-dm_*)"):
        dm.setFromOptions()
    if ours:
        opts.delValue("dm_distribute")
    if dm.getChart() != chart:                    # -dm_refine: new points, no serial number
        original = np.full(dm.getChart()[1] - dm.getChart()[0], -1, dtype=np.int64)
    dm.setAttr(ORIGINAL_POINTS, original)
    dm.setName("mesh")
    return dm


def original_points(dm: PETSc.DMPlex) -> np.ndarray:
    """Each local point's number in the serial mesh (-1: none; see ``distribute``)."""
    out = dm.getAttr(ORIGINAL_POINTS)
    return np.arange(*dm.getChart()) if out is None else out


@dataclass
class Mesh:
    """A distributed simplicial DMPlex with the arrays that assembly needs.

    Attributes (local to this rank):
      cell_vertices (nc, d+1): vertex indices relative to vStart, ascending;
      cell_edges (nc, ne): edge points in the VTK order of ``reference.EDGES``;
      vertex_coords (nv, d); edge_midpoints (nedge, d);
      J, Jinv (nc, d, d), detJ (nc,): affine map x = x0 + J xi; h (nc,) longest edge;
      fracture: the ``fracture.FractureSurface`` of a split mesh, or None.
    """
    dm: PETSc.DMPlex
    dim: int = 0
    cell_vertices: np.ndarray = field(default=None, repr=False)
    cell_edges: np.ndarray = field(default=None, repr=False)
    vertex_coords: np.ndarray = field(default=None, repr=False)
    edge_vertices: np.ndarray = field(default=None, repr=False)
    x0: np.ndarray = field(default=None, repr=False)
    J: np.ndarray = field(default=None, repr=False)
    Jinv: np.ndarray = field(default=None, repr=False)
    detJ: np.ndarray = field(default=None, repr=False)
    h: np.ndarray = field(default=None, repr=False)

    def __post_init__(self):
        dm = self.dm
        self.dim = dim = dm.getDimension()
        self.rdim = dim
        topo = VertexTopology(dm)
        self._topo = topo
        self.cstart, self.cend = simplex_stratum(dm, dim)
        self.vstart, self.vend = dm.getDepthStratum(0)
        self.estart, self.eend = simplex_stratum(dm, 1)
        cells = np.arange(self.cstart, self.cend, dtype=compat.INT)
        self.vertex_coords = topo.coords
        self.cell_vertices = topo.point_vertices(cells, dim)
        self.edge_vertices = topo.cones[1] - self.vstart
        self.cell_edges = self._ordered_cell_edges(topo, cells)
        self._geometry()
        #: the fracture faces of a mesh split along its fractures (``fracture.split_fractures``), or None
        split = dm.comm.tompi4py().allreduce(int(dm.hasLabel(MINUS_LABEL)), op=_mpi_max())
        self.fracture = FractureSurface(self) if split else None

    # -- topology -----------------------------------------------------------
    def _ordered_cell_edges(self, topo, cells):
        return ordered_edges(topo, cells, self.dim, self.cell_vertices, self.edge_vertices, self.estart)

    def _geometry(self):
        self.x0, self.J, self.detJ, self.Jinv, self.h = simplex_geometry(
            self.vertex_coords[self.cell_vertices], self.dim)

    @property
    def ncells(self) -> int:
        return self.cend - self.cstart

    def edge_midpoints(self) -> np.ndarray:
        ev = self.edge_vertices
        return 0.5 * (self.vertex_coords[ev[:, 0]] + self.vertex_coords[ev[:, 1]])

    def point_coordinates(self, points: np.ndarray) -> np.ndarray:
        """Coordinates of vertex points and (midpoints of) edge points."""
        points = np.asarray(points)
        out = np.empty((len(points), self.dim))
        isv = (points >= self.vstart) & (points < self.vend)
        out[isv] = self.vertex_coords[points[isv] - self.vstart]
        ise = (points >= self.estart) & (points < self.eend)
        out[ise] = self.edge_midpoints()[points[ise] - self.estart]
        return out

    def inside_points(self, points: np.ndarray) -> np.ndarray:
        """For each vertex or edge point, the centroid of a cell whose closure
        holds it (n, dim): which side of a split fracture a node is on (the
        cells of its copy lie on that side only); NaN for a point of no local cell."""
        points = np.asarray(points)
        nodes = np.hstack([self.cell_vertices + self.vstart, self.cell_edges]) if self.ncells else \
            np.zeros((0, 1), dtype=compat.INT)
        flat, first = np.unique(nodes.ravel(), return_index=True)
        cells = first // nodes.shape[1]
        centroids = self.vertex_coords[self.cell_vertices].mean(axis=1)
        out = np.full((len(points), self.dim), np.nan)
        pos = np.searchsorted(flat, points)
        found = (pos < len(flat)) & (flat[np.minimum(pos, len(flat) - 1)] == points)
        out[found] = centroids[cells[pos[found]]]
        return out

    # -- boundaries ---------------------------------------------------------
    def label_points(self, name: str | None, depth: int | None = None,
                     label: str | None = None) -> np.ndarray:
        """Local points carrying a boundary label (or the DMLabel ``label``),
        optionally of one depth."""
        lname = label or label_name(name)
        if not self.dm.hasLabel(lname) or self.dm.getStratumSize(lname, 1) == 0:
            return np.zeros(0, dtype=compat.INT)
        pts = np.asarray(self.dm.getStratumIS(lname, 1).getIndices(), dtype=compat.INT)
        if depth is not None:
            lo, hi = simplex_stratum(self.dm, depth)
            pts = pts[(pts >= lo) & (pts < hi)]
        return pts

    def boundary_facets(self, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Facets of a named boundary part: (cell index, local facet number, measure).

        The local facet number ``f`` is the facet opposite the cell's local
        vertex ``f`` (the convention of ``fe.facet_points``).
        """
        dim = self.dim
        facets = self.label_points(name, dim - 1)
        if facets.size == 0:
            return (np.zeros(0, dtype=compat.INT),) * 2 + (np.zeros(0),)
        topo = self._topo
        cells = np.asarray([self.dm.getSupport(int(f))[0] for f in facets], dtype=compat.INT)
        fverts = topo.point_vertices(facets, dim - 1)
        cverts = self.cell_vertices[cells - self.cstart]
        inside = (cverts[:, :, None] == fverts[:, None, :]).any(axis=2)
        local = np.argmin(inside, axis=1)
        X = self.vertex_coords[fverts]
        if dim == 2:
            measure = np.linalg.norm(X[:, 1] - X[:, 0], axis=1)
        elif dim == 3:
            measure = 0.5 * np.linalg.norm(np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]), axis=1)
        else:
            measure = np.ones(len(facets))
        return cells - self.cstart, local, measure

    def outward_normals(self, cells: np.ndarray, local: np.ndarray) -> np.ndarray:
        """Unit outward normal of facet ``local`` of each cell (reference normal mapped)."""
        dim = self.dim
        nref = np.vstack([np.ones(dim) / np.sqrt(dim), -np.eye(dim)])   # outward on ref facets
        n = np.einsum("cka,ck->ca", self.Jinv[cells], nref[local])
        return n / np.linalg.norm(n, axis=1, keepdims=True)

    def global_cell_count(self) -> int:
        return self.dm.comm.tompi4py().allreduce(self.ncells)
