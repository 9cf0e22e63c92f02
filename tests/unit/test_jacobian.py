"""Jacobian of the heat operator (mass, advection, conduction, SUPG incl. the
P2 Laplacian term, Neumann and Robin facets) against finite differences."""
import dataclasses

import numpy as np
import pytest
from petsc4py import PETSc

from petthm.discretisation.fields import Discretisation
from petthm.discretisation.model import MATRIX, CellJacobian
from petthm.discretisation.problem import Problem
from petthm.run.driver import Run, make_scene
from petthm.verification.jacobian import jacobian_fd_error


def _heat_problem(tmp_path, dim, degree, **opts):
    from conftest import build_problem
    return build_problem(tmp_path, "heat_mms", thm_mms_dim=dim, thm_fe_degree=degree,
                         thm_mesh_size=0.5 if dim == 3 else 0.25, **opts)


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("degree", [1, 2])
def test_heat_jacobian_matches_finite_differences(tmp_path, dim, degree):
    # strong advection so that the SUPG terms dominate the Jacobian
    problem = _heat_problem(tmp_path, dim, degree, thm_rock_conductivity=0.01,
                            thm_mms_velocity="3,2,1")
    assert problem.model.facets, "Neumann/Robin terms must be part of the check"
    err = jacobian_fd_error(problem, t=0.3, shift=4.0)
    print("jacobian fd error", dim, degree, err)
    assert err <= 1e-6, err


def test_jacobian_check_detects_a_missing_term(tmp_path):
    """Negative control: dropping the consistent SUPG Laplacian block must fail."""
    problem = _heat_problem(tmp_path, 2, 2, thm_rock_conductivity=0.5, thm_mms_velocity="3,2")
    terms = problem.region(MATRIX).model.jacobians          # the matrix assembler's term table
    jb = terms[0]
    assert jb.g2_lap is not None
    terms[0] = dataclasses.replace(jb, g2_lap=None)
    err = jacobian_fd_error(problem, t=0.3, shift=4.0)
    print("jacobian fd error without g2_lap", err)
    assert err > 1e-4, err


def test_heat_jacobian_without_advection(tmp_path):
    """Cell-constant coefficients take the weighted reference-tensor path."""
    o = PETSc.Options()
    for k in list(o.getAll()):
        o.delValue(k)
    o.setValue("thm_output_dir", str(tmp_path))
    o.setValue("thm_mesh_size", 2.0)
    run = Run(make_scene("heat_erfc"))
    _, problem, *_ = run.setup(run.build_mesh())
    assert problem.model.jacobians[0].g1 is None
    err = jacobian_fd_error(problem, t=10.0, shift=0.1)
    print("jacobian fd error (conduction only)", err)
    assert err <= 1e-6


def _vector_problem(tmp_path, constant: bool):
    """3-component elasticity-like operator on a small 3D box (vector path of the assembly)."""
    from petthm.discretisation.assembly import FieldScale
    from petthm.discretisation.fields import FieldSpec
    from petthm.discretisation.model import CellResidual, Model
    from petthm.mesh import generate as meshing
    from petthm.mesh.plex import Mesh, distribute, read_plex
    path = str(tmp_path / "box.msh")
    meshing.box(path, [1.0, 1.0, 1.0], 0.5)
    mesh = Mesh(distribute(read_plex(path, PETSc.COMM_WORLD)))
    lam, mu = 2.0, 1.5
    I = np.eye(3)
    C = lam * np.einsum("ae,bf->aebf", I, I) + mu * (np.einsum("ab,ef->aebf", I, I)
                                                     + np.einsum("af,eb->aebf", I, I))

    def f0(ctx):
        return 3.0 * ctx.dot("u") + 0.5 * ctx.value("u") ** 3

    def f1(ctx):
        G = ctx.grad("u")
        eps = 0.5 * (G + np.swapaxes(G, 2, 3))
        return 2 * mu * eps + lam * np.trace(eps, axis1=2, axis2=3)[..., None, None] * I

    def g0(ctx):
        return 3.0 * ctx.shift * I + 1.5 * ctx.value("u")[..., :, None] ** 2 * I

    def g3(ctx):
        return C[None, None] if constant else np.broadcast_to(C, ctx.shape + C.shape).copy()

    model = Model([FieldSpec("u", 3, 2)], [CellResidual("u", f0, f1)],
                  [CellJacobian("u", "u", g0=g0, g3=g3)])
    disc = Discretisation(mesh, model.fields, {})
    return Problem(disc, model, {"u": FieldScale()}, [])


@pytest.mark.parametrize("constant", [True, False])
def test_vector_jacobian_matches_finite_differences(tmp_path, constant):
    problem = _vector_problem(tmp_path, constant)
    err = jacobian_fd_error(problem, t=0.0, shift=2.0)
    print("vector jacobian fd error", constant, err)
    assert err <= 1e-6


def test_cell_constant_and_pointwise_coefficients_give_the_same_matrix(tmp_path):
    vals = []
    for constant in (True, False):
        p = _vector_problem(tmp_path, constant)
        xl = np.linspace(-1, 1, p.disc.nlocal)
        vals.append(p.region(MATRIX).jacobian_values(xl, xl, 0.0, 2.0))
    assert np.allclose(vals[0], vals[1], rtol=1e-12, atol=1e-12 * np.abs(vals[1]).max())


def _split_vector_problem(tmp_path, declared_constant: str):
    """The vector operator with its state-dependent g0 and its constant g3 as
    two terms; ``declared_constant`` names the term declared ``constant``."""
    p = _vector_problem(tmp_path, constant=True)
    jb = p.region(MATRIX).model.jacobians[0]
    terms = [dataclasses.replace(jb, g3=None, constant=declared_constant == "g0"),
             dataclasses.replace(jb, g0=None, constant=declared_constant == "g3")]
    p.model.jacobians[:] = terms
    p.region(MATRIX).model.jacobians[:] = terms
    p.region(MATRIX).build_pattern()
    return p


@pytest.mark.parametrize("declared_constant", ["g3", "g0"])
def test_constant_terms_are_assembled_once(tmp_path, declared_constant):
    """``Problem`` keeps the values of the ``constant`` terms (elasticity) in
    its Jacobian buffer: a re-assembly at another state, and one after the
    residual scaling changed, give what a fresh problem assembles.  Negative
    control: a state-dependent term (g0) declared constant is caught."""
    p = _split_vector_problem(tmp_path, declared_constant)
    n = p.disc.nlocal
    xa, xb = np.linspace(-1, 1, n), np.cos(np.arange(n))
    p.jacobian_values(xa, xa, 0.0, 2.0)

    def fresh(x, rscale=1.0):
        q = _split_vector_problem(tmp_path, declared_constant)
        q.scales["u"].rscale = rscale
        q._update_row_scales()
        return q.jacobian_values(x, x, 0.0, 2.0).copy()

    kept = p.jacobian_values(xb, xb, 0.0, 2.0).copy()
    p.scales["u"].rscale = 3.0
    p._update_row_scales()
    p.jacobian_values(xa, xa, 0.0, 2.0)
    rescaled = p.jacobian_values(xb, xb, 0.0, 2.0).copy()
    diff = [np.abs(kept - fresh(xb)).max(), np.abs(rescaled - fresh(xb, 3.0)).max()]
    scale = np.abs(kept).max()
    print("kept constant terms", declared_constant, diff, scale)
    if declared_constant == "g3":
        assert max(diff) <= 1e-14 * scale
    else:
        assert min(diff) > 1e-6 * scale
