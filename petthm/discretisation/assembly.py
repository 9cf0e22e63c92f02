"""Generic vectorised finite-element assembly (no physics in here).

For a batch of cells the local solution is gathered with fancy indexing,
field values/gradients at the quadrature points are formed with matrix
products against the tabulated reference basis, the model's kernels are
called once per batch, and the results are contracted back:

    r_i  = sum_q w_q |J| ( phi_i f0 + grad phi_i . f1 )
    K_ij = sum_q w_q |J| ( phi_i g0 phi_j + phi_i g1 . grad phi_j
                           + grad phi_i . g2 phi_j + grad phi_i . g3 . grad phi_j
                           + grad phi_i . g2_lap lap phi_j )

Physical gradients are mapped to the reference cell (J^-1), so every
contraction is one BLAS matrix product with a tensor of the reference basis.
The Jacobian's COO pattern is fixed at set-up, one entry per nonzero: the
element matrices are summed into it (``sparsity.NodePairs``) before
MatSetValuesCOO.  Terms declared ``constant`` (linear elasticity and its
couplings) are computed once: the caller's value buffer keeps the sums of
blocks with constant terms only (``jacobian_values(keep_constant=True)``).
P1 fields (gradients constant over an affine cell) take their gradients and
the residual's flux term from the cell's physical basis gradients, computed
once, at one point per cell.

Scaling: unknowns are stored as x_hat = (x - offset)/scale per field and
residual rows are divided by a per-field reference ``rscale`` so that
solver tolerances are dimensionless.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from petthm.discretisation import fe, sparsity
from petthm.discretisation.context import CellContext, FacetContext, physical_gradient
from petthm.discretisation.fields import Adjacent, Discretisation, FieldRef
from petthm.discretisation.functionals import Functionals
from petthm.discretisation.mapping import adjacent_gradients, reference_flux
from petthm.discretisation.model import MATRIX, Model, Region
from petthm.discretisation.p1blocks import constant_gradient_terms

CHUNK = 16384


@dataclass
class FieldScale:
    """x_SI = offset + scale * x_hat; residual rows divided by rscale."""
    scale: float = 1.0
    offset: float = 0.0
    rscale: float = 1.0


@dataclass
class _FacetBatch:
    """Boundary facets that share the local facet number within their cell."""
    cells: np.ndarray
    points: np.ndarray            # reference-cell points of the facet rule (nq, d)
    weights: np.ndarray           # (nf, nq) physical weights
    normals: np.ndarray           # (nf, d)
    tabs: dict


def _distinct_prepares(terms):
    """The terms' ``prepare`` hooks, each once (terms may share one)."""
    seen = set()
    for term in terms:
        if term.prepare is not None and id(term.prepare) not in seen:
            seen.add(id(term.prepare))
            yield term.prepare


