"""Mesh generation with the gmsh Python API (run on rank 0 only).

Every generator writes a straight-sided, first-order gmsh 4.1 ASCII file with
one physical group for the domain; petthm places the P2 nodes at the edge
midpoints itself.  Sizes are characteristic lengths in metres.
"""
from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from petthm.mesh.limits import check_cell_limit


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
               [(0, 0), (lengths[other[0]], 0), (lengths[other[0]], lengths[other[1]]),
                (0, lengths[other[1]])]]
        loop = occ.addCurveLoop([occ.addLine(pts[i], pts[(i + 1) % 4]) for i in range(4)])
        ent = occ.addPlaneSurface([loop])
        kind = "SurfacesList"
    occ.synchronize()
    thr = _threshold(gmsh.model.mesh.field, kind, [ent], grading.size_min, size, grading.distance,
                     sampling=200)
    _background_size(gmsh, [thr])
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
    tag = occ.addRectangle(0, 0, 0, *lengths) if dim == 2 else occ.addBox(0, 0, 0, *lengths)
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


#: physical-group tag of fracture ``i`` (PETSc reads it into the "Face Sets" label)
FRACTURE_TAG0 = 10
#: physical groups: the outer boundary (facets), fracture i's tip (codimension 2), well i (points)
BOUNDARY_TAG, TIP_TAG0, WELL_TAG0 = 2, 200, 100


@dataclass(frozen=True)
class Fracture:
    """A planar fracture: a segment (2D: ``p0``, ``p1``) or, in 3D, a disc
    (``center``, ``radius``) or rectangle (``center``, ``half`` sizes) lying in
    the plane z = center_z, then rotated by ``dip`` degrees about the
    ``strike`` axis (0: x, 1: y) through its centre."""
    kind: str
    p0: tuple = ()
    p1: tuple = ()
    center: tuple = ()
    radius: float = 0.0
    half: tuple = ()
    dip: float = 0.0
    strike: int = 0
    size: float = 0.0          # mesh size on the fracture (0: the nominal size)


def _add_fracture(gmsh, f: Fracture):
    occ = gmsh.model.occ
    if f.kind == "segment":
        return (1, occ.addLine(occ.addPoint(*f.p0, 0.0), occ.addPoint(*f.p1, 0.0)))
    c = f.center
    if f.kind == "disc":
        tag = occ.addDisk(c[0], c[1], c[2], f.radius, f.radius)
    elif f.kind == "rectangle":
        tag = occ.addRectangle(c[0] - f.half[0], c[1] - f.half[1], c[2], 2 * f.half[0], 2 * f.half[1])
    else:
        raise ValueError(f"unknown fracture kind '{f.kind}'")
    if f.dip:
        axis = [1.0, 0.0, 0.0] if f.strike == 0 else [0.0, 1.0, 0.0]
        occ.rotate([(2, tag)], c[0], c[1], c[2], *axis, np.deg2rad(f.dip))
    return (2, tag)


