"""Command line of the deck geometry tool (manual: user guide, decks):

    python -m petthm.run.deckbox --lower 0,0,-3000 --upper 2000,2000,-1000 --size 200 \\
        --layers granite:-2000,sandstone:-1000 --well inj:1000,1000,-2800/1000,1000,-1200 \\
        --fracture crack:600,600,-1500/1400,600,-1500/1400,1400,-1500/600,1400,-1500 --out reservoir.msh

writes the mesh (``deckmesh.layered_deck_box``: named layers, faces west,
east, south, north, bottom, top) and beside it a starter options file
(``reservoir.opts``) that names the mesh and lists every option of its
boundaries, commented out, for the user to fill in.
"""
from __future__ import annotations

import argparse
import os
import sys

from petthm.errors import InputError


def _numbers(text: str, what: str) -> list[float]:
    try:
        return [float(v) for v in text.split(",")]
    except ValueError:
        raise InputError(f"{what} = {text}: comma-separated numbers (x,y[,z])") from None


def _layers(text: str) -> list[tuple[str, float]]:
    out = []
    for item in filter(None, text.split(",")):
        name, _, top = item.partition(":")
        try:
            out.append((name, float(top)))
        except ValueError:
            raise InputError(f"--layers = {text}: NAME:TOP,... (a layer's name and the height of its "
                             "top, from the bottom up)") from None
    return out


def _named_points(text: str, what: str, least: int) -> tuple[str, list]:
    """NAME:x,y,z/x,y,z/... (a well: 3D a polyline, 2D points; a fracture:
    3D a plane polygon, 2D a polyline), ``least`` points at least."""
    name, _, rest = text.partition(":")
    points = [_numbers(p, f"--{what} {text}") for p in rest.split("/") if p]
    if not name or len(points) < least:
        raise InputError(f"--{what} = {text}: NAME:x,y,z/x,y,z/... (the {what}'s name and its points, "
                         f"{least} or more)")
    return name, points


def starter_options(mesh: str, boundaries, regions, wells=(), fractures=()) -> str:
    """An options file for a deck on ``mesh``: the mesh, gravity, the
    initial state, and every boundary's and region's options commented out."""
    import dataclasses

    from petthm.scenes.deckinput import REGION_FIELDS
    from petthm.scenes.reservoir import BoundaryValues
    lines = [f"# a deck on {os.path.basename(mesh)} (regions: {', '.join(regions)}); "
             "python -m petthm reservoir -options_file THIS_FILE",
             f"-thm_mesh_file {mesh}", "-thm_gravity 9.81", "# -thm_initial_temperature 20+(-z)*0.03",
             "# -thm_initial_pressure (-z)*9810",
             "# -thm_insitu_stress sxx,syy,szz,syz,sxz,sxy  (compression positive; must balance gravity)"]
    for name in boundaries:
        lines.append(f"# boundary {name}")
        lines += [f"# -thm_bc_{name}_{f.name} VALUE    ({f.metadata['unit']}: {f.metadata['help']})"
                  for f in dataclasses.fields(BoundaryValues)]
    for name in regions:
        lines.append(f"# region {name} (default: the global -thm_rock_* values)")
        lines += [f"# -thm_region_{name}_{f} VALUE" for f in REGION_FIELDS]
    if wells:
        lines.append(f"# -thm_wells {','.join(wells)}")
    for name in wells:
        lines.append(f"# -thm_well_{name}_rate Q   (or _pressure P; _times, _temperature, _radius)")
    if fractures:
        lines += ["# a deck's fractures are rigid: flow and heat, no u",
                  f"-thm_fractures {','.join(fractures)}", "-thm_fields pm,pf,Tm,Tf"]
    lines += [f"# -thm_fracture_{name}_aperture A" for name in fractures]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m petthm.run.deckbox", description=__doc__.splitlines()[0])
    ap.add_argument("--lower", required=True, help="the box's lowest corner, x,y[,z] (m; the last is up)")
    ap.add_argument("--upper", required=True, help="the box's highest corner")
    ap.add_argument("--size", type=float, required=True, help="mesh size (m)")
    ap.add_argument("--layers", default="", help="NAME:TOP,... from the bottom up (default: one region rock)")
    ap.add_argument("--rotation", type=float, default=0.0, help="turn the mesh about the vertical (degrees)")
    ap.add_argument("--well", action="append", default=[],
                    help="NAME:x,y,z/x,y,z/... a well (3D: a polyline; 2D: points), repeated for more")
    ap.add_argument("--fracture", action="append", default=[],
                    help="NAME:x,y,z/x,y,z/... a fracture (3D: a plane polygon; 2D: a polyline), repeated "
                    "for more")
    ap.add_argument("--out", required=True,
                    help="the mesh file to write (.msh); the options beside it (.opts)")
    args = ap.parse_args(argv)
    from petthm.mesh.deckmesh import FACE_NAMES_2D, FACE_NAMES_3D, layered_deck_box
    try:
        lower, upper = _numbers(args.lower, "--lower"), _numbers(args.upper, "--upper")
        if len(lower) != len(upper) or len(lower) not in (2, 3):
            raise InputError("--lower and --upper: two or three coordinates each, the same number")
        layers = _layers(args.layers)
        if not args.out.endswith(".msh"):
            raise InputError(f"--out = {args.out}: a .msh file")
        wells = [_named_points(w, "well", len(lower) - 1) for w in args.well]
        fractures = [_named_points(f, "fracture", len(lower)) for f in args.fracture]
        for what, named in (("well", wells), ("fracture", fractures)):
            if any(len(p) != len(lower) for _, pts in named for p in pts):
                raise InputError(f"--{what}: points of {len(lower)} coordinates, as --lower")
        layered_deck_box(args.out, lower, upper, args.size, layers, rotation=args.rotation, wells=wells,
                         fractures=fractures)
    except InputError as e:
        print(f"petthm: error: {e}", file=sys.stderr)
        return 2
    faces = (FACE_NAMES_3D if len(lower) == 3 else FACE_NAMES_2D).values()
    opts = os.path.splitext(args.out)[0] + ".opts"
    with open(opts, "w") as f:
        f.write(starter_options(args.out, faces, [n for n, _ in layers] or ["rock"], [n for n, _ in wells],
                                [n for n, _ in fractures]))
    print(f"wrote {args.out} and {opts}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
