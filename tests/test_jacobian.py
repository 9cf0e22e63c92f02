"""Jacobian of the heat operator (mass, advection, conduction, SUPG incl. the
P2 Laplacian term, Neumann and Robin facets) against finite differences."""
import dataclasses

import numpy as np
import pytest
from petsc4py import PETSc

from petthm import params as P
from petthm.app import Run, make_scene
from petthm.fields import Discretisation
from petthm.model import CellJacobian
from petthm.solver import Problem
from petthm.verify import jacobian_fd_error


def _heat_problem(tmp_path, dim, degree, **opts):
    o = PETSc.Options()
    for k in list(o.getAll()):
        o.delValue(k)
    o.setValue("thm_mms_dim", dim)
    o.setValue("thm_fe_degree", degree)
    o.setValue("thm_mesh_size", 0.5 if dim == 3 else 0.25)
    o.setValue("thm_output_dir", str(tmp_path))
    for k, v in opts.items():
        o.setValue(k, v)
    scene = make_scene("heat_mms")
    run = Run(scene)
    mesh = run.build_mesh()
    disc, problem, control, _ = run.setup(mesh)
    return problem


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
    jb = problem.model.jacobians[0]
    assert jb.g2_lap is not None
    problem.model.jacobians[0] = dataclasses.replace(jb, g2_lap=None)
    err = jacobian_fd_error(problem, t=0.3, shift=4.0)
    print("jacobian fd error without g2_lap", err)
    assert err > 1e-4, err
