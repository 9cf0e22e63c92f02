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
import sys
import traceback
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


def direct_solver_defaults(comm) -> dict[str, str]:
    """A sparse direct solve: MUMPS, else SuperLU_dist, else PETSc's LU
    (serial) or, in parallel, PETSc's LU on a redundant copy of the matrix."""
    out = {"ksp_type": "gmres", "ksp_max_it": "50"}
    for package in ("mumps", "superlu_dist"):
        if PETSc.Sys.hasExternalPackage(package):
            return dict(out, pc_type="lu", pc_factor_mat_solver_type=package)
    # PETSc's own LU does not pivot: rows with a zero diagonal (the contact
    # multipliers) are first swapped with rows that have a non-zero there, and
    # a zero pivot that still occurs is shifted (GMRES corrects the inexact LU)
    lu = {"pc_factor_nonzeros_along_diagonal": "", "pc_factor_shift_type": "nonzero"}
    if comm.size == 1:
        return dict(out, pc_type="lu", **lu)
    # on the gathered copy, PETSc 3.26.1's inode LU stopped with "Node size not
    # yet supported" (error 56: Scene 2 with lumped heat terms on 2 ranks), so
    # the copy is factored without inodes
    redundant = {"redundant_" + k: v for k, v in lu.items()}
    return dict(out, pc_type="redundant", redundant_pc_type="lu", mat_no_inode="", **redundant)


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
    components: tuple | None = None        # constrained components of a vector field (None: all)

    def entry(self):
        """The boundary entry of ``fields.Discretisation``."""
        return self.boundary if self.components is None else (self.boundary, self.components)


@dataclass
class StepControl:
    final_time: float
    dt_initial: float
    growth: float = 1.0
    dt_max: float = math.inf
    hit_times: tuple = ()        # times to land on exactly


