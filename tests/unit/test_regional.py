"""Rock properties per region (petthm.physics.kernels.regional): every
coupling block of the u-pm-Tm model on a rock of two regions whose every
property differs is exact (finite differences, with a negative control),
and a rock of two regions with the same values assembles exactly what one
rock does, over cells of the two regions interleaved (batches of index
arrays)."""
import dataclasses
from functools import partial

import numpy as np
import pytest
from petsc4py import PETSc
from test_builders import held_at_the_bottom, square_mesh

from petthm import params
from petthm.discretisation.model import MATRIX
from petthm.discretisation.problem import Problem
from petthm.physics import materials as mt
from petthm.physics.builders import ModelBuilder
from petthm.physics.kernels import poroelastic as pe
from petthm.physics.kernels.regional import Regional, at, per_region
from petthm.verification.jacobian import jacobian_fd_block_errors

ROCK = mt.group("Rock", mt.ELASTIC + mt.ROCK_HEAT + mt.FLUID_HEAT + mt.FLUID_FLOW + (
    "rock_biot_coefficient", "rock_porosity", "rock_permeability", "rock_thermal_expansion",
    "initial_temperature", "thermomechanical_heating", *mt.HEAT_DISCRETISATION), rock_porosity=0.2,
    rock_permeability=(1e-13,))

#: a second rock whose every property differs from the first's
OTHER = dict(rock_youngs_modulus=8e9, rock_poisson_ratio=0.3, rock_biot_coefficient=0.6,
             rock_porosity=0.05, rock_permeability=(3e-14, 1e-14, 5e-15), rock_thermal_expansion=4e-5,
             rock_density=2400.0, rock_heat_capacity=1000.0, rock_conductivity=1.5)


def _parameters(heating: bool, scheme: str):
    opts = PETSc.Options()
    for k in list(opts.getAll()):
        opts.delValue(k)
    opts.setValue("thm_thermomechanical_heating", "1" if heating else "0")
    opts.setValue("thm_heat_transport", scheme)
    return params.read_all([ROCK], base=mt.Parameters)


def two_rock_problem(tmp_path, heating: bool, scheme: str, other: dict, interleaved: bool = True) -> Problem:
    """u, pm, Tm on a square of two rocks: the cells alternate between them
    (``interleaved``) or split at x = 5; the second rock's parameters are the
    first's with ``other``."""
    mesh = square_mesh(tmp_path)
    p = _parameters(heating, scheme)
    rocks = (p, dataclasses.replace(p, **other))
    b = ModelBuilder(p, 2, rocks)
    b.elasticity(2, biot=True, thermal=True)
    b.matrix_flow(1, permeability=b.rock(lambda q: q.permeability(2)), storage=b.rock(lambda q: q.storage),
                  thermal_storage=b.rock(lambda q: q.rock_porosity * q.fluid_thermal_expansion), heat=True)
    b.matrix_heat(1)
    model = b.build()
    centroids = mesh.vertex_coords[mesh.cell_vertices].mean(axis=1)
    model.cell_regions = (np.arange(mesh.ncells) % 2 if interleaved else (centroids[:, 0] > 5).astype(int))
    return held_at_the_bottom(mesh, model, p)


@pytest.mark.parametrize("scheme", ["supg", "limited"])
@pytest.mark.parametrize("heating", [True, False])
def test_the_blocks_of_a_rock_of_two_regions_match_finite_differences(tmp_path, heating, scheme):
    """Every block exact where E, nu, alpha, phi, k (anisotropic), beta_s,
    rho_s, C_s and lambda_s differ between the regions.  Negative control:
    the u-u block with the first region's moduli on every cell fails."""
    problem = two_rock_problem(tmp_path, heating, scheme, OTHER)
    errs = jacobian_fd_block_errors(problem, t=10.0, shift=0.1, eps=(1e-6, 1e-4))
    print({k: f"{v:.1e}" for k, v in errs.items()})
    assert max(errs.values()) <= 1e-6, errs
    asm = problem.region(MATRIX)
    jac = asm.model.jacobians
    k = next(i for i, j in enumerate(jac) if j.test == "u" and j.trial == "u")
    elastic = jac[k].g3.obj
    assert isinstance(elastic.youngs_modulus, Regional)
    first = at(elastic, type("Batch", (), {"region": 0})())
    jac[k] = dataclasses.replace(jac[k], g3=partial(pe._g3_uu, first))
    asm.build_pattern()
    problem.J = None
    errs = jacobian_fd_block_errors(problem, t=10.0, shift=0.1, eps=(1e-6, 1e-4))
    assert errs[("u", "u")] > 1e-3, errs


def _residual_and_jacobian(problem):
    X = problem.X.duplicate()
    problem.X.copy(X)
    rng = np.random.default_rng(1)
    X.getArray()[:] += 0.1 * rng.standard_normal(X.getLocalSize())
    Xdot = X.duplicate()
    Xdot.getArray()[:] = 0.01 * rng.standard_normal(X.getLocalSize())
    F = X.duplicate()
    problem.ifunction(None, 10.0, X, Xdot, F)
    J = problem.create_matrix()
    problem.ijacobian(None, 10.0, X, Xdot, 0.1, J, J)
    return F.getArray().copy(), J


@pytest.mark.parametrize("interleaved", [True, False])
def test_two_regions_of_the_same_rock_assemble_what_one_rock_does(tmp_path, interleaved):
    """Same residual and Jacobian, to round-off, as the uniform rock, with
    the batches of each region index arrays (cells interleaved) or slices;
    the values are given per region (Regional with equal entries), so the
    regional path runs.  Negative control: the second region's Young's
    modulus 1 % larger changes the residual."""
    uniform = two_rock_problem(tmp_path / "uniform", True, "limited", {}, interleaved)
    F0, J0 = _residual_and_jacobian(uniform)
    regional_problem = _forced_regional(tmp_path / "forced", interleaved, scale=1.0)
    F1, J1 = _residual_and_jacobian(regional_problem)
    assert np.abs(F1 - F0).max() <= 1e-12 * np.abs(F0).max()
    J1.axpy(-1.0, J0)
    assert J1.norm() <= 1e-12 * J0.norm()
    F2, _ = _residual_and_jacobian(_forced_regional(tmp_path / "stiffer", interleaved, scale=1.01))
    assert np.abs(F2 - F0).max() > 1e-6 * np.abs(F0).max()


def _forced_regional(tmp_path, interleaved, scale):
    """The uniform two-rock problem with its Young's modulus a Regional of
    (E, scale E): the regional kernels on every cell."""
    import petthm.physics.builders as builders
    original = builders.per_region

    def regional_always(values):
        values = tuple(values)
        return Regional(values) if np.ndim(values[0]) == 0 else original(values)
    builders.per_region = regional_always
    try:
        E = _parameters(True, "limited").rock_youngs_modulus
        return two_rock_problem(tmp_path, True, "limited", {"rock_youngs_modulus": scale * E}, interleaved)
    finally:
        builders.per_region = original


def test_per_region_is_a_number_where_the_regions_agree():
    """One value where every region has it (a uniform rock computes as
    before); a Regional, whose truth is whether any value is not zero,
    where they differ."""
    assert per_region([2.0, 2.0]) == 2.0
    K = per_region([np.eye(2), np.eye(2)])
    assert isinstance(K, np.ndarray)
    r = per_region([0.0, 1.0])
    assert isinstance(r, Regional) and r and not per_region([0.0, 0.0]) and r[1] == 1.0
