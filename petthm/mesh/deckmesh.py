"""Meshes for decks (../shared/docs/reservoir.md section 1; manual: user
guide, decks): a box of named rock layers with named faces, optionally
turned about the vertical axis, meshed with gmsh."""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from petthm.mesh.generate import _embed_curves, _start, _write

#: the names of a deck box's faces: (axis, side) -> name (z up in 3D, y up in 2D)
FACE_NAMES_3D = {(0, 0): "west", (0, 1): "east", (1, 0): "south", (1, 1): "north", (2, 0): "bottom",
                 (2, 1): "top"}
FACE_NAMES_2D = {(0, 0): "west", (0, 1): "east", (1, 0): "bottom", (1, 1): "top"}


def layered_deck_box(path: str, lower: Sequence[float], upper: Sequence[float], size: float,
                     layers: Sequence[tuple[str, float]] = (), rotation: float = 0.0,
                     wells: Sequence[tuple[str, Sequence]] = (),
                     fractures: Sequence[tuple[str, Sequence]] = ()) -> str:
    """A box (2 or 3 corners' coordinates) of rock layers for a deck
    (../shared/docs/reservoir.md section 1): ``layers`` lists (name, top)
    from the bottom up, each layer a named region up to its top (the last
    reaches ``upper``; none: one region ``rock``); the faces are named
    west/east (x), south/north (y, 3D), bottom/top (the vertical axis).
    ``wells`` lists (name, points): in 3D a polyline through the points,
    in 2D the points, embedded in the mesh as a named group of dimension 1
    (0).  ``fractures`` lists (name, points): in 3D a plane polygon through
    the points, in 2D a polyline, embedded as a named group of dimension 2
    (1) (a deck names it in -thm_fractures).  ``rotation`` (degrees) turns the whole mesh about the vertical
    axis (3D) or the out-of-plane axis (2D) through the origin after meshing."""
    dim = len(lower)
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    layers = list(layers) or [("rock", float(upper[-1]))]
    gmsh = _start("deck")
    occ = gmsh.model.occ
    tops = [float(t) for _, t in layers[:-1]] + [float(upper[-1])]
    bottoms = [float(lower[-1])] + tops[:-1]
    cells = []
    for z0, z1 in zip(bottoms, tops, strict=True):
        lo, ext = lower.copy(), upper - lower
        lo[-1], ext[-1] = z0, z1 - z0
        cells.append(occ.addRectangle(*lo, 0, *ext) if dim == 2 else occ.addBox(*lo, *ext))
    tools = [[(dim, c)] for c in cells[1:]] + [_well_entities(occ, dim, pts) for _, pts in wells] + \
        [_fracture_entities(occ, dim, pts) for _, pts in fractures]
    mapping = []
    if tools:
        _, mapping = occ.fragment([(dim, cells[0])], [e for t in tools for e in t])
    occ.synchronize()
    _name_deck_groups(gmsh, dim, lower, upper, layers)
    first = len(cells) - 1
    _name_pieces(gmsh, dim - 2, wells, tools, mapping[1:], first)
    _name_pieces(gmsh, dim - 1, fractures, tools, mapping[1:], first + len(wells))
    if dim == 3 and wells and fractures:
        pieces = sum(len(tools[first + j]) for j in range(len(wells)))
        _embed_well_curves(gmsh, mapping[1 + first:1 + first + pieces])
    gmsh.option.setNumber("Mesh.MeshSizeMin", size)
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    return _write(gmsh, dim, path, place=None if not rotation else lambda g: _rotate_nodes(g, dim, rotation))


