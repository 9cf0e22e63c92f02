"""Model builders (petthm.physics.builders): a coupled model composed with no scene
code; the thermo-mechanical heating of physics.md section 6 switched on in
a Biot (u, pm, Tm) model by the option alone, its blocks exact."""
import numpy as np
import pytest
from petsc4py import PETSc

from petthm import params
from petthm.discretisation.assembly import FieldScale
from petthm.discretisation.constraints import Dirichlet, boundary_entries
from petthm.discretisation.fields import Discretisation
from petthm.discretisation.model import MATRIX
from petthm.discretisation.problem import Problem
from petthm.mesh import generate as meshing
from petthm.mesh.plex import Mesh, distribute, label_boundaries, read_plex
from petthm.physics import materials as mt
from petthm.physics.builders import ModelBuilder
from petthm.verification.jacobian import jacobian_fd_block_errors

THM_ROCK = mt.group("Thermo-poro-elastic rock", mt.ELASTIC + mt.ROCK_HEAT + mt.FLUID_HEAT + mt.FLUID_FLOW + (
    "rock_biot_coefficient", "rock_porosity", "rock_permeability", "rock_thermal_expansion",
    "initial_temperature", "thermomechanical_heating", *mt.HEAT_DISCRETISATION), rock_porosity=0.2,
    rock_permeability=(1e-13,))


def _parameters(heating: bool, scheme: str, water: bool = False):
    opts = PETSc.Options()
    for k in list(opts.getAll()):
        opts.delValue(k)
    opts.setValue("thm_thermomechanical_heating", "1" if heating else "0")
    opts.setValue("thm_heat_transport", scheme)
    if water:
        opts.setValue("thm_fluid_viscosity", "water")
    return params.read_all([THM_ROCK], base=mt.Parameters)


def biot_thm_problem(tmp_path, heating: bool, scheme: str = "auto", deck: bool = False) -> Problem:
    """u, pm, Tm on a square: elasticity with Biot and thermal strain, Darcy
    flow with mu(T)-free mobility, advection-conduction of Tm by ``scheme``
    (-thm_heat_transport).  ``deck``: as a deck builds it, with gravity in
    Darcy's law, mu(T) of water, and the in-situ pressure and temperature
    functions of position."""
    mesh = square_mesh(tmp_path)
    p = _parameters(heating, scheme, water=deck)
    b = ModelBuilder(p, 2)
    refs = dict(p_ref=lambda x: 1e4 * (10 - x[:, 1]),
                T_ref=lambda x: p.T0 + 0.5 * (10 - x[:, 1])) if deck else {}
    b.elasticity(2, biot=True, thermal=True, **refs)
    b.matrix_flow(1, permeability=p.permeability(2), storage=p.storage,
                  thermal_storage=p.rock_porosity * p.fluid_thermal_expansion, heat=True,
                  gravity=(0.0, -1000.0 * 9.81) if deck else ())
    b.matrix_heat(1)
    return held_at_the_bottom(mesh, b.build(), p)


def square_mesh(tmp_path) -> Mesh:
    """A 10 m square of 2.5 m cells, its bottom labelled."""
    path = meshing.box(str(tmp_path / "square.msh"), [10.0, 10.0], 2.5)
    dm = read_plex(path, PETSc.COMM_WORLD)
    label_boundaries(dm, {"bottom": lambda x: np.isclose(x[:, 1], 0.0)})
    return Mesh(distribute(dm))


def held_at_the_bottom(mesh, model, p) -> Problem:
    """The u, pm, Tm problem of ``model`` with u = 0, pm = 0 and Tm = T0 on the bottom, at T0."""
    bcs = [Dirichlet("u", "bottom", lambda x, t: np.zeros((len(x), 2))),
           Dirichlet("pm", "bottom", lambda x, t: np.zeros(len(x))),
           Dirichlet("Tm", "bottom", lambda x, t: np.full(len(x), p.T0))]
    disc = Discretisation(mesh, model.fields, boundary_entries(bcs))
    scales = {"u": FieldScale(1e-3), "pm": FieldScale(1e6), "Tm": FieldScale(50.0, p.T0)}
    problem = Problem(disc, model, scales, bcs)
    problem.set_initial({"Tm": lambda x: np.full(len(x), p.T0)})
    problem.auto_residual_scales(0.0, 1.0)
    return problem


