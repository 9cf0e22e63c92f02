"""Fields on the fracture surface (the - faces of the cohesive cells):
section, element arrays and surface assembly with tangential gradients."""
import numpy as np
import pytest
from petsc4py import PETSc

from petthm.discretisation.assembly import FieldScale
from petthm.discretisation.constraints import Dirichlet
from petthm.discretisation.fields import Discretisation, FieldSpec
from petthm.discretisation.model import FRACTURE, CellJacobian, CellResidual, Domain, Model
from petthm.discretisation.problem import Problem
from petthm.mesh import fracture as F
from petthm.mesh import generate as M
from petthm.mesh.plex import Mesh, distribute, label_boundaries, read_plex


def _fracture_problem(path, dim, degree, exact, source=0.0):
    """Steady surface Laplace problem for pf with Dirichlet data at both ends."""
    dm = read_plex(str(path), PETSc.COMM_WORLD)
    label_boundaries(dm, {"x0": lambda x: np.isclose(x[:, 0], 0.0), "x1": lambda x: np.isclose(x[:, 0], 1.0)})
    dm, _ = F.split_fractures(dm)
    mesh = Mesh(distribute(dm))
    surf = mesh.fracture
    k = 2.5

    def f1(ctx):
        return k * ctx.grad("pf")

    def f0(ctx):
        return np.full(ctx.shape + (1,), k * source)      # -div(k grad p) + k s = 0

    def g3(ctx):
        return (k * np.eye(dim))[None, None, None, :, None, :]
    model = Model([FieldSpec("pf", 1, degree, region=Domain.FRACTURE)],
                  [CellResidual("pf", f0, f1, region=FRACTURE)],
                  [CellJacobian("pf", "pf", g3=g3, region=FRACTURE)])
    disc = Discretisation(mesh, model.fields, {"pf": ["x0", "x1"]}, regions={Domain.FRACTURE: surf})
    bcs = [Dirichlet("pf", b, lambda x, t: exact(x)) for b in ("x0", "x1")]
    return Problem(disc, model, {"pf": FieldScale(1.0)}, bcs), surf


def solve_and_error(problem, exact):
    """One linear solve (GMRES, tight tolerance); max relative nodal error over all ranks."""
    J = problem.create_matrix()
    problem.ijacobian(None, 0.0, problem.X, problem.X, 0.0, J, J)
    F_ = problem.X.duplicate()
    problem.ifunction(None, 0.0, problem.X, problem.X.duplicate(), F_)
    ksp = PETSc.KSP().create(comm=problem.dm.comm)
    ksp.setOperators(J)
    ksp.setType("gmres")
    ksp.getPC().setType("jacobi")
    ksp.setTolerances(rtol=1e-14, atol=1e-300, max_it=5000)
    dx = problem.X.duplicate()
    ksp.solve(F_, dx)
    problem.X.axpy(-1.0, dx)
    p = problem.field_values("pf")[:, 0]
    x = problem.disc.field_node_coordinates("pf")
    err = np.abs(p - exact(x)).max() / np.abs(exact(x)).max() if len(p) else 0.0
    from mpi4py import MPI
    return problem.dm.comm.tompi4py().allreduce(err, op=MPI.MAX), p


CASES = [("linear", d, p) for d in (2, 3) for p in (1, 2)] + [("quadratic", d, 2) for d in (2, 3)]


