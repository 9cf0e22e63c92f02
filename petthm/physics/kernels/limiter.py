"""The flux limiter of ``-thm_heat_transport limited``: algebraic flux
correction of the upwinded heat transport (theory manual, "Discrete bounds").

The upwinding (``kernels/transport.py``) adds to row i the diffusion
sum_j d_ij (T_i - T_j).  Taking it away again gives back the Galerkin
scheme; each element pair (i, j) carries the anti-diffusive flux

    g_ij = d_ij (T_i - T_j) = -g_ji

that does so.  The limited scheme gives back alpha_ij g_ij, alpha_ij =
alpha_ji in [0, 1] (the residual keeps (1 - alpha_ij) d_ij (T_i - T_j)),
with Zalesak's nodal factors in the form of stationary algebraic flux
correction (Kuzmin, "Algebraic flux correction I", 2012; Barrenechea,
John and Knobloch, 2017):

    P_i+ = sum_e,j max(0, g_ij),         P_i- = sum_e,j min(0, g_ij),
    Q_i+ = gamma q_i (T_i^max - T_i),    Q_i- = gamma q_i (T_i^min - T_i),
    q_i = sum_e,j d_ij,   T_i^max, T_i^min: the extremes of T over the
    elements of node i (the node itself included),
    R_i+- = min(1, Q_i+- / P_i+-) = min(1, gamma |T_i^max,min - T_i| / max(|P_i+-| / q_i, dT0)),
    dT0 = 1e-6 K (|P| / q = 0 where q_i = 0),
    alpha_ij = min(R_i+, R_i-, R_j+, R_j-).

Zalesak's alpha takes R_i+ and R_j- where g_ij > 0 (R_i- and R_j+
otherwise); here the limiter is evaluated at the start of the step (below)
and the sign of the step's own flux is not known, so alpha is the smaller
of both: whichever way the flux goes, the fluxes into node i add at most
Q_i+ and take away at most |Q_i-|.  A local extremum has Q_i+ = 0 or Q_i-
= 0 and keeps the upwinded row (an M-matrix row), so no new extremum
forms; where T is smooth and away from its extremes R = 1 and the scheme
is the Galerkin one, second order.  ``gamma``: how much of the bound room each
node offers, relative to its upwinding diffusion q_i; with gamma >= 1 a
linear T is not limited in the interior of a uniform 1D mesh (P_i = q_i
|dT| / 2 there).

The limiter is evaluated at the state at the start of the step (backward
Euler's x - x_dot / shift), so that while Newton solves the step alpha is a
constant and the step's equations are those of a fixed linear combination
of the upwinded and the Galerkin operators: Newton keeps its quadratic
convergence and the Jacobian is exact (with alpha from the state being
solved for, alpha switches between Newton iterates, which then cycle;
theory manual, "Limited flux correction").  The start's bounds do not
bound the step's end: with long steps the solved state's fluxes can exceed
the room of its own neighbourhoods, an extremum forms, the next step
(limited at it) takes it away, and the temperature oscillates from step to
step.  So a step is settled at its solved state (``tighten``, called from
Newton's convergence test, ``solvers/settling.py``): at a node that is an
extreme of the solved state's neighbourhood (no room: Q+ = 0 or Q- = 0)
the limited fluxes must not push further beyond it; where they do by more
than ``SETTLE`` of the temperature range (their sum over q_i), the factors
of the node's pairs fall to the solved state's, and Newton solves the
step's new equations on from where it stands.  alpha only falls within a
step; after ``MAX_TIGHTENINGS`` passes the pairs still in excess are
upwinded, so that the passes end.  The accepted state satisfies Zalesak's
condition at every extreme of its own (to ``SETTLE``), which is what the
discrete maximum principle needs: the node where the state is largest is
such an extreme, and its row is the upwinded one there.

The sums run over all cells of the region: a pass before the assembly
(``__call__``, the assembly's ``prepare`` hook), the nodal sums and
extremes completed across processes through the mesh's section star
forest, so that a run gives the same alpha on any number of ranks.
Where a node has no room (Q = 0: its temperature is an extreme of its
neighbours', as everywhere in a uniform start), R = 0 even without a flux
to limit (P = 0): the flux that the step itself creates there is upwinded;
the floor dT0 keeps R continuous there, and where the state has no flow
(q_i = 0).  A node with a Dirichlet condition has R = 1: its row is the
condition, and the fluxes to its neighbours are limited by their room (a
boundary node is an extreme of its one-sided patch wherever the
temperature varies across the boundary: with R = 0 every boundary of a
smooth solution would be upwinded).  Tied nodes (the rock's wall nodes of
the equilibrium exchange) keep the room of their own side's cells.
"""
from __future__ import annotations

