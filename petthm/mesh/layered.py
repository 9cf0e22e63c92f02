"""A layered mesh around an inclined disc fracture (Scene 3).

The rock's thermal boundary layer next to a fracture is thin (sqrt(kappa t):
0.3 m after a day, 19 m after ten years for kappa = 1.15e-6 m2/s).  Isotropic tetrahedra
resolve it only with cells as small as the layer everywhere along the
fracture; layers parallel to the fracture resolve it at the cost of a few
cells across.  ``meshing.layered_half_box_with_disc`` does that for a
horizontal disc by extruding the plane's triangles.  A dipping disc in an
axis-aligned box (the box keeps its rollers and its faces x, y, z = +-L)
is made here in the same way, in a sheared frame:

* the horizontal plane z = 0 of the box is meshed with triangles: the disc's
  vertical projection (an ellipse, semi-axes R cos(dip) along x and R along
  y) at the fracture's size, the wells' base points at theirs, growing to the
  far-field size;
* the plane is extruded up and down in N uniform layers of a unit height
  (each prism cut into tetrahedra, as gmsh extrudes simplices);
* every node then moves vertically: level k of the column over (x, y) goes
  to z = z_p(x) +- b_k(x), z_p(x) = -x tan(dip) the fracture plane, b_k the
  layer boundaries of that column.  The plane maps onto the dipping
  fracture plane and level N onto the box's top (bottom) face.

The layer boundaries, vertical distances from the plane: first ``layer`` /
cos(dip) (``layer`` is the thickness across the fracture), growing by
``ratio``, at most ``cap`` thick up to the highest ``heights`` (the
perforations' ends, which become boundaries, so that a vertical well over a
base point is a line of the mesh), the same in every column up to half the
shortest column; the rest of each column is filled by the remaining layers
of the geometric sequence scaled to its height.  The columns are vertical,
so vertical wells stay lines of the mesh.
"""
from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from petthm.mesh.generate import (
    _background_size,
    _start,
    _tag_domain,
    _tag_fracture,
    _threshold,
    _write,
    tag_well_points,
)


def shared_boundaries(layer: float, ratio: float, cap: float, heights: Sequence[float],
                      limit: float) -> np.ndarray:
    """Layer boundaries 0 < b_1 < ... <= ``limit`` common to every column: a
    geometric sequence from ``layer`` by ``ratio``, steps at most ``cap`` up
    to max(``heights``), each of ``heights`` a boundary (a boundary closer to
    it than 0.3 of the local step is dropped)."""
    top = max(heights, default=0.0)
    b, step = [0.0], layer
    while b[-1] + step <= limit:
        b.append(b[-1] + (min(step, cap) if b[-1] < top else step))
        step *= ratio
    b = np.array(b)
    for h in heights:
        if not 0.0 < h < limit:
            raise ValueError(f"a well height {h:g} m is outside the layered zone (0, {limit:g}) m")
        gaps = np.diff(b)
        i = int(np.argmin(np.abs(b - h)))
        local = gaps[min(i, len(gaps) - 1)]
        b = b[(np.abs(b - h) >= 0.3 * local) | (b == 0.0)]
        b = np.sort(np.append(b, h))
    return b


def level_heights(shared: np.ndarray, ratio: float, count: int, H: np.ndarray,
                  k: np.ndarray) -> np.ndarray:
    """The height above the plane of level ``k`` in a column of height ``H``
    (per node): ``shared[k]`` in the common layers, above them ``count``
    layers growing by ``ratio`` scaled to reach ``H``."""
    g = ratio ** np.arange(1, count + 1)
    frac = np.concatenate([[0.0], np.cumsum(g) / g.sum()])
    n = len(shared) - 1
    far = np.clip(k - n, 0, count)
    return np.where(k <= n, shared[np.minimum(k, n)], shared[-1] + (H - shared[-1]) * frac[far])


def far_layers(shared: np.ndarray, ratio: float, H_max: float) -> int:
    """How many geometric layers continue ``shared`` up to ``H_max`` (at least 1)."""
    step, top, n = shared[-1] - shared[-2], shared[-1], 0
    while top < H_max or n == 0:
        step *= ratio
        top += step
        n += 1
    return n