class Assembler(Functionals):
    """Residual and Jacobian of a ``Model`` on a ``Discretisation``."""

    def __init__(self, disc: Discretisation, model: Model, scales: dict[str, FieldScale],
                 quad_degree: int | None = None, region: Region = MATRIX, inv_rscale=None):
        """``region``: the elements integrated over (the mesh's cells, or the
        fracture's: ``disc.regions[Domain.FRACTURE]``, a
        ``fracture.FractureSurface``) and the rule; only the model's terms on
        that region are assembled.  A lumped region has the vertex
        quadrature rule (row-sum lumping of P1 mass-type terms: capacity,
        wall exchange), which keeps the discrete maximum principle where the
        consistent mass matrix breaks it (thin elements, small steps).
        ``inv_rscale``: per local dof, 1/(residual scale of the row it is
        added to) (default: from ``scales``)."""
        self.disc, self.region = disc, region
        self.base = region.domain
        self.model = Model(model.fields, [t for t in model.residuals if t.region == region],
                           [t for t in model.jacobians if t.region == region],
                           model.facets if region == MATRIX else [])
        self.mesh = disc.regions[self.base]
        #: the rock region of each cell, or the fracture of each fracture face (None: one set of values)
        self.cell_regions = model.cell_regions if self.base == MATRIX.domain else model.fracture_regions
        self._region_batches = None
        self.scales = scales
        self.inv_rscale = inv_rscale if inv_rscale is not None else self.default_inv_rscale(disc, scales)
        dim = self.mesh.rdim
        pmax = max(f.degree for f in disc.fields)
        if region.lumped:
            self.rule = fe.vertex_rule(dim)
        elif region.nodal:
            self.rule = fe.nodal_rule(dim, pmax)
        else:
            self.rule = fe.rule(dim, quad_degree or 2 * pmax)
        duals = (False, True) if region.dual else (False,)
        self._tabs = {(p, dual): fe.ReferenceTable(dim, p, self.rule.points, dual)
                      for p in (1, 2) for dual in duals}
        self.W = np.abs(self.mesh.detJ)[:, None] * self.rule.weights[None, :]
        self._ref_cache = {}
        self._basis_gradients = {}
        self._facets = {ft.boundary: self._facet_batches(ft.boundary, 2 * pmax) for ft in self.model.facets}
        self.build_pattern()

    @staticmethod
    def default_inv_rscale(disc, scales) -> np.ndarray:
        """1/rscale of each local dof's field (ties: of the target field)."""
        inv = np.ones(disc.nlocal)
        for f in disc.fields:
            inv[disc.field_local_dofs(f.name).ravel()] = 1.0 / scales[f.name].rscale
        for t in disc.ties:
            inv[t.dofs] = 1.0 / scales[t.target].rscale
        return inv

    def dofs(self, name: FieldRef) -> np.ndarray:
        """Element dofs of a field (or a ``Trace``) on this region's elements."""
        return self.disc.region_dofs(self.base, name)

    def scale(self, name) -> FieldScale:
        return self.scales[self.disc.field(name).name]

    # -- tabulations ----------------------------------------------------------
    def basis(self, name) -> tuple[int, bool]:
        """(degree, dual) of the basis a field (reference) is seen in here:
        the region's own fields in a dual region are in the dual basis."""
        f = self.disc.field(name)
        return f.degree, self.region.dual and isinstance(name, str) and f.region == self.base

    def tab(self, name) -> fe.ReferenceTable:
        return self._tabs[self.basis(name)]

    def basis_gradients(self, name, cells) -> np.ndarray:
        """Physical gradients of the basis functions of a field whose
        reference gradients are constant (``_Tab.constant_grad``: P1), on each
        cell: B[c, i, a] (nc, nb, dim); computed once (the geometry is fixed)."""
        key = self.basis(name)
        if key not in self._basis_gradients:
            dphi = self._tabs[key].dphi[0]                                  # (nb, r)
            B = physical_gradient(dphi.T[None, None], self.mesh.Jinv)                  # (ncells, 1, nb, d)
            self._basis_gradients[key] = np.ascontiguousarray(B[:, 0])
        return self._basis_gradients[key][cells]

    def adjacent_gradients(self, ref: Adjacent, cells) -> np.ndarray:
        """Physical gradients of the basis of the rock cell next to each
        fracture face (an ``Adjacent`` field) at this region's quadrature
        points, as G[c, q, a, j] (nc, nq, d, nb; nq = 1 for P1): a stack of
        matrices, so that gradients are batched matrix products; computed
        once (the geometry is fixed)."""
        if ref not in self._basis_gradients:
            G = adjacent_gradients(self.mesh, ref.side, self.disc.field(ref).degree, self.rule.points)
            self._basis_gradients[ref] = np.ascontiguousarray(G.transpose(0, 1, 3, 2))
        return self._basis_gradients[ref][cells]

    def basis_laplacian(self, name, cells) -> np.ndarray:
        """Laplacian of every basis function on each cell, (nc, nb)."""
        Jinv = self.mesh.Jinv[cells]
        M = np.einsum("cka,cla->ckl", Jinv, Jinv)
        return np.einsum("ikl,ckl->ci", self.tab(name).hess, M)

    def _facet_batches(self, boundary, degree):
        m = self.mesh
        cells, local, measure = m.boundary_facets(boundary)
        frule = fe.rule(m.dim - 1, degree)
        normals = m.outward_normals(cells, local) if len(cells) else np.zeros((0, m.dim))
        batches = []
        for f in range(m.dim + 1):
            sel = local == f
            if not sel.any():
                continue
            pts = fe.facet_points(m.dim, f, frule.points)
            w = measure[sel, None] * frule.weights[None, :] / fe.REFERENCE_VOLUME[m.dim - 1]
            tabs = {p: fe.ReferenceTable(m.dim, p, pts) for p in (1, 2)}
            batches.append(_FacetBatch(cells[sel], pts, w, normals[sel], tabs))
        return batches

    # -- sparsity -------------------------------------------------------------
    def build_pattern(self):
        """The terms' element values, one ``sparsity.Slab`` per cell term,
        then per facet term and batch, and the blocks they are summed into
        (one per pair of fields, or facet batch; made when first needed).
        Called again, it forgets the blocks' node pairs and sums, which the
        next Jacobian or pattern then makes afresh (``Problem.discard_matrix``)."""
        n = self.mesh.ncells
        slabs = [sparsity.Slab((jb.test, jb.trial), self._entries(jb.test, jb.trial, n), jb.constant)
                 for jb in self.model.jacobians]
        slabs += [sparsity.Slab((ft.field, ft.boundary, i), self._entries(ft.field, ft.field, len(fb.cells)))
                  for ft in self.model.facets if ft.g0 is not None
                  for i, fb in enumerate(self._facets[ft.boundary])]
        self.sums = sparsity.SummedBlocks(slabs, self._node_pairs)
        self.nvalues = sum(sl.size for sl in slabs)
        self._like = {}

    def _entries(self, test, trial, ncells: int) -> int:
        """Number of element entries of one term on ``ncells`` cells."""
        return int(ncells) * self.dofs(test).shape[1] * self.dofs(trial).shape[1]

    def _node_pairs(self, key) -> sparsity.NodePairs:
        """The block of a slab key; blocks over the same element node tables
        share their node-pair index (``_node_tables``)."""
        simplex_dim = self.mesh.rdim        # own and trace tables: the region's simplices, one per row
        if len(key) == 2:
            test, trial = key
            rows, cols = self.dofs(test), self.dofs(trial)
            tables = (self._node_tables(test), self._node_tables(trial))
            if isinstance(test, Adjacent) or isinstance(trial, Adjacent):
                simplex_dim = None          # rock cells next to fracture faces: another element
        else:
            field, boundary, i = key
            test = trial = field
            rows = cols = self.dofs(field)[self._facets[boundary][i].cells]
            tables = (boundary, i, self.disc.field(field).degree)
        m, n = self.disc.field(test).ncomp, self.disc.field(trial).ncomp
        block = sparsity.NodePairs(rows, cols, m, n, self.disc.nlocal, like=self._like.get(tables),
                                   simplex_dim=simplex_dim)
        self._like.setdefault(tables, block)
        return block

    def _node_tables(self, ref) -> tuple:
        """What a field reference's element dof table is made from on this
        region: the mesh points (the elements' vertices, + edges for P2) of
        the region's elements, of a face's, or of the rock cells next to a
        face."""
        kind = type(ref).__name__ if not isinstance(ref, str) else "own"
        side = getattr(ref, "side", None)
        return kind, side, self.disc.field(ref).degree

    @property
    def nnz(self) -> int:
        """Number of summed Jacobian entries (one per nonzero of each block)."""
        return self.sums.nnz

    def coo_pattern(self, rows: np.ndarray | None = None, cols: np.ndarray | None = None):
        """Global COO rows and columns (-1: a constrained row or column) in
        the order ``jacobian_values`` fills them, written into ``rows`` and
        ``cols`` (``nnz`` entries each) when they are given (a slice of the
        whole matrix's pattern: no intermediate copies)."""
        return self.sums.pattern(self.disc.global_index, rows, cols)

    # -- residual -------------------------------------------------------------
    def chunks(self):
        """The region's cells in batches of ``CHUNK``: bounded memory for the
        per-point arrays of P2 in 3D.  Slices, or with ``cell_regions`` the
        cells of one rock region per batch (slices where a region's cells
        are consecutive, else index arrays): a batch's coefficients are
        one region's (``CellContext.region``)."""
        n = self.mesh.ncells
        if self.cell_regions is None:
            for s in range(0, n, CHUNK):
                yield slice(s, min(n, s + CHUNK))
            return
        if self._region_batches is None:
            self._region_batches = list(self._batches_by_region())
        yield from self._region_batches

    def _batches_by_region(self):
        for region in np.unique(self.cell_regions):
            cells = np.flatnonzero(self.cell_regions == region)
            consecutive = cells[-1] - cells[0] + 1 == len(cells)
            for s in range(0, len(cells), CHUNK):
                part = cells[s:s + CHUNK]
                yield slice(int(part[0]), int(part[-1]) + 1) if consecutive else part

    def region_of(self, cells) -> int | None:
        """The rock region of a batch of ``chunks`` (None: one rock)."""
        if self.cell_regions is None:
            return None
        first = cells.start if isinstance(cells, slice) else cells[0]
        return int(self.cell_regions[first])

    def residual(self, xl: np.ndarray, xdl: np.ndarray, t: float, shift: float = 0.0) -> np.ndarray:
        """Local residual vector (scaled) from local solution and its time
        derivative; ``shift``: 1/dt of the step (a kernel that needs the
        increment x - x_old = x_dot / shift, the friction law)."""
        out = np.zeros(self.disc.nlocal)
        self._prepare(self.model.residuals, xl, xdl, t, shift)
        for cells in self.chunks():
            ctx = CellContext(self, cells, xl, xdl, t, shift)
            W = self.W[cells]
            nc = W.shape[0]
            for term in self.model.residuals:
                tab = self.tab(term.field)
                r = 0.0
                if term.f0 is not None:
                    r = tab.phi.T @ (W[:, :, None] * term.f0(ctx))          # (nc, nb, m)
                if term.f1 is not None:
                    f1 = term.f1(ctx)                                       # (nc, nq, m, d)
                    if tab.constant_grad:
                        r = r + self._constant_gradient_flux(term.field, cells, W, f1)
                    else:
                        f1ref = reference_flux(W[:, :, None, None] * f1, ctx.Jinv)
                        r = r + tab.D.T @ f1ref.reshape(nc, -1, f1.shape[2])
                if term.element is not None:
                    r = r + term.element(ctx)                               # (nc, nb, m)
                self._scatter(out, term.field, cells, r)
        for ft in self.model.facets:
            for fb in self._facets[ft.boundary]:
                ctx = FacetContext(self, fb, xl, xdl, t)
                tab = fb.tabs[self.disc.field(ft.field).degree]
                r = tab.phi.T @ (fb.weights[:, :, None] * ft.f0(ctx))
                self._scatter(out, ft.field, fb.cells, r)
        return out

    def tighten(self, xl) -> bool:
        """Each distinct ``prepare`` of the terms that can be tightened at a
        solved state (``prepare.tighten(asm, xl)``, the flux limiter): whether
        any changed the step's equations (collective)."""
        changed = False
        for pre in _distinct_prepares(self.model.residuals):
            if hasattr(pre, "tighten"):
                changed = pre.tighten(self, xl) or changed
        return changed

    def _prepare(self, terms, xl, xdl, t, shift):
        """Each distinct ``prepare`` of the terms, once, before the cells."""
        for pre in _distinct_prepares(terms):
            pre(self, xl, xdl, t, shift)

    def _constant_gradient_flux(self, name, cells, W, f1):
        """sum_q W grad phi_i . f1 for test functions with gradients constant
        over the cell (P1): the cell integral of the flux against the
        physical basis gradients, (nc, nb, m)."""
        constant = f1.shape[1] == 1                                        # constant over the cell too
        F = f1[:, 0] * W.sum(axis=1)[:, None, None] if constant else np.einsum("cq,cqma->cma", W, f1)
        B = self.basis_gradients(name, cells)                              # (nc, nb, d)
        r = B[:, :, None, 0] * F[:, None, :, 0]
        for a in range(1, B.shape[2]):
            r += B[:, :, None, a] * F[:, None, :, a]
        return r

    def _scatter(self, out, name, cells, r):
        idx = self.dofs(name)[cells].ravel()
        out += np.bincount(idx, weights=np.ravel(r) * self.inv_rscale[idx], minlength=out.size)

    # -- Jacobian -------------------------------------------------------------
    def jacobian_values(self, xl, xdl, t, shift, out: np.ndarray | None = None,
                        keep_constant: bool = False) -> np.ndarray:
        """The (scaled) Jacobian dF/dx + shift dF/dx_dot summed per nonzero,
        in ``coo_pattern``'s order, written into ``out`` (of ``nnz``
        entries) when it is given.  ``keep_constant``: the ``constant``
        terms are as in the last call (the caller knows that the scaling has
        not changed since): their element values are not computed again, and
        the blocks of constant terms only are left as they are in ``out``
        (the buffer of the last call)."""
        keep_constant = keep_constant and out is not None
        sums = self.sums
        self._prepare(self.model.jacobians, xl, xdl, t, shift)
        for cells in self.chunks():
            ctx = CellContext(self, cells, xl, xdl, t, shift)        # shared by the blocks of the chunk
            for jb, slab in zip(self.model.jacobians, sums.slabs, strict=False):
                if not sums.skips(slab, keep_constant):
                    K = self._cell_block(jb, ctx, cells)              # (nc, m, n, nbF, nbG)
                    rowfac = self._row_factors(jb.test, jb.trial, self.dofs(jb.test)[cells])
                    sums.store(slab, K, rowfac, cells)
        facet_slabs = iter(sums.slabs[len(self.model.jacobians):])
        for ft in self.model.facets:
            if ft.g0 is None:
                continue
            for fb in self._facets[ft.boundary]:
                ctx = FacetContext(self, fb, xl, xdl, t, shift)
                phi = fb.tabs[self.disc.field(ft.field).degree].phi
                K = self._mass_like(fb.weights[:, :, None, None] * ft.g0(ctx), phi, phi)
                rowfac = self._row_factors(ft.field, ft.field, self.dofs(ft.field)[fb.cells])
                sums.store(next(facet_slabs), K, rowfac, slice(None))
        # (``sum`` zeroes every block it fills: a new buffer need not be zero)
        return sums.sum(out if out is not None else np.empty(self.nnz), keep_constant)

    def _row_factors(self, test, trial, rowdofs) -> np.ndarray:
        """1/(residual scale) of each row times the trial field's scale, as
        (nc, nb, m) for element rows ``rowdofs`` (nc, nb*m)."""
        m = self.disc.field(test).ncomp
        return (self.inv_rscale[rowdofs] * self.scale(trial).scale).reshape(len(rowdofs), -1, m)

    @staticmethod
    def _mass_like(g0w, phiF, phiG):
        """sum_q phiF_i g0w[a,b] phiG_j -> (nc, m, n, nbF, nbG)."""
        nc, nq, m, n = g0w.shape
        M0 = (phiF[:, :, None] * phiG[:, None, :]).reshape(nq, -1)
        K = g0w.transpose(0, 2, 3, 1).reshape(nc * m * n, nq) @ M0
        return K.reshape(nc, m, n, phiF.shape[1], phiG.shape[1])

    def _reference_tensors(self, degF, degG):
        """Products of reference basis functions/gradients per quadrature point
        (``q``) and summed with the rule's weights (``w``, for coefficients
        that are constant over each cell).  Cached per pair of degrees."""
        key = (degF, degG)                  # each a (degree, dual) basis
        if key not in self._ref_cache:
            tF, tG = self._tabs[degF], self._tabs[degG]
            nq = self.rule.weights.size
            w = self.rule.weights
            DF = tF.dphi.transpose(0, 2, 1)                                   # (nq, d, nbF)
            DG = tG.dphi.transpose(0, 2, 1)
            M0 = tF.phi[:, :, None] * tG.phi[:, None, :]                       # (q, i, j)
            M1 = tF.phi[:, None, :, None] * DG[:, :, None, :]                  # (q, l, i, j)
            M2 = DF[:, :, :, None] * tG.phi[:, None, None, :]                  # (q, k, i, j)
            M3 = DF[:, :, None, :, None] * DG[:, None, :, None, :]             # (q, k, l, i, j)
            ref = {}
            for name, M in (("0", M0), ("1", M1), ("2", M2), ("3", M3), ("L", DF)):
                ref[name, False] = M.reshape(nq * int(np.prod(M.shape[1:-2 if name != "L" else -1])), -1)
                Mw = np.tensordot(w, M, axes=(0, 0))
                ref[name, True] = Mw.reshape(int(np.prod(Mw.shape[:-2 if name != "L" else -1])), -1)
            self._ref_cache[key] = ref
        return self._ref_cache[key]

    @staticmethod
    def _at_quadrature(raw, nc, nq, tail):
        """Broadcast a kernel result; a size-1 quadrature axis means 'constant over
        the cell' and is kept, so that the weighted reference tensor is used."""
        raw = np.asarray(raw)
        const = raw.ndim == 2 + len(tail) and raw.shape[1] == 1
        return np.broadcast_to(raw, (nc, 1 if const else nq) + tail), const

    def _adjacent_block(self, jb, ctx, cells):
        """K_ij = sum_q W grad phi_i . g3 . grad psi_j with psi the basis of the
        rock cell next to each fracture face (an ``Adjacent`` trial field, one
        component): (nc, 1, 1, nbF, nbG)."""
        W = self.W[cells]
        (nc, nq), d = W.shape, self.mesh.dim
        G = self.adjacent_gradients(jb.trial, cells)                       # (nc, nq or 1, d, nbG)
        tab = self.tab(jb.test)
        gw = physical_gradient(tab.dphi.transpose(0, 2, 1)[None], ctx.Jinv)  # (nc, nq, nbF, d)
        g = np.broadcast_to(jb.g3(ctx), (nc, nq, 1, d, 1, d))[:, :, 0, :, 0, :]
        T = (g @ G).reshape(nc, nq * d, -1)
        U = (W[:, :, None, None] * gw).transpose(0, 2, 1, 3).reshape(nc, -1, nq * d)
        return (U @ T)[:, None, None]

    #: gradient terms of P1 test and trial functions summed over the cell first
    #: (``_constant_gradient_terms``); False: the reference-tensor path for every term
    CONSTANT_GRADIENT_PATH = True
    _constant_gradient_terms = constant_gradient_terms

    def _cell_block(self, jb, ctx, cells):
        if isinstance(jb.trial, Adjacent):
            return self._adjacent_block(jb, ctx, cells)
        fF, fG = self.disc.field(jb.test), self.disc.field(jb.trial)
        tF, tG = self.tab(jb.test), self.tab(jb.trial)
        fast = {"g1": tG.constant_grad, "g2": tF.constant_grad, "g3": tF.constant_grad}
        fast = {k: v and self.CONSTANT_GRADIENT_PATH and getattr(jb, k) is not None for k, v in fast.items()}
        ref = self._reference_tensors(self.basis(jb.test), self.basis(jb.trial))
        Jinv, JinvT = ctx.Jinv, np.swapaxes(ctx.Jinv, 1, 2)
        W = self.W[cells]
        absdet = np.abs(self.mesh.detJ[cells])[:, None]
        nc, nq, d = W.shape[0], W.shape[1], self.mesh.dim
        nbF, nbG = self.tab(jb.test).phi.shape[1], self.tab(jb.trial).phi.shape[1]
        m, n = fF.ncomp, fG.ncomp
        K = np.zeros((nc * m * n, nbF * nbG))

        def weights(const):
            return absdet if const else W

        if jb.g0 is not None:
            g, c = self._at_quadrature(jb.g0(ctx), nc, nq, (m, n))
            g = g * weights(c)[:, :, None, None]
            K += g.transpose(0, 2, 3, 1).reshape(nc * m * n, -1) @ ref["0", c]
        if any(fast.values()):
            K += self._constant_gradient_terms(jb, ctx, cells, fast).reshape(K.shape)
        if jb.g1 is not None and not fast["g1"]:
            g, c = self._at_quadrature(jb.g1(ctx), nc, nq, (m, n, d))
            g = np.einsum("cqabe,cle->cabql", g, Jinv) * weights(c)[:, None, None, :, None]
            K += g.reshape(nc * m * n, -1) @ ref["1", c]
        if jb.g2 is not None and not fast["g2"]:
            g, c = self._at_quadrature(jb.g2(ctx), nc, nq, (m, d, n))
            g = np.einsum("cqaeb,cke->cabqk", g, Jinv) * weights(c)[:, None, None, :, None]
            K += g.reshape(nc * m * n, -1) @ ref["2", c]
        if jb.g2_lap is not None:
            g, c = self._at_quadrature(jb.g2_lap(ctx), nc, nq, (m, d, n))
            g = np.einsum("cqaeb,cke->cabqk", g, Jinv) * weights(c)[:, None, None, :, None]
            T = g.reshape(nc * m * n, -1) @ ref["L", c]                       # (nc m n, nbF)
            lap = self.basis_laplacian(jb.trial, cells)                       # (nc, nbG)
            K += (T.reshape(nc, m * n, nbF, 1) * lap[:, None, None, :]).reshape(K.shape)
        if jb.g3 is not None and not fast["g3"]:
            g, c = self._at_quadrature(jb.g3(ctx), nc, nq, (m, d, n, d))
            if m == 1 and n == 1:   # J^-1 g3 J^-T per quadrature point, as batched matmul
                g = Jinv[:, None] @ g[:, :, 0, :, 0, :] @ JinvT[:, None]
                g = g * weights(c)[:, :, None, None]
            else:
                g = Jinv[:, None, None, None] @ g.transpose(0, 1, 2, 4, 3, 5) @ JinvT[:, None, None, None]
                g = (g * weights(c)[:, :, None, None, None, None]).transpose(0, 2, 3, 1, 4, 5)
            K += g.reshape(nc * m * n, -1) @ ref["3", c]
        if jb.element is not None:
            K += np.asarray(jb.element(ctx)).reshape(K.shape)
        return K.reshape(nc, m, n, nbF, nbG)
