"""The multiplicative (block Gauss-Seidel) sweep of ``fieldsplit.VIFieldSplit``
over the lower blocks only.

With splits 1..n of the unknowns, block Gauss-Seidel solves split k for

    A_kk y_k = x_k - sum_{j<k} A_kj y_j,

each A_kk^-1 by the split's own KSP.  PETSc's PCFIELDSPLIT (multiplicative,
more than two splits) forms the sum as the product of split k's whole row
block with the whole y, zeros included, and copies every split's row block
at each set-up.  When a split before the mechanics holds other fields (the
heat fields first, Scene 3's order) that product runs over all the
elasticity's rows and columns (the bulk of the matrix) at every application,
although only the columns of the splits before k are non-zero.  This sweep
keeps, per split, only A_k,<k (its rows, the columns of the splits before
it), so an application multiplies each matrix entry below the block
diagonal once and none above it.  The result is the same preconditioner
(PETSc's sweep, to round-off).
"""
from __future__ import annotations

import numpy as np
from petsc4py import PETSc

from petthm import compat


class LowerSweep:
    """Block Gauss-Seidel over ``isets`` (the splits in their order) with the
    split solvers ``ksps`` (set up on the diagonal blocks) and the lower
    blocks of ``P`` (the preconditioning matrix, as PCFIELDSPLIT uses by
    default)."""

    def __init__(self, P: PETSc.Mat, isets: list[PETSc.IS], ksps: list[PETSc.KSP], names: list[str]):
        comm = P.getComm()
        x = P.createVecRight()
        self.ksps = ksps
        self.events = [PETSc.Log.Event(f"VISweep_{name}") for name in names]   # -log_view, by split
        self.scatters, self.rhs, self.sol, self.lower, self.lower_scatter = [], [], [], [], []
        self.lower_in, self.lower_out = [], []
        for k, iset in enumerate(isets):
            n = iset.getLocalSize()
            v = PETSc.Vec().createMPI((n, PETSc.DECIDE), comm=comm)
            self.rhs.append(v)
            self.sol.append(v.duplicate())
            self.scatters.append(PETSc.Scatter().create(x, iset, v, None))
            if k == 0:
                for lst in (self.lower, self.lower_scatter, self.lower_in, self.lower_out):
                    lst.append(None)
                continue
            before = np.sort(np.concatenate([s.getIndices() for s in isets[:k]])).astype(compat.INT)
            cols = PETSc.IS().createGeneral(before, comm=comm)
            L = P.createSubMatrix(iset, cols)
            vin, vout = L.createVecs()
            self.lower.append(L)
            self.lower_in.append(vin)
            self.lower_out.append(vout)
            self.lower_scatter.append(PETSc.Scatter().create(x, cols, vin, None))
            cols.destroy()
        x.destroy()

    def apply(self, x: PETSc.Vec, y: PETSc.Vec) -> None:
        """y = the sweep's answer to x (every split solved once, in order)."""
        INSERT = PETSc.InsertMode.INSERT
        FORWARD, REVERSE = PETSc.ScatterMode.FORWARD, PETSc.ScatterMode.REVERSE
        y.set(0.0)
        for k, ksp in enumerate(self.ksps):
            rhs, sol = self.rhs[k], self.sol[k]
            self.scatters[k].scatter(x, rhs, INSERT, FORWARD)
            if self.lower[k] is not None:
                self.lower_scatter[k].scatter(y, self.lower_in[k], INSERT, FORWARD)
                self.lower[k].mult(self.lower_in[k], self.lower_out[k])
                rhs.axpy(-1.0, self.lower_out[k])
            self.events[k].begin()
            ksp.solve(rhs, sol)
            self.events[k].end()
            if ksp.getConvergedReason() < 0:
                # a split solver that failed (a zero pivot, a diverged inner
                # Krylov method): hand the outer Krylov method a NaN, which it
                # reports as a failed linear solve (the step is cut), rather
                # than a wrong correction
                y.set(float("nan"))
                return
            self.scatters[k].scatter(sol, y, INSERT, REVERSE)

    def destroy(self) -> None:
        for lst in (self.scatters, self.rhs, self.sol, self.lower, self.lower_scatter, self.lower_in,
                    self.lower_out):
            for obj in lst:
                if obj is not None:
                    obj.destroy()
            lst.clear()
