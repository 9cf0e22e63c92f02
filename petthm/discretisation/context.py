"""What a kernel sees: the fields of the model at the quadrature points of a
batch of cells (``CellContext``) or of boundary facets (``FacetContext``),
in SI units, with the geometry of the batch.

Kernels (``petthm.physics.kernels``) call only the public methods and properties:
``value``, ``grad``, ``dot``, ``grad_dot``, ``lap``, ``x``, ``h``, ``t``,
``shift``, ``shape``, ``normals`` (fracture faces), ``n`` (facets),
``cell_values`` and ``cached`` (point data several kernels of a batch share);
element terms (``model.CellResidual.element``) also ``nodal``,
``nodal_rate``, ``weights``, ``basis``, ``basis_gradients`` and
``basis_gradients_at_points``.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from petthm.discretisation.fields import Adjacent


def physical_gradient(G, Jinv):
    """grad[c,q,m,a] = sum_k G[c,q,k,m] Jinv[c,k,a] for reference gradients G (nc,nq,d,m).

    Written as d broadcast multiply-adds: numpy's batched matmul is slow for
    millions of 3x3 products."""
    d = Jinv.shape[1]
    out = G[:, :, 0, :, None] * Jinv[:, None, None, 0, :]
    for k in range(1, d):
        out += G[:, :, k, :, None] * Jinv[:, None, None, k, :]
    return out


class CellContext:
    """Fields at the quadrature points of a batch of cells (SI units).

    ``value(f)`` (nc, nq, ncomp), ``grad(f)`` (nc, nq, ncomp, dim),
    ``dot(f)`` time derivative values, ``lap(f)`` (nc, 1, ncomp) Laplacian
    (constant per cell for P1/P2 on affine cells); ``x`` (nc, nq, dim)
    physical points, ``h`` (nc, 1) cell size, ``t`` time, ``shift`` the
    d(x_dot)/dx of the time integrator.
    """

    def __init__(self, asm, cells: slice, xl, xdl, t, shift=0.0):      # asm: an assembly.Assembler
        self._asm, self._cells, self._xl, self._xdl = asm, cells, xl, xdl
        self.t, self.shift = t, shift
        m = asm.mesh
        self.dim = m.dim
        self.Jinv = m.Jinv[cells]
        self.h = m.h[cells][:, None]
        #: the rock region of the batch (kernels/regional.py; None: one rock)
        self.region = asm.region_of(cells)
        self._cache = {}

    def cached(self, key, compute: Callable):
        """``compute()`` once per context (a batch of cells at one state): for
        point data that several kernels of the batch share."""
        if key not in self._cache:
            self._cache[key] = compute()
        return self._cache[key]

    def cell_values(self, per_cell: np.ndarray) -> np.ndarray:
        """The rows of a per-element array (of this region) for this batch."""
        return per_cell[self._cells]

    @property
    def normals(self) -> np.ndarray:
        """Unit normal of each fracture face (nc, 1, d), from the - to the + face
        (fracture regions only)."""
        return self.cached("normals", lambda: self._asm.mesh.normals[self._cells][:, None, :])

    @property
    def shape(self) -> tuple[int, int]:
        """(number of cells, number of quadrature points) of this batch."""
        return (self.Jinv.shape[0], self._asm.rule.weights.size)

    @property
    def x(self):
        """Physical coordinates of the quadrature points (nc, nq, dim)."""
        if "x" not in self._cache:
            m = self._asm.mesh
            self._cache["x"] = m.x0[self._cells][:, None, :] + \
                np.einsum("cak,qk->cqa", m.J[self._cells], self._asm.rule.points)
        return self._cache["x"]

    def _nodal(self, name, dot=False, offset=True):
        """The field's nodal values on the cells, SI (its rate's with ``dot``);
        without ``offset``, less the field's constant offset: what a gradient
        is taken of (the constant has none, and a large offset, an absolute
        pressure of 1 MPa against changes of 0.1 MPa, would cost the gradient
        its digits)."""
        key = ("n", name, dot, offset)
        if key not in self._cache:
            a = self._asm
            f = a.disc.field(name)
            sc = a.scale(name)
            src = self._xdl if dot else self._xl
            v = src[a.dofs(name)[self._cells]] * sc.scale
            if offset and not dot:
                v = v + sc.offset
            self._cache[key] = v.reshape(v.shape[0], -1, f.ncomp)
        return self._cache[key]

    def value(self, name):
        key = ("v", name)
        if key not in self._cache:
            self._cache[key] = self._asm.tab(name).phi @ self._nodal(name)
        return self._cache[key]

    def nodal(self, name):
        """The field's values at the element's nodes (nc, nb, ncomp), SI."""
        return self._nodal(name)

    def nodal_rate(self, name):
        """The rate of the field's nodal values (nc, nb, ncomp), SI."""
        return self._nodal(name, dot=True)

    def basis_gradients_at_points(self, name):
        """Physical gradients of the field's basis at the quadrature points (nc, nq, nb, dim)."""
        tab = self._asm.tab(name)
        nq, nb, r = tab.dphi.shape
        G = np.broadcast_to(tab.dphi.transpose(0, 2, 1)[None], (self.Jinv.shape[0], nq, r, nb))
        return physical_gradient(G, self.Jinv)

    @property
    def weights(self):
        """Quadrature weights times |det J| (nc, nq)."""
        return self._asm.W[self._cells]

    def basis(self, name):
        """The field's basis at the quadrature points (nq, nb)."""
        return self._asm.tab(name).phi

    def basis_gradients(self, name):
        """Physical gradients of a P1 field's basis on each cell (nc, nb, dim)."""
        return self._asm.basis_gradients(name, self._cells)

    def dot(self, name):
        key = ("d", name)
        if key not in self._cache:
            self._cache[key] = self._asm.tab(name).phi @ self._nodal(name, dot=True)
        return self._cache[key]

    def grad(self, name):
        """Gradient (nc, nq, ncomp, dim); (nc, 1, ncomp, dim) where it is
        constant over each cell (P1 fields)."""
        key = ("g", name)
        if key not in self._cache:
            self._cache[key] = self._gradient(name, self._nodal(name, offset=False))
        return self._cache[key]

    def grad_dot(self, name):
        """Gradient of the time derivative (nc, nq, ncomp, dim) (or nq = 1, as ``grad``)."""
        key = ("gd", name)
        if key not in self._cache:
            self._cache[key] = self._gradient(name, self._nodal(name, dot=True))
        return self._cache[key]

    def _gradient(self, name, X):
        """Physical gradient of the field with nodal values X (nc, nb, m); of
        an ``Adjacent`` field: in the rock cell next to each fracture face."""
        if isinstance(name, Adjacent):
            G = self._asm.adjacent_gradients(name, self._cells)                 # (nc, nq, d, nb)
            nc, nq, d, nb = G.shape
            return (G.reshape(nc, nq * d, nb) @ X).reshape(nc, nq, d, -1).transpose(0, 1, 3, 2)
        tab = self._asm.tab(name)
        if tab.constant_grad:          # one point per cell: sum_i X_i grad phi_i
            B = self._asm.basis_gradients(name, self._cells)                 # (nc, nb, d)
            G = X[:, 0, :, None] * B[:, None, 0, :]
            for i in range(1, B.shape[1]):
                G += X[:, i, :, None] * B[:, None, i, :]
            return G[:, None]
        nc, nq, r = X.shape[0], tab.phi.shape[0], self.Jinv.shape[1]
        return physical_gradient((tab.D @ X).reshape(nc, nq, r, -1), self.Jinv)

    def lap(self, name):
        key = ("l", name)
        if key not in self._cache:
            lapb = self._asm.basis_laplacian(name, self._cells)         # (nc, nb)
            self._cache[key] = np.einsum("ci,cim->cm", lapb, self._nodal(name, offset=False))[:, None, :]
        return self._cache[key]


