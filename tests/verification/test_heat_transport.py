"""-thm_heat_transport upwind (kernels/transport.py) and limited
(kernels/limiter.py): the exact Jacobians of the algebraic upwinding and of
its flux correction against finite differences with negative controls, the
temperatures within the bounds the scene gives (theory manual, "Discrete
bounds") where SUPG leaves them, the energy balance, the first-order rate
of the upwinding and the second-order rate of the limited scheme on the heat
MMS."""
import dataclasses

import pytest

from conftest import build_problem, fitted_slope, read_csv, run_petthm
from petthm.discretisation.model import FRACTURE
from petthm.verification.jacobian import jacobian_fd_block_errors

COARSE_LAUWERIER = dict(thm_mesh_size=40, thm_lauwerier_fracture_size=10, thm_lauwerier_width=20,
                        thm_final_time=1e6)
#: acceptance (issue 49): the largest excursion beyond the bounds, as a fraction of their range
BOUND_TOLERANCE = 1e-3


def _coupled(tmp_path, scheme="upwind"):
    """The closed coupled MMS (P1): Tf advected by the cubic law through the
    aperture a(lam, u+-), Tm by Darcy flow, mu(T) of water."""
    return build_problem(tmp_path, "coupled_mms", thm_fe_degree=1, thm_mesh_size=0.25,
                         thm_coupled_mms_state="closed", thm_heat_transport=scheme)


def _lauwerier(tmp_path, exchange, scheme="upwind"):
    return build_problem(tmp_path, "lauwerier", thm_fe_degree=1, thm_fluid_viscosity="water",
                         thm_fracture_heat_exchange=exchange, thm_heat_transport=scheme,
                         **COARSE_LAUWERIER)


@pytest.mark.parametrize("scheme", ["upwind", "limited"])
def test_upwinding_jacobian_blocks_match_finite_differences(tmp_path, scheme):
    # rates of the size the step moves each unknown by (the limited scheme's factors are evaluated at
    # X - Xdot/shift, which unit rates would put outside mu(T)'s range)
    err = jacobian_fd_block_errors(_coupled(tmp_path / "mms", scheme), t=0.5, shift=2.0, eps=(1e-6, 1e-4),
                                   rate=2.0)
    print({f"{a}-{b}": float(f"{v:.2g}") for (a, b), v in err.items()})
    assert {("Tm", "pm"), ("Tm", "Tm"), ("Tf", "pf"), ("Tf", "Tf"), ("Tf", "lam"), ("Tf", "u")} <= set(err)
    assert max(err.values()) <= 1e-6
    # the rock's capacity lumped, Tm-Tf is the conduction alone: a small linear block in rows of
    # large terms, whose differences need a large step (their round-off falls as 1/step)
    for exchange in ("nusselt", "equilibrium"):
        err = jacobian_fd_block_errors(_lauwerier(tmp_path / exchange, exchange, scheme), t=1e5, shift=1e-4,
                                       eps=(1e-6, 1e-4, 1e-2), rate=1e-4)
        print(exchange, {f"{a}-{b}": float(f"{v:.2g}") for (a, b), v in err.items()})
        assert max(err.values()) <= 1e-6


def _without(problem, region, keep):
    """The problem with the upwinding's element blocks on ``region`` that
    ``keep`` rejects left out of the Jacobian."""
    asm = problem.region(region)
    asm.model.jacobians[:] = [j for j in asm.model.jacobians if j.element is None or keep(j)]
    asm.build_pattern()
    problem.J = None
    return problem


@pytest.mark.parametrize("trial", ["pf", "lam", "Tf"])
def test_upwinding_jacobian_check_fails_without_a_block(tmp_path, trial):
    """Negative controls: without the upwinding's derivative with respect to
    the pressure (b ~ grad pf), the aperture (b ~ a^3: lam) or the
    temperature (the diffusion itself and mu(T)), that block is wrong."""
    problem = _without(_coupled(tmp_path), FRACTURE, lambda j: not (j.test == "Tf" and j.trial == trial))
    err = jacobian_fd_block_errors(problem, t=0.5, shift=2.0, eps=1e-6)
    print(trial, err[("Tf", trial)])
    assert err[("Tf", trial)] > 1e-3


