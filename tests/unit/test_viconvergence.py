"""The VI Newton solvers honour -snes_stol (``petthm.solvers.viconvergence``):
vinewtonrsls's own test ignores it, so a residual on a round-off floor above
-snes_atol ran to -snes_max_it (Scene 3 with a 0.22 m first layer)."""
import math

import numpy as np
import pytest
from petsc4py import PETSc

from petthm import compat
from petthm.solvers.viconvergence import DefaultConvergence, VIConvergence

Reason = PETSc.SNES.ConvergedReason


def _snes(rtol=1e-10, atol=1e-12, stol=1e-14, prefix="viconv_"):
    snes = PETSc.SNES().create(PETSc.COMM_SELF)
    snes.setOptionsPrefix(prefix)
    snes.setTolerances(rtol=rtol, atol=atol, stol=stol)
    return snes


def test_the_reasons_of_the_vi_default_and_the_step_length():
    snes, test = _snes(), VIConvergence()
    assert test.reason(snes, 0, 8.0, 0.0, 1.0e-2) == Reason.CONVERGED_ITERATING
    # Scene 3's stalled iteration: |dx| = 2.4e-14 against |x| = 8, residual 4e-12 > atol
    assert test.reason(snes, 5, 8.0, 2.4e-14, 4.0e-12) == Reason.CONVERGED_SNORM_RELATIVE
    # negative controls: a real update, a diverged iterate (|x| huge, so any update is small:
    # fracture_inflation once reached |F| = 1e32), and the first iteration (no update yet)
    assert test.reason(snes, 5, 8.0, 1.0e-9, 4.0e-12) == Reason.CONVERGED_ITERATING
    assert test.reason(snes, 5, 1.0e30, 1.0e15, 6.9e30) == Reason.CONVERGED_ITERATING
    assert test.reason(snes, 5, 8.0, 2.4e-14, 2.0e-7) == Reason.CONVERGED_ITERATING   # > sqrt(rtol) |F0|
    assert test.reason(snes, 0, 8.0, 0.0, 4.0e-12) == Reason.CONVERGED_ITERATING
    assert test.reason(snes, 3, 8.0, 1.0, 5.0e-13) == Reason.CONVERGED_FNORM_ABS
    test.reason(snes, 0, 8.0, 0.0, 1.0)
    assert test.reason(snes, 2, 8.0, 1.0, 5.0e-11) == Reason.CONVERGED_FNORM_RELATIVE
    assert test.reason(snes, 2, 8.0, 1.0, math.nan) == compat.SNES_DIVERGED_NAN


class _NoisyResidual:
    """F(x) = x - 1 plus a deterministic 1e-9 noise that changes at every
    evaluation: Newton (J = I) reaches x = 1 to 1e-9 and cannot go further,
    a residual floor above atol as thin cells give Scene 3."""

    def __init__(self):
        self.calls = 0

    def __call__(self, snes, X, F):
        self.calls += 1
        noise = 1e-9 * np.sin(1.0 + self.calls * np.arange(1, X.getLocalSize() + 1))
        F.getArray()[:] = X.getArray(readonly=True) - 1.0 + noise


def _noisy_snes(snes_type: str, prefix: str):
    """A SNES of ``snes_type`` on the noisy residual (J = I, LU, basic line search)."""
    n = 4
    snes = _snes(atol=1e-12, stol=1e-8, prefix=prefix)
    snes.setTolerances(max_it=20)
    snes.setType(snes_type)
    J = PETSc.Mat().createAIJ([n, n], nnz=1, comm=PETSc.COMM_SELF)
    J.setUp()
    for i in range(n):
        J.setValue(i, i, 1.0)
    J.assemble()
    snes.setFunction(_NoisyResidual(), PETSc.Vec().createSeq(n))
    snes.setJacobian(lambda snes, X, A, P: None, J)
    snes.getKSP().setType("preonly")
    snes.getKSP().getPC().setType("lu")
    PETSc.Options(snes.getOptionsPrefix()).setValue("snes_linesearch_type", "basic")
    snes.setFromOptions()
    return snes, n


def _solve(snes_type: str, install: bool):
    snes, n = _noisy_snes(snes_type, "viconv_")
    lower, upper = PETSc.Vec().createSeq(n), PETSc.Vec().createSeq(n)
    lower.set(0.0)
    upper.set(PETSc.INFINITY)
    snes.setVariableBounds(lower, upper)
    if install:
        VIConvergence().install(snes)
    X = PETSc.Vec().createSeq(n)
    X.set(3.0)
    snes.solve(None, X)
    return snes.getConvergedReason(), snes.getIterationNumber(), X.getArray().copy()


@pytest.mark.parametrize("snes_type", ["vinewtonrsls", "vinewtonssls"])
def test_a_residual_floor_above_atol_converges_on_the_step_length(snes_type):
    reason, its, x = _solve(snes_type, install=True)
    assert reason == Reason.CONVERGED_SNORM_RELATIVE and its < 20
    assert np.abs(x - 1.0).max() < 1e-8
    # negative control: vinewtonrsls's own test (SNESConvergedDefault_VI) runs to the
    # iteration limit; vinewtonssls's (PETSc's SNESConvergedDefault) has the step-length test
    reason, its, _ = _solve(snes_type, install=False)
    if snes_type == "vinewtonrsls":
        assert reason == Reason.DIVERGED_MAX_IT and its == 20
    else:
        assert reason == Reason.CONVERGED_SNORM_RELATIVE


def _solve_unbounded(install: bool):
    """newtonls on the noisy residual: PETSc's SNESConvergedDefault, or its
    Python copy that the limited heat transport's settling wraps."""
    snes, n = _noisy_snes("newtonls", "defconv_")
    if install:
        DefaultConvergence().install(snes)
    X = PETSc.Vec().createSeq(n)
    X.set(3.0)
    snes.solve(None, X)
    return snes.getConvergedReason(), snes.getIterationNumber()


def test_the_python_default_test_is_petscs():
    assert _solve_unbounded(True) == _solve_unbounded(False)
    assert _solve_unbounded(True)[0] == Reason.CONVERGED_SNORM_RELATIVE
    snes, test = _snes(prefix="defconv_"), DefaultConvergence()
    assert test.reason(snes, 0, 8.0, 0.0, 1.0) == Reason.CONVERGED_ITERATING
    assert test.reason(snes, 2, 8.0, 1.0, 5.0e-11) == Reason.CONVERGED_FNORM_RELATIVE
    assert test.reason(snes, 2, 8.0, 1.0, 2.0e4) == Reason.DIVERGED_DTOL            # 1e4 |F0|
    assert test.reason(snes, 2, 8.0, 1.0, math.nan) == compat.SNES_DIVERGED_NAN
    assert test.reason(snes, 2, 8.0, 1.0, 0.5) == Reason.CONVERGED_ITERATING
