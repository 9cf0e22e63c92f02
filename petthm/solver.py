"""TS (backward Euler) + SNES + KSP around an ``Assembler``: IFunction/IJacobian
callbacks, Dirichlet values, automatic residual scaling, step control.

physics.md section 10: monolithic Newton inside backward Euler; user-set
first step, growth factor and largest step; a failed nonlinear solve is
retried with a step four times smaller (PETSc's TSAdapt does this), up to
``-ts_max_reject`` times, after which the run stops with the last accepted
state.  Solver defaults are proposed here and inserted only where the user's
options database has no value for the key.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np
from petsc4py import PETSc

from . import compat
from .assembly import Assembler, FieldScale
from .fields import Discretisation
from .model import Model

#: Dirichlet data: f(x (n, d), t) -> values (n,) or (n, ncomp); optional time derivative
BoundaryFunction = Callable[[np.ndarray, float], np.ndarray]

SOLVER_DEFAULTS = {
    "ts_type": "beuler",
    "ts_adapt_type": "none",
    "snes_type": "newtonls",
    "snes_linesearch_type": "basic",
    "snes_rtol": "1e-10",
    "snes_atol": "1e-10",
    "snes_stol": "1e-14",
    "snes_max_it": "25",
    "ksp_type": "gmres",
    "ksp_rtol": "1e-10",
    "ksp_atol": "1e-14",
    "ksp_gmres_restart": "200",
    "ksp_max_it": "2000",
    "pc_type": "gamg",
}


#: option names petthm inserted itself (never reported as unused)
PROPOSED: set[str] = set()


def propose_defaults(defaults: dict[str, str]) -> None:
    """Insert solver options the user has not set (the user's options always win)."""
    opts = PETSc.Options()
    for k, v in defaults.items():
        if not opts.hasName(k):
            opts.setValue(k, v)
            PROPOSED.add(k)


@dataclass
class Dirichlet:
    field: str
    boundary: str
    value: BoundaryFunction
    rate: BoundaryFunction | None = None   # d value / dt (default 0)


@dataclass
class StepControl:
    final_time: float
    dt_initial: float
    growth: float = 1.0
    dt_max: float = math.inf


class Problem:
    """A transient FE problem: fields, model, Dirichlet data, initial state."""

    def __init__(self, disc: Discretisation, model: Model, scales: dict[str, FieldScale],
                 dirichlet: list[Dirichlet], quad_degree: int | None = None, region=None):
        self.disc, self.model, self.dm = disc, model, disc.mesh.dm
        self.scales = scales
        self.asm = Assembler(disc, model, scales, quad_degree, region)
        self._bc = [(d, next(b for b in disc.dirichlet if b.field == d.field and b.boundary == d.boundary))
                    for d in dirichlet]
        self.X = self.dm.createGlobalVec()
        self.X.setName("solution")
        self._Xl = self.dm.createLocalVec()
        self._Xdl = self.dm.createLocalVec()
        self._Fl = self.dm.createLocalVec()
        self.J = None
        self._ev_res = PETSc.Log.Event("thm.residual")
        self._ev_jac = PETSc.Log.Event("thm.jacobian")

    # -- local vectors with Dirichlet values ------------------------------------
    def local_arrays(self, X: PETSc.Vec, t: float, Xdot: PETSc.Vec | None = None):
        """Local (scaled) solution and rate arrays with Dirichlet values inserted."""
        self.dm.globalToLocal(X, self._Xl, addv=PETSc.InsertMode.INSERT_VALUES)
        xl = self._Xl.getArray()
        xdl = self._Xdl.getArray()
        if Xdot is not None:
            self.dm.globalToLocal(Xdot, self._Xdl, addv=PETSc.InsertMode.INSERT_VALUES)
        else:
            xdl[:] = 0.0
        for d, dofs in self._bc:
            sc = self.scales[d.field]
            if dofs.dofs.size == 0:
                continue
            shape = dofs.dofs.shape
            vals = np.asarray(d.value(dofs.coords, t), dtype=float).reshape(shape)
            xl[dofs.dofs] = (vals - sc.offset) / sc.scale
            rate = 0.0 if d.rate is None else \
                np.asarray(d.rate(dofs.coords, t), dtype=float).reshape(shape) / sc.scale
            xdl[dofs.dofs] = rate
        return xl, xdl

    def set_initial(self, funcs: dict[str, Callable[[np.ndarray], np.ndarray]], t0: float = 0.0):
        """Fill X from initial-value functions of the node coordinates (SI)."""
        xl = self._Xl.getArray()
        xl[:] = 0.0
        for name, f in funcs.items():
            sc = self.scales[name]
            dofs = self.disc.field_local_dofs(name)
            vals = np.asarray(f(self.disc.field_node_coordinates(name)), dtype=float)
            xl[dofs] = (vals.reshape(dofs.shape) - sc.offset) / sc.scale
        self.dm.localToGlobal(self._Xl, self.X, addv=PETSc.InsertMode.INSERT_VALUES)

    def field_values(self, name: str, X: PETSc.Vec | None = None, t: float = 0.0):
        """SI nodal values (n, ncomp) of a field on this rank's local nodes (ghosts included)."""
        xl, _ = self.local_arrays(X or self.X, t)
        sc = self.scales[name]
        return xl[self.disc.field_local_dofs(name)] * sc.scale + sc.offset

    # -- callbacks ---------------------------------------------------------------
    def ifunction(self, ts, t, X, Xdot, F):
        self._ev_res.begin()
        xl, xdl = self.local_arrays(X, t, Xdot)
        self._Fl.getArray()[:] = self.asm.residual(xl, xdl, t)
        F.zeroEntries()
        self.dm.localToGlobal(self._Fl, F, addv=PETSc.InsertMode.ADD_VALUES)
        self._ev_res.end()

    def ijacobian(self, ts, t, X, Xdot, shift, J, P):
        self._ev_jac.begin()
        xl, xdl = self.local_arrays(X, t, Xdot)
        compat.coo_set_values(P, self.asm.jacobian_values(xl, xdl, t, shift))
        P.assemble()
        if J != P:
            J.assemble()
        self._ev_jac.end()

    def create_matrix(self) -> PETSc.Mat:
        if self.J is None:
            self.J = self.asm.create_matrix()
        return self.J

    def auto_residual_scales(self, t: float, shift: float) -> dict[str, float]:
        """Set each field's residual scale to the mean |diagonal| of its
        Jacobian rows at the initial state, so that all rows are O(1)."""
        J = self.create_matrix()
        xl, xdl = self.local_arrays(self.X, t)
        for sc in self.scales.values():
            sc.rscale = 1.0
        compat.coo_set_values(J, self.asm.jacobian_values(xl, xdl, t, shift))
        J.assemble()
        diag = J.getDiagonal()
        names, isets, sub = self.dm.createFieldDecomposition()
        out = {}
        for name, iset in zip(names, isets):
            d = diag.getSubVector(iset)
            n = d.getSize()
            mean = d.norm(PETSc.NormType.NORM_1) / max(n, 1)
            diag.restoreSubVector(iset, d)
            self.scales[name].rscale = mean if mean > 0 and math.isfinite(mean) else 1.0
            out[name] = self.scales[name].rscale
        return out


class TimeStepper:
    """Backward-Euler TS on a ``Problem`` with growth-limited steps and monitors."""

    def __init__(self, problem: Problem, control: StepControl,
                 monitor: Callable[[int, float, float], None] | None = None):
        self.problem, self.control = problem, control
        ts = self.ts = PETSc.TS().create(comm=problem.dm.comm)
        ts.setDM(problem.dm)
        ts.setProblemType(PETSc.TS.ProblemType.NONLINEAR)
        ts.setType(PETSc.TS.Type.BEULER)
        ts.setIFunction(problem.ifunction, problem.dm.createGlobalVec())
        J = problem.create_matrix()
        ts.setIJacobian(problem.ijacobian, J, J)
        ts.setTime(0.0)
        ts.setTimeStep(control.dt_initial)
        ts.setMaxTime(control.final_time)
        ts.setMaxSteps(10 ** 9)
        ts.setExactFinalTime(PETSc.TS.ExactFinalTime.MATCHSTEP)
        ts.setMaxSNESFailures(-1)          # every failed solve is retried with a smaller step,
        ts.setMaxStepRejections(8)         # at most 8 times in a row (-ts_max_reject /
        ts.setFromOptions()                # -ts_max_step_rejections override)
        ts.setErrorIfStepFails(False)
        ts.setPostStep(self._post_step)
        self._user_monitor = monitor
        ts.setMonitor(self._monitor)
        self.rejected = 0
        self.error = None

    def _post_step(self, ts):
        """Grow the step, clipped to the largest step and to the final time."""
        c = self.control
        dt = min(ts.getTimeStep() * c.growth, c.dt_max)
        remaining = c.final_time - ts.getTime()
        if remaining > 0:
            ts.setTimeStep(min(dt, remaining))

    def _monitor(self, ts, step, t, X):
        """Call the user's monitor; an exception stops the run cleanly and is
        re-raised by ``solve`` (exceptions must not cross the C callback)."""
        if self._user_monitor is None or self.error is not None:
            return
        try:
            self._user_monitor(step, t, X)
        except Exception as e:  # noqa: BLE001 - re-raised after TSSolve returns
            self.error = e
            ts.setConvergedReason(PETSc.TS.ConvergedReason.CONVERGED_USER)

    def solve(self) -> int:
        """Run to the final time; returns TS converged reason (negative: failed)."""
        self.ts.solve(self.problem.X)
        if self.error is not None:
            raise self.error
        self.rejected = self.ts.getStepRejections()
        return int(self.ts.getConvergedReason())

    def iterations(self) -> tuple[int, int]:
        return self.ts.getSNESIterations(), self.ts.getKSPIterations()
