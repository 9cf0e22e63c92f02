"""Write a scene-style gmsh mesh without running a scene.

    python meshes/generate.py box LX LY [LZ] SIZE OUT.msh
    python meshes/generate.py PRESET SIZE OUT.msh        (fractured meshes)

Presets (gmsh Python API through ``petthm.meshing.box_with_fractures``;
fracture i is the physical group 10 + i of facets, the domain group 1):

  line2d          100 x 120 m rectangle, a horizontal 100 m fracture cutting x = 0 and x = 100
  buried_line2d   the same fracture buried in a 400 x 300 m rectangle (tips inside)
  disc            300 m cube, horizontal disc R = 100 m at its centre, a vertex at the centre
  inclined_disc   400 m cube, disc R = 100 m dipping 30 degrees
  rectangle       100 m cube, a 60 x 40 m horizontal rectangle
  two_rectangles  100 m cube, two parallel rectangles
  penny_wells     400 m cube, horizontal disc R = 100 m with wells at (+-50, 0) from its centre

``python scripts/split_report.py OUT.msh`` prints the cohesive split's statistics.
"""
import sys

from petthm import meshing as M


def presets(size):
    F = M.Fracture
    return {
        "line2d": dict(lengths=[100, 120], fractures=[F("segment", p0=(0, 60), p1=(100, 60))]),
        "buried_line2d": dict(lengths=[400, 300], origin=(-150, -150),
                              fractures=[F("segment", p0=(0, 0), p1=(100, 0))], wells=[(0, 0), (100, 0)]),
        "disc": dict(lengths=[300] * 3, fractures=[F("disc", center=(150, 150, 150), radius=100)],
                     wells=[(150, 150, 150)]),
        "inclined_disc": dict(lengths=[400] * 3,
                              fractures=[F("disc", center=(200, 200, 200), radius=100, dip=30)]),
        "rectangle": dict(lengths=[100] * 3, fractures=[F("rectangle", center=(50, 50, 50), half=(30, 20))]),
        "two_rectangles": dict(lengths=[100] * 3,
                               fractures=[F("rectangle", center=(50, 50, 30), half=(30, 20)),
                                          F("rectangle", center=(50, 50, 70), half=(30, 20))]),
        "penny_wells": dict(lengths=[400] * 3, fractures=[F("disc", center=(200, 200, 200), radius=100)],
                            wells=[(150, 200, 200), (250, 200, 200)]),
    }


def main(argv):
    if len(argv) >= 4 and argv[0] == "box":
        *lengths, size, out = argv[1:]
        M.box(out, [float(v) for v in lengths], float(size))
    elif len(argv) == 3 and argv[0] in presets(1.0):
        name, size, out = argv[0], float(argv[1]), argv[2]
        p = presets(size)[name]
        M.box_with_fractures(out, p["lengths"], size, p["fractures"], grading_distance=2 * size,
                             origin=p.get("origin", ()), wells=p.get("wells", ()),
                             well_size=0.25 * size if p.get("wells") else 0.0)
    else:
        print(__doc__)
        return 2
    print(argv[-1])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
