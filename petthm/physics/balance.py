"""Global mass and energy balance per time step (theory manual, "Equations: fracture heat").

For a conserved quantity Q (fluid volume, or energy) with stored amount

    S(X) = sum over regions of int s(X) dx        (an explicit integrand)

the balance residual of the step t_n -> t_n+1 is

    [ S(X_n+1) - S(X_n) - dt (W + B) ] / max(dt (|W| + |B|), |S(X_n+1) - S(X_n)|, REST (S_1 + dt B_1))

with W the net inflow from the wells (evaluated from the well model) and B
the net inflow through Dirichlet boundaries, which is the sum of the
residual rows of the constrained dofs (the variationally consistent
boundary flux).  S_1 and B_1 are what a rise of every unknown by its scale
(``Problem.scales``; the Dirichlet values kept) would store and drive
through the boundaries: a step whose flows and change are below ``REST``
of them is at rest (a shut-in), and its residual, round-off over
round-off, is not reported as a balance error of order 1.  The
stored amount is integrated directly from the fields, not taken from the
residual, so the residual measures the scheme's conservation together with
the nonlinear solver's convergence.
"""
from __future__ import annotations

from dataclasses import dataclass

from petthm.discretisation.model import Region


@dataclass(frozen=True)
class Conserved:
    """One balance: its name, the fields whose equations it sums (the well
    terms of each count: fracture and matrix wells), and the stored-amount
    integrand per region."""
    name: str
    fields: tuple
    storage: dict            # {Domain: integrand(ctx) -> (nc, nq)}


#: below this fraction of the stored amount of a unit change a step is at rest (see the module docstring)
REST = 1e-6


class BalanceMonitor:
    """Evaluates every ``Conserved`` balance of a problem after each step."""

    def __init__(self, problem, balances: list[Conserved]):
        self.problem, self.balances = problem, balances
        self._prev = None
        self._unit: dict[str, tuple[float, float]] = {}
        self.last_residual = None         # scaled local residual of the last step (reactions)

    def stored(self, xl, t) -> dict:
        out = {}
        for b in self.balances:
            out[b.name] = sum(self.problem.region(Region(d)).integrate(xl, f, t) for d,
                              f in b.storage.items())
        return out

    def _unit_change(self, X, t: float, stored: dict) -> dict:
        """Per balance: (|S(X + 1) - S(X)|, |B(X + 1) - B(X)|): what a rise of
        every scaled unknown by 1 (each field by its scale; the Dirichlet
        values kept) stores, and drives through the boundaries (the second
        matters where nothing is stored: an incompressible fluid in a rigid
        fracture).  Residuals without rates: the boundary flows of the states."""
        pb = self.problem
        xl, xdl = pb.local_arrays(X, t)
        at_rest = pb.step_residual(X, t, 0.0, xl, xdl).copy()
        Y = X.copy()
        Y.shift(1.0)
        yl, ydl = pb.local_arrays(Y, t)
        raised = self.stored(yl, t)
        rl = pb.step_residual(Y, t, 0.0, yl, ydl)
        Y.destroy()
        out = {}
        for b in self.balances:
            names = pb.dirichlet_boundaries(b.fields)
            inflow = sum(abs(pb.reaction(rl, b.fields, (name,)) - pb.reaction(at_rest, b.fields, (name,)))
                         for name in names)
            out[b.name] = (abs(raised[b.name] - stored[b.name]), inflow)
        return out

    def __call__(self, t: float, X) -> dict:
        """Balance residuals of the step that ended at ``t`` (0 at the first call);
        NaN unless the time integrator is backward Euler (the step's rate is
        taken as (X - X_prev)/dt)."""
        from petsc4py import PETSc
        pb = self.problem
        if PETSc.Options().getString("ts_type", "beuler") not in ("beuler", "be"):
            return {f"{b.name}_balance": float("nan") for b in self.balances}
        if self._prev is None:
            xl, _ = pb.local_arrays(X, t)
            self._prev = (t, X.copy(), self.stored(xl, t))
            self._unit = self._unit_change(X, t, self._prev[2])
            return {f"{b.name}_balance": 0.0 for b in self.balances}
        t0, X0, S0 = self._prev
        dt = t - t0
        Xdot = X.duplicate()
        Xdot.waxpy(-1.0, X0, X)
        Xdot.scale(1.0 / dt)
        xl, xdl = pb.local_arrays(X, t, Xdot)
        rl = pb.step_residual(X, t, 1.0 / dt, xl, xdl)
        self.last_residual = rl
        S1 = self.stored(xl, t)
        out = {}
        for b in self.balances:
            W = Wabs = 0.0
            for f in b.fields:
                w, wa = pb.well_inflow(xl, t, f)
                W, Wabs = W + w, Wabs + wa
            names = pb.dirichlet_boundaries(b.fields)
            B = pb.reaction(rl, b.fields, names)          # each constrained dof once (edges of two faces)
            Babs = sum(abs(pb.reaction(rl, b.fields, (name,))) for name in names)
            dS = S1[b.name] - S0[b.name]
            unit_stored, unit_inflow = self._unit[b.name]
            scale = max(dt * (Wabs + Babs), abs(dS), REST * (unit_stored + dt * unit_inflow), 1e-300)
            out[f"{b.name}_balance"] = (dS - dt * (W + B)) / scale
            out[f"{b.name}_boundary_inflow"] = B
        X0.destroy()
        self._prev = (t, X.copy(), S1)
        Xdot.destroy()
        return out