class Problem:
    """A transient FE problem: fields, model (terms on the matrix cells, the
    fracture faces and at well nodes), Dirichlet data, ties, initial state."""

    def __init__(self, disc: Discretisation, model: Model, scales: dict[str, FieldScale],
                 dirichlet: list[Dirichlet], quad_degree: int | None = None):
        self.disc, self.model, self.dm = disc, model, disc.mesh.dm
        self.scales = scales
        for t in disc.ties:
            a, b = scales[t.field], scales[t.target]
            if (a.scale, a.offset) != (b.scale, b.offset):
                raise ValueError(f"tied fields {t.field} and {t.target} need the same unknown scaling")
        self.inv_rscale = Assembler.default_inv_rscale(disc, scales)
        self.assemblers = [Assembler(disc, model, scales, quad_degree, region=r, inv_rscale=self.inv_rscale)
                           for r in model.regions()]
        self.asm = self.assemblers[0]
        self.points = [_PointDofs(disc, pt) for pt in model.points]
        self._dirichlet = list(dirichlet)
        byname = {(d.field, d.boundary, d.components): d for d in dirichlet}
        self._bc = []
        for dd in disc.dirichlet:
            d = byname.get((dd.source or dd.field, dd.boundary, dd.components))
            if d is not None:
                self._bc.append((d, dd))
        self.X = self.dm.createGlobalVec()
        self.X.setName("solution")
        self._Xl = self.dm.createLocalVec()
        self._Xdl = self.dm.createLocalVec()
        self._Fl = self.dm.createLocalVec()
        self._tie_setup()
        self.J = None
        self._ev_res = PETSc.Log.Event("thm.residual")
        self._ev_jac = PETSc.Log.Event("thm.jacobian")

    # -- ties: matrix dofs on the fracture walls that are fracture unknowns --------
    def _tie_setup(self):
        ties = self.disc.ties
        self._tie_dofs = np.concatenate([t.dofs for t in ties]).astype(compat.INT) if ties else \
            np.zeros(0, dtype=compat.INT)
        target = np.concatenate([t.target_global for t in ties]).astype(compat.INT) if ties else \
            np.zeros(0, dtype=compat.INT)
        self._tie_vec = PETSc.Vec().createSeq(len(target), comm=PETSc.COMM_SELF)
        src = PETSc.IS().createGeneral(target, comm=PETSc.COMM_SELF)
        self._tie_scatter = PETSc.Scatter().create(self.X, src, self._tie_vec, None)

    def _tie_values(self, X, xl):
        if not self.disc.ties:
            return
        self._tie_scatter.scatter(X, self._tie_vec, PETSc.InsertMode.INSERT_VALUES,
                                  PETSc.ScatterMode.FORWARD)
        xl[self._tie_dofs] = self._tie_vec.getArray()

    def _tie_add(self, rl, F):
        """Add the residual rows of tied dofs into their targets' rows of F."""
        if not self.disc.ties:
            return
        self._tie_vec.getArray()[:] = rl[self._tie_dofs]
        self._tie_scatter.scatter(self._tie_vec, F, PETSc.InsertMode.ADD_VALUES,
                                  PETSc.ScatterMode.REVERSE)

    # -- local vectors with Dirichlet values ------------------------------------
    def local_arrays(self, X: PETSc.Vec, t: float, Xdot: PETSc.Vec | None = None):
        """Local (scaled) solution and rate arrays with Dirichlet and tied values inserted."""
        self.dm.globalToLocal(X, self._Xl, addv=PETSc.InsertMode.INSERT_VALUES)
        xl = self._Xl.getArray()
        xdl = self._Xdl.getArray()
        self._tie_values(X, xl)
        if Xdot is not None:
            self.dm.globalToLocal(Xdot, self._Xdl, addv=PETSc.InsertMode.INSERT_VALUES)
            self._tie_values(Xdot, xdl)
        else:
            xdl[:] = 0.0
        for d, dofs in self._bc:
            sc = self.scales[dofs.field]
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

    def point_value(self, name: str, point, X: PETSc.Vec | None = None, t: float = 0.0,
                    component: int = 0) -> float:
        """SI value of a field's component at the node nearest to ``point`` (all ranks)."""
        from mpi4py import MPI
        v = self.field_values(name, X, t)[:, component]
        x = self.disc.field_node_coordinates(name)
        d = np.linalg.norm(x - np.asarray(point)[None, :x.shape[1]], axis=1) if len(v) else np.zeros(0)
        k = int(np.argmin(d)) if len(d) else 0
        best = (float(d[k]), float(v[k])) if len(d) else (np.inf, 0.0)
        return self.dm.comm.tompi4py().allreduce(best, op=MPI.MINLOC)[1]

    def max_nodal_error(self, name: str, exact: Callable, X: PETSc.Vec | None = None, t: float = 0.0,
                        component: int = 0) -> float:
        """max over all nodes and ranks of |value - exact(node coordinates)| of a field's component (SI)."""
        from mpi4py import MPI
        v = self.field_values(name, X, t)[:, component]
        x = self.disc.field_node_coordinates(name)
        err = float(np.abs(v - exact(x)).max()) if len(v) else 0.0
        return self.dm.comm.tompi4py().allreduce(err, op=MPI.MAX)

    def variable_bounds(self) -> tuple[PETSc.Vec, PETSc.Vec]:
        """Global (scaled) lower and upper bounds of the unknowns from
        ``model.bounds`` (everything else unbounded)."""
        lo, hi = self.dm.createLocalVec(), self.dm.createLocalVec()
        lo.set(PETSc.NINFINITY)
        hi.set(PETSc.INFINITY)
        for name, (a, b) in self.model.bounds.items():
            sc, dofs = self.scales[name], self.disc.field_local_dofs(name)
            if a is not None:
                lo.getArray()[dofs] = (a - sc.offset) / sc.scale
            if b is not None:
                hi.getArray()[dofs] = (b - sc.offset) / sc.scale
        XL, XU = self.dm.createGlobalVec(), self.dm.createGlobalVec()
        self.dm.localToGlobal(lo, XL, addv=PETSc.InsertMode.INSERT_VALUES)
        self.dm.localToGlobal(hi, XU, addv=PETSc.InsertMode.INSERT_VALUES)
        return XL, XU

    def field_splits(self, space: np.ndarray | None = None) -> list[tuple[str, PETSc.IS]]:
        """(field name, sorted global indices) of every field, the rigid-body
        modes of ``u`` composed on its index set as "nearnullspace" (for
        GAMG on the displacement block, petsc-notes "Field split").
        ``space``: this rank's part of the sorted global unknowns of a reduced
        system (the inactive set of a VI solve); the index sets are then
        restricted to it and numbered in the reduced system."""
        names, isets, _ = self.dm.createFieldDecomposition()
        offset = 0 if space is None else self._space_offset(space)
        out = []
        for name, iset in zip(names, isets):
            if space is not None:
                idx = iset.getIndices()
                pos = np.searchsorted(space, idx[np.isin(idx, space)]) + offset
                iset = PETSc.IS().createGeneral(pos.astype(compat.INT), comm=self.dm.comm)
            if name == "u":
                iset.compose("nearnullspace", self.rigid_body_modes(iset, space, offset))
            out.append((name, iset))
        return out

    def rigid_body_modes(self, iset: PETSc.IS, space: np.ndarray | None = None, offset: int = 0) -> PETSc.NullSpace:
        """Translations and rotations of the u unknowns in ``iset`` (owned,
        sorted indices; components fixed by rollers are absent, so the
        vectors are built per unknown, not with a block size), orthonormalised.
        ``space``, ``offset``: the reduced system ``iset`` numbers (see
        ``field_splits``); default: all unknowns."""
        d = self.disc.mesh.dim
        dofs = self.disc.field_local_dofs("u")                      # (n, d) local
        x = self.disc.field_node_coordinates("u")
        x = x - x.mean(axis=0) if len(x) else x
        gidx = self.disc.global_index[dofs]
        own = self.disc._owned(gidx) & ~np.isin(dofs, self._constrained_local())
        if space is not None:
            own &= np.isin(gidx, space)
        target = gidx[own] if space is None else np.searchsorted(space, gidx[own]) + offset
        rows = np.searchsorted(iset.getIndices(), target)
        comp = np.broadcast_to(np.arange(d), dofs.shape)[own]
        xs = np.broadcast_to(x[:, None, :], dofs.shape + (d,))[own]
        modes = [np.asarray(comp == k, dtype=float) for k in range(d)]
        rot = [(0, 1)] if d == 2 else [(0, 1), (1, 2), (2, 0)]
        for a, b in rot:                                            # rotation in the (a, b) plane
            modes.append(np.where(comp == a, -xs[:, b], 0.0) + np.where(comp == b, xs[:, a], 0.0))
        vecs = []
        n = iset.getLocalSize()
        for m in modes:
            v = PETSc.Vec().createMPI((n, PETSc.DECIDE), comm=self.dm.comm)
            v.getArray()[rows] = m
            for w in vecs:                                          # modified Gram-Schmidt
                v.axpy(-v.dot(w), w)
            nv = v.norm()
            if nv > 1e-12:
                v.scale(1.0 / nv)
                vecs.append(v)
        return PETSc.NullSpace().create(vectors=vecs, comm=self.dm.comm)

    def _space_offset(self, space: np.ndarray) -> int:
        """First row of this rank in a reduced system of which it holds ``space``."""
        return self.dm.comm.tompi4py().exscan(len(space)) or 0

    def _constrained_local(self) -> np.ndarray:
        """Local dofs held by Dirichlet constraints or ties (not unknowns)."""
        parts = [dd.dofs.ravel() for dd in self.disc.dirichlet] + [t.dofs for t in self.disc.ties]
        return np.concatenate(parts) if parts else np.zeros(0, dtype=compat.INT)

    def region(self, name: str) -> Assembler:
        return next(a for a in self.assemblers if a.region == name)

    def reaction(self, rl: np.ndarray, fields, boundaries=None) -> float:
        """Sum over ranks of the (SI) residual rows of Dirichlet-constrained
        dofs of ``fields`` (on ``boundaries``, default all): the net inflow
        through those boundaries (the variationally consistent flux)."""
        idx = [dd.dofs.ravel() for d, dd in self._bc if dd.field in fields and dd.dofs.size
               and (boundaries is None or dd.boundary in boundaries)]
        idx = np.unique(np.concatenate(idx)) if idx else np.zeros(0, dtype=compat.INT)
        acc = float(np.sum(rl[idx] / self.inv_rscale[idx]))
        return self.dm.comm.tompi4py().allreduce(acc)

    def dirichlet_boundaries(self, fields) -> list[str]:
        """Names of the boundaries with Dirichlet conditions on ``fields`` (all ranks)."""
        return sorted({d.boundary for d in self._dirichlet if d.field in fields})

    def well_inflow(self, xl, t, field: str) -> tuple[float, float]:
        """(net inflow, sum of |inflow| over the wells) (SI) into ``field``'s
        equation from the well terms."""
        net = tot = 0.0
        for p in self.points:
            if p.dofs and field in p.dofs:
                q = -p.term.residual(p.values(xl, self.scales), t).get(field, 0.0)
                net, tot = net + q, tot + abs(q)
        return tuple(float(v) for v in self.dm.comm.tompi4py().allreduce(np.array([net, tot])))

    # -- evaluation --------------------------------------------------------------
    def local_residual(self, xl, xdl, t) -> np.ndarray:
        """Scaled local residual of all regions and well terms (rows of every
        local dof, constrained and tied ones included)."""
        r = self.assemblers[0].residual(xl, xdl, t)
        for a in self.assemblers[1:]:
            r += a.residual(xl, xdl, t)
        for p in self.points:
            p.add_residual(r, xl, t, self.scales, self.inv_rscale)
        return r

    def ifunction(self, ts, t, X, Xdot, F):
        self._ev_res.begin()
        xl, xdl = self.local_arrays(X, t, Xdot)
        rl = self.local_residual(xl, xdl, t)
        self._Fl.getArray()[:] = rl
        F.zeroEntries()
        self.dm.localToGlobal(self._Fl, F, addv=PETSc.InsertMode.ADD_VALUES)
        self._tie_add(rl, F)
        self._ev_res.end()

    def jacobian_values(self, xl, xdl, t, shift) -> np.ndarray:
        vals = [a.jacobian_values(xl, xdl, t, shift) for a in self.assemblers]
        vals += [p.jacobian_values(xl, t, self.scales, self.inv_rscale) for p in self.points]
        vals.append(np.zeros(len(self._diagonal())))
        return np.concatenate(vals)

    def _diagonal(self) -> np.ndarray:
        """Global indices of the owned rows: their diagonal entries are in the
        pattern (zero where no term puts one, e.g. the contact rows), as
        MatDiagonalSet in SNES VI needs."""
        if getattr(self, "_diag", None) is None:
            lo, hi = self.disc.ownership_range()
            self._diag = np.arange(lo, hi, dtype=compat.INT)
        return self._diag

    def ijacobian(self, ts, t, X, Xdot, shift, J, P):
        self._ev_jac.begin()
        xl, xdl = self.local_arrays(X, t, Xdot)
        compat.coo_set_values(P, self.jacobian_values(xl, xdl, t, shift))
        P.assemble()
        if J != P:
            J.assemble()
        self._ev_jac.end()

    def create_matrix(self) -> PETSc.Mat:
        if self.J is None:
            rows = [a.coo_rows for a in self.assemblers] + [p.coo_rows for p in self.points] + [self._diagonal()]
            cols = [a.coo_cols for a in self.assemblers] + [p.coo_cols for p in self.points] + [self._diagonal()]
            self.J = self.dm.createMat()
            compat.coo_preallocate(self.J, np.concatenate(rows), np.concatenate(cols))
        return self.J

    def auto_residual_scales(self, t: float, shift: float) -> dict[str, float]:
        """Set each field's residual scale to the mean |diagonal| of its
        Jacobian rows at the initial state, so that all rows are O(1)."""
        J = self.create_matrix()
        xl, xdl = self.local_arrays(self.X, t)
        for sc in self.scales.values():
            sc.rscale = 1.0
        self._update_row_scales()
        compat.coo_set_values(J, self.jacobian_values(xl, xdl, t, shift))
        J.assemble()
        diag = J.getDiagonal()
        rowmax = None
        names, isets, sub = self.dm.createFieldDecomposition()
        out = {}
        for name, iset in zip(names, isets):
            d = diag.getSubVector(iset)
            n = d.getSize()
            mean = d.norm(PETSc.NormType.NORM_1) / max(n, 1)
            diag.restoreSubVector(iset, d)
            if mean == 0.0:              # a multiplier's rows (contact): their largest entries
                rowmax = rowmax or self._row_max_abs(J)
                d = rowmax.getSubVector(iset)
                mean = d.norm(PETSc.NormType.NORM_1) / max(n, 1)
                rowmax.restoreSubVector(iset, d)
            self.scales[name].rscale = mean if mean > 0 and math.isfinite(mean) else 1.0
            out[name] = self.scales[name].rscale
        self._update_row_scales()
        return out

    @staticmethod
    def _row_max_abs(J: PETSc.Mat) -> PETSc.Vec:
        """max_j |J_ij| of every row, as a vector with J's row layout."""
        ai, aj, av = J.getValuesCSR()
        v = J.createVecLeft()
        nz = np.diff(ai) > 0
        out = np.zeros(len(ai) - 1)
        if av.size:
            out[nz] = np.maximum.reduceat(np.abs(av), ai[:-1][nz])
        v.getArray()[:] = out
        return v

    def _update_row_scales(self):
        self.inv_rscale[:] = Assembler.default_inv_rscale(self.disc, self.scales)


