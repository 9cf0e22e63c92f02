"""Mesh generation with the gmsh Python API (run on rank 0 only).

Every generator writes a straight-sided, first-order gmsh 4.1 ASCII file with
one physical group for the domain; petthm places the P2 nodes at the edge
midpoints itself.  Sizes are characteristic lengths in metres.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Sequence


@dataclass(frozen=True)
class Grading:
    """Refine toward the plane ``x[axis] = 0``: size ``size_min`` there, growing
    linearly to the nominal size at distance ``distance``."""
    axis: int
    size_min: float
    distance: float


def _start(name: str):
    import gmsh
    if gmsh.isInitialized():
        gmsh.finalize()
    gmsh.initialize(["gmsh"], readConfigFiles=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("General.NumThreads", 1)
    gmsh.model.add(name)
    return gmsh


def _grade(gmsh, dim: int, lengths: Sequence[float], size: float, grading: Grading | None) -> None:
    if grading is None:
        return
    occ = gmsh.model.occ
    # a plane (line in 2D) at x[axis] = 0 to measure the distance from
    lo = [0.0, 0.0, 0.0]
    if dim == 2:
        p0 = occ.addPoint(*lo)
        hi = list(lo)
        hi[1 - grading.axis] = lengths[1 - grading.axis]
        p1 = occ.addPoint(*hi)
        ent = occ.addLine(p0, p1)
        kind = "CurvesList"
    else:
        other = [a for a in range(3) if a != grading.axis]
        x = lambda u, v: [  # noqa: E731
            {grading.axis: 0.0, other[0]: u, other[1]: v}[k] for k in range(3)]
        pts = [occ.addPoint(*x(u, v)) for u, v in
               [(0, 0), (lengths[other[0]], 0), (lengths[other[0]], lengths[other[1]]), (0, lengths[other[1]])]]
        loop = occ.addCurveLoop([occ.addLine(pts[i], pts[(i + 1) % 4]) for i in range(4)])
        ent = occ.addPlaneSurface([loop])
        kind = "SurfacesList"
    occ.synchronize()
    mf = gmsh.model.mesh.field
    dist = mf.add("Distance")
    mf.setNumbers(dist, kind, [ent])
    mf.setNumber(dist, "Sampling", 200)
    thr = mf.add("Threshold")
    mf.setNumber(thr, "InField", dist)
    mf.setNumber(thr, "SizeMin", grading.size_min)
    mf.setNumber(thr, "SizeMax", size)
    mf.setNumber(thr, "DistMin", 0.0)
    mf.setNumber(thr, "DistMax", grading.distance)
    mf.setAsBackgroundMesh(thr)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 0)


def box(path: str, lengths: Sequence[float], size: float, grading: Grading | None = None,
        structured: bool = False) -> str:
    """Rectangle (2 lengths) or box (3 lengths) [0, L] with simplices of size ~``size``.

    ``structured`` gives a regular (transfinite) mesh with ``round(L/size)``
    divisions per side, useful for convergence studies.
    """
    dim = len(lengths)
    gmsh = _start("box")
    occ = gmsh.model.occ
    if dim == 2:
        tag = occ.addRectangle(0, 0, 0, *lengths)
    else:
        tag = occ.addBox(0, 0, 0, *lengths)
    occ.synchronize()
    if structured:
        for (_, c) in gmsh.model.getEntities(1):
            bb = gmsh.model.getBoundingBox(1, c)
            length = max(abs(bb[3] - bb[0]), abs(bb[4] - bb[1]), abs(bb[5] - bb[2]))
            gmsh.model.mesh.setTransfiniteCurve(c, max(1, round(length / size)) + 1)
        for (_, s) in gmsh.model.getEntities(2):
            gmsh.model.mesh.setTransfiniteSurface(s)
        if dim == 3:
            gmsh.model.mesh.setTransfiniteVolume(tag)
    gmsh.model.addPhysicalGroup(dim, [tag], 1)
    gmsh.option.setNumber("Mesh.MeshSizeMin", (grading.size_min if grading else size))
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    _grade(gmsh, dim, lengths, size, grading)
    return _write(gmsh, dim, path)


def _write(gmsh, dim: int, path: str) -> str:
    gmsh.model.mesh.generate(dim)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.Binary", 0)
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    gmsh.write(path)
    gmsh.finalize()
    return path
