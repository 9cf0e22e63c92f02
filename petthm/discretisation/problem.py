"""A transient FE problem: state, residual and Jacobian callbacks, scaling.

``Problem`` holds the solution vector and evaluates F(t, X, Xdot) and
dF/dX + shift dF/dXdot (TS's IFunction/IJacobian, theory manual, "Time stepping and solvers")
from one ``assembly.Assembler`` per region of the model (the matrix
cells, the fracture faces, and their lumped variants) plus the point terms
of the wells.  The dofs that are not unknowns are ``constraints.Constraints``;
the scaling is ``assembly.FieldScale`` per field:

* unknowns x_hat = (x - offset)/scale, with the scales a scene gives;
* residual rows divided by the mean |diagonal| of their field's Jacobian
  rows at the initial state (``auto_residual_scales``), so that all rows
  are O(1) and solver tolerances are dimensionless.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from petsc4py import PETSc

from petthm import compat
from petthm.discretisation.assembly import Assembler, FieldScale
from petthm.discretisation.constraints import Constraints, Dirichlet
from petthm.discretisation.fields import Discretisation, Domain, base_field
from petthm.discretisation.model import Model, PointTerm, Region
from petthm.discretisation.nodesets import NodeSetDofs


@dataclass(frozen=True)
class OnSides:
    """An initial state ``values(x, inside)`` of a field that jumps across a
    fracture: ``inside`` is, for each node, a point of a cell next to it
    (``Problem.set_initial``)."""
    values: Callable[[np.ndarray, np.ndarray], np.ndarray]


class Problem:
    """Fields, model (terms on the matrix cells, the fracture faces and at
    well nodes), constraints and the state."""

    def __init__(self, disc: Discretisation, model: Model, scales: dict[str, FieldScale],
                 dirichlet: list[Dirichlet], quad_degree: int | None = None):
        self.disc, self.model, self.dm = disc, model, disc.mesh.dm
        self.scales = scales
        for t in disc.ties:
            a, b = scales[t.field], scales[t.target]
            if (a.scale, a.offset) != (b.scale, b.offset):
                raise ValueError(f"tied fields {t.field} and {t.target} need the same unknown scaling")
        self.inv_rscale = Assembler.default_inv_rscale(disc, scales)
        self.assemblers = {r: Assembler(disc, model, scales, quad_degree, region=r,
                                        inv_rscale=self.inv_rscale)
                           for r in model.regions()}
        self.points = [PointDofs(disc, pt) for pt in model.points]
        self.node_sets = [NodeSetDofs(disc, ns) for ns in model.node_sets]
        self.X = self.dm.createGlobalVec()
        self.X.setName("solution")
        self.constraints = Constraints(disc, dirichlet, self.X)
        self._Xl = self.dm.createLocalVec()
        self._Xdl = self.dm.createLocalVec()
        self._Fl = self.dm.createLocalVec()
        lo, hi = disc.ownership_range()
        # the owned rows' diagonal entries are in the pattern (zero where no term
        # puts one, e.g. the contact rows), as MatDiagonalSet in SNES VI needs
        self._diagonal = np.arange(lo, hi, dtype=compat.INT)
        self.J: PETSc.Mat | None = None
        self._term_blocks: dict[str, tuple[PETSc.Mat, list[Assembler]]] = {}
        self._jacobian_point = None               # (xl, xdl, t, shift) of the last Jacobian
        self.residual_shift = 1.0                 # 1/dt of a residual evaluated without a TS
        self._jvals: np.ndarray | None = None     # the Jacobian's COO values (reused buffer)
        self._jvals_constant = False              # it holds the constant terms' values (model.CellJacobian)
        self._residual_memo = None                # (t, shift, X, local residual) of the last ifunction
        self.probe_nodes: dict = {}               # probes.point_value's (rank, node) per (field, point)
        self._averaging: dict[Region, Assembler] = {}     # ``nodal_average``'s, per region
        self._ev_res = PETSc.Log.Event("thm.residual")
        self._ev_jac = PETSc.Log.Event("thm.jacobian")

    def region(self, region: Region) -> Assembler:
        """The assembler of one region (for integrals and error norms)."""
        return self.assemblers[region]

    # -- local vectors with Dirichlet values -------------------------------------------
    def local_arrays(self, X: PETSc.Vec, t: float, Xdot: PETSc.Vec | None = None):
        """Local (scaled) solution and rate arrays with Dirichlet and tied values inserted."""
        self.dm.globalToLocal(X, self._Xl, addv=PETSc.InsertMode.INSERT_VALUES)
        xl = self._Xl.getArray()
        xdl = self._Xdl.getArray()
        self.constraints.tie_values(X, xl)
        if Xdot is not None:
            self.dm.globalToLocal(Xdot, self._Xdl, addv=PETSc.InsertMode.INSERT_VALUES)
            self.constraints.tie_values(Xdot, xdl)
        else:
            xdl[:] = 0.0
        self.constraints.insert(xl, xdl, t, self.scales)
        return xl, xdl

    def set_initial(self, funcs: dict[str, Callable[[np.ndarray], np.ndarray]]) -> None:
        """Fill X from initial-value functions of the node coordinates (SI);
        an ``OnSides`` function also receives, for each node, a point inside
        a cell of the node: the two copies of a node on a fracture take the
        values of their sides."""
        xl = self._Xl.getArray()
        xl[:] = 0.0
        for name, f in funcs.items():
            sc = self.scales[name]
            dofs = self.disc.field_local_dofs(name)
            x = self.disc.field_node_coordinates(name)
            if isinstance(f, OnSides):         # a field discontinuous across a fracture: f(x, inside)
                vals = np.asarray(f.values(x, self.disc.mesh.inside_points(self.disc.node_points(name))))
            else:
                vals = np.asarray(f(x), dtype=float)
            xl[dofs] = (vals.reshape(dofs.shape) - sc.offset) / sc.scale
        self.dm.localToGlobal(self._Xl, self.X, addv=PETSc.InsertMode.INSERT_VALUES)

    def field_values(self, name: str, X: PETSc.Vec | None = None, t: float = 0.0, nodes=None):
        """SI nodal values (n, ncomp) of a field on this rank's local nodes
        (ghosts included), or on the rows ``nodes`` of them (collective: the
        ghost update; a rank without nodes passes an empty selection)."""
        xl, _ = self.local_arrays(X or self.X, t)
        sc = self.scales[name]
        dofs = self.disc.field_local_dofs(name)
        return xl[dofs if nodes is None else dofs[nodes]] * sc.scale + sc.offset

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

    # -- fluxes through constraints and wells ----------------------------------------------
    def reaction(self, rl: np.ndarray, fields, boundaries=None) -> float:
        """Sum over ranks of the (SI) residual rows of Dirichlet-constrained
        dofs of ``fields`` (on ``boundaries``, default all): the net inflow
        through those boundaries (the variationally consistent flux)."""
        idx = self.constraints.reaction_dofs(fields, boundaries)
        acc = float(np.sum(rl[idx] / self.inv_rscale[idx]))
        return self.dm.comm.tompi4py().allreduce(acc)

    def summed_over_ranks(self, parts) -> list[np.ndarray]:
        """Each local array in ``parts`` with every unknown's entry summed over
        the ranks that hold it (collective; a constrained dof keeps this
        rank's entry)."""
        loc, glob = self.dm.createLocalVec(), self.dm.createGlobalVec()
        sums = []
        for part in parts:
            loc.getArray()[:] = part
            glob.set(0.0)
            self.dm.localToGlobal(loc, glob, addv=PETSc.InsertMode.ADD_VALUES)
            self.dm.globalToLocal(glob, loc, addv=PETSc.InsertMode.INSERT_VALUES)
            sums.append(loc.getArray().copy())
        loc.destroy()
        glob.destroy()
        return sums

    def nodal_average(self, name: str, integrand: Callable, X: PETSc.Vec | None = None,
                      t: float = 0.0, width: int = 1) -> np.ndarray:
        """At each node of the field ``name``: the average over the cells
        around it of f = ``integrand(ctx)`` ((nc, nq) SI, or (nc, nq, width))
        evaluated at the node in each cell, weighted by the nodal rule's
        weights (``fe.nodal_rule``: positive, the cell's share of the node's
        area or volume).  For an f that is a polynomial in each cell with an
        O(h^p) error at every point, the average has that error too.  SI
        values (n,) or (n, width) at the field's local nodes in the order of
        ``field_values``, the same on every rank that holds the node
        (collective).  A node no cell of the field's region reaches keeps the
        field's own value (the first component's)."""
        region = Region(self.disc.field(name).region, nodal=True)
        if region not in self._averaging:                 # no terms: not one of the residual's assemblers
            model = Model(self.model.fields, cell_regions=self.model.cell_regions,
                          fracture_regions=self.model.fracture_regions)
            self._averaging[region] = Assembler(self.disc, model, self.scales, region=region)
        xl, _ = self.local_arrays(X or self.X, t)
        num, den = self._averaging[region].nodal_moments(xl, name, integrand, t, width)
        dofs = self.disc.field_local_dofs(name)[:, 0]
        points = self.disc.node_points(name) - self.disc.pstart
        parts, npoints = [], self.dm.getChart()[1] - self.disc.pstart
        for col in [den] + [num[:, m] for m in range(width)]:
            part = np.zeros(npoints)
            part[points] = col[dofs]
            parts.append(part)
        sums = [s[points] for s in self.summed_at_points(parts)]
        sc = self.scales[name]
        out = np.repeat((xl[dofs] * sc.scale + sc.offset)[:, None], width, axis=1)
        reached = sums[0] != 0.0
        for m in range(width):
            out[reached, m] = sums[1 + m][reached] / sums[0][reached]
        return out if width > 1 else out[:, 0]

    def summed_at_points(self, parts) -> list[np.ndarray]:
        """Each array in ``parts`` (one entry per mesh point of this rank's
        chart) with every point's entry summed over the ranks that hold the
        point, on each of them (collective; the mesh's point star forest:
        reduced onto the owner, sent back to the ghosts).  Unlike
        ``summed_over_ranks`` it holds for every point, a constrained one too."""
        if self.dm.comm.size == 1:
            return [np.array(p, dtype=float) for p in parts]
        from mpi4py import MPI
        sf = self.dm.getPointSF()
        out = []
        for part in parts:
            leaf = np.ascontiguousarray(part, dtype=float)
            root = leaf.copy()
            sf.reduceBegin(MPI.DOUBLE, leaf, root, MPI.SUM)
            sf.reduceEnd(MPI.DOUBLE, leaf, root, MPI.SUM)
            total = root.copy()
            sf.bcastBegin(MPI.DOUBLE, root, total, MPI.REPLACE)
            sf.bcastEnd(MPI.DOUBLE, root, total, MPI.REPLACE)
            out.append(total)
        return out

    def dirichlet_boundaries(self, fields) -> list[str]:
        return self.constraints.boundaries(fields)

    def well_inflow(self, xl, t, field: str) -> tuple[float, float]:
        """(net inflow, sum of |inflow| over the wells) (SI) into ``field``'s
        equation from the well terms."""
        net = tot = 0.0
        for p in self.points:
            if p.dofs and field in p.dofs:
                q = -p.term.residual(p.values(xl, self.scales), t).get(field, 0.0)
                net, tot = net + q, tot + abs(q)
        for ns in self.node_sets:
            q, a = ns.inflow(xl, t, self.scales, field)
            net, tot = net + q, tot + a
        return tuple(float(v) for v in self.dm.comm.tompi4py().allreduce(np.array([net, tot])))

    # -- evaluation ------------------------------------------------------------------------
    def local_residual(self, xl, xdl, t, shift: float = 0.0) -> np.ndarray:
        """Scaled local residual of all regions and well terms (rows of every
        local dof, constrained and tied ones included); ``shift``: 1/dt."""
        asm = list(self.assemblers.values())
        r = asm[0].residual(xl, xdl, t, shift)
        for a in asm[1:]:
            r += a.residual(xl, xdl, t, shift)
        for p in self.points + self.node_sets:
            p.add_residual(r, xl, t, self.scales, self.inv_rscale)
        return r

    def step_residual(self, X: PETSc.Vec, t: float, shift: float, xl, xdl) -> np.ndarray:
        """The local residual at the end of a step (X at time t, rate from
        ``xl``, ``xdl``): the last ``ifunction``'s when it was evaluated at
        this X, t and shift (the Newton solver's convergence test evaluates
        it at the accepted state; the time integrator's copy of that state
        may differ from it by round-off, 1e-16 of the scaled unknowns), else
        computed."""
        memo = self._residual_memo
        x = X.getArray(readonly=True)
        if memo is not None and memo[0] == t and math.isclose(memo[1], shift, rel_tol=1e-9) \
                and memo[2].shape == x.shape \
                and (x.size == 0 or np.abs(memo[2] - x).max() <= 1e-13 * max(1.0, np.abs(x).max())):
            return memo[3]
        return self.local_residual(xl, xdl, t, shift)

    def tighten(self, X: PETSc.Vec, t: float) -> bool:
        """Lower the flux limiters' factors of the step being solved to those
        of its solved state X at time t where they exceed them
        (``kernels/limiter.py``): whether the step's equations changed and
        must be solved again (collective)."""
        xl, _ = self.local_arrays(X, t)
        changed = False
        for asm in self.assemblers.values():
            changed = asm.tighten(xl) or changed
        return changed

    def has_tightening(self) -> bool:
        """Whether a term's equations depend on the solved state of the step
        through a limiter that ``tighten`` lowers."""
        return any(hasattr(term.prepare, "tighten") for term in self.model.residuals)

    def ifunction(self, ts, t, X, Xdot, F):
        self._ev_res.begin()
        xl, xdl = self.local_arrays(X, t, Xdot)
        shift = 1.0 / ts.getTimeStep() if ts is not None else self.residual_shift
        rl = self.local_residual(xl, xdl, t, shift)
        self._residual_memo = (t, shift, X.getArray(readonly=True).copy(), rl)
        self._Fl.getArray()[:] = rl
        F.zeroEntries()
        self.dm.localToGlobal(self._Fl, F, addv=PETSc.InsertMode.ADD_VALUES)
        self.constraints.tie_add(rl, F)
        self._ev_res.end()

    def jacobian_values(self, xl, xdl, t, shift) -> np.ndarray:
        """The COO values of the Jacobian in ``create_matrix``'s order, in one
        buffer kept across calls (each assembler writes its own slice)."""
        sizes = [a.nnz for a in self.assemblers.values()] + \
            [len(p.coo_rows) for p in self.points + self.node_sets] + [len(self._diagonal)]
        if self._jvals is None or self._jvals.size != sum(sizes):
            self._jvals = np.empty(sum(sizes))
            self._jvals_constant = False
        pos = 0
        for a in self.assemblers.values():
            a.jacobian_values(xl, xdl, t, shift, out=self._jvals[pos:pos + a.nnz],
                              keep_constant=self._jvals_constant)
            pos += a.nnz
        self._jvals_constant = True
        for p in self.points + self.node_sets:
            v = p.jacobian_values(xl, t, self.scales, self.inv_rscale)
            self._jvals[pos:pos + v.size] = v
            pos += v.size
        self._jvals[pos:] = 0.0
        return self._jvals

    def ijacobian(self, ts, t, X, Xdot, shift, J, P):
        self._ev_jac.begin()
        xl, xdl = self.local_arrays(X, t, Xdot)
        values = self.jacobian_values(xl, xdl, t, shift)
        if not np.isfinite(np.sum(values)):
            if ts is None:      # a check outside the time stepper (verification/jacobian.py)
                raise FloatingPointError("the Jacobian is not finite at this state")
            # a state where a property is not defined (mu(T) overflowing far outside the
            # fluid's range): Newton stops there and the step is cut, rather than a
            # preconditioner built on NaN (manual, user guide: reliability)
            compat.set_jacobian_domain_error(ts.getSNES())
            values[~np.isfinite(values)] = 0.0
        compat.coo_set_values(P, values)
        P.assemble()
        self._jacobian_point = (xl.copy(), xdl.copy(), t, shift)   # for the blocks of some terms, below
        if J != P:
            J.assemble()
        self._ev_jac.end()

    def create_matrix(self) -> PETSc.Mat:
        """The Jacobian matrix (created once, with its COO pattern)."""
        if self.J is None:
            rows, cols = self._coo_pattern(list(self.assemblers.values()), [(p.coo_rows, p.coo_cols)
                                           for p in self.points + self.node_sets] +
                                           [(self._diagonal, self._diagonal)])
            self.J = compat.coo_matrix(self.dm, rows, cols, copy=False)
        return self.J

    def discard_matrix(self) -> None:
        """Forget the Jacobian matrix, its values and every assembler's
        sparsity pattern, so that the next ``create_matrix`` makes them from
        nothing (benchmarks/scene_assembly.py times that).  The old matrix is
        only dropped, not destroyed: whoever still holds it keeps it."""
        self.J, self._jvals, self._jvals_constant = None, None, False
        for a in self.assemblers.values():
            a.build_pattern()

    @staticmethod
    def _coo_pattern(assemblers, extra=()) -> tuple[np.ndarray, np.ndarray]:
        """The COO rows and columns of ``assemblers`` (each writes its slice
        in place) followed by the ``extra`` (rows, cols) pairs."""
        sizes = [a.nnz for a in assemblers] + [len(r) for r, _ in extra]
        rows, cols = np.empty(sum(sizes), compat.INT), np.empty(sum(sizes), compat.INT)
        pos = 0
        for a in assemblers:
            a.coo_pattern(rows[pos:pos + a.nnz], cols[pos:pos + a.nnz])
            pos += a.nnz
        for r, c in extra:
            rows[pos:pos + len(r)], cols[pos:pos + len(r)] = r, c
            pos += len(r)
        return rows, cols

    def preconditioner_blocks(self) -> PETSc.Mat | None:
        """The model's ``preconditioner`` blocks (e.g. the fixed-stress term),
        scaled like the Jacobian, at the state, time and shift of the last
        Jacobian; None when the model has none."""
        return self._terms_at_jacobian_point("preconditioner", self.model.preconditioner)

    def face_load_blocks(self) -> PETSc.Mat | None:
        """The Jacobian's terms whose test function is the displacement on a
        fracture region (the faces' loads: the fracture fluid pressure and
        the contact traction on the walls, the theory manual eq. (4)), without the
        rock's body terms (Biot, thermal strain), at the last Jacobian's
        point; None when the model has none."""
        terms = [j for j in self.model.jacobians
                 if j.region.domain != Domain.MATRIX and base_field(j.test) == "u"]
        return self._terms_at_jacobian_point("face_loads", terms)

    def _terms_at_jacobian_point(self, key: str, terms: list) -> PETSc.Mat | None:
        """The matrix of the Jacobian ``terms`` alone (full-system numbering,
        scaled like the Jacobian; its pattern made once per ``key``) at the
        last Jacobian's state, time and shift."""
        if not terms or self._jacobian_point is None:
            return None
        if key not in self._term_blocks:
            model = Model(self.model.fields, [], terms, cell_regions=self.model.cell_regions,
                          fracture_regions=self.model.fracture_regions)
            assemblers = [Assembler(self.disc, model, self.scales, region=r, inv_rscale=self.inv_rscale)
                          for r in sorted({j.region for j in terms})]
            mat = compat.coo_matrix(self.dm, *self._coo_pattern(assemblers), copy=False)
            self._term_blocks[key] = (mat, assemblers)
        mat, assemblers = self._term_blocks[key]
        xl, xdl, t, shift = self._jacobian_point
        compat.coo_set_values(mat, np.concatenate([a.jacobian_values(xl, xdl, t, shift) for a in assemblers]))
        mat.assemble()
        return mat

    # -- residual scaling --------------------------------------------------------------------
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
        names, isets, _ = self.dm.createFieldDecomposition()
        out = {}
        for name, iset in zip(names, isets, strict=False):
            d = diag.getSubVector(iset)
            n = d.getSize()
            mean = d.norm(PETSc.NormType.NORM_1) / max(n, 1)
            diag.restoreSubVector(iset, d)
            if mean == 0.0:              # a multiplier's rows (contact): their largest entries
                rowmax = rowmax or _row_max_abs(J)
                d = rowmax.getSubVector(iset)
                mean = d.norm(PETSc.NormType.NORM_1) / max(n, 1)
                rowmax.restoreSubVector(iset, d)
            self.scales[name].rscale = mean if mean > 0 and math.isfinite(mean) else 1.0
            out[name] = self.scales[name].rscale
        self._update_row_scales()
        return out

    def _update_row_scales(self):
        self.inv_rscale[:] = Assembler.default_inv_rscale(self.disc, self.scales)
        self._jvals_constant = False              # the constant terms' values change with the scaling


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


class PointDofs:
    """A ``PointTerm`` located: the local dofs of its fields at the node, on the
    rank that owns the node (other ranks hold it with no dofs)."""

    def __init__(self, disc: Discretisation, term: PointTerm):
        self.term = term
        mesh = disc.mesh
        f0 = term.fields[0]
        pts = disc.support[f0]
        X = mesh.point_coordinates(pts)
        dist = np.linalg.norm(X - np.asarray(term.point)[None, :mesh.dim],
                              axis=1) if len(pts) else np.zeros(0)
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