def box_with_fractures(path: str, lengths: Sequence[float], size: float,
                       fractures: Sequence[Fracture], grading_distance: float = 0.0,
                       origin: Sequence[float] = (), wells: Sequence[tuple] = (),
                       well_size: float = 0.0, well_lines: Sequence[tuple] = ()) -> str:
    """Box (or rectangle) ``origin + [0, lengths]`` with embedded fractures; the
    mesh conforms to them.

    Physical groups: the domain (cells, tag 1, named "rock"), its outer
    boundary (facets, ``BOUNDARY_TAG``, "boundary"), fracture ``i`` (facets,
    ``FRACTURE_TAG0 + i``, "fracture<i>"), its tip (the fracture's edges, or
    end points in 2D, inside the domain, ``TIP_TAG0 + i``, "tip<i>") and well
    ``i`` (a point, ``WELL_TAG0 + i``, "well<i>"): the names let a deck run
    on the mesh (``reservoir``; manual: the paper's scenes as decks).
    With ``grading_distance`` > 0 the size grows
    linearly from each fracture's ``size`` to ``size`` over that distance.
    ``wells``: points (on a fracture) that become mesh vertices, with mesh
    size ``well_size`` (default: the fracture's) growing away from them.
    ``well_lines``: segments ((x0, y0, z0), (x1, y1, z1)) embedded in the
    mesh (the perforated intervals of matrix wells: their nodes lie on the
    segment, ``petthm.physics.matrixwells``), with the size ``well_size`` along them.
    """
    dim = len(lengths)
    o = tuple(origin) or (0.0,) * dim
    gmsh = _start("fractured_box")
    occ = gmsh.model.occ
    dom = occ.addRectangle(*o[:2], 0, *lengths) if dim == 2 else occ.addBox(*o, *lengths)
    tools = [_add_fracture(gmsh, f) for f in fractures]
    wpts = [(0, occ.addPoint(*(tuple(w) + (0.0,) * (3 - len(w))))) for w in wells]
    wlines = [(1, occ.addLine(occ.addPoint(*a), occ.addPoint(*b))) for a, b in well_lines]
    _, mapping = occ.fragment([(dim, dom)], tools + wpts + wlines)
    occ.synchronize()
    mapping = _drop_outside(gmsh, dim, mapping)
    on_outer = _tag_domain(gmsh, dim, [t for (d, t) in mapping[0] if d == dim])
    for i, m in enumerate(mapping[1:1 + len(fractures)]):
        _tag_fracture(gmsh, dim, i, [t for (d, t) in m if d == dim - 1], on_outer)
    line_maps = mapping[1 + len(fractures) + len(wells):]
    _embed_curves(gmsh, dim, [t for m in line_maps for (d, t) in m if d == 1],
                  [t for (d, t) in mapping[0] if d == dim])
    for i, m in enumerate(mapping[1 + len(fractures):1 + len(fractures) + len(wells)]):
        gmsh.model.addPhysicalGroup(0, [t for (d, t) in m if d == 0], WELL_TAG0 + i, name=f"well{i}")
    fine = [f.size or size for f in fractures] + ([well_size] if (wells or well_lines) and well_size else [])
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    gmsh.option.setNumber("Mesh.MeshSizeMin", min(fine))
    if grading_distance > 0:
        mf = gmsh.model.mesh.field
        fields = []
        for f, m in zip(fractures, mapping[1:], strict=False):
            ents = [t for (d, t) in m if d == dim - 1]
            fields.append(_threshold(mf, "CurvesList" if dim == 2 else "SurfacesList", ents,
                                     f.size or size, size, grading_distance))
        if wells and well_size:
            ents = [t for m in mapping[1 + len(fractures):1 + len(fractures) + len(wells)]
                    for (d, t) in m if d == 0]
            fields.append(_threshold(mf, "PointsList", ents, well_size, size, grading_distance))
        if well_lines and well_size:
            ents = [t for m in line_maps for (d, t) in m if d == 1]
            fields.append(_threshold(mf, "CurvesList", ents, well_size, size, grading_distance))
        _background_size(gmsh, fields)
    return _write(gmsh, dim, path)


def layer_heights(first: float, ratio: float, total: float) -> np.ndarray:
    """Geometric layer thicknesses ``first``, ``first ratio``, ... summing to ``total``
    (the last layers scaled down so that they fit)."""
    h = [first]
    while sum(h) < total:
        h.append(h[-1] * ratio)
    h = np.array(h)
    return h * (total / h.sum())


def _extrude_in_layers(gmsh, ents: list, direction: Sequence[float], total: float, layer: float,
                       ratio: float) -> list:
    """Extrude the entities ``ents`` ((dim, tag)) to both sides along the unit
    ``direction`` over ``total`` in layers of thickness ``layer`` growing by
    ``ratio`` (``layer_heights``; simplices, not recombined).  Returns the
    tags of the cells made on the + side: in 2D a line extruded along +y
    gives clockwise triangles, which the caller turns over."""
    occ = gmsh.model.occ
    h = layer_heights(layer, ratio, total)
    cum = list(np.cumsum(h) / total)
    dim = ents[0][0] + 1
    plus = []
    for sign in (1.0, -1.0):
        out = occ.extrude(ents, *(sign * total * c for c in direction), numElements=[1] * len(h),
                          heights=cum, recombine=False)
        if sign > 0:
            plus += [t for (d, t) in out if d == dim]
    occ.synchronize()
    return plus


