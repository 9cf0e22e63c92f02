"""Self-checks petthm can run on any problem: Jacobian against finite differences."""
from __future__ import annotations

import numpy as np
from petsc4py import PETSc


def _perturbed_state(problem, t: float, shift: float, rng, rate: float = 1.0):
    """X (the problem's current state plus a random perturbation, so that
    nonlinear terms are exercised away from special points), a random Xdot
    of standard deviation ``rate`` (scaled unknowns per second), and the
    backward-Euler Jacobian J = dF/dX + shift dF/dXdot there.  The step's
    start is X - Xdot / shift: terms evaluated there (the limited heat
    transport's factors) see a state that moved by ``rate / shift`` scales."""
    X = problem.X.duplicate()
    problem.X.copy(X)
    X.getArray()[:] += 0.1 * rng.standard_normal(X.getLocalSize())
    Xdot = X.duplicate()
    Xdot.getArray()[:] = rate * rng.standard_normal(X.getLocalSize())
    J = problem.create_matrix()
    problem.ijacobian(None, t, X, Xdot, shift, J, J)
    return X, Xdot, J


def _central_difference(problem, t: float, shift: float, X, Xdot, d, eps: float):
    """(F(X + eps d) - F(X - eps d)) / (2 eps) as a local array, with F
    evaluated along X(s) = X + s d, Xdot(s) = Xdot + shift s d."""
    F = []
    problem.residual_shift = shift
    for s in (eps, -eps):
        Xs, Xds, Fs = X.duplicate(), Xdot.duplicate(), X.duplicate()
        Xs.waxpy(s, d, X)
        Xds.waxpy(shift * s, d, Xdot)
        problem.ifunction(None, t, Xs, Xds, Fs)
        F.append(Fs.getArray().copy())
    return (F[0] - F[1]) / (2 * eps)


def jacobian_fd_error(problem, t: float = 0.0, shift: float = 1.0, eps: float = 1e-6,
                      seed: int = 0, rate: float = 1.0) -> float:
    """Relative error ||J d - (F(x+eps d) - F(x-eps d))/(2 eps)|| / ||J d||
    at a perturbed state (``_perturbed_state``, ``rate``: the size of its
    random rates) along a random direction d."""
    rng = np.random.default_rng(seed + problem.dm.comm.rank)
    X, Xdot, J = _perturbed_state(problem, t, shift, rng, rate)
    d = X.duplicate()
    d.getArray()[:] = rng.standard_normal(d.getLocalSize())
    Jd = X.duplicate()
    J.mult(d, Jd)
    fd = _central_difference(problem, t, shift, X, Xdot, d, eps)
    comm = problem.dm.comm.tompi4py()
    num = comm.allreduce(float(np.sum((fd - Jd.getArray()) ** 2)))
    return np.sqrt(num) / max(Jd.norm(), 1e-300)


def jacobian_fd_block_errors(problem, t: float = 0.0, shift: float = 1.0, eps=1e-6,
                             seed: int = 0, rate: float = 1.0) -> dict:
    """{(test field, trial field): relative error} of every coupling block, the
    check of ``jacobian_fd_error`` with d restricted to the trial field's
    unknowns and the error measured on the test field's rows (so that a wrong
    small block is not hidden by large correct ones).  A block that is zero
    in both the Jacobian and the differences is left out; one that is zero in
    the Jacobian only has error inf.

    ``eps`` may be a tuple of steps: each block's error is then the smallest
    over them.  A small block in rows with large unrelated terms needs a
    large step (its round-off error grows as 1/step), a block with a kink
    nearby a small one (truncation); a wrong block is wrong at every step.
    ``rate``: the size of the random rates (``_perturbed_state``); rates
    of unit size with a small ``shift`` describe a step that moved every
    unknown by 1/shift of its scale, whose increment terms (backward
    Euler's exact quotients, rate x rate / shift) swamp a small block's rows
    with round-off."""
    if not np.isscalar(eps):
        out = {}
        for e in eps:
            for k, v in jacobian_fd_block_errors(problem, t, shift, e, seed, rate).items():
                out[k] = min(v, out.get(k, np.inf))
        return out
    rng = np.random.default_rng(seed + problem.dm.comm.rank)
    X, Xdot, J = _perturbed_state(problem, t, shift, rng, rate)
    names, isets, _ = problem.dm.createFieldDecomposition()
    lo = X.getOwnershipRange()[0]
    rows = {n: iset.getIndices() - lo for n, iset in zip(names, isets, strict=False)}
    comm = problem.dm.comm.tompi4py()
    out = {}
    for trial in names:
        d = X.duplicate()
        d.set(0.0)
        d.getArray()[rows[trial]] = rng.standard_normal(len(rows[trial]))
        Jd = X.duplicate()
        J.mult(d, Jd)
        fd = _central_difference(problem, t, shift, X, Xdot, d, eps)
        jd = Jd.getArray()
        for test in names:
            r = rows[test]
            num = comm.allreduce(float(np.sum((fd[r] - jd[r]) ** 2)))
            den = comm.allreduce(float(np.sum(jd[r] ** 2)))
            ref = comm.allreduce(float(np.sum(fd[r] ** 2)))
            if den == 0.0 and ref == 0.0:
                continue
            out[(test, trial)] = np.sqrt(num / den) if den > 0 else float("inf")
    return out


__all__ = ["jacobian_fd_error", "PETSc"]
