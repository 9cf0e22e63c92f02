"""Newton's first iterate of a step (``predictor.LinearPredictor``,
``-thm_predictor``): the line through the last two accepted states, on a
step's first try only."""
from types import SimpleNamespace

import numpy as np
import pytest
from petsc4py import PETSc

from petthm.solvers.predictor import LinearPredictor


def _vec(values):
    v = PETSc.Vec().createSeq(len(values), comm=PETSc.COMM_SELF)
    v.getArray()[:] = values
    return v


def _ts(step, t, dt):
    return SimpleNamespace(getStepNumber=lambda: step, getTime=lambda: t, getTimeStep=lambda: dt)


def test_the_first_try_starts_on_the_line_through_the_last_two_states():
    clock = {"step": 0, "t": 0.0, "dt": 1.0}            # TS numbers the steps it has completed
    ts = SimpleNamespace(getStepNumber=lambda: clock["step"], getTime=lambda: clock["t"],
                         getTimeStep=lambda: clock["dt"])
    pred = LinearPredictor(ts)
    pred.accepted(0.0, _vec([1.0, 5.0]))              # the initial state
    x = _vec([2.0, 4.0])
    pred(None, x)                                      # step 1: one state only, no line yet
    assert np.allclose(x.getArray(), [2.0, 4.0])
    pred.accepted(1.0, x)                              # step 1 accepted at t = 1 (dt 1)
    clock.update(step=1, t=1.0, dt=2.0)
    start = _vec([2.0, 4.0])
    pred(None, start)                                  # step 2 (dt 2): X_1 + 2 (X_1 - X_0)
    assert np.allclose(start.getArray(), [4.0, 2.0]) and pred.used == 1
    retry = _vec([2.0, 4.0])
    pred(None, retry)                                  # the same step tried again: X_1
    assert np.allclose(retry.getArray(), [2.0, 4.0]) and pred.used == 1
    pred.destroy()


def test_a_start_that_is_not_the_last_state_is_left_alone():
    pred = LinearPredictor(_ts(5, 3.0, 1.0))
    pred.accepted(1.0, _vec([0.0]))
    pred.accepted(2.0, _vec([1.0]))                    # recorded up to t = 2; the TS is at t = 3
    x = _vec([7.0])
    pred(None, x)
    assert x.getArray()[0] == 7.0 and pred.used == 0
    pred.destroy()


@pytest.mark.first_pass_only
def test_the_predictor_cuts_newton_iterations_and_keeps_the_result(tmp_path):
    """Scene 2 coarse (layered mesh, the block path) to 3e8 s, SUPG: the same
    injection pressure and production temperature to 1e-10 with fewer Newton
    and Krylov iterations than from the last state.  Both runs converge
    Newton to -snes_atol 1e-11 (the block path's default is 1e-9): at 1e-9 the
    two converged states differ inside that tolerance, by 3.0e-10 on one
    machine and 1.2e-8 on another (the same code; the round-off differs),
    which says nothing about the predictor.
    Measured at 1e-11, to 3e8 s (73 steps): PETSc 3.18 1.3e-11, Newton 150
    against 178, Krylov 1 484 against 1 824.  To 1e9 s (the same savings
    over more steps): PETSc 3.18 9.1e-13, Newton 220 against 252, Krylov
    2 181 against 2 878; PETSc 3.26 1.3e-12, Newton 220 against 252,
    Krylov 2 429 against 3 311.  With the default limited scheme the
    predictor saves less (PETSc 3.18, to 1e9 s: Newton 361 against 393,
    Krylov 4 205 against 4 529)."""
    from conftest import ROOT, run_petthm
    opts = ("-options_file", f"{ROOT}/options/scenes/penny_impermeable.opts", "-thm_scene2_fracture_size", 40,
            "-thm_scene2_well_size", 20, "-thm_final_time", 3e8, "-thm_direct_max_unknowns", 0,
            "-snes_atol", 1e-11, "-ksp_atol", 1e-12, "-thm_heat_transport", "supg")
    runs = {p: run_petthm("penny_impermeable", tmp_path / p, *opts, "-thm_predictor", p)[1]
            for p in ("linear", "none")}
    lin, none = runs["linear"], runs["none"]
    assert lin["status"] == none["status"] == "completed" and lin["steps"] == none["steps"]
    keys = ("injection_pressure", "production_temperature")
    worst = max(abs(lin[k] - none[k]) / abs(none[k]) for k in keys)
    print(f"predictor: Newton {lin['snes_iterations']} against {none['snes_iterations']}, Krylov "
          f"{lin['ksp_iterations']} against {none['ksp_iterations']}, results {worst:.1e}")
    assert worst <= 1e-10
    assert lin["snes_iterations"] < none["snes_iterations"]
    assert lin["ksp_iterations"] < 0.85 * none["ksp_iterations"]