def tag_well_points(gmsh, wells: Sequence[tuple], tol: float) -> list[int]:
    """Give the geometry's points at each of ``wells`` (coordinates padded
    with zeros to 3D; within ``tol``) the physical group WELL_TAG0 + i;
    returns their tags."""
    points = [(t, np.array(gmsh.model.getValue(0, t, []))) for (_, t) in gmsh.model.getEntities(0)]
    tags = []
    for i, w in enumerate(wells):
        w = np.array(tuple(w) + (0.0,) * (3 - len(w)), dtype=float)
        near = [t for (t, x) in points if np.linalg.norm(x - w) < tol]
        gmsh.model.addPhysicalGroup(0, near, WELL_TAG0 + i, name=f"well{i}")
        tags += near
    return tags


def layered_half_box_with_disc(path: str, half: float, radius: float, size: float, disc_size: float,
                               layer: float, ratio: float, wells: Sequence[tuple] = (),
                               well_size: float = 0.0) -> str:
    """The half box [-L, L] x [0, L] x [-L, L] (L = ``half``) around the half
    disc fracture z = 0, x^2 + y^2 < R^2, y >= 0, meshed in layers: the plane
    z = 0 is meshed with triangles (size ``disc_size`` on the disc and
    ``well_size`` at the ``wells``, growing to ``size`` over the distance R), then extruded up
    and down in layers of thickness ``layer`` growing by ``ratio`` (each
    prism cut into tetrahedra).  Thin cells next to the fracture resolve the
    thermal boundary layer of the rock (sqrt(kappa t): 0.4 m at 1e5 s) at
    the cost of cells only as many as the layers.  Physical groups as in
    ``box_with_fractures``."""
    gmsh = _start("layered_disc")
    occ = gmsh.model.occ
    rect = occ.addRectangle(-half, 0.0, 0.0, 2 * half, half)
    disc = occ.addDisk(0.0, 0.0, 0.0, radius, radius)
    wpts = [occ.addPoint(*(tuple(w) + (0.0,) * (3 - len(w)))) for w in wells]
    out, _ = occ.fragment([(2, rect)], [(2, disc)] + [(0, w) for w in wpts])
    occ.synchronize()
    plane = []
    for (d, t) in out:
        if d == 2:
            if occ.getCenterOfMass(2, t)[1] < 0:
                occ.remove([(2, t)], recursive=True)
            else:
                plane.append(t)
    occ.synchronize()
    on_disc = [t for t in plane if np.hypot(*occ.getCenterOfMass(2, t)[:2]) < radius]
    _extrude_in_layers(gmsh, [(2, t) for t in plane], (0.0, 0.0, 1.0), half, layer, ratio)
    on_outer = _tag_domain(gmsh, 3, [t for (_, t) in gmsh.model.getEntities(3)])
    _tag_fracture(gmsh, 3, 0, on_disc, on_outer)
    well_tags = tag_well_points(gmsh, wells, 1e-9 * half)
    mf = gmsh.model.mesh.field
    fields = [_threshold(mf, "SurfacesList", on_disc, disc_size, size, radius)]
    if well_tags and well_size:
        fields.append(_threshold(mf, "PointsList", well_tags, well_size, size, radius))
    _background_size(gmsh, fields)
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    return _write(gmsh, 3, path)


def layered_slab_with_fracture(path: str, extent: Sequence[float], width: float, fracture_size: float,
                               layer: float, ratio: float) -> str:
    """The slab [0, L] x [0, 2W] (2D, ``extent`` = (L,)) or [0, L] x [0, H] x
    [0, 2W] (3D, ``extent`` = (L, H)) around the planar fracture y = W (2D) or
    z = W (3D) that cuts the whole slab, meshed in layers: the fracture is
    meshed at ``fracture_size`` and extruded to both sides in layers of
    thickness ``layer`` growing by ``ratio`` (each quadrilateral or prism cut
    into simplices).  The thin cells next to the fracture resolve the rock's
    thermal boundary layer (sqrt(kappa t): 0.09 m at 1e4 s in granite), the
    cells stay aligned with the conduction normal to the fracture, and the
    count grows only with the number of layers.  Physical groups as in
    ``box_with_fractures`` (the fracture reaches the outer boundary: no tip)."""
    dim = len(extent) + 1
    gmsh = _start("layered_slab")
    occ = gmsh.model.occ
    if dim == 2:
        base = occ.addLine(occ.addPoint(0.0, width, 0.0), occ.addPoint(extent[0], width, 0.0))
        shift = (0.0, 1.0, 0.0)
    else:
        base = occ.addRectangle(0.0, 0.0, width, extent[0], extent[1])
        shift = (0.0, 0.0, 1.0)
    plus = _extrude_in_layers(gmsh, [(dim - 1, base)], shift, width, layer, ratio)
    if dim == 2:             # a line extruded toward +y gives clockwise triangles: turn them over
        for t in plus:
            gmsh.model.mesh.setReverse(2, t)
    on_outer = _tag_domain(gmsh, dim, [t for (_, t) in gmsh.model.getEntities(dim)])
    _tag_fracture(gmsh, dim, 0, [base], on_outer)
    gmsh.option.setNumber("Mesh.MeshSizeMin", fracture_size)
    gmsh.option.setNumber("Mesh.MeshSizeMax", fracture_size)
    return _write(gmsh, dim, path)