import numpy as np

from petthm.discretisation.context import CellContext
from petthm.physics.kernels.transport import Upwinding, upwinding_diffusion

#: the limiter's default bound room (module docstring)
GAMMA = 1.0
#: K: temperature differences below this count as none in the limiter's ratios
FLOOR = 1e-6
#: the scaled unknowns of two evaluations' start states differ by no more than this within a step
START_ROUNDOFF = 1e-12
#: a solved state settles its step when the limited fluxes push none of its local extremes further
#: by more than this fraction of the state's temperature range (``tighten``;
#: -thm_heat_limiter_settle)
SETTLE = 1e-4
#: passes of lowering alpha in one step, after which the pairs still in excess are upwinded
MAX_TIGHTENINGS = 6


def _logical_and():
    from mpi4py import MPI
    return MPI.LAND


def _logical_or():
    from mpi4py import MPI
    return MPI.LOR


def step_start(xl, xdl, shift):
    """The state the limiter is evaluated at: backward Euler's x - x_dot /
    shift, the start of the step (x itself without a step)."""
    return xl - xdl / shift if shift > 0.0 else xl


class FluxLimiter:
    """The limiter of one region's upwinded heat transport; ``keep`` holds
    1 - alpha_ij of every element of the region (ncells, nb, nb)."""

    def __init__(self, gamma: float = GAMMA, settle: float = SETTLE):
        self.gamma, self.settle = gamma, settle
        self.upwinding: Upwinding | None = None
        self.keep: np.ndarray | None = None
        self._vecs = None
        self._dirichlet = None
        self._start = None                    # (the start state, t, shift) of ``keep``
        self.t = self.shift = 0.0             # the step's time and 1/dt
        self.tightenings = 0                  # passes of ``tighten`` in this step

    def bind(self, u: Upwinding) -> None:
        self.upwinding = u

    def __call__(self, asm, xl, xdl, t, shift) -> None:
        xl = step_start(xl, xdl, shift)
        if self._same_start(asm, xl, t, shift):
            return
        self.t, self.shift, self.tightenings = t, shift, 0
        self.keep = self._keep(asm, xl, xdl, t, shift)

    def _keep(self, asm, xl, xdl, t, shift) -> np.ndarray:
        """1 - alpha_ij of every element for the state ``xl`` (ncells, nb, nb)."""
        nodal, pairs = self._nodal(asm, xl, xdl, t, shift)
        return self._keep_where(asm, nodal, pairs, np.ones(asm.disc.nlocal, dtype=bool))

    def _nodal(self, asm, xl, xdl, t, shift):
        """The nodal sums of the state ``xl`` (completed across ranks) and, per
        batch of cells, (cells, dofs, g_ij, d_ij, T)."""
        u = self.upwinding
        nodal = _NodalSums(asm.disc.nlocal)
        pairs = []
        for cells in asm.chunks():
            D, dT, T = upwinding_diffusion(u, CellContext(asm, cells, xl, xdl, t, shift))
            idx = asm.dofs(u.heat.T)[cells]
            nodal.add(idx, D * dT, D, T)
            pairs.append((cells, idx, D * dT, D, T))
        nodal.complete(asm, self._vectors(asm))
        return nodal, pairs

    def _keep_where(self, asm, nodal, pairs, nodes) -> np.ndarray:
        """1 - alpha_ij from the factors R of ``nodal`` on the pairs with a
        node in ``nodes`` (a mask of the local dofs), 0 elsewhere."""
        R = np.minimum(*nodal.ratios(self.gamma))
        R[self._prescribed(asm)] = 1.0
        nb = pairs[0][1].shape[1] if pairs else 0
        keep = np.zeros((asm.mesh.ncells, nb, nb))
        for cells, idx, *_ in pairs:
            r = R[idx]
            touched = nodes[idx]
            keep[cells] = np.where(touched[:, :, None] | touched[:, None, :],
                                   1.0 - np.minimum(r[:, :, None], r[:, None, :]), 0.0)
        return keep

    def tighten(self, asm, xl) -> bool:
        """At a solved state ``xl`` of the step: the nodes that are extremes
        of the state's neighbourhoods (no room) and that the step's limited
        fluxes push further beyond, their sum over q_i (a temperature) more
        than ``settle`` times the state's temperature range.  On their pairs
        alpha_ij falls to the factors of that state (alpha only falls within
        a step), and the step's equations are to be solved again (True);
        after ``MAX_TIGHTENINGS`` such passes those pairs are upwinded
        (alpha = 0).  Collective."""
        xdl = (xl - self._start[0]) * self.shift
        nodal, pairs = self._nodal(asm, xl, xdl, self.t, self.shift)
        applied = _NodalSums(asm.disc.nlocal)
        for cells, idx, g, D, T in pairs:
            applied.add(idx, (1.0 - self.keep[cells]) * g, D, T)
        applied.complete(asm, self._vectors(asm))
        excess = nodal.excess(applied)
        excess[self._prescribed(asm)] = 0.0
        comm = asm.disc.mesh.dm.comm.tompi4py()
        span = nodal.span(comm)
        over = excess > self.settle * span
        if not comm.allreduce(bool(over.any()), op=_logical_or()):
            return False
        self.tightenings += 1
        keep = self._keep_where(asm, nodal, pairs, over)
        if self.tightenings >= MAX_TIGHTENINGS:
            keep = np.where(keep > 0.0, 1.0, keep)
        self.keep = np.maximum(self.keep, keep)
        return True

    def _same_start(self, asm, start, t, shift) -> bool:
        """Whether ``keep`` belongs to this step's start already (every
        residual and Jacobian of a step has the same start, up to the
        round-off of x - x_dot / shift): decided on all ranks together, as
        the factors are completed across them."""
        last, self._start = self._start, (start.copy(), t, shift)
        same = last is not None and last[1:] == (t, shift) and last[0].shape == start.shape and \
            (start.size == 0 or float(np.abs(start - last[0]).max()) <= START_ROUNDOFF)
        comm = asm.disc.mesh.dm.comm.tompi4py()
        return bool(comm.allreduce(same, op=_logical_and()))

    def _prescribed(self, asm) -> np.ndarray:
        """The local dofs of this field with a Dirichlet condition: their rows
        are the condition, so their bounds need no room (R = 1 there); the
        fluxes between them and their neighbours are limited by the
        neighbours' room alone."""
        if self._dirichlet is None:
            name = self.upwinding.heat.T
            parts = [dd.dofs.ravel() for dd in asm.disc.dirichlet if dd.field == name]
            self._dirichlet = np.concatenate(parts) if parts else np.zeros(0, dtype=int)
        return self._dirichlet

    def _vectors(self, asm):
        """The mesh's section star forest (local dofs to their owners' global
        ones) and the number of this rank's owned dofs."""
        if self._vecs is None:
            dm = asm.disc.mesh.dm
            self._vecs = (dm.getSectionSF(), dm.getGlobalSection().getStorageSize())
        return self._vecs