def _name_deck_groups(gmsh, dim, lower, upper, layers) -> None:
    """One physical group per layer (by its centre height) and per outer face."""
    model = gmsh.model
    tol = 1e-9 * float(np.max(upper - lower))
    regions: dict[str, list] = {name: [] for name, _ in layers}
    tops = [t for _, t in layers[:-1]] + [float(upper[-1])]
    for _, tag in model.getEntities(dim):
        bb = model.getBoundingBox(dim, tag)
        mid = 0.5 * (bb[dim - 1] + bb[3 + dim - 1])
        k = next(i for i, t in enumerate(tops) if mid < t + tol)
        regions[layers[k][0]].append(tag)
    for tag, (name, ents) in enumerate(regions.items(), start=1):
        model.addPhysicalGroup(dim, ents, tag, name=name)
    names = FACE_NAMES_3D if dim == 3 else FACE_NAMES_2D
    faces: dict[str, list] = {name: [] for name in names.values()}
    for _, tag in model.getEntities(dim - 1):
        bb = np.asarray(model.getBoundingBox(dim - 1, tag))
        for (axis, side), name in names.items():
            at = (lower, upper)[side][axis]
            if abs(bb[axis] - at) < tol and abs(bb[3 + axis] - at) < tol:
                faces[name].append(tag)
    for tag, (name, ents) in enumerate(faces.items(), start=len(regions) + 1):
        model.addPhysicalGroup(dim - 1, ents, tag, name=name)


def _well_entities(occ, dim: int, points) -> list:
    """The lines of a polyline (3D) or the points (2D) of a well."""
    tags = [occ.addPoint(*(list(map(float, x)) + [0.0] * (3 - len(x)))) for x in points]
    if dim == 2:
        return [(0, t) for t in tags]
    if len(tags) < 2:
        raise ValueError("a well in 3D is a polyline of two points or more")
    return [(1, occ.addLine(a, b)) for a, b in zip(tags, tags[1:], strict=False)]


def _fracture_entities(occ, dim: int, points) -> list:
    """The lines of a polyline (2D) or the plane polygon (3D) of a fracture."""
    tags = [occ.addPoint(*(list(map(float, x)) + [0.0] * (3 - len(x)))) for x in points]
    if dim == 2:
        if len(tags) < 2:
            raise ValueError("a fracture in 2D is a polyline of two points or more")
        return [(1, occ.addLine(a, b)) for a, b in zip(tags, tags[1:], strict=False)]
    if len(tags) < 3:
        raise ValueError("a fracture in 3D is a plane polygon of three points or more")
    lines = [occ.addLine(a, b) for a, b in zip(tags, tags[1:] + tags[:1], strict=True)]
    return [(2, occ.addPlaneSurface([occ.addCurveLoop(lines)]))]


def _name_pieces(gmsh, edim: int, named, tools, pieces, first: int) -> None:
    """One physical group per (name, points) of ``named`` (the tools from
    index ``first`` on): the pieces of dimension ``edim`` its entities were cut into."""
    model = gmsh.model
    start = max([t for _, t in model.getPhysicalGroups()] or [0]) + 1
    owner = [k for k, t in enumerate(tools) for _ in t]         # the tool of each fragmented entity
    for j, (name, _) in enumerate(named):
        ents = sorted({e[1] for i, piece in enumerate(pieces) if owner[i] == first + j for e in piece
                       if e[0] == edim})
        model.addPhysicalGroup(edim, ents, start + j, name=name)


def _embed_well_curves(gmsh, pieces) -> None:
    """Embed the wells' curves that run through the rock in the volume around
    them: OCC's fragment embeds a curve in a volume by itself only where no
    surface (a fracture) is embedded there too.  A curve in a fracture's
    plane stays the fracture's."""
    model = gmsh.model
    on_surfaces = {t for _, s in model.getEntities(2) for d, t in model.mesh.getEmbedded(2, s) if d == 1}
    on_surfaces |= {t for _, t in model.getBoundary(model.getEntities(2), combined=False, oriented=False)}
    curves = sorted({t for piece in pieces for d, t in piece if d == 1} - on_surfaces)
    _embed_curves(gmsh, 3, curves, [t for _, t in model.getEntities(3)])


def _rotate_nodes(gmsh, dim: int, degrees: float) -> None:
    """Turn every node about the vertical (3D: z; 2D: out-of-plane) axis through the origin."""
    c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    tags, xyz, _ = gmsh.model.mesh.getNodes()
    x = xyz.reshape(-1, 3).copy()
    x[:, 0], x[:, 1] = c * xyz[0::3] - s * xyz[1::3], s * xyz[0::3] + c * xyz[1::3]
    for t, p in zip(tags, x, strict=True):
        gmsh.model.mesh.setNode(int(t), list(p), [])