def _limiting(problem):
    """The fraction of the limited scheme's element pairs with 0 < alpha < 1
    in the last assembly of each region (the limiter is active)."""
    from petthm.physics.kernels.limiter import FluxLimiter
    out = []
    for asm in problem.assemblers.values():
        for term in asm.model.residuals:
            if isinstance(term.prepare, FluxLimiter):
                alpha = 1.0 - term.prepare.keep
                out.append(float(((alpha > 1e-3) & (alpha < 1 - 1e-3)).mean()))
    return out


def test_limiter_jacobian_check_fails_with_the_limiter_at_the_solved_state(tmp_path, monkeypatch):
    """Negative control: the limiter's alpha is a constant of the step because
    it is evaluated at the step's start; evaluated at the state being solved
    for, the residual depends on alpha(T), which the Jacobian leaves out."""
    from petthm.physics.kernels import limiter
    problem = _coupled(tmp_path / "solved", "limited")
    err = jacobian_fd_block_errors(problem, t=0.5, shift=2.0, eps=1e-6)
    partly = _limiting(problem)
    print("limiting", partly, "Tf-Tf", err[("Tf", "Tf")], "Tm-Tm", err[("Tm", "Tm")])
    assert partly and min(partly) > 0.05                     # the check above exercised the limiter
    monkeypatch.setattr(limiter, "step_start", lambda xl, xdl, shift: xl)
    err = jacobian_fd_block_errors(_coupled(tmp_path / "lagless", "limited"), t=0.5, shift=2.0, eps=1e-6)
    print("at the solved state", err[("Tf", "Tf")], err[("Tm", "Tm")])
    assert max(err[("Tf", "Tf")], err[("Tm", "Tm")]) > 1e-3


def _excursion(summary, field):
    b = summary["bounds"][field]
    return b["violation"] / (b["upper"] - b["lower"])


@pytest.mark.parametrize("scheme", ["upwind", "limited"])
def test_upwinding_keeps_an_advected_front_in_bounds(tmp_path, scheme):
    """heat_advection at cell Peclet >= 100: SUPG over- and undershoots, the
    upwinding and the limited scheme do not (Newton: one iteration for each
    solve, as for a linear problem)."""
    _, s = run_petthm("heat_advection", tmp_path / scheme, "-thm_fe_degree", 1,
                      "-thm_heat_transport", scheme)
    _, supg = run_petthm("heat_advection", tmp_path / "supg", "-thm_fe_degree", 1,
                         "-thm_heat_transport", "supg")
    print(f"excursion {scheme}", _excursion(s, "Tm"), "supg", _excursion(supg, "Tm"),
          "newton", s["snes_iterations"], "steps", s["steps"])
    assert s["cell_peclet_min"] >= 100
    assert _excursion(s, "Tm") <= BOUND_TOLERANCE
    assert _excursion(s, "Tm") < 0.01 * _excursion(supg, "Tm")
    # one Newton iteration for each solve of fixed equations: a step, and each settling pass
    passes = s["limiter_settling_passes"] or 0
    assert s["rejected_steps"] == 0 and s["snes_iterations"] <= s["steps"] + passes + 2
    rows = read_csv(tmp_path / scheme / "history.csv")
    assert float(rows[-1]["Tm_min"]) < 21.0                   # the front has entered


def test_limited_scheme_settles_long_steps_within_their_own_bounds(tmp_path):
    """heat_advection with steps of ten times the Courant limit: with the
    factors of each step's start alone, the front's end state leaves the
    bounds by 2.8e-4 of the range; settled at the solved state, by no more
    than the settling tolerance (1e-4 of the range, -thm_heat_limiter_settle)."""
    runs = {}
    for settle in (1e-4, 1e9):
        _, runs[settle] = run_petthm("heat_advection", tmp_path / f"s{settle:g}", "-thm_fe_degree", 1,
                                     "-thm_heat_transport", "limited", "-thm_dt_initial", 2e6,
                                     "-thm_heat_limiter_settle", settle)
    settled, lagged = runs[1e-4], runs[1e9]
    print("settled", _excursion(settled, "Tm"), settled["limiter_settling_passes"], "start factors only",
          _excursion(lagged, "Tm"), lagged["limiter_settling_passes"])
    assert settled["limiter_settling_passes"] > 0 and lagged["limiter_settling_passes"] == 0
    assert _excursion(settled, "Tm") <= 1e-4
    assert _excursion(lagged, "Tm") > 10 * _excursion(settled, "Tm")      # the negative control


