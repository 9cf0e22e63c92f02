"""Cohesive split of the DMPlex along fractures (issue 3, deliverable 2):
counts, tips, pairs, orientation and DMPlex checks, serial and on 2/3 ranks."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import MPI_ENV, ROOT
from petthm.mesh import generate as M

MESHES = {
    "line2d": ([1, 1], 0.1, [M.Fracture("segment", p0=(0.25, 0.5), p1=(0.75, 0.5))]),
    "cut2d": ([1, 1], 0.1, [M.Fracture("segment", p0=(0.0, 0.5), p1=(0.6, 0.5))]),
    "disc3d": ([1, 1, 1], 0.2, [M.Fracture("disc", center=(0.5, 0.5, 0.5), radius=0.3, size=0.1)]),
    "inclined3d": ([1, 1, 1], 0.2, [M.Fracture("disc", center=(0.5, 0.5, 0.5), radius=0.3, dip=30)]),
    "two3d": ([1, 1, 1], 0.2, [M.Fracture("rectangle", center=(0.5, 0.5, 0.3), half=(0.2, 0.2)),
                               M.Fracture("rectangle", center=(0.5, 0.5, 0.7), half=(0.3, 0.2))]),
}


def _stats(path, ranks):
    cmd = [sys.executable, os.path.join(ROOT, "scripts", "split_report.py"), str(path)]
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
    assert s["cohesive_apart_from_rock"] == 0


def test_partition_groups_cohesive_cells_with_their_rock(meshes):
    """``partition._grouped_owners``: a partition that puts neighbouring cells
    on alternate ranks splits cohesive cells from their rock cells; the
    grouped one puts each cohesive cell and its two rock cells on one rank
    and moves no other cell."""
    import numpy as np
    from petsc4py import PETSc

    from petthm.mesh import partition
    from petthm.mesh.fracture import split_fractures
    from petthm.mesh.plex import read_plex
    dm, _ = split_fractures(read_plex(meshes["disc3d"], PETSc.COMM_SELF))
    coh, rock = partition.cohesive_neighbours(dm)
    assert len(coh) and (rock >= 0).all()
    n = dm.getHeightStratum(0)[1]
    owner = np.arange(n) % 3
    apart = (owner[coh] != owner[rock[:, 0]]) | (owner[coh] != owner[rock[:, 1]])
    assert apart.sum() > len(coh) // 2                   # the test partition splits most of them
    grouped = partition._grouped_owners(dm, owner)
    assert (grouped[coh] == grouped[rock[:, 0]]).all() and (grouped[coh] == grouped[rock[:, 1]]).all()
    others = np.setdiff1d(np.arange(n), np.concatenate([coh, rock.ravel()]))
    assert (grouped[others] == owner[others]).all()


def _heat_on(path, split):
    """Cool the bottom of a square for 1e6 s; returns node y and T (K)."""
    import numpy as np
    from petsc4py import PETSc

    from petthm.discretisation.assembly import FieldScale
    from petthm.discretisation.constraints import Dirichlet
    from petthm.discretisation.fields import Discretisation, FieldSpec
    from petthm.discretisation.model import Domain, Model
    from petthm.discretisation.problem import Problem
    from petthm.mesh import fracture as F
    from petthm.mesh.plex import Mesh, distribute, label_boundaries, read_plex
    from petthm.physics.kernels import heat
    from petthm.solvers.options import SOLVER_DEFAULTS, Proposals
    from petthm.solvers.timestepper import StepControl, TimeStepper
    dm = read_plex(str(path), PETSc.COMM_WORLD)
    label_boundaries(dm, {"bottom": lambda x: np.isclose(x[:, 1], 0.0)})
    if split:
        dm, _ = F.split_fractures(dm)
    mesh = Mesh(distribute(dm))
    model = Model([FieldSpec("Tm", 1, 2)])
    model.add(heat.heat_terms(heat.Heat(Domain.MATRIX, "Tm", 1.0, 0.05, degree=2)))
    disc = Discretisation(mesh, model.fields, {"Tm": ["bottom"]})
    problem = Problem(disc, model, {"Tm": FieldScale(60.0, 353.15)},
                      [Dirichlet("Tm", "bottom", lambda x, t: np.full(len(x), 293.15))])
    problem.set_initial({"Tm": lambda x: np.full(len(x), 353.15)})
    Proposals().propose(SOLVER_DEFAULTS)
    problem.auto_residual_scales(0.0, 1.0)
    stepper = TimeStepper(problem, StepControl(final_time=4.0, dt_initial=1.0))
    assert stepper.solve() > 0
    y = disc.field_node_coordinates("Tm")[:, 1]
    return y, problem.field_values("Tm")[:, 0]


def test_matrix_field_is_discontinuous_across_a_split(meshes, tmp_path):
    """A fracture cutting the whole square insulates the upper half (the split
    decouples the duplicated nodes); without the split, heat crosses."""
    import numpy as np
    path = M.box_with_fractures(str(tmp_path / "through.msh"), [1, 1], 0.1,
                                [M.Fracture("segment", p0=(0.0, 0.5), p1=(1.0, 0.5))])
    y, T = _heat_on(path, split=True)
    upper = y > 0.5 + 1e-9
    assert np.abs(T[upper] - 353.15).max() < 1e-8
    assert T[y < 0.5 - 1e-9].min() < 353.15 - 1.0
    y, T = _heat_on(path, split=False)
    assert T[y > 0.5 + 1e-9].min() < 353.15 - 1e-3


def test_layered_box_with_segment(tmp_path):
    """Issue 16: Scene 1's layered mesh (the line through the fracture
    extruded in layers up and down): the cells tile the box, all
    counter-clockwise; the layers next to the fracture are as thin as asked;
    the split's checks pass with a tip at each end of the fracture (shared,
    unduplicated vertices) and one cohesive cell per fracture facet."""
    import meshio
    import numpy as np
    path = M.layered_box_with_segment(str(tmp_path / "layered.msh"), (-1.0, 2.0), 1.0, (0.0, 1.0), 0.5, 0.1,
                                      0.01, 1.5, 0.5)
    m = meshio.read(path)
    x, tri = m.points[:, :2], m.cells_dict["triangle"]
    e1, e2 = x[tri[:, 1]] - x[tri[:, 0]], x[tri[:, 2]] - x[tri[:, 0]]
    area = 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    assert area.min() > 0 and abs(area.sum() - 6.0) < 1e-9
    levels = np.unique(np.round(x[:, 1], 9))
    first = M.layer_heights(0.01, 1.5, 1.0)[0]
    assert 0.005 < first <= 0.01 and np.isclose(np.abs(levels[levels != 0]).min(), first)
    s = _stats(path, 1)
    after = s["serial"]
    (nv, nt), = s["before"]["fracture_vertices"].values()
    assert sum(s["before"]["facets"].values()) == 10 and after["cohesive_cells"] == 10
    assert nt == 2 and after["shared_tip_pairs"] > 0
    assert after["orientation_errors"] == 0 and after["plex_checks_failed"] == 0
    assert after["pair_mismatch"] == 0.0


def test_layered_slab_with_fracture(tmp_path):
    """lauwerier's 2D layered mesh: the cells tile the slab, all
    counter-clockwise; the split
    passes its checks with the fracture cutting the slab (no tip)."""
    import meshio
    path = M.layered_slab_with_fracture(str(tmp_path / "slab.msh"), (3.0,), 1.0, 0.1, 0.01, 1.5)
    m = meshio.read(path)
    x, tri = m.points[:, :2], m.cells_dict["triangle"]
    e1, e2 = x[tri[:, 1]] - x[tri[:, 0]], x[tri[:, 2]] - x[tri[:, 0]]
    area = 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    assert area.min() > 0 and abs(area.sum() - 6.0) < 1e-9
    s = _stats(path, 1)
    after = s["serial"]
    assert after["cohesive_cells"] == sum(s["before"]["facets"].values()) == 30
    assert after["orientation_errors"] == 0 and after["plex_checks_failed"] == 0
    assert after["pair_mismatch"] == 0.0


def test_layered_box_with_inclined_disc(tmp_path):
    """Scene 3's layered mesh: the tetrahedra tile the box with positive
    volumes; the fracture's faces lie on the dipping plane and cover the
    disc; the first layer is ``layer`` thick across the fracture; the wells'
    columns are vertical lines of the mesh with vertices at the
    perforations' ends; the split passes its checks."""
    import meshio

    from petthm.mesh import layered as layeredmesh
    L, R, dip, layer = 3.0, 1.0, 30.0, 0.02
    path = layeredmesh.layered_box_with_inclined_disc(str(tmp_path / "inc.msh"), L, R, dip, 1.5, 0.25, layer,
                                                      1.5, wells=[(0.0, -0.75), (0.0, 0.75)], well_size=0.1,
                                                      well_heights=(0.05, 0.15))
    m = meshio.read(path)
    X, tet = m.points, m.cells_dict["tetra"]
    vol = np.einsum("ij,ij->i", np.cross(X[tet[:, 1]] - X[tet[:, 0]], X[tet[:, 2]] - X[tet[:, 0]]),
                    X[tet[:, 3]] - X[tet[:, 0]]) / 6
    assert vol.min() > 0 and abs(vol.sum() - (2 * L) ** 3) < 1e-9 * (2 * L) ** 3
    d = np.radians(dip)
    n = np.array([np.sin(d), 0.0, np.cos(d)])
    tri = m.cells_dict["triangle"][m.cell_data_dict["gmsh:physical"]["triangle"] == M.FRACTURE_TAG0]
    assert np.abs(X[tri.ravel()] @ n).max() < 1e-12 * L
    area = np.linalg.norm(np.cross(X[tri[:, 1]] - X[tri[:, 0]], X[tri[:, 2]] - X[tri[:, 0]]),
                          axis=1).sum() / 2
    assert 0.97 * np.pi * R ** 2 < area <= np.pi * R ** 2
    dist = np.abs(X @ n)
    assert np.min(dist[dist > 1e-12]) == pytest.approx(layer, rel=1e-9)
    for y in (-0.75, 0.75):
        z = X[(np.abs(X[:, 0]) < 1e-12) & (np.abs(X[:, 1] - y) < 1e-12), 2]
        assert np.any(np.isclose(z, 0.05, atol=1e-12)) and np.any(np.isclose(z, 0.15, atol=1e-12))
    s = _stats(path, 1)
    after = s["serial"]
    assert after["cohesive_cells"] == len(tri)
    assert after["orientation_errors"] == 0 and after["plex_checks_failed"] == 0
    assert after["pair_mismatch"] == 0.0