class _NodalSums:
    """P+-, q and the extremes of T per local dof."""

    def __init__(self, n: int):
        self.n = n
        self.pplus, self.pminus, self.q, self.T = (np.zeros(n) for _ in range(4))
        self.tmax = np.full(n, -np.inf)
        self.tmin = np.full(n, np.inf)
        self.touched = np.zeros(n, dtype=bool)

    def add(self, idx, g, D, T):
        flat = idx.ravel()
        self.pplus += np.bincount(flat, np.maximum(g, 0.0).sum(axis=2).ravel(), self.n)
        self.pminus += np.bincount(flat, np.minimum(g, 0.0).sum(axis=2).ravel(), self.n)
        self.q += np.bincount(flat, D.sum(axis=2).ravel(), self.n)
        nb = idx.shape[1]
        np.maximum.at(self.tmax, flat, np.repeat(T.max(axis=1), nb))
        np.minimum.at(self.tmin, flat, np.repeat(T.min(axis=1), nb))
        self.T[flat] = T.ravel()
        self.touched[flat] = True

    def complete(self, asm, vecs):
        """The sums and extremes over every rank's cells (the dofs that are
        not unknowns of their own, tied ones, keep this rank's): reduced onto
        the owning rank through the mesh's section star forest, sent back to
        the ghosts."""
        from mpi4py import MPI
        sf, nroots = vecs
        free = asm.disc.global_index >= 0
        big = np.finfo(float).max
        for name, op, fill in (("pplus", MPI.SUM, 0.0), ("pminus", MPI.SUM, 0.0), ("q", MPI.SUM, 0.0),
                               ("tmax", MPI.MAX, -big), ("tmin", MPI.MIN, big)):
            a = getattr(self, name)
            leaf = np.where(self.touched, a, fill)
            root = np.full(nroots, fill)
            sf.reduceBegin(MPI.DOUBLE, leaf, root, op)
            sf.reduceEnd(MPI.DOUBLE, leaf, root, op)
            got = np.full_like(leaf, fill)
            sf.bcastBegin(MPI.DOUBLE, root, got, MPI.REPLACE)
            sf.bcastEnd(MPI.DOUBLE, root, got, MPI.REPLACE)
            setattr(self, name, np.where(free & self.touched, got, a))

    def excess(self, applied: _NodalSums) -> np.ndarray:
        """Per local dof that is an extreme of its neighbourhood (no room,
        Q+ = 0 or Q- = 0), the fluxes ``applied`` towards beyond it (their
        P+ or -P-) over q_i: a temperature (0 elsewhere and where q_i = 0)."""
        q = np.where(self.q > 0.0, self.q, 1.0)
        up = np.where(self.tmax <= self.T, applied.pplus / q, 0.0)
        down = np.where(self.tmin >= self.T, -applied.pminus / q, 0.0)
        return np.where(self.q > 0.0, np.maximum(np.maximum(up, down), 0.0), 0.0)

    def span(self, comm) -> float:
        """The range of T over the region, on all ranks together."""
        from mpi4py import MPI
        hi = float(self.tmax[self.touched].max()) if self.touched.any() else -np.inf
        lo = float(self.tmin[self.touched].min()) if self.touched.any() else np.inf
        return comm.allreduce(hi, op=MPI.MAX) - comm.allreduce(lo, op=MPI.MIN)

    def ratios(self, gamma):
        """R+ and R- per local dof: Q/P written as gamma times the room over
        the mean difference the fluxes span, P/q, that at least ``FLOOR``.
        R is then continuous where the fluxes vanish and where the flow does
        (a uniform start, a state without flow: q = 0, P/q = 0), so that
        round-off does not switch it between 0 and 1."""
        q = np.where(self.q > 0.0, self.q, 1.0)
        spread_p = np.where(self.q > 0.0, self.pplus / q, 0.0)
        spread_m = np.where(self.q > 0.0, -self.pminus / q, 0.0)
        room_p = np.maximum(self.tmax - self.T, 0.0)
        room_m = np.maximum(self.T - self.tmin, 0.0)
        Rp = np.minimum(1.0, gamma * room_p / np.maximum(spread_p, FLOOR))
        Rm = np.minimum(1.0, gamma * room_m / np.maximum(spread_m, FLOOR))
        return Rp, Rm