@pytest.mark.parametrize("scheme", ["upwind", "limited"])
def test_upwinding_keeps_lauwerier_in_bounds_with_its_energy_balance(tmp_path, scheme):
    """Lauwerier (P1): Tf and Tm within [Tinj, T0] (SUPG with a consistent
    rock capacity: Tm 20 K above T0 next to the cooled wall), every step's
    energy balance at round-off, the outlet temperature within 6 % (limited:
    6.5 %) of the analytical solution (the early outlet error is that of the
    lumped rock capacity: the limited scheme does not reduce it)."""
    _, s = run_petthm("lauwerier", tmp_path, "-thm_fe_degree", 1, "-thm_heat_transport", scheme)
    for f in ("Tf", "Tm"):
        print(f, s["bounds"][f])
        assert _excursion(s, f) <= BOUND_TOLERANCE
    rows = read_csv(tmp_path / "history.csv")
    assert max(abs(float(r["energy_balance"])) for r in rows) <= 1e-8
    print("errors", s["error"])
    assert s["error"]["outlet_max_rel_t_ge_1e4"] <= {"upwind": 0.06, "limited": 0.065}[scheme]
    assert s["error"]["profile_max_rel_t1e+08"] <= 2e-3


@pytest.mark.parametrize("scheme", ["upwind", "limited"])
def test_upwinding_keeps_scene3_in_bounds(tmp_path, scheme):
    """Scene 3, case 3, coarse mesh, 30 years: SUPG leaves [Tinj, T0] by
    18 K below and 26 K above; with upwinding or the limited scheme Tf and Tm
    stay within 1e-3 of the range, with no step rejected."""
    _, s = run_petthm("inclined_penny", tmp_path, "-options_file",
                      "options/scenes/inclined_penny_coarse.opts", "-thm_scene3_case", 3,
                      "-thm_heat_transport", scheme)
    assert s["status"] == "completed" and s["rejected_steps"] == 0
    for f in ("Tf", "Tm"):
        print(f, s["bounds"][f])
        assert _excursion(s, f) <= BOUND_TOLERANCE
        assert "heating_allowance" not in s["bounds"][f]          # no heating, no allowance for it


def test_thermomechanical_heating_stays_within_its_allowance(tmp_path):
    """Scene 3, case 2, coarse, limited, with -thm_thermomechanical_heating:
    the rock's strain and pressure heating may take the temperatures out of
    [Tinj, T0]; at every step the excursion stays within what those terms
    alone produce by then (the history's heating_allowance, K) and the
    scheme's own 1e-3 of the range."""
    _, s = run_petthm("inclined_penny", tmp_path, "-options_file",
                      "options/scenes/inclined_penny_coarse.opts", "-thm_scene3_case", 2,
                      "-thm_heat_transport", "limited", "-thm_thermomechanical_heating", "true")
    assert s["status"] == "completed"
    rows = read_csv(tmp_path / "history.csv")
    allowance = [float(r["heating_allowance"]) for r in rows]
    assert allowance[0] == 0.0 and allowance[-1] > 0.0
    assert all(b >= a for a, b in zip(allowance, allowance[1:], strict=False))      # a running sum
    for f in ("Tf", "Tm"):
        b = s["bounds"][f]
        print(f, b)
        assert b["heating_allowance"] == pytest.approx(allowance[-1], rel=1e-9)
        span = b["upper"] - b["lower"]
        for r, a in zip(rows, allowance, strict=True):
            out = max(0.0, float(r[f"{f}_max"]) - b["upper"], b["lower"] - float(r[f"{f}_min"]))
            assert out <= a + BOUND_TOLERANCE * span, (r["step"], out, a)


