"""Newton's first iterate of a time step (``-thm_predictor``).

Backward Euler (theory manual, "Time stepping and solvers") is unchanged: only the state Newton
starts from is.  PETSc's TS starts every step from the last accepted state.
``linear`` starts it from the line through the last two accepted states,

    X_0 = X_n + (dt / dt_prev) (X_n - X_{n-1}),

so that the first Newton iteration corrects only what changes faster than
linearly.  At Scene 2's long steps the first Newton iteration from X_n
reduced the residual 4x and the second converged; from the line it reduces
it ~1500x (manual, solver guide).  The VI Newton methods project the
start onto the bounds.

A step tried again after a failed solve, and the first two steps of a run
and of a restart, start from X_n, as before: the line through a failed
attempt is no evidence, and the line through the initial state would repeat
the jump a run starts with (wells switched on at t = 0), which the first
step absorbs (Scene 3 in 0.2-year steps: step 2 took 5 Newton iterations on
that line against 4 from X_1).  PETSc's own
``-ts_theta_initial_guess_extrapolate`` extrapolates a retry from the failed
attempt's last iterate, hence this class.
"""
from __future__ import annotations

from petsc4py import PETSc


class LinearPredictor:
    """SNES's initial-guess hook (``SNESSetComputeInitialGuess``) and the
    TS post-step's record of accepted states (``accepted``)."""

    def __init__(self, ts: PETSc.TS):
        self.ts = ts
        self._last = None        # (t, X) of the last accepted state
        self._change = None      # (dt, X_n - X_{n-1}) of the last accepted step
        self._tried = None       # the step number whose first try was made
        self.used = 0            # steps started from the line

    def accepted(self, t: float, X: PETSc.Vec) -> None:
        """Record the state X at time t that the TS has accepted (from its post-step)."""
        if self._last is not None and t > self._last[0]:
            t0, X0 = self._last
            change = self._change[1] if self._change is not None else X.duplicate()
            X.copy(change)
            change.axpy(-1.0, X0)
            self._change = (t - t0, change)
            X.copy(X0)
            self._last = (t, X0)
        else:
            self._last = (t, X.copy())

    def __call__(self, snes: PETSc.SNES, x: PETSc.Vec) -> None:
        """Move ``x`` (the TS's start, X_n) along the line, on a step's first try only."""
        step = self.ts.getStepNumber()
        first_try, self._tried = self._tried != step, step
        if not first_try or self._change is None:          # _change implies _last
            return
        if abs(self.ts.getTime() - self._last[0]) > 1e-12 * max(abs(self._last[0]), 1.0):
            return                                   # x is not the state recorded last
        dt_prev, change = self._change
        x.axpy(self.ts.getTimeStep() / dt_prev, change)
        self.used += 1

    def destroy(self) -> None:
        for item in (self._last, self._change):
            if item is not None:
                item[1].destroy()
        self._last = self._change = None
