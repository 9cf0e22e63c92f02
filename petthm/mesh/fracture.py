"""Cohesive split of a DMPlex along its fractures (theory manual, "Unknowns").

Each fracture is a set of facets (gmsh physical group ``FRACTURE_TAG0 + i``,
read into the "Face Sets" label).  Following PyLith's recipe, on the serial
mesh (before distribution, see petsc-notes.md) and one fracture at a time:

1. label the fracture facets and their closure;
2. the tip: fracture points of codimension 2 (edges in 3D, vertices in 2D)
   that bound exactly one fracture facet and are not on the domain boundary,
   plus (3D) their vertices -- these are not duplicated;
3. DMPlexCreateSubmesh of the facets, DMPlexOrient, the subpoint map as the
   cohesive label (value = depth), DMPlexLabelCohesiveComplete with the tip;
4. the side convention: the original facet (cone[0] of the cohesive cell)
   stays on the bulk cells on the -n side, n being the fracture's unit normal
   (so n points from the - face to the + face);
5. DMPlexConstructCohesiveCells.

The split DM has the cohesive (prism-tensor) cells at the end of the cell
stratum; ``fracture_faces`` returns, per cohesive cell, the - and + facet
vertices paired by position.  Labels made before the split survive it.
"""
from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np
from petsc4py import PETSc

from petthm import compat
from petthm.mesh.generate import FRACTURE_TAG0
from petthm.mesh.reference import EDGES
from petthm.mesh.topology import label_name, ordered_edges, simplex_geometry

FACE_SETS = "Face Sets"
#: label (value 1) on the closure of the - faces of all cohesive cells: the
#: support of the fracture fields; made on the serial mesh, before distribution
MINUS_LABEL = "thm_fracture_minus"
#: label (value 1) on the closure of the + faces (tip points included)
PLUS_LABEL = "thm_fracture_plus"


class Side(enum.Enum):
    """A face of a fracture; ``sign`` is +1 on the face the normal points to."""
    MINUS = "-"
    PLUS = "+"

    @property
    def sign(self) -> float:
        return 1.0 if self is Side.PLUS else -1.0


def _stratum(dm, name, value) -> np.ndarray:
    if not dm.hasLabel(name) or dm.getStratumSize(name, value) == 0:
        return np.zeros(0, dtype=compat.INT)
    return np.asarray(dm.getStratumIS(name, value).getIndices(), dtype=compat.INT)


def _vertex_coords(dm) -> np.ndarray:
    cdim = dm.getCoordinateDim()
    return dm.getCoordinatesLocal().getArray().reshape(-1, cdim)


def _closure_vertices(dm, points) -> list[np.ndarray]:
    vs, ve = dm.getDepthStratum(0)
    out = []
    for p in points:
        cl = dm.getTransitiveClosure(int(p))[0]
        out.append(cl[(cl >= vs) & (cl < ve)] - vs)
    return out


def _tip_label(dm, facets: np.ndarray, boundary: set) -> PETSc.DMLabel:
    """Codimension-2 fracture points bounding one fracture facet, off the domain boundary."""
    dim = dm.getDimension()
    tip = PETSc.DMLabel().create("thm_tip")
    ridges = np.concatenate([dm.getCone(int(f)) for f in facets]) if len(facets) else np.zeros(0, int)
    uniq, counts = np.unique(ridges, return_counts=True)
    for r in uniq[counts == 1]:
        if int(r) in boundary:
            continue
        tip.setValue(int(r), 1)
        if dim == 3:
            for v in dm.getCone(int(r)):
                tip.setValue(int(v), 1)
    return tip


def _side_votes(dm, coh, normal) -> int:
    """Sum over fracture facets of sign(n . (x_cell - x_facet)) for the bulk
    cells DMPlexLabelCohesiveComplete put on the side that keeps the facet."""
    dim = dm.getDimension()
    X = _vertex_coords(dm)
    votes = 0
    for f in _stratum_label(coh, dim - 1):
        xf = X[_closure_vertices(dm, [f])[0]].mean(axis=0)
        for c in dm.getSupport(int(f)):
            if coh.getValue(int(c)) == 100 + dim:
                xc = X[_closure_vertices(dm, [c])[0]].mean(axis=0)
                votes += 1 if np.dot(xc - xf, normal) > 0 else -1
    return votes