class _PointDofs:
    """A ``PointTerm`` located: the local dofs of its fields at the node, on the
    rank that owns the node (other ranks hold it with no dofs)."""

    def __init__(self, disc: Discretisation, term):
        self.term = term
        mesh = disc.mesh
        f0 = term.fields[0]
        pts = disc.support[f0]
        X = mesh.point_coordinates(pts)
        dist = np.linalg.norm(X - np.asarray(term.point)[None, :mesh.dim], axis=1) if len(pts) else np.zeros(0)
        here = np.flatnonzero(dist < 1e-9 * max(float(mesh.h.max()) if mesh.ncells else 1.0, 1e-300))
        lo, hi = disc.ownership_range()
        self.dofs = {}
        if len(here):
            p = pts[here[0]]
            dofs = {f: int(disc.offsets[f][p - disc.pstart]) for f in term.fields}
            g = disc.global_index[dofs[f0]]
            if lo <= g < hi:
                self.dofs = dofs
        found = mesh.dm.comm.tompi4py().allreduce(int(bool(self.dofs)))
        if found != 1:
            raise ValueError(f"well '{term.name}' at {tuple(term.point)}: no {f0} node there "
                             "(wells must sit on a mesh vertex of the fracture)")
        pairs = list(term.jacobian({f: 0.0 for f in term.fields}, 0.0).keys()) if self.dofs else []
        self.pairs = pairs
        g = disc.global_index
        self.coo_rows = np.asarray([g[self.dofs[a]] for a, b in pairs], dtype=compat.INT)
        self.coo_cols = np.asarray([g[self.dofs[b]] for a, b in pairs], dtype=compat.INT)

    def values(self, xl, scales) -> dict:
        return {f: xl[d] * scales[f].scale + scales[f].offset for f, d in self.dofs.items()}

    def add_residual(self, r, xl, t, scales, inv_rscale):
        if not self.dofs:
            return
        for f, v in self.term.residual(self.values(xl, scales), t).items():
            r[self.dofs[f]] += v * inv_rscale[self.dofs[f]]

    def jacobian_values(self, xl, t, scales, inv_rscale) -> np.ndarray:
        if not self.dofs:
            return np.zeros(0)
        jac = self.term.jacobian(self.values(xl, scales), t)
        return np.asarray([jac[(a, b)] * inv_rscale[self.dofs[a]] * scales[b].scale
                           for a, b in self.pairs], dtype=float)


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
        if problem.model.bounds:
            self._set_bounds(ts.getSNES())
        self._set_field_splits(ts.getSNES().getKSP().getPC())
        ts.setPostStep(self._post_step)
        self._user_monitor = monitor
        ts.setMonitor(self._monitor)
        self.rejected = 0
        self.error = None
        self._last_dt_cut = None

    def _set_field_splits(self, pc):
        """A field-split preconditioner gets one split per field, named by the
        field (-fieldsplit_u_..., -fieldsplit_pm_...), with the rigid-body
        modes on u, unless the options group fields themselves
        (-pc_fieldsplit_0_fields ...).  The Python PC ``VIFieldSplit`` is
        given the problem and the SNES (it splits the VI's reduced system)."""
        if pc.getType() == "python":
            VIFieldSplit.solving = (self.problem, self.ts.getSNES())
            return
        if pc.getType() != "fieldsplit" or PETSc.Options().hasName("pc_fieldsplit_0_fields"):
            return
        pc.setFieldSplitIS(*self.problem.field_splits())

    def _set_bounds(self, snes):
        """Variable bounds (contact) need one of SNES's VI Newton methods."""
        from .errors import InputError
        if snes.getType() not in ("vinewtonrsls", "vinewtonssls"):
            raise InputError(f"-snes_type {snes.getType()} cannot honour the contact bounds of "
                             f"{', '.join(self.problem.model.bounds)}: use vinewtonrsls or vinewtonssls")
        self._lower, upper = self.problem.variable_bounds()
        snes.setVariableBounds(self._lower, upper)
        self._bounded = self._lower.getArray() > PETSc.NINFINITY
        self._previous = None
        snes.setUpdate(self._release_biactive)

    def _release_biactive(self, snes, it):
        """Make PETSc's reduced-space VI Newton release a bounded unknown whose
        last Newton step wanted to cross its bound.

        ``vinewtonrsls`` fixes an unknown at its bound only if the residual
        there is > 0.  The contact residual (the opening) does not depend on
        the bounded traction itself, so after a step that solved a node as
        closed (opening 0) and then projected its negative traction back to 0,
        the residual is 0 to round-off and the node stays closed for ever.
        Such a node (at its bound, and pushed below it by the last step) gets
        a residual of +1e-300 (it opens: the same rule as in a primal-dual
        active-set method); a wrong release is undone by the next step."""
        X = snes.getSolution()
        if it > 0 and self._previous is not None and snes.getType() == "vinewtonrsls":
            x, lo = X.getArray(readonly=True), self._lower.getArray(readonly=True)
            wanted = self._previous.getArray(readonly=True) - snes.getSolutionUpdate().getArray(readonly=True)
            trapped = self._bounded & (x <= lo) & (wanted < lo)
            if trapped.any():
                f = snes.getFunction()[0].getArray()
                f[trapped] = np.maximum(f[trapped], 1e-300)
        if self._previous is None:
            self._previous = X.duplicate()
        X.copy(self._previous)

    def _post_step(self, ts):
        """Grow the step, clipped to the largest step and to the final time."""
        c = self.control
        t = ts.getTime()
        dt = min(ts.getTimeStep() * c.growth, c.dt_max)
        if self._last_dt_cut is not None:        # resume the growth sequence after a hit
            dt = min(self._last_dt_cut, c.dt_max)
            self._last_dt_cut = None
        remaining = c.final_time - t
        upcoming = [h - t for h in c.hit_times if h - t > 1e-9 * max(abs(t), 1.0)]
        if upcoming and min(upcoming) < dt * (1 + 1e-9):
            self._last_dt_cut = dt
            dt = min(upcoming)
        if remaining > 0:
            ts.setTimeStep(min(dt, remaining))

    def _monitor(self, ts, step, t, X):
        """Call the user's monitor; an exception stops the run cleanly and is
        re-raised by ``solve`` (exceptions must not cross the C callback).
        In parallel a failure on some ranks only would leave the others
        waiting in the next step's collectives (and they may be inside the
        monitor's own), so the failing rank prints its traceback and aborts
        the whole run."""
        if self._user_monitor is None or self.error is not None:
            return
        try:
            self._user_monitor(step, t, X)
        except Exception as e:  # noqa: BLE001 - re-raised after TSSolve returns
            if ts.comm.size > 1:
                _abort_all(ts.comm, f"rank {ts.comm.rank}: the step monitor failed at step {step}, t = {t:.6g} s")
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