def test_upwinding_converges_at_first_order_on_the_heat_mms(tmp_path):
    """The low-order scheme's price: its diffusion ~ |b| h makes the L2 error
    first order (SUPG: second), H1 stays first order."""
    hs, l2, h1 = [], [], []
    for k, size in enumerate([0.25, 0.125, 0.0625, 0.03125]):
        _, s = run_petthm("heat_mms", tmp_path / f"r{k}", "-thm_fe_degree", 1, "-thm_mesh_size", size,
                          "-thm_heat_transport", "upwind")
        hs.append(s["h_max"])
        l2.append(s["error"]["Tm_l2"])
        h1.append(s["error"]["Tm_h1"])
    sl2, sh1 = fitted_slope(hs, l2), fitted_slope(hs, h1)
    print(f"upwind heat_mms 2D P1: L2 slope {sl2:.3f}, H1 slope {sh1:.3f}, errors {l2} {h1}")
    assert sl2 >= 1.0 and abs(sh1 - 1.0) <= 0.2
    assert sl2 < 1.8                       # not the second order of the Galerkin and SUPG schemes


def test_limited_scheme_converges_at_second_order_on_the_heat_mms(tmp_path):
    """The flux correction gives the Galerkin scheme back where T is smooth:
    L2 second order (within 0.2 of theory on each level pair), H1 first, and
    the L2 error within 1.3 times SUPG's on the finest mesh."""
    hs, l2, h1 = [], [], []
    sizes = [0.125, 0.0625, 0.03125, 0.015625]
    for k, size in enumerate(sizes):
        _, s = run_petthm("heat_mms", tmp_path / f"r{k}", "-thm_fe_degree", 1, "-thm_mesh_size", size,
                          "-thm_heat_transport", "limited")
        hs.append(s["h_max"])
        l2.append(s["error"]["Tm_l2"])
        h1.append(s["error"]["Tm_h1"])
    _, supg = run_petthm("heat_mms", tmp_path / "supg", "-thm_fe_degree", 1, "-thm_mesh_size", sizes[-1])
    rates = [fitted_slope(hs[k:k + 2], l2[k:k + 2]) for k in range(len(hs) - 1)]
    sh1 = fitted_slope(hs, h1)
    print(f"limited heat_mms 2D P1: L2 rates {rates}, H1 slope {sh1:.3f}, errors {l2}, "
          f"SUPG finest {supg['error']['Tm_l2']}")
    assert min(rates) >= 1.8 and abs(sh1 - 1.0) <= 0.2
    assert l2[-1] <= 1.3 * supg["error"]["Tm_l2"]


@pytest.mark.parametrize("scheme", ["upwind", "limited"])
def test_upwinding_needs_p1(tmp_path, scheme):
    proc, _ = run_petthm("heat_advection", tmp_path, "-thm_fe_degree", 2, "-thm_heat_transport", scheme,
                         check=False)
    assert proc.returncode == 2                      # an input error
    assert proc.stderr.strip().splitlines()[-1].startswith(
        f"petthm: error: option -thm_heat_transport {scheme}: P1 temperatures only")


def test_supg_wall_conduction_needs_supg(tmp_path):
    """The rock's wall conduction is a term of SUPG's residual: asked for with
    the limited scheme it is an input error, not silently left out."""
    proc, _ = run_petthm("lauwerier", tmp_path, "-thm_fe_degree", 1, "-thm_heat_transport", "limited",
                         "-thm_fracture_supg_wall_conduction", "true", check=False)
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines()[-1].startswith(
        "petthm: error: option -thm_fracture_supg_wall_conduction: a term of the SUPG residual")
    assert not (tmp_path / "summary.json").exists()


def test_upwinding_is_registered_only_for_advected_heat():
    """Heat that is not advected has the capacity lumped and no upwinding term."""
    from petthm.discretisation.model import Domain
    from petthm.physics.kernels import heat as hk
    h = hk.Heat(Domain.MATRIX, "Tm", 1.0, 1.0, degree=1, supg=False, lumped=True)
    with pytest.raises(ValueError):
        hk.heat_terms(dataclasses.replace(h, upwind=True))
    with pytest.raises(ValueError):                  # the limiter corrects the upwinding, nothing else
        hk.heat_terms(dataclasses.replace(h, limited=True))
    assert not any(t.element for t in hk.heat_terms(h)[0])
