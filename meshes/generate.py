"""Write a scene-style gmsh mesh without running a scene.

    python meshes/generate.py box LX LY [LZ] SIZE OUT.msh
"""
import sys

from petthm import meshing


def main(argv):
    if len(argv) < 4 or argv[0] != "box":
        print(__doc__)
        return 2
    *lengths, size, out = argv[1:]
    meshing.box(out, [float(v) for v in lengths], float(size))
    print(out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