@pytest.mark.parametrize("kind,dim,degree", CASES)
def test_pressure_on_a_fracture_is_exact(tmp_path, kind, dim, degree):
    """Patch tests on a fracture cutting the domain: a linear pf (P1, P2) and,
    with a uniform source, the quadratic pf = x^2 (P2) are reproduced to
    round-off; the quadratic case checks the surface measure and the
    tangential-gradient map, which the linear one cannot."""
    if dim == 2:
        fr = [M.Fracture("segment", p0=(0.0, 0.5), p1=(1.0, 0.5))]
        lengths, area = [1, 1], 1.0
    else:
        fr = [M.Fracture("rectangle", center=(0.5, 0.5, 0.5), half=(0.5, 0.3))]
        lengths, area = [1, 1, 1], 0.6
    path = M.box_with_fractures(str(tmp_path / "m.msh"), lengths, 0.25, fr)
    if kind == "linear":
        exact, source = (lambda x: 3.0 + 2.0 * x[:, 0]), 0.0          # noqa: E731
    else:
        exact, source = (lambda x: 1.0 + x[:, 0] ** 2), 2.0           # -lap p + 2 = 0
    problem, surf = _fracture_problem(path, dim, degree, exact, source)
    assert surf.area() == pytest.approx(area, rel=1e-12)
    err, p = solve_and_error(problem, exact)
    print(f"{kind} {dim}D P{degree}: fracture nodes {len(p)}, max relative error {err:.1e}")
    assert len(p) > 0 and err <= 1e-10


PARALLEL_SCRIPT = """
import sys, petsc4py; petsc4py.init()
sys.path.insert(0, {tests!r})
import numpy as np
from test_fracture_fields import _fracture_problem, solve_and_error
problem, surf = _fracture_problem({path!r}, {dim}, 2, lambda x: 1.0 + x[:, 0] ** 2, 2.0)
err, _ = solve_and_error(problem, lambda x: 1.0 + x[:, 0] ** 2)
sizes = problem.disc.global_sizes()
area = surf.area()
if problem.dm.comm.rank == 0:
    print(err, sizes["pf"], area)
"""


@pytest.mark.parallel
@pytest.mark.parametrize("dim", [2, 3])
def test_fracture_field_in_parallel(tmp_path, dim):
    """2 and 3 ranks: same number of fracture unknowns, same area, still exact."""
    import os
    import subprocess
    import sys

    from conftest import MPI_ENV, ROOT
    fr = [M.Fracture("segment", p0=(0.0, 0.5), p1=(1.0, 0.5))] if dim == 2 else \
        [M.Fracture("rectangle", center=(0.5, 0.5, 0.5), half=(0.5, 0.3))]
    path = M.box_with_fractures(str(tmp_path / "m.msh"), [1] * dim, 0.25 if dim == 3 else 0.1, fr)
    script = tmp_path / "run.py"
    script.write_text(PARALLEL_SCRIPT.format(tests=os.path.join(ROOT, "tests", "unit"), path=path, dim=dim))
    out = {}
    for n in (1, 2, 3):
        cmd = [sys.executable, str(script)]
        cmd = cmd if n == 1 else ["mpiexec", "-n", str(n)] + cmd
        p = subprocess.run(cmd, cwd=ROOT,
                           env=dict(os.environ, **MPI_ENV), capture_output=True, text=True, timeout=300)
        assert p.returncode == 0, p.stderr
        err, ndof, area = p.stdout.split()
        out[n] = (float(err), int(ndof), float(area))
    print(out)
    for n in (2, 3):
        assert out[n][0] <= 1e-10 and out[n][1] == out[1][1]
        assert out[n][2] == pytest.approx(out[1][2], rel=1e-12)


def test_same_points_matches_copies_exactly_and_near_ones_within_the_tolerance():
    """A tied node finds the row with its coordinates: bit-equal copies (also
    -0.0 against 0.0) by the sort, rows off by less than the tolerance by the
    k-d tree, a row farther than it nowhere (-1)."""
    from petthm.discretisation.fields import same_points
    rng = np.random.default_rng(0)
    ref = rng.random((500, 3))
    rows = rng.permutation(500)[:200]
    ref[rows[0]] = [0.0, -0.0, 1.0]
    query = ref[rows].copy()
    query[0] = [-0.0, 0.0, 1.0]
    assert np.array_equal(same_points(ref, query, 1e-8), rows)
    assert np.array_equal(same_points(ref, query + 1e-12, 1e-8), rows)
    query[5] += 1e-3
    found = same_points(ref, query, 1e-8)
    assert found[5] == -1 and np.array_equal(np.delete(found, 5), np.delete(rows, 5))
    assert np.array_equal(same_points(np.zeros((0, 3)), query[:2], 1e-8), [-1, -1])