def layered_box_with_segment(path: str, x_range: Sequence[float], half: float, segment: Sequence[float],
                             size: float, fracture_size: float, layer: float, ratio: float,
                             grading_distance: float) -> str:
    """The box [x0, x1] x [-H, H] (``x_range``, H = ``half``) around the
    fracture y = 0, s0 < x < s1 (``segment``, its tips inside the box),
    meshed in layers: the line y = 0 is meshed at ``fracture_size`` on the
    fracture, growing to ``size`` over ``grading_distance`` beyond it, then
    extruded up and down in layers of thickness ``layer`` growing by
    ``ratio`` (each quadrilateral cut into two triangles).  The 2D analogue
    of ``layered_half_box_with_disc``: thin cells along the whole fracture
    resolve the rock's thermal boundary layer, the cell count grows only with
    the number of layers.  Physical groups as in ``box_with_fractures``."""
    gmsh = _start("layered_segment")
    occ = gmsh.model.occ
    xs = (x_range[0], segment[0], segment[1], x_range[1])
    pts = [occ.addPoint(x, 0.0, 0.0) for x in xs]
    lines = [occ.addLine(pts[i], pts[i + 1]) for i in range(3)]
    for t in _extrude_in_layers(gmsh, [(1, t) for t in lines], (0.0, 1.0, 0.0), half, layer, ratio):
        gmsh.model.mesh.setReverse(2, t)          # clockwise triangles above the line: turn them over
    on_outer = _tag_domain(gmsh, 2, [t for (_, t) in gmsh.model.getEntities(2)])
    _tag_fracture(gmsh, 2, 0, [lines[1]], on_outer)
    mf = gmsh.model.mesh.field
    _background_size(gmsh, [_threshold(mf, "CurvesList", [lines[1]], fracture_size, size, grading_distance)])
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    return _write(gmsh, 2, path)


def _embed_curves(gmsh, dim: int, curves: list, cells: list) -> None:
    """Embed each curve in the cell (volume) that contains it: the OCC
    fragment embeds a curve inside a volume by itself only when no surface
    is embedded there too."""
    for c in curves:
        lo, hi = gmsh.model.getParametrizationBounds(1, c)
        mid = np.asarray(gmsh.model.getValue(1, c, [0.5 * (lo[0] + hi[0])]))
        for v in cells:
            if (1, c) in gmsh.model.mesh.getEmbedded(dim, v):
                break
            box = np.asarray(gmsh.model.getBoundingBox(dim, v))
            if np.all(mid >= box[:3]) and np.all(mid <= box[3:]):       # the domains here are boxes
                gmsh.model.mesh.embed(1, [c], dim, v)
                break


def _tag_domain(gmsh, dim: int, cells: list) -> set:
    """Physical groups of the domain's cells (tag 1) and of its outer boundary
    (``BOUNDARY_TAG``).  Returns the entities that bound the outer boundary:
    a fracture's rim there is not a tip."""
    gmsh.model.addPhysicalGroup(dim, cells, 1, name="rock")
    outer = gmsh.model.getBoundary([(dim, c) for c in cells], combined=True, oriented=False)
    gmsh.model.addPhysicalGroup(dim - 1, [t for (_, t) in outer], BOUNDARY_TAG, name="boundary")
    return {t for (_, t) in gmsh.model.getBoundary(outer, combined=False, oriented=False)}


