"""The null-space preconditioner of the closed contact (petthm.solvers.contactpc):
its Krylov count does not grow with the crack mesh when the glued
elasticity is solved exactly, and stays small with one GAMG V-cycle."""
import numpy as np
import pytest
from petsc4py import PETSc

from conftest import build_problem
from petthm.solvers.contactpc import ContactNullspacePC
from petthm.solvers.fieldsplit import SolverContext, serve


def closed_jacobian(tmp_path, crack_size):
    """partial_opening (P1 u) at t = 0: every crack node closed."""
    problem = build_problem(tmp_path, "partial_opening", thm_partial_crack_size=crack_size, thm_fe_degree=1)
    J = problem.create_matrix()
    Xdot = problem.X.duplicate()
    Xdot.set(0.0)
    problem.ijacobian(None, 0.05, problem.X, Xdot, 10.0, J, J)
    return problem, J


def fgmres_iterations(J, context, pc_class=ContactNullspacePC, max_it=300):
    """FGMRES iterations to 1e-8 on a random right side (inf: no convergence)."""
    ksp = PETSc.KSP().create()
    ksp.setOperators(J)
    ksp.setType("fgmres")
    ksp.setGMRESRestart(300)
    ksp.setTolerances(rtol=1e-8, max_it=max_it)
    pc = ksp.getPC()
    pc.setType("python")
    pc.setPythonContext(pc_class())
    serve(pc, context)
    b = J.createVecLeft()
    b.setRandom()
    x = b.duplicate()
    ksp.solve(b, x)
    its = ksp.getIterationNumber() if ksp.getConvergedReason() > 0 else np.inf
    ksp.destroy()
    return its


def _iterations(tmp_path, crack_size, inner):
    problem, J = closed_jacobian(tmp_path, crack_size)
    context = SolverContext(problem)
    opts = PETSc.Options()
    opts["contact_pc_type"] = inner
    try:
        return fgmres_iterations(J, context)
    finally:
        del opts["contact_pc_type"]
        context.destroy()


@pytest.mark.parametrize("inner,limit", [("lu", 20), ("gamg", 40)])
def test_contact_nullspace_pc_is_mesh_independent(tmp_path, inner, limit):
    its = [_iterations(tmp_path / f"h{k}", h, inner) for k, h in enumerate((0.05, 0.0125))]
    print(inner, "FGMRES iterations over crack sizes c/20, c/80:", its)
    assert max(its) <= limit
    if inner == "lu":
        assert its[1] <= its[0] + 2                  # exact glued solve: the count does not grow


def test_the_pc_needs_its_lam_recovery(tmp_path):
    """Negative control: with lam taken as 0 instead of the glue force the
    preconditioner is far worse."""
    class NoLam(ContactNullspacePC):
        def apply(self, pc, x, y):
            super().apply(pc, x, y)
            sub = y.getSubVector(self.maps.ilam)
            sub.set(0.0)
            y.restoreSubVector(self.maps.ilam, sub)
    problem, J = closed_jacobian(tmp_path, 0.05)
    context = SolverContext(problem)
    its = fgmres_iterations(J, context, NoLam, max_it=200)
    context.destroy()
    assert its > 40, its


def sticking_jacobian(tmp_path):
    """friction_patch 3D (P1 u) at t = 0: every node closed and sticking."""
    problem = build_problem(tmp_path, "friction_patch", thm_friction_dim=3, thm_fe_degree=1)
    J = problem.create_matrix()
    Xdot = problem.X.duplicate()
    Xdot.set(0.0)
    problem.ijacobian(None, 0.05, problem.X, Xdot, 10.0, J, J)
    return problem, J


@pytest.mark.parametrize("inner,limit", [("lu", 2), ("gamg", 40)])
def test_sticking_nodes_are_glued_whole(tmp_path, inner, limit):
    """Friction (issue 13): a closed sticking node's lam and tau rows glue
    its two copies in every direction (u+ = u-), so with an exact glued
    solve the preconditioner is the exact null-space method (measured: 1
    FGMRES iteration; one GAMG V-cycle: within ``limit``)."""
    problem, J = sticking_jacobian(tmp_path)
    context = SolverContext(problem)
    opts = PETSc.Options()
    opts["contact_pc_type"] = inner
    try:
        its = fgmres_iterations(J, context)
    finally:
        del opts["contact_pc_type"]
        context.destroy()
    print(inner, "FGMRES iterations", its)
    assert its <= limit


def test_the_pc_needs_the_tangential_glue(tmp_path, monkeypatch):
    """Negative control: with the sticking tau rows eliminated instead of
    glued (as the open rows are) the exact-solve count is far worse."""
    import petthm.solvers.contactpc as contactpc
    original = contactpc.glue_maps

    def normal_glue_only(K, structure, rows):
        maps = original(K, structure, rows)
        maps.glued.getArray()[maps.kind > 0] = 0.0
        return maps
    monkeypatch.setattr(contactpc, "glue_maps", normal_glue_only)
    problem, J = sticking_jacobian(tmp_path)
    context = SolverContext(problem)
    opts = PETSc.Options()
    opts["contact_pc_type"] = "lu"
    try:
        its = fgmres_iterations(J, context, max_it=100)
    finally:
        del opts["contact_pc_type"]
        context.destroy()
    print("FGMRES iterations without the tangential glue", its)
    assert its > 20


def test_the_glue_products_equal_those_with_the_whole_elasticity(tmp_path):
    """The apply's two products with the elasticity A are formed once at the
    set-up on the fracture's unknowns alone (A P^T and P A): they give A (P^T s)
    and P (A u) for any s, u; the PC keeps no copy of the whole A."""
    problem, J = closed_jacobian(tmp_path, 0.05)
    context = SolverContext(problem)
    pc = PETSc.PC().create()
    pc.setOperators(J)
    pc.setType("python")
    ctx = ContactNullspacePC()
    pc.setPythonContext(ctx)
    serve(pc, context)
    pc.setUp()
    m = ctx.maps
    assert not np.any(m.glued.getArray(readonly=True) == 0.0)      # closed: nothing eliminated, A = K_uu
    A = J.createSubMatrix(m.iu, m.iu)
    s, u = m.b.duplicate(), A.createVecRight()
    s.setRandom()
    u.setRandom()
    up, whole, part = A.createVecRight(), A.createVecLeft(), A.createVecLeft()
    m.pt.multTranspose(s, up)
    A.mult(up, whole)
    ctx.A_pt.mult(s, part)
    scale = whole.norm(PETSc.NormType.INFINITY)
    assert np.allclose(part.getArray(), whole.getArray(), rtol=0, atol=1e-12 * scale)
    Au, lam_whole, lam_part = A.createVecLeft(), m.b.duplicate(), m.b.duplicate()
    A.mult(u, Au)
    m.pt.mult(Au, lam_whole)
    ctx.pt_A.mult(u, lam_part)
    scale = lam_whole.norm(PETSc.NormType.INFINITY)
    assert scale > 0
    assert np.allclose(lam_part.getArray(), lam_whole.getArray(), rtol=0, atol=1e-12 * scale)
    assert not hasattr(ctx, "A")
    pc.destroy()
    context.destroy()
