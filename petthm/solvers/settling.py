"""The Newton convergence test of a run with the flux-limited heat transport:
a step is solved when Newton has converged and the limiter's factors hold at
the solved state (theory manual, "Limited flux correction").

The limiter's factors alpha_ij are evaluated at the start of a step and held
fixed while Newton solves it (exact Jacobian, quadratic convergence).  Bounds
from the start of a step do not bound its end: with long steps the fluxes of
the solved state can exceed the room of the solved state's neighbourhoods,
and an extremum forms that the next step, limited at it, takes away again
(a step-to-step oscillation).  ``Settling`` wraps the run's test: when it
reports convergence, the limiters compare their factors with those of the
solved state (``Problem.tighten``); where the step's exceed them, they are
lowered, the residual is evaluated again at the same state, and Newton goes
on with the step's new equations from where it stands.  The factors only
fall within a step, and after a few passes the pairs still in excess are
upwinded, so that this ends; the state it accepts satisfies Zalesak's
conditions with its own bounds.
"""
from __future__ import annotations

from petsc4py import PETSc

Reason = PETSc.SNES.ConvergedReason


class Settling:
    """``inner`` (a ``viconvergence`` test) and the limiters' check at the
    solved state; install with ``install(snes)``.  ``passes``: the Newton
    solves that a tightening sent on, in all."""

    def __init__(self, problem, ts: PETSc.TS, inner):
        self.problem, self.ts, self.inner = problem, ts, inner
        self.passes = 0

    def install(self, snes: PETSc.SNES) -> None:
        snes.setConvergenceTest(self)

    def __call__(self, snes: PETSc.SNES, it: int, norms) -> int:
        reason = self.inner(snes, it, norms)
        if reason <= 0:
            return reason
        X = snes.getSolution()
        t = self.ts.getTime() + self.ts.getTimeStep()       # backward Euler's stage time
        if not self.problem.tighten(X, t):
            return reason
        self.passes += 1
        F = snes.getFunction()[0]
        snes.computeFunction(X, F)
        return Reason.CONVERGED_ITERATING
