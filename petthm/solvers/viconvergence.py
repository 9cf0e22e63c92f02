"""The convergence test of the reduced-space VI Newton solver (contact), with -snes_stol.

PETSc's reduced-space VI solver (vinewtonrsls, the contact scenes' default)
installs its own test, SNESConvergedDefault_VI, which checks the function norm
against -snes_atol and -snes_rtol only: unlike the SNESConvergedDefault of
newtonls and vinewtonssls it never reports CONVERGED_SNORM_RELATIVE, so
-snes_stol is silently ignored (PETSc 3.18 and 3.26 alike).  A Newton
iteration whose residual sits on its round-off floor above atol then runs to
-snes_max_it with updates of the size of x's last bits, and the time step is
rejected.  This happened with thin rock layers next to the fracture (Scene 3,
a first layer of 0.22 m: the scaled residual 6.5e-11, 4.3e-12, then 3.7-5.0e-12
for 21 iterations, each update |dx| = 2.4e-14 against |x| = 8.0; manual, Scene 3).

``VIConvergence``, installed for vinewtonrsls, is the VI test plus the
step-length test that -snes_stol documents for every SNES: converged when
|dx| < stol |x| after the first iteration, provided the function norm has
fallen to sqrt(rtol) of its initial value (half the digits asked for).  The
proviso keeps a diverging iteration from passing: fracture_inflation's VI
Newton once ran off to |F| = 1e32, where |x| is so large that any update is
"small" (measured: without it the run accepted such states and failed).
Everything else is the VI default's: NaN, atol, rtol times the initial norm,
the function-evaluation limit.  With -snes_rtol 0 the proviso admits no state
but |F| = 0, so the step-length test is off.
"""
from __future__ import annotations

import math

from petsc4py import PETSc

from petthm import compat

Reason = PETSc.SNES.ConvergedReason


class DefaultConvergence:
    """PETSc's SNESConvergedDefault in Python (NaN, -snes_atol, the
    function-evaluation limit, -snes_rtol times the initial norm, -snes_stol,
    -snes_divergence_tolerance), for a test that adds to it
    (``solvers/settling.py``); install with ``install(snes)``."""

    divergence_test = True

    def __init__(self):
        self.ttol = 0.0
        self.floor_tol = 0.0
        self.norm0 = 0.0

    def install(self, snes: PETSc.SNES) -> None:
        snes.setConvergenceTest(self)

    def __call__(self, snes: PETSc.SNES, it: int, norms) -> int:
        return self.reason(snes, it, *norms)

    def reason(self, snes: PETSc.SNES, it: int, xnorm: float, ynorm: float, fnorm: float) -> int:
        """The reason for the norms of iteration ``it``: |x|, the update |dx|
        and the function norm."""
        rtol, atol, stol, _ = snes.getTolerances()
        if it == 0:
            self.ttol = fnorm * rtol
            self.floor_tol = fnorm * math.sqrt(rtol)
            self.norm0 = fnorm
        if math.isnan(fnorm):
            return compat.SNES_DIVERGED_NAN
        if fnorm < atol:
            return Reason.CONVERGED_FNORM_ABS
        max_funcs = snes.getMaxFunctionEvaluations()
        if 0 <= max_funcs <= snes.getFunctionEvaluations():
            return Reason.DIVERGED_FUNCTION_COUNT
        if it > 0 and fnorm <= self.ttol:
            return Reason.CONVERGED_FNORM_RELATIVE
        if it > 0 and self.small_step(xnorm, ynorm, fnorm, stol):
            return Reason.CONVERGED_SNORM_RELATIVE
        divtol = _divergence_tolerance() if self.divergence_test else -1.0
        if it > 0 and divtol > 0 and fnorm > divtol * self.norm0:
            return Reason.DIVERGED_DTOL
        return Reason.CONVERGED_ITERATING

    def small_step(self, xnorm: float, ynorm: float, fnorm: float, stol: float) -> bool:
        return ynorm < stol * xnorm


def _divergence_tolerance() -> float:
    """-snes_divergence_tolerance (PETSc's default 1e4; -1 switches the test off)."""
    return PETSc.Options().getReal("snes_divergence_tolerance", 1e4)


class VIConvergence(DefaultConvergence):
    """SNESConvergedDefault_VI with the -snes_stol test (module docstring):
    the step-length test only where the function norm has fallen to
    sqrt(rtol) of its initial value, and no divergence test; install with
    ``install(snes)``."""

    divergence_test = False

    def small_step(self, xnorm: float, ynorm: float, fnorm: float, stol: float) -> bool:
        return ynorm < stol * xnorm and fnorm <= self.floor_tol