def _abort_all(comm, message: str) -> None:
    """Print the current exception's traceback with ``message`` and abort every rank."""
    traceback.print_exc()
    print(f"petthm: {message}; aborting all ranks", file=sys.stderr)
    sys.stderr.flush()
    comm.tompi4py().Abort(1)


class VIFieldSplit:
    """Field split for the reduced systems of PETSc's VI Newton methods
    (``-pc_type python -pc_python_type petthm.solver.VIFieldSplit``).

    ``vinewtonrsls`` solves on the inactive set, which changes with the
    contact state; a PCFIELDSPLIT set up once would keep index sets of the
    wrong space (petsc-notes "Contact and SNES VI").  This PC rebuilds an
    inner PCFIELDSPLIT at every set-up: one split per field restricted to
    ``SNES.getVIInactiveSet()`` (all unknowns for ``vinewtonssls``), named by
    the field, the rigid-body modes on u.  The inner PC takes its options
    with the prefix ``vi_`` (``-vi_pc_fieldsplit_type schur``,
    ``-vi_fieldsplit_u_pc_type gamg``, ...).

    ``-vi_groups NAME=F1+F2,NAME2=...`` merges fields into named splits
    (fields the scene does not have are skipped, empty groups dropped), so
    that one two-split Schur recipe serves u with lam alone and u with
    {lam, pf, Tf, Tm}: ``-vi_groups u=u,rest=lam+pm+pf+Tm+Tf``."""

    #: (Problem, SNES) of the solve in progress, set by ``TimeStepper`` (PETSc
    #: may create a new instance of this class whenever it reads the options)
    solving: tuple | None = None

    def __init__(self):
        self.inner = None

    def setUp(self, pc):
        A, P = pc.getOperators()
        if self.solving is None:
            raise RuntimeError("VIFieldSplit is set up by petthm's TimeStepper only")
        problem, snes = self.solving
        space = None
        if snes.getType() == "vinewtonrsls" and P.getSize()[0] != problem.X.getSize():
            space = np.asarray(snes.getVIInactiveSet().getIndices(), dtype=compat.INT)
        splits = problem.field_splits(space)
        splits = self._grouped([(n, s) for n, s in splits if s.getSize() > 0], pc)
        if self.inner is not None:
            self.inner.destroy()
        self.inner = PETSc.PC().create(comm=pc.getComm())
        self.inner.setOptionsPrefix((pc.getOptionsPrefix() or "") + "vi_")
        self.inner.setOperators(A, P)
        self.inner.setType("fieldsplit")
        self.inner.setFieldSplitIS(*splits)
        self.inner.setFromOptions()
        self.inner.setUp()

    @staticmethod
    def _grouped(splits: list, pc) -> list:
        """The splits merged by ``-vi_groups`` (see the class docstring)."""
        from .errors import InputError
        text = PETSc.Options((pc.getOptionsPrefix() or "") + "vi_").getString("groups", "")
        if not text:
            return splits
        by_name = dict(splits)
        grouped = {f for item in text.split(",") for f in item.partition("=")[2].split("+")}
        missing = [n for n in by_name if n not in grouped]
        if missing:
            raise InputError(f"option -vi_groups = {text} leaves out the field(s) {', '.join(missing)}")
        out = []
        for item in text.split(","):
            name, _, members = item.partition("=")
            parts = [by_name[f] for f in members.split("+") if f in by_name]
            if not name or not members:
                raise InputError(f"option -vi_groups: '{item}' is not NAME=FIELD+FIELD...")
            if len(parts) == 1:
                out.append((name, parts[0]))
            elif parts:
                idx = np.unique(np.concatenate([p.getIndices() for p in parts])).astype(compat.INT)
                out.append((name, PETSc.IS().createGeneral(idx, comm=pc.getComm())))
        return out

    def reset(self, pc):
        if self.inner is not None:
            self.inner.destroy()
            self.inner = None

    def apply(self, pc, x, y):
        self.inner.apply(x, y)