def _stratum_label(label, value) -> np.ndarray:
    if label.getStratumSize(value) == 0:
        return np.zeros(0, dtype=compat.INT)
    return np.asarray(label.getStratumIS(value).getIndices(), dtype=compat.INT)


def _flip_sides(coh, dim) -> None:
    for d in range(dim + 1):
        plus, minus = _stratum_label(coh, 100 + d).copy(), _stratum_label(coh, -(100 + d)).copy()
        for p in plus:
            coh.clearValue(int(p), 100 + d)
            coh.setValue(int(p), -(100 + d))
        for p in minus:
            coh.clearValue(int(p), -(100 + d))
            coh.setValue(int(p), 100 + d)


def facet_normal(dm, facets: np.ndarray) -> np.ndarray:
    """Mean unit normal of planar facets (sign arbitrary but consistent: +z, +y, +x first)."""
    X = _vertex_coords(dm)[:, :dm.getDimension()]
    verts = _closure_vertices(dm, facets[:1])
    P = X[verts[0]]
    if dm.getDimension() == 2:
        t = P[1] - P[0]
        n = np.array([-t[1], t[0]])
    else:
        n = np.cross(P[1] - P[0], P[2] - P[0])
    n = n / np.linalg.norm(n)
    for k in range(len(n) - 1, -1, -1):        # orient: first non-zero of (z, y, x) positive
        if abs(n[k]) > 1e-8:
            return n if n[k] > 0 else -n
    return n


@dataclass
class SplitInfo:
    """What the split did to one fracture (serial counts)."""
    tag: int
    facets: int
    tip_points: int
    normal: np.ndarray


def split_fractures(dm: PETSc.DMPlex, fracture_tags=None) -> tuple[PETSc.DMPlex, list[SplitInfo]]:
    """Insert cohesive cells along the fractures of a serial DM (collective;
    all the mesh lives on rank 0): the "Face Sets" values ``fracture_tags``
    (None: every value from ``FRACTURE_TAG0`` up).  Returns the split DM and
    per-fracture info; fracture k (in the order of the tags) is labelled
    ``thm_fracture_k``."""
    infos = []
    if not dm.hasLabel(FACE_SETS):
        return dm, infos
    if fracture_tags is None:
        tags = sorted(int(v) for v in dm.getLabel(FACE_SETS).getValueIS().getIndices()
                      if v >= FRACTURE_TAG0) if dm.comm.rank == 0 else []
        tags = dm.comm.tompi4py().bcast(tags, root=0)
    else:
        tags = [int(t) for t in fracture_tags]
    for k, tag in enumerate(tags):
        dm, info = _split_one(dm, tag, k)
        infos.append(info)
    if tags:
        _label_minus_faces(dm)
    return dm, infos


#: boundary-condition names (``mesh.label_name``) of all fracture points and of the tips
FRACTURE_BC, TIP_BC = "fracture", "fracture_tip"


def _label_minus_faces(dm: PETSc.DMPlex) -> None:
    """Labels on the closures of the - faces and of the + faces (serial mesh)."""
    for name, side in ((MINUS_LABEL, 0), (PLUS_LABEL, 1)):
        dm.createLabel(name)
        label = dm.getLabel(name)
        for c in cohesive_cells(dm):
            label.setValue(int(dm.getCone(int(c))[side]), 1)
        dm.labelComplete(label)
    dm.createLabel(label_name(FRACTURE_BC))
    both = dm.getLabel(label_name(FRACTURE_BC))
    for name in (MINUS_LABEL, PLUS_LABEL):
        for p in _stratum(dm, name, 1):
            both.setValue(int(p), 1)