def _tag_fracture(gmsh, dim: int, i: int, ents: list, on_outer: set) -> None:
    """Physical groups of fracture ``i``: its facets (``FRACTURE_TAG0 + i``) and
    its tip (``TIP_TAG0 + i``), the part of its rim inside the domain."""
    gmsh.model.addPhysicalGroup(dim - 1, ents, FRACTURE_TAG0 + i, name=f"fracture{i}")
    rim = gmsh.model.getBoundary([(dim - 1, e) for e in ents], combined=True, oriented=False)
    tip = [t for (_, t) in rim if t not in on_outer]
    if tip:
        gmsh.model.addPhysicalGroup(dim - 2, tip, TIP_TAG0 + i, name=f"tip{i}")


def _background_size(gmsh, fields: list) -> None:
    """The smallest of the size ``fields`` sets the mesh size everywhere (sizes
    from points and boundaries off)."""
    mf = gmsh.model.mesh.field
    mn = mf.add("Min")
    mf.setNumbers(mn, "FieldsList", fields)
    mf.setAsBackgroundMesh(mn)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)


def _drop_outside(gmsh, dim: int, mapping: list) -> list:
    """Remove the parts of the fractures that lie outside the domain (a
    fracture cut by a symmetry plane): a fracture piece is kept if it bounds a
    cell of the domain."""
    inside = set()
    for (d, t) in mapping[0]:
        if d == dim:
            for (_, b) in gmsh.model.getBoundary([(d, t)], combined=False, oriented=False):
                inside.add(b)
            inside.update(gmsh.model.mesh.getEmbedded(d, t) and
                          [e for (ed, e) in gmsh.model.mesh.getEmbedded(d, t) if ed == dim - 1])
            _, down = gmsh.model.getAdjacencies(d, t)
            inside.update(int(b) for b in down)
    out = [mapping[0]]
    drop = []
    for m in mapping[1:]:
        keep = [(d, t) for (d, t) in m if d != dim - 1 or t in inside]
        drop += [(d, t) for (d, t) in m if d == dim - 1 and t not in inside]
        out.append(keep)
    if drop:
        gmsh.model.occ.remove(drop, recursive=True)
        gmsh.model.occ.synchronize()
    return out


def _threshold(mf, kind: str, ents, size_min: float, size_max: float, distance: float,
               sampling: int = 100) -> int:
    """A size field growing linearly from ``size_min`` on the entities to
    ``size_max`` at ``distance`` (distances sampled at ``sampling`` points per curve or surface)."""
    dist = mf.add("Distance")
    mf.setNumbers(dist, kind, ents)
    mf.setNumber(dist, "Sampling", sampling)
    thr = mf.add("Threshold")
    mf.setNumber(thr, "InField", dist)
    mf.setNumber(thr, "SizeMin", size_min)
    mf.setNumber(thr, "SizeMax", size_max)
    mf.setNumber(thr, "DistMin", 0.0)
    mf.setNumber(thr, "DistMax", distance)
    return thr


#: the largest mesh a generator may make (cells), ``set_cell_limit``
#: (-thm_max_cells); gmsh needs ~1 kB per tetrahedron and petthm ~10x that
def _write(gmsh, dim: int, path: str, place=None) -> str:
    """Mesh, let ``place(gmsh)`` move the nodes (if given), write ``path``."""
    check_cell_limit(gmsh, dim)
    gmsh.model.mesh.generate(dim)
    if place is not None:
        place(gmsh)
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
    gmsh.option.setNumber("Mesh.Binary", 0)
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    gmsh.write(path)
    gmsh.finalize()
    check_complete(path)
    return path


def check_complete(path: str) -> None:
    """gmsh does not report a failed write (a full disk leaves a truncated
    file): a mesh file whose last line is not a section's end ($End...) is
    an ``OSError`` (ENOSPC when the file system is full)."""
    import errno
    with open(path, "rb") as f:
        f.seek(max(0, os.path.getsize(path) - 64))
        tail = f.read().rstrip().rsplit(b"\n", 1)[-1]
    if not tail.startswith(b"$End"):
        st = os.statvfs(os.path.dirname(os.path.abspath(path)))
        full = st.f_bavail * st.f_frsize < (1 << 16)
        raise OSError(errno.ENOSPC if full else errno.EIO,
                      "No space left on device" if full else "the mesh file was written incompletely", path)

