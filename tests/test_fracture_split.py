"""Cohesive split of the DMPlex along fractures (issue 3, deliverable 2):
counts, tips, pairs, orientation and DMPlex checks, serial and on 2/3 ranks."""
import json
import os
import subprocess
import sys

import pytest

from conftest import MPI_ENV, ROOT
from petthm import meshing as M

MESHES = {
    "line2d": ([1, 1], 0.1, [M.Fracture("segment", p0=(0.25, 0.5), p1=(0.75, 0.5))]),
    "cut2d": ([1, 1], 0.1, [M.Fracture("segment", p0=(0.0, 0.5), p1=(0.6, 0.5))]),
    "disc3d": ([1, 1, 1], 0.2, [M.Fracture("disc", center=(0.5, 0.5, 0.5), radius=0.3, size=0.1)]),
    "inclined3d": ([1, 1, 1], 0.2, [M.Fracture("disc", center=(0.5, 0.5, 0.5), radius=0.3, dip=30)]),
    "two3d": ([1, 1, 1], 0.2, [M.Fracture("rectangle", center=(0.5, 0.5, 0.3), half=(0.2, 0.2)),
                               M.Fracture("rectangle", center=(0.5, 0.5, 0.7), half=(0.3, 0.2))]),
}


def _stats(path, ranks):
    cmd = [sys.executable, "-m", "petthm.fracture", str(path)]
    if ranks > 1:
        cmd = ["mpiexec", "-n", str(ranks)] + cmd
    p = subprocess.run(cmd, cwd=ROOT, env=dict(os.environ, **MPI_ENV), capture_output=True,
                       text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def meshes(tmp_path_factory):
    d = tmp_path_factory.mktemp("fractures")
    return {k: M.box_with_fractures(str(d / f"{k}.msh"), *v) for k, v in MESHES.items()}


@pytest.mark.parametrize("name", list(MESHES))
def test_split_serial(meshes, name):
    s = _stats(meshes[name], 1)
    before, after = s["before"], s["serial"]
    nfacets = sum(before["facets"].values())
    assert nfacets > 0
    # one cohesive cell per fracture facet; bulk cells unchanged
    assert after["cohesive_cells"] == nfacets
    assert after["cells"] == before["cells"]
    # every fracture vertex is duplicated except on the tip
    added = sum(nv - nt for nv, nt in before["fracture_vertices"].values())
    assert after["vertices"] - before["vertices"] == added
    # tip vertices exist for buried fractures, and appear as shared (unduplicated) pairs
    assert all(nt > 0 for _, nt in before["fracture_vertices"].values())
    assert after["shared_tip_pairs"] > 0
    # paired - / + vertices coincide; - faces lie on the -n side; DMPlexCheck* pass
    assert after["pair_mismatch"] == 0.0
    assert after["orientation_checked"] == 2 * nfacets and after["orientation_errors"] == 0
    assert after["plex_checks_failed"] == 0


def test_fracture_through_the_boundary_is_split_there(meshes):
    """cut2d: the end on x = 0 is not a tip, so it is duplicated: one tip vertex only."""
    s = _stats(meshes["cut2d"], 1)
    (nv, nt), = s["before"]["fracture_vertices"].values()
    assert nt == 1 and s["serial"]["vertices"] - s["before"]["vertices"] == nv - 1


def test_inclined_normal(meshes):
    s = _stats(meshes["inclined3d"], 1)
    n = s["normals"][0]
    assert abs(abs(n[1]) - 0.5) < 1e-6 and abs(n[2] - 3 ** 0.5 / 2) < 1e-6


@pytest.mark.parallel
@pytest.mark.parametrize("name", ["line2d", "disc3d", "inclined3d", "two3d"])
@pytest.mark.parametrize("ranks", [2, 3])
def test_split_distributed_matches_serial(meshes, name, ranks):
    s = _stats(meshes[name], ranks)
    ser, dis = s["serial"], s["distributed"]
    for key in ("cells", "cohesive_cells", "vertices", "shared_tip_pairs"):
        assert dis[key] == ser[key], key
    assert dis["orientation_errors"] == 0 and dis["plex_checks_failed"] == 0
    assert dis["pair_mismatch"] == 0.0
