"""Fields on the fracture surface (the - faces of the cohesive cells):
section, element arrays and surface assembly with tangential gradients."""
import numpy as np
import pytest
from petsc4py import PETSc

from petthm import fracture as F, meshing as M
from petthm.assembly import Assembler, FieldScale
from petthm.fields import Discretisation, FieldSpec
from petthm.mesh import Mesh, distribute, label_boundaries, read_plex
from petthm.model import CellJacobian, CellResidual, Model
from petthm.solver import Dirichlet, Problem


def _fracture_problem(path, dim, degree, exact, source=0.0):
    """Steady surface Laplace problem for pf with Dirichlet data at both ends."""
    dm = read_plex(str(path), PETSc.COMM_WORLD)
    label_boundaries(dm, {"x0": lambda x: np.isclose(x[:, 0], 0.0), "x1": lambda x: np.isclose(x[:, 0], 1.0)})
    dm, _ = F.split_fractures(dm)
    mesh = Mesh(distribute(dm))
    surf = F.FractureSurface(mesh)
    k = 2.5

    def f1(ctx):
        return k * ctx.grad("pf")

    def f0(ctx):
        return np.full(ctx.shape + (1,), k * source)      # -div(k grad p) + k s = 0

    def g3(ctx):
        return (k * np.eye(dim))[None, None, None, :, None, :]
    model = Model([FieldSpec("pf", 1, degree, region="fracture")], [CellResidual("pf", f0, f1)],
                  [CellJacobian("pf", "pf", g3=g3)])
    disc = Discretisation(mesh, model.fields, {"pf": ["x0", "x1"]}, regions={"fracture": surf})
    bcs = [Dirichlet("pf", b, lambda x, t: exact(x)) for b in ("x0", "x1")]
    return Problem(disc, model, {"pf": FieldScale(1.0)}, bcs, region=surf), surf


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
    J = problem.create_matrix()
    problem.ijacobian(None, 0.0, problem.X, problem.X, 0.0, J, J)
    F_ = problem.X.duplicate()
    problem.ifunction(None, 0.0, problem.X, problem.X.duplicate(), F_)
    ksp = PETSc.KSP().create()
    ksp.setOperators(J)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    dx = problem.X.duplicate()
    ksp.solve(F_, dx)
    problem.X.axpy(-1.0, dx)
    p = problem.field_values("pf")[:, 0]
    x = problem.disc.field_node_coordinates("pf")
    err = np.abs(p - exact(x)).max() / np.abs(exact(x)).max()
    print(f"{kind} {dim}D P{degree}: fracture nodes {len(p)}, max relative error {err:.1e}")
    assert len(p) > 0 and err <= 1e-10