def _split_one(dm: PETSc.DMPlex, tag: int, k: int):
    dim = dm.getDimension()
    facets = _stratum(dm, FACE_SETS, tag)
    name = f"thm_fracture_{k}"
    dm.createLabel(name)
    frac = dm.getLabel(name)
    for f in facets:
        frac.setValue(int(f), 1)
    dm.labelComplete(frac)
    dm.createLabel("thm_domain_boundary")
    dm.markBoundaryFaces("thm_domain_boundary", 1)
    bd = dm.getLabel("thm_domain_boundary")
    dm.labelComplete(bd)
    boundary = set(_stratum(dm, "thm_domain_boundary", 1).tolist())
    dm.removeLabel("thm_domain_boundary")
    tip = _tip_label(dm, facets, boundary)
    normal = dm.comm.tompi4py().bcast(facet_normal(dm, facets) if len(facets) else None, root=0)
    sub = compat.create_submesh(dm, frac, 1)
    sub.orient()
    coh = compat.subpoint_label(sub)
    coh.clearStratum(dim)
    compat.label_cohesive_complete(dm, coh, tip, False, sub)
    votes = dm.comm.tompi4py().allreduce(_side_votes(dm, coh, normal))
    if votes > 0:
        _flip_sides(coh, dim)
    dm.createLabel(label_name(TIP_BC))                  # carried over by the split
    tips = dm.getLabel(label_name(TIP_BC))
    for p in _stratum_label(tip, 1):
        tips.setValue(int(p), 1)
    split = compat.construct_cohesive_cells(dm, coh)
    info = SplitInfo(tag, len(facets), tip.getStratumSize(1), normal)
    tip.destroy()
    coh.destroy()
    sub.destroy()
    return split, info


def cohesive_cells(dm: PETSc.DMPlex) -> np.ndarray:
    """Local cohesive (prism-tensor) cells: the end of the cell stratum."""
    cs, ce = dm.getHeightStratum(0)
    _, se = compat.simplex_range(dm, 0)
    return np.arange(se, ce, dtype=compat.INT)


def fracture_faces(dm: PETSc.DMPlex, cells: np.ndarray | None = None):
    """Per cohesive cell: (- facet, + facet, - vertices, + vertices) with the
    vertices paired by position (same coordinates; shared at the tip)."""
    cells = cohesive_cells(dm) if cells is None else cells
    vs, _ = dm.getDepthStratum(0)
    minus, plus, vm, vp = [], [], [], []
    for c in cells:
        cone = dm.getCone(int(c))
        minus.append(cone[0])
        plus.append(cone[1])
        cl = _closure_vertices(dm, [c])[0]
        n = len(cl) // 2
        vm.append(cl[:n])
        vp.append(cl[n:])
    n = dm.getDimension()
    return (np.asarray(minus, dtype=compat.INT), np.asarray(plus, dtype=compat.INT),
            np.asarray(vm, dtype=compat.INT).reshape(-1, n), np.asarray(vp, dtype=compat.INT).reshape(-1, n))


def _owned(dm, points: np.ndarray) -> np.ndarray:
    try:
        _, leaves, _ = dm.getPointSF().getGraph()
    except ValueError:          # no point SF yet (serial, or not distributed)
        return np.ones(len(points), dtype=bool)
    ghost = np.zeros(0, dtype=int) if leaves is None else np.asarray(leaves)
    return ~np.isin(points, ghost)


