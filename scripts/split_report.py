"""Cohesive split statistics of a gmsh mesh (docs/verification/fracture-flow-and-heat.md):

    [mpiexec -n N] python scripts/split_report.py MESH.msh

splits the mesh along its fractures, distributes it as petthm does (every
cohesive cell with its two rock cells: ``partition``) and prints JSON: the
counts before the split, and the vertex/cell/tip counts, orientation and
pairing checks and DMPlex checks after it, serial and distributed."""
import json
import sys

import petsc4py


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    petsc4py.init([sys.argv[0]] + argv[1:])
    from petsc4py import PETSc

    from petthm.mesh.fracture import FACE_SETS, fracture_vertex_counts, split_fractures, split_statistics
    from petthm.mesh.partition import split_count
    from petthm.mesh.plex import distribute, read_plex
    dm = read_plex(argv[0], PETSc.COMM_WORLD)
    counts = fracture_vertex_counts(dm)
    comm = dm.comm.tompi4py()
    before = {"cells": comm.allreduce(dm.getHeightStratum(0)[1]),
              "vertices": comm.allreduce(dm.getDepthStratum(0)[1] - dm.getDepthStratum(0)[0]),
              "facets": {t: int(dm.getStratumSize(FACE_SETS, t)) for t in counts},
              "fracture_vertices": counts}
    dm, infos = split_fractures(dm)
    normals = [i.normal for i in infos]
    serial = split_statistics(dm, normals)
    if dm.comm.size > 1:
        dm = distribute(dm)
    stats = {"before": before, "serial": serial, "distributed": split_statistics(dm, normals),
             "ranks": dm.comm.size, "normals": [n.tolist() for n in normals],
             "cohesive_apart_from_rock": split_count(dm)}
    if dm.comm.rank == 0:
        print(json.dumps(stats))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
