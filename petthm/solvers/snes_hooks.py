"""The SNES update hooks of ``solver.TimeStepper`` (called at the start of
every Newton iteration): the preconditioner's reuse across Newton
iterations and time steps (``-thm_pc_reuse``) and the release of a bounded
contact unknown trapped at its bound by the reduced-space VI Newton."""
from __future__ import annotations

import numpy as np
from petsc4py import PETSc

from petthm import compat


class SNESUpdates:
    """The SNES update hook (called at the start of every Newton iteration):
    the hooks of the VI release and of the preconditioner reuse, in order."""

    def __init__(self):
        self.hooks: list = []

    def __call__(self, snes, it):
        for hook in self.hooks:
            hook(snes, it)


class PreconditionerReuse:
    """Keep the preconditioner (above all an LU factorisation) across Newton
    iterations and time steps (``-thm_pc_reuse``): the Jacobian changes with
    the state and the step, and GMRES preconditioned by the older
    factorisation corrects that, for a fraction of a new factorisation's
    cost.  It is rebuilt at the next Newton iteration

    * with ``max_krylov`` = 0 (the default), when the Krylov iterations the
      reuse has added since the last set-up (each solve's iterations above
      the first solve's after it, at the measured time per iteration) have
      cost as much as that set-up did: a rule without a tuned constant that
      never spends more than twice the best of the two choices;
    * with ``max_krylov`` > 0, when the last linear solve needed more
      iterations than that;

    and always when a linear solve failed or a step is tried again after a
    failed solve.  The VI Newton method RSLS rebuilds it anyway when the
    active set changes."""

    def __init__(self, ts: PETSc.TS, max_krylov: int = 0):
        self.ts, self.max_krylov = ts, max_krylov
        self.step_start = None
        self.rebuilds = 0
        self._setups = PETSc.Log.Event("PCSetUp")
        self._solves = PETSc.Log.Event("KSPSolve")
        self._seen = (0, 0.0, 0.0)              # PCSetUp count and time, KSPSolve time at the last call
        self.setup_cost = 0.0                   # seconds of the last set-up
        self.base_its = None                    # iterations of the first solve after it
        self.extra = 0.0                        # seconds the reuse has added since
        compat.snes_lag_preconditioner(ts.getSNES(), -1, persists=True)

    def _last_solve(self, ksp) -> tuple[int, float]:
        """(iterations, seconds) of the last linear solve; notes a new set-up."""
        setup, solve = self._setups.getPerfInfo(), self._solves.getPerfInfo()
        count, t_setup, t_solve = int(setup["count"]), float(setup["time"]), float(solve["time"])
        if count > self._seen[0]:                                   # a set-up since the last call
            self.setup_cost = t_setup - self._seen[1]
            self.base_its, self.extra = None, 0.0
        seconds = t_solve - self._seen[2]
        self._seen = (count, t_setup, t_solve)
        return ksp.getIterationNumber(), seconds

    def _costly(self, its: int, seconds: float) -> bool:
        if self.max_krylov > 0:
            return its > self.max_krylov
        if its == 0:
            return False
        if self.base_its is None:
            self.base_its = its
        self.extra += max(its - self.base_its, 0) * seconds / its
        return self.extra > self.setup_cost

    def __call__(self, snes, it):
        ksp = snes.getKSP()
        its, seconds = self._last_solve(ksp)
        rebuild = ksp.getConvergedReason() < 0 or self._costly(its, seconds)
        if it == 0:
            t = self.ts.getTime()
            rebuild = rebuild or t == self.step_start        # the same step again: its solve failed
            self.step_start = t
        # the set-up is collective: every rank decides as the one that wants it most
        # (each measures its own times)
        rebuild = snes.comm.tompi4py().allreduce(bool(rebuild), op=_mpi_lor())
        if rebuild:
            compat.snes_lag_preconditioner(snes, -2)      # rebuild once, then reuse again
            self.rebuilds += 1


class BiactiveRelease:
    """SNES update hook that makes PETSc's reduced-space VI Newton release a
    bounded unknown whose last Newton step wanted to cross its bound.

    ``vinewtonrsls`` fixes an unknown at its bound only if the residual
    there is > 0.  The contact residual (the opening) does not depend on
    the bounded traction itself, so after a step that solved a node as
    closed (opening 0) and then projected its negative traction back to 0,
    the residual is 0 to round-off and the node stays closed for ever.
    Such a node (at its bound, and pushed below it by the last step) gets
    a residual of +1e-300 (it opens: the same rule as in a primal-dual
    active-set method); a wrong release is undone by the next step."""

    def __init__(self, lower: PETSc.Vec):
        self.lower = lower
        self.bounded = lower.getArray() > PETSc.NINFINITY
        self.previous = lower.duplicate()
        self.has_previous = False

    def __call__(self, snes, it):
        X = snes.getSolution()
        if it > 0 and self.has_previous and snes.getType() == "vinewtonrsls":
            x, lo = X.getArray(readonly=True), self.lower.getArray(readonly=True)
            wanted = self.previous.getArray(readonly=True) - snes.getSolutionUpdate().getArray(readonly=True)
            trapped = self.bounded & (x <= lo) & (wanted < lo)
            if trapped.any():
                f = snes.getFunction()[0].getArray()
                f[trapped] = np.maximum(f[trapped], 1e-300)
        X.copy(self.previous)
        self.has_previous = True


def _mpi_lor():
    from mpi4py import MPI
    return MPI.LOR
