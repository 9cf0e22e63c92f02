"""The balance monitor's residual at the end of a step is the Newton
solver's last one when that was evaluated at the accepted state
(``Problem.step_residual``), and is computed afresh otherwise."""
import numpy as np

from conftest import build_problem


def test_the_last_residual_is_reused_only_at_its_own_state(tmp_path):
    p = build_problem(tmp_path, "heat_erfc", thm_mesh_size=2.0)
    X = p.X.copy()
    X.getArray()[:] += np.linspace(0.0, 0.1, X.getLocalSize())
    Xdot = X.duplicate()
    Xdot.set(0.3)
    F = X.duplicate()
    p.residual_shift = 0.5
    p.ifunction(None, 10.0, X, Xdot, F)
    xl, xdl = (a.copy() for a in p.local_arrays(X, 10.0, Xdot))
    fresh = p.local_residual(xl, xdl, 10.0, 0.5)
    kept = p.step_residual(X, 10.0, 0.5, xl, xdl)
    assert kept is p._residual_memo[3] and np.array_equal(kept, fresh)
    # negative controls: another state, time or shift is computed afresh
    Y = X.copy()
    Y.getArray()[:] += 1e-6
    yl, ydl = (a.copy() for a in p.local_arrays(Y, 10.0, Xdot))
    other = p.step_residual(Y, 10.0, 0.5, yl, ydl)
    assert other is not p._residual_memo[3]
    assert np.array_equal(other, p.local_residual(yl, ydl, 10.0, 0.5))
    assert p.step_residual(X, 11.0, 0.5, xl, xdl) is not p._residual_memo[3]
    assert p.step_residual(X, 10.0, 0.25, xl, xdl) is not p._residual_memo[3]