def split_statistics(dm: PETSc.DMPlex, normals: list[np.ndarray]) -> dict:
    """Global counts and consistency checks of a split (possibly distributed) DM.

    ``orientation_errors``: cohesive cells whose - facet's bulk cell is not on
    the -n side (n the normal of the fracture the cell belongs to);
    ``pair_mismatch``: largest distance between paired - and + vertices.
    """
    comm = dm.comm.tompi4py()
    dim = dm.getDimension()
    X = _vertex_coords(dm)[:, :dim]
    coh = cohesive_cells(dm)
    minus, plus, vm, vp = fracture_faces(dm, coh)
    vs, ve = dm.getDepthStratum(0)
    bulk = compat.simplex_range(dm, 0)
    wrong, checked = 0, 0
    frac_of = {}
    for k in range(len(normals)):
        for c in _stratum(dm, f"thm_fracture_{k}", 1):
            frac_of[int(c)] = k
    for m, p, a, _b in zip(minus, plus, vm, vp, strict=False):
        xf = X[a].mean(axis=0)
        k = frac_of.get(int(m), frac_of.get(int(p), 0))
        for face, sign in ((m, -1), (p, +1)):
            for c in dm.getSupport(int(face)):
                if bulk[0] <= c < bulk[1]:
                    xc = X[_closure_vertices(dm, [c])[0]].mean(axis=0)
                    checked += 1
                    wrong += int(sign * np.dot(xc - xf, normals[k]) <= 0)
    verts = np.arange(vs, ve)
    checks = compat.plex_checks(dm)
    return {
        "cells": comm.allreduce(bulk[1] - bulk[0]),
        "cohesive_cells": comm.allreduce(len(coh)),
        "vertices": comm.allreduce(int(_owned(dm, verts).sum())),
        "shared_tip_pairs": comm.allreduce(int((vm == vp).sum())),
        "orientation_checked": comm.allreduce(checked),
        "orientation_errors": comm.allreduce(wrong),
        "pair_mismatch": comm.allreduce(float(np.abs(X[vm] - X[vp]).max()) if len(vm) else 0.0,
                                        op=_mpi_max()),
        "plex_checks_failed": comm.allreduce(sum(1 for v in checks.values() if v)),
    }


def _mpi_max():
    from mpi4py import MPI
    return MPI.MAX


def fracture_vertex_counts(dm: PETSc.DMPlex) -> dict[int, tuple[int, int]]:
    """Serial, before the split: per fracture tag, (vertices on the fracture,
    vertices on its tip), for checking the split's vertex count."""
    out = {}
    if not dm.hasLabel(FACE_SETS):
        return out
    vs, ve = dm.getDepthStratum(0)
    dm.createLabel("thm_bd_tmp")
    dm.markBoundaryFaces("thm_bd_tmp", 1)
    dm.labelComplete(dm.getLabel("thm_bd_tmp"))
    boundary = set(_stratum(dm, "thm_bd_tmp", 1).tolist())
    dm.removeLabel("thm_bd_tmp")
    for v in dm.getLabel(FACE_SETS).getValueIS().getIndices():
        if v < FRACTURE_TAG0:
            continue
        facets = _stratum(dm, FACE_SETS, int(v))
        verts = np.unique(np.concatenate(_closure_vertices(dm, facets)))
        tip = _tip_label(dm, facets, boundary)
        tipv = [p for p in _stratum_label(tip, 1) if vs <= p < ve] if dm.getDimension() == 3 else \
            list(_stratum_label(tip, 1))
        out[int(v)] = (len(verts), len(tipv))
        tip.destroy()
    return out