class FacetContext(CellContext):
    """Fields at the quadrature points of boundary facets (same API) plus ``n``."""

    def __init__(self, asm, fb, xl, xdl, t, shift=0.0):
        self._asm, self._cells, self._xl, self._xdl = asm, fb.cells, xl, xdl
        self.t, self.shift = t, shift
        m = asm.mesh
        self.dim = m.dim
        self.Jinv = m.Jinv[fb.cells]
        self.h = m.h[fb.cells][:, None]
        self.region = None
        self._fb = fb
        self._cache = {"x": m.x0[fb.cells][:, None, :] + np.einsum("cak,qk->cqa", m.J[fb.cells], fb.points)}
        self.n = np.broadcast_to(fb.normals[:, None, :], self.x.shape)

    @property
    def shape(self) -> tuple[int, int]:
        return self.x.shape[:2]

    def value(self, name):
        key = ("v", name)
        if key not in self._cache:
            self._cache[key] = self._fb.tabs[self._asm.disc.field(name).degree].phi @ self._nodal(name)
        return self._cache[key]

    def dot(self, name):
        key = ("d", name)
        if key not in self._cache:
            self._cache[key] = self._fb.tabs[self._asm.disc.field(name).degree].phi @ \
                self._nodal(name, dot=True)
        return self._cache[key]

    def grad(self, name):  # pragma: no cover - not needed by the present facet terms
        raise NotImplementedError("facet kernels receive values only")
