"""The direct solve petthm proposes: PETSc's own LU for serial 2D runs
without bounded unknowns, MUMPS (or SuperLU_dist) otherwise
(``solver.serial_plane_direct``; measured in docs/performance/index.md)."""
import pytest

from petthm.solvers.options import serial_plane_direct

MUMPS = {"ksp_type": "gmres", "ksp_max_it": "50", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}


def test_a_serial_2d_run_gets_petsc_lu():
    out = serial_plane_direct(MUMPS, dim=2, ranks=1, bounded=False)
    assert out["pc_factor_mat_solver_type"] == "petsc"
    assert out["pc_factor_shift_type"] == "nonzero"
    assert {k: v for k, v in out.items() if not k.startswith("pc_factor")} == \
        {k: v for k, v in MUMPS.items() if not k.startswith("pc_factor")}


@pytest.mark.parametrize("dim, ranks, bounded", [(3, 1, False), (2, 2, False), (2, 1, True)])
def test_3d_parallel_and_contact_runs_keep_mumps(dim, ranks, bounded):
    assert serial_plane_direct(MUMPS, dim=dim, ranks=ranks, bounded=bounded) == MUMPS


def test_an_iterative_default_is_left_alone():
    gamg = {"ksp_type": "gmres", "pc_type": "gamg"}
    assert serial_plane_direct(gamg, dim=2, ranks=1, bounded=False) == gamg