class FractureSurface:
    """The - faces of the local cohesive cells as (dim-1)-simplices embedded in
    the mesh: the element region of the fracture fields ``pf``, ``Tf``.

    Same attributes as ``mesh.Mesh`` for assembly: ``cell_vertices`` (sorted,
    relative to vStart), ``cell_edges`` (P2 node points in ``reference.EDGES`` order),
    the affine maps ``x0, J, detJ, Jinv`` (left inverse: tangential
    gradients), ``h``; ``dim`` is the space dimension, ``rdim = dim - 1``.
    """

    def __init__(self, mesh):
        self.mesh = mesh
        self.dm = mesh.dm
        self.dim = mesh.dim
        self.rdim = mesh.dim - 1
        self.vstart = mesh.vstart
        self.cells = cohesive_cells(self.dm)
        self.faces = np.asarray([self.dm.getCone(int(c))[0] for c in self.cells], dtype=compat.INT)
        topo = mesh._topo
        self.cell_vertices = topo.point_vertices(self.faces, self.rdim) if len(self.faces) else \
            np.zeros((0, self.rdim + 1), dtype=compat.INT)
        self.cell_edges = ordered_edges(topo, self.faces, self.rdim, self.cell_vertices,
                                        mesh.edge_vertices, mesh.estart) if len(self.faces) else \
            np.zeros((0, len(EDGES[self.rdim])), dtype=compat.INT)
        self.x0, self.J, self.detJ, self.Jinv, self.h = simplex_geometry(
            mesh.vertex_coords[self.cell_vertices], self.rdim)
        self.plus_faces = np.asarray([self.dm.getCone(int(c))[1] for c in self.cells], dtype=compat.INT)
        self.plus_vertices = self._paired_plus_vertices(topo)
        self.plus_edges = ordered_edges(topo, self.plus_faces, self.rdim, self.plus_vertices,
                                        mesh.edge_vertices, mesh.estart) if len(self.faces) else \
            np.zeros_like(self.cell_edges)
        self.normals = self._unit_normals()
        self._adjacent = {}

    def _paired_plus_vertices(self, topo) -> np.ndarray:
        """Vertices of each + face in the order of the - face's vertices (paired
        by coordinates: the copies coincide; a tip vertex is its own pair)."""
        if not len(self.faces):
            return np.zeros_like(self.cell_vertices)
        pv = topo.point_vertices(self.plus_faces, self.rdim)
        X = self.mesh.vertex_coords
        d = np.linalg.norm(X[self.cell_vertices][:, :, None, :] - X[pv][:, None, :, :], axis=3)
        match = np.argmin(d, axis=2)
        if np.take_along_axis(d, match[:, :, None], axis=2).max() > 1e-9 * max(self.h.max(), 1e-300):
            raise RuntimeError("+ and - fracture faces do not coincide")
        return np.take_along_axis(pv, match, axis=1)

    def _unit_normals(self) -> np.ndarray:
        """Unit normal n of each - face, from the - side to the + side: the
        split's convention, first non-zero component among (z, y, x) positive
        (planar fractures; see ``split_fractures``)."""
        if not self.ncells:
            return np.zeros((0, self.dim))
        if self.dim == 2:
            t = self.J[:, :, 0]
            n = np.stack([-t[:, 1], t[:, 0]], axis=1)
        else:
            n = np.cross(self.J[:, :, 0], self.J[:, :, 1])
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        lead = np.zeros(len(n))
        for k in range(self.dim):               # x, then y, then (3D) z override
            big = np.abs(n[:, k]) > 1e-8
            lead[big] = n[big, k]
        n[lead < 0] *= -1
        return n

    def adjacent_cells(self, side) -> np.ndarray:
        """The rock cell next to each face on ``side`` (a ``Side``), as
        an index among the mesh's cells.  ``mesh.distribute`` keeps every
        cohesive cell on the rank of its two rock cells."""
        if not self._adjacent:
            from petthm.mesh.partition import cohesive_neighbours
            _, rock = cohesive_neighbours(self.dm)             # same order as self.cells
            if (rock < 0).any():
                raise RuntimeError(f"{int((rock < 0).any(axis=1).sum())} fracture faces have no local "
                                   "rock cell on one side (the partition split them)")
            self._adjacent = {"-": rock[:, 0] - self.mesh.cstart, "+": rock[:, 1] - self.mesh.cstart}
        return self._adjacent[side.value]

    def thinnest_wall_layer(self) -> float:
        """The smallest ratio, over all faces and both sides (all ranks), of
        the rock cell's height over the face (dim V / A) to the face's size;
        inf without faces."""
        from math import factorial

        ratio = np.inf
        if self.ncells:
            area = np.abs(self.detJ) / factorial(self.rdim)
            for side in (Side.MINUS, Side.PLUS):
                rc = self.adjacent_cells(side)
                height = self.dim * np.abs(self.mesh.detJ[rc]) / factorial(self.dim) / area
                ratio = min(ratio, float(np.min(height / self.h)))
        from mpi4py import MPI
        return self.dm.comm.tompi4py().allreduce(ratio, op=MPI.MIN)

    @property
    def ncells(self) -> int:
        return len(self.faces)

    def area(self) -> float:
        from math import factorial
        return self.dm.comm.tompi4py().allreduce(float(np.abs(self.detJ).sum()) / factorial(self.rdim))


