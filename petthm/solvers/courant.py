"""The Courant number of a temperature front over one time step (the
``-thm_dt_courant`` limit, theory manual, "Time stepping and solvers"): how many cells the front
of an advected temperature moved in the step.

An isotherm moves at |dT/dt| / |grad T|; over a step of length dt through a
cell of size h that is |Delta T| / (|grad T| h) cells.  Per cell of the
field's region: the largest nodal change |Delta T| of the step and the
temperature difference across the cell |grad T| h (largest over its
quadrature points), both as fractions of the field's range (its scale).
Only cells that hold a front count (a difference across the cell of at
least ``FRONT`` of the range): elsewhere the ratio measures nothing.  The
fields are the fracture temperature and the rock temperature where water
flows through the rock (an advected front); a conduction front in
impermeable rock is not limited (its thin wall cells would stall the steps).
"""
from __future__ import annotations

import numpy as np

from petthm.discretisation import probes
from petthm.discretisation.context import CellContext

#: a cell holds a front when the temperature across it differs by this fraction of the range
FRONT = 0.02


def advected_temperatures(model) -> list[str]:
    """The temperature fields whose fronts are advected: Tf, and Tm with a matrix flow."""
    out = ["Tf"] if model.has("Tf") else []
    if model.has("Tm") and model.has("pm"):
        out.append("Tm")
    return out


def front_courant(problem, X_old, X_new, t: float) -> float:
    """Largest number of cells any advected temperature front moved in the
    step from ``X_old`` to ``X_new`` (0 where no cell holds a front; the same
    on every rank)."""
    xl_old = problem.local_arrays(X_old, t)[0].copy()
    xl_new = problem.local_arrays(X_new, t)[0]
    worst = 0.0
    for name in advected_temperatures(problem.model):
        worst = max(worst, _cells_moved(problem, name, xl_old, xl_new, t))
    return probes.global_max(problem.dm.comm, [worst], empty=0.0)


class FrontStepLimit:
    """The ``-thm_dt_courant`` cap on the next step (``solver.TimeStepper``
    calls it after each accepted step): ``dt`` cut so that the fronts would
    move at most ``courant`` cells at the speed they had in the step just
    taken; it keeps the last accepted state for the next estimate."""

    def __init__(self, problem, courant: float):
        self.problem, self.courant, self.X_prev = problem, courant, None

    def start(self, X) -> None:
        """The state before the first step."""
        if self.courant > 0.0 and self.X_prev is None:
            self.X_prev = X.copy()

    def __call__(self, ts, dt: float) -> float:
        if self.courant <= 0.0:
            return dt
        X = ts.getSolution()
        if self.X_prev is None:
            self.X_prev, moved = X.duplicate(), 0.0
        else:
            moved = front_courant(self.problem, self.X_prev, X, ts.getTime())
        X.copy(self.X_prev)
        return min(dt, ts.getTimeStep() * self.courant / moved) if moved > self.courant else dt


def _cells_moved(problem, name: str, xl_old, xl_new, t: float) -> float:
    domain = problem.disc.field(name).region
    asm = problem.region(min(r for r in problem.assemblers if r.domain == domain))   # Gauss before lumped
    worst = 0.0
    for cells in asm.chunks():
        dofs = asm.dofs(name)[cells]
        change = np.abs(xl_new[dofs] - xl_old[dofs]).max(axis=1)             # scaled: fraction of range
        grad = CellContext(asm, cells, xl_new, xl_new, t).grad(name)[:, :, 0, :]
        across = np.linalg.norm(grad, axis=-1).max(axis=1) * asm.mesh.h[cells] / problem.scales[name].scale
        front = across >= FRONT
        if front.any():
            worst = max(worst, float(np.max(change[front] / across[front])))
    return worst