def _blocks(problem):
    """How many registered Jacobian blocks each (test, trial) pair of Tm rows has."""
    from collections import Counter
    return Counter((str(j.test),
                    str(j.trial)) for j in problem.region(MATRIX).model.jacobians if j.test == "Tm")


@pytest.mark.parametrize("scheme", ["supg", "limited"])
def test_heating_is_switched_on_by_the_option_alone(tmp_path, scheme):
    """With -thm_thermomechanical_heating the builder adds the blocks of
    section 6 (Tm-u: strain heating, Tm-pm: pore fluid, Tm-Tm: T times both
    rates) to those of heat transport; without it, none.  With SUPG heat
    transport's own Tm-u block is SUPG's alpha d(div u)/dt (the T div b of
    its residual)."""
    on, off = (_blocks(biot_thm_problem(tmp_path / name, heating, scheme))
               for name, heating in (("on", True), ("off", False)))
    print(on, off)
    assert on[("Tm", "u")] == off[("Tm", "u")] + 1
    assert on[("Tm", "pm")] == off[("Tm", "pm")] + 1 and on[("Tm", "Tm")] == off[("Tm", "Tm")] + 1
    if scheme == "supg":
        assert off[("Tm", "u")] == 1


@pytest.mark.parametrize("scheme", ["supg", "limited"])
@pytest.mark.parametrize("heating", [True, False])
def test_biot_thm_blocks_match_finite_differences(tmp_path, heating, scheme):
    """Every coupling block of the composed u-pm-Tm model against finite
    differences; negative control: the heating residual without its blocks fails."""
    problem = biot_thm_problem(tmp_path, heating, scheme)
    errs = jacobian_fd_block_errors(problem, t=10.0, shift=0.1, eps=(1e-6, 1e-4))
    print({k: f"{v:.1e}" for k, v in errs.items()})
    assert max(errs.values()) <= 1e-6, errs
    if heating:
        asm = problem.region(MATRIX)
        asm.model.jacobians[:] = [j for j in asm.model.jacobians if not (j.test == "Tm" and j.trial == "u")]
        asm.build_pattern()
        problem.J = None
        errs = jacobian_fd_block_errors(problem, t=10.0, shift=0.1, eps=(1e-6, 1e-4))
        assert errs[("Tm", "u")] > 1e-3, errs


def test_the_blocks_of_a_deck_with_gravity_match_finite_differences(tmp_path):
    """Gravity in Darcy's law with mu(T) (the pm-Tm block carries rho_f g)
    and in-situ references that vary with position; rates small enough that
    the step's start keeps water liquid (mu(T)).  Negative control: the
    pm-Tm block of the same flow without gravity fails."""
    import dataclasses
    from functools import partial

    from petthm.physics.kernels import flow as fk
    problem = biot_thm_problem(tmp_path, False, "limited", deck=True)
    errs = jacobian_fd_block_errors(problem, t=10.0, shift=0.1, eps=(1e-6, 1e-4), rate=0.01)
    assert max(errs.values()) <= 1e-6, errs
    asm = problem.region(MATRIX)
    jac = asm.model.jacobians
    k = next(i for i, j in enumerate(jac) if j.test == "pm" and j.trial == "Tm")
    flow = jac[k].g2.args[0]
    assert flow.gravity
    jac[k] = dataclasses.replace(jac[k], g2=partial(fk.flow_g2_pT, dataclasses.replace(flow, gravity=())))
    asm.build_pattern()
    problem.J = None
    errs = jacobian_fd_block_errors(problem, t=10.0, shift=0.1, eps=(1e-6, 1e-4), rate=0.01)
    assert errs[("pm", "Tm")] > 1e-3, errs