def layered_box_with_inclined_disc(path: str, half: float, radius: float, dip: float, size: float,
                                   disc_size: float, layer: float, ratio: float,
                                   wells: Sequence[tuple] = (), well_size: float = 0.0,
                                   well_heights: Sequence[float] = ()) -> str:
    """The box [-L, L]^3 (L = ``half``) around the disc of ``radius`` through
    the origin dipping ``dip`` degrees about y (normal (sin, 0, cos)), meshed
    in layers parallel to it (module docstring).  ``wells``: base points
    (x, y) whose vertical columns carry the wells, at x where the plane is
    z = 0 only (x = 0), mesh size ``well_size`` there; ``well_heights``:
    vertical distances above the plane that become layer boundaries (the
    perforations' ends).  Physical groups as in ``meshing.box_with_fractures``;
    well ``i`` is its base point."""
    d = math.radians(dip)
    tan, cos = math.tan(d), math.cos(d)
    if tan >= 1.0:
        raise ValueError(f"dip {dip:g} degrees: the layered box needs the plane inside it (dip < 45)")
    H_min, H_max = half * (1.0 - tan), half * (1.0 + tan)
    shared = shared_boundaries(layer / cos, ratio, well_size or np.inf, well_heights, 0.5 * H_min)
    count = far_layers(shared, ratio, H_max)
    N = len(shared) - 1 + count
    gmsh = _start("layered_inclined_disc")
    occ = gmsh.model.occ
    rect = occ.addRectangle(-half, -half, 0.0, 2 * half, 2 * half)
    disc = occ.addDisk(0.0, 0.0, 0.0, radius, radius * cos)          # OCC: major radius along x
    occ.rotate([(2, disc)], 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, math.pi / 2)  # the projection: R cos along x
    wpts = [occ.addPoint(x, y, 0.0) for (x, y) in wells]
    out, mapping = occ.fragment([(2, rect)], [(2, disc)] + [(0, w) for w in wpts])
    occ.synchronize()
    plane = [t for (dd, t) in out if dd == 2]
    on_disc = [t for (dd, t) in mapping[1] if dd == 2]
    for sign in (1.0, -1.0):
        occ.extrude([(2, t) for t in plane], 0.0, 0.0, sign, numElements=[1] * N,
                    heights=list(np.arange(1, N + 1) / N), recombine=False)
    occ.synchronize()
    on_outer = _tag_domain(gmsh, 3, [t for (_, t) in gmsh.model.getEntities(3)])
    _tag_fracture(gmsh, 3, 0, on_disc, on_outer)
    well_tags = tag_well_points(gmsh, wells, 1e-9 * half)
    mf = gmsh.model.mesh.field
    fields = [_threshold(mf, "SurfacesList", on_disc, disc_size * cos, size, radius)]
    if well_tags and well_size:
        fields.append(_threshold(mf, "PointsList", well_tags, well_size, size, radius))
    _background_size(gmsh, fields)
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)

    def place(g):
        _place_levels(g, N, half, tan, shared, ratio, count)
    return _write(gmsh, 3, path, place)


def _place_levels(gmsh, N: int, half: float, tan: float, shared: np.ndarray, ratio: float,
                  count: int) -> None:
    """Move every node of level k (z = +-k/N after the extrusion) to
    z_p(x) +- b_k(x) (module docstring)."""
    tags, X, _ = gmsh.model.mesh.getNodes()
    X = X.reshape(-1, 3)
    zeta = X[:, 2]
    k = np.rint(np.abs(zeta) * N).astype(int)
    if np.any(np.abs(np.abs(zeta) * N - k) > 1e-6):
        raise RuntimeError("layered mesh: a node off the extrusion levels")
    zp = -X[:, 0] * tan
    up = zeta >= 0
    H = np.where(up, half - zp, half + zp)
    z = zp + np.where(up, 1.0, -1.0) * level_heights(shared, ratio, count, H, k)
    z[k == N] = np.where(up, half, -half)[k == N]
    for t, x, y, zz in zip(tags, X[:, 0], X[:, 1], z, strict=False):
        gmsh.model.mesh.setNode(int(t), [x, y, zz], [])


__all__ = ["layered_box_with_inclined_disc", "shared_boundaries", "level_heights"]
