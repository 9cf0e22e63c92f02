"""Wells with one bottom-hole pressure (petthm.physics.linewells) as node
sets (petthm.discretisation.nodesets): every block exact against finite
differences under rate and pressure control, with a negative control; the
rate of a rate-controlled well splits by the nodes' indices and heads."""
import dataclasses

import numpy as np
import pytest
from test_builders import _parameters, held_at_the_bottom, square_mesh

from petthm.discretisation.model import NodeSetTerm
from petthm.physics.builders import ModelBuilder
from petthm.physics.linewells import LineWell, Schedule, state, well_term
from petthm.verification.jacobian import jacobian_fd_block_errors


def interior_vertices(mesh, n: int = 3) -> np.ndarray:
    """``n`` vertices of the square's interior (the same on every rank: the lowest by a fixed order)."""
    x = mesh.vertex_coords
    inside = x[(np.min(x, axis=1) > 1.0) & (np.max(x, axis=1) < 9.0)]
    order = np.lexsort(inside.T[::-1])
    return inside[order[:n]]


def well(points, control: str, T0: float, rho_c: float) -> LineWell:
    kw = {"rate": Schedule((0.0,), (2e-4,))} if control == "rate" else {"pressure": Schedule((0.0,), (3e5,))}
    return LineWell("w", points, index=np.array([1e-9, 2e-9, 4e-9]), head=np.array([0.0, 1e4, 3e4]),
                    temperature=T0 - 30.0, rho_c=rho_c, **kw)


def well_problem(tmp_path, control: str, term=None):
    """u, pm, Tm on the square (as test_builders) with a well of three nodes."""
    mesh = square_mesh(tmp_path)
    p = _parameters(False, "limited", water=True)
    b = ModelBuilder(p, 2)
    b.elasticity(2, biot=True, thermal=True)
    b.matrix_flow(1, permeability=p.permeability(2), storage=p.storage,
                  thermal_storage=p.rock_porosity * p.fluid_thermal_expansion, heat=True)
    b.matrix_heat(1)
    w = well(interior_vertices(mesh), control, p.T0, p.fluid_rho_c)
    b.model.node_sets.append(term or well_term(w))
    return held_at_the_bottom(mesh, b.build(), p), w


@pytest.mark.parametrize("control", ["rate", "pressure"])
def test_the_blocks_of_a_well_match_finite_differences(tmp_path, control):
    """pm-pm (dense under rate control: the eliminated bottom-hole
    pressure), Tm-pm and Tm-Tm, at a state where some nodes inject and
    others may produce.  Negative controls: the rate well's pm-pm block
    without the coupling between its nodes fails, and so does the Tm-pm
    block left out."""
    problem, w = well_problem(tmp_path, control)
    errs = jacobian_fd_block_errors(problem, t=10.0, shift=0.1, eps=(1e-6, 1e-4), rate=0.01)
    print({k: f"{v:.1e}" for k, v in errs.items()})
    assert max(errs.values()) <= 1e-6, errs
    if control == "rate":
        term = well_term(w)

        def diagonal_only(ctx):
            jac = term.jacobian(ctx)
            keep = np.zeros_like(jac[("pm", "pm")])
            keep[np.arange(len(ctx.owned)), ctx.owned] = 1.0
            return {**jac, ("pm", "pm"): jac[("pm", "pm")] * keep}
        cut, _ = well_problem(tmp_path / "cut", control, dataclasses.replace(term, jacobian=diagonal_only))
        errs = jacobian_fd_block_errors(cut, t=10.0, shift=0.1, eps=(1e-6, 1e-4), rate=0.01)
        assert errs[("pm", "pm")] > 1e-3, errs

        def without_heat_by_pressure(ctx):
            jac = term.jacobian(ctx)
            return {**jac, ("Tm", "pm"): 0.0 * jac[("Tm", "pm")]}
        cut, _ = well_problem(tmp_path / "cut2", control,
                              dataclasses.replace(term, jacobian=without_heat_by_pressure))
        errs = jacobian_fd_block_errors(cut, t=10.0, shift=0.1, eps=(1e-6, 1e-4), rate=0.01)
        assert errs[("Tm", "pm")] > 1e-3, errs


def test_a_rate_splits_by_index_and_head(tmp_path):
    """At a uniform rock pressure the node rates are PI_k (p_w + h_k - p)
    with p_w such that they sum to Q: with these indices and heads, exactly
    the split computed here by hand."""
    problem, w = well_problem(tmp_path, "rate")
    ns = problem.node_sets[0]
    xl, _ = problem.local_arrays(problem.X, 0.0)
    ctx = ns.context(xl, 0.0, problem.scales)
    s = state(w, ctx)
    p = float(ctx.values["pm"][0]) if len(ctx.owned) else 0.0
    PI, h = w.index, w.head
    pw = (2e-4 + np.sum(PI * (p - h))) / PI.sum()
    assert s.pressure == pytest.approx(pw, rel=1e-12)
    assert np.allclose(s.q, (PI * (pw + h - p))[ctx.owned], rtol=1e-12, atol=1e-20)
    assert float(ctx.total([s.q.sum()])[0]) == pytest.approx(2e-4, rel=1e-12)
    assert isinstance(well_term(w), NodeSetTerm)


def test_a_schedule_holds_each_value_up_to_its_end():
    s = Schedule((0.0, 10.0, 20.0), (1.0, 2.0, 3.0))
    assert [s.at(t) for t in (0.0, 5.0, 10.0, 10.5, 20.0, 25.0)] == [1.0, 1.0, 1.0, 2.0, 2.0, 3.0]
