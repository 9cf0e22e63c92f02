"""Algebraic upwinding of the heat transport: the low-order, bound-preserving
scheme of ``-thm_heat_transport upwind`` (theory manual, "Discrete bounds").

For P1 temperatures the Galerkin advection of the conservative form
(``kernels/heat.py``: the residual's -grad w . b T) is, element by element,
the matrix

    k_ij = -int_e grad phi_i . b phi_j dx

whose off-diagonal entries have either sign: where one is positive, a node
is driven away from its neighbour's temperature and a new extremum can
form.  Discrete upwinding (Kuzmin, "Algebraic flux correction I", 2012)
adds the symmetric element diffusion

    d_ij = max(0, k_ij, k_ji)   (i != j),      r_i += sum_j d_ij (T_i - T_j),

which makes every off-diagonal entry k_ij - d_ij <= 0 and leaves every row
and column sum of the operator unchanged: sum_i r_i = 0, so the energy
balance is that of the Galerkin scheme.  With the capacity lumped and no
stabilisation term, the transport operator of a backward-Euler step is then
an M-matrix up to the flow's mass change (T m, with m the fluid stored at
the node: theory manual, "Discrete bounds"), and the nodal temperatures stay
between their neighbours'.  The price is first-order accuracy where the
flow dominates the conduction of an element (d_ij ~ |b| h).

The matrix k uses b at the quadrature points of the Galerkin term, so that
d_ij bounds exactly the entries it corrects.  Its Jacobian is exact away
from the kinks of the max (where the branch taken is differentiated):
with respect to T (the nodal values, and the mobility M(T) in b), to the
pressure (b = -rho_f C_f M K grad p) and, on a deformable fracture, to the
aperture (b ~ a^3) and through it to lam and u+-.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from petthm.discretisation.model import CellJacobian, CellResidual, Region


@dataclass(frozen=True)
class Upwinding:
    """The discrete upwinding of one region's heat transport (``heat.Heat``,
    P1, advected); ``point(heat, ctx)`` gives its data at the quadrature
    points (``heat.heat_point``: the Darcy flux b, the mobility, the aperture)."""
    heat: object
    point: Callable


class _Element:
    """k, d and what their derivatives need, on a batch of cells."""

    def __init__(self, u: Upwinding, ctx):
        h = u.heat
        hp = u.point(h, ctx)
        self.hp = hp
        self.Wphi = ctx.weights[:, :, None] * ctx.basis(h.T)[None]            # (nc, nq, nb)
        self.G = ctx.basis_gradients(h.T)                                      # (nc, nb, d)
        B = np.einsum("cqj,cqa->cja", self.Wphi, np.broadcast_to(hp.b, ctx.shape + (ctx.dim,)))
        K = -self.G @ B.transpose(0, 2, 1)                                     # (nc, i, j)
        Kt = K.transpose(0, 2, 1)
        off = ~np.eye(K.shape[1], dtype=bool)[None]
        self.s1 = (Kt <= K) & (K > 0) & off                   # d_ij = k_ij
        self.s2 = (Kt > K) & (Kt > 0) & off                   # d_ij = k_ji
        self.D = np.where(self.s1, K, 0.0) + np.where(self.s2, Kt, 0.0)
        T = ctx.nodal(h.T)[..., 0]
        self.dT = T[:, :, None] - T[:, None, :]                                # T_i - T_j

    def chain(self, dK):
        """sum_j (T_i - T_j) dd_ij/dx_k for dk_ij/dx_k = dK[c, i, j, k...]."""
        dKt = np.swapaxes(dK, 1, 2)
        sel = self.s1.reshape(self.s1.shape + (1,) * (dK.ndim - 3))
        sel2 = self.s2.reshape(sel.shape)
        dT = self.dT.reshape(sel.shape)
        return (dT * (np.where(sel, dK, 0.0) + np.where(sel2, dKt, 0.0))).sum(axis=2)


def _element(u: Upwinding, ctx) -> _Element:
    return ctx.cached(("upwinding", id(u)), lambda: _Element(u, ctx))


def upwinding_residual(u: Upwinding, ctx):
    e = _element(u, ctx)
    return (e.D * e.dT).sum(axis=2)[..., None]


def upwinding_TT(u: Upwinding, ctx):
    """d r_i / d T_k: the diffusion's own matrix, and through the mobility M(T) in b."""
    e = _element(u, ctx)
    A = -e.D
    idx = np.arange(A.shape[1])
    A[:, idx, idx] = e.D.sum(axis=2)
    hp = e.hp
    if np.any(hp.m):
        phi = ctx.basis(u.heat.T)
        BT = np.einsum("cqj,qk,cqa->cjka", e.Wphi, phi, hp.m[..., None] * hp.b)
        A = A + e.chain(-np.einsum("cia,cjka->cijk", e.G, BT))
    return A[:, None, None]


def _coefficient(u: Upwinding, ctx):
    """M (a^3 on a deformable fracture) at the quadrature points: b = -rho_f C_f coef K grad p."""
    hp = _element(u, ctx).hp
    return hp.M if hp.ap is None else hp.M * hp.ap.a ** 3


def upwinding_Tp(u: Upwinding, ctx):
    """d r_i / d p_k: dk_ij/dp_k = rho_f C_f (sum_q W phi_j coef) grad phi_i . K grad psi_k."""
    e = _element(u, ctx)
    h = u.heat
    Cj = np.einsum("cqj,cq->cj", e.Wphi, np.broadcast_to(_coefficient(u, ctx), ctx.shape))
    Gp = ctx.basis_gradients(h.flow.p)
    GKG = e.G @ h.flow.permeability @ Gp.transpose(0, 2, 1)                  # (nc, i, k)
    dK = h.fluid_rho_c * Cj[:, None, :, None] * GKG[:, :, None, :]
    return e.chain(dK)[:, None, None]


def upwinding_aperture(u: Upwinding, ctx):
    """d r_i / d a_q (nc, nb, nq): db_q/da_q = 3 b_q / a_q."""
    e = _element(u, ctx)
    hp = e.hp
    Gb = np.einsum("cia,cqa->ciq", e.G, hp.b)                                  # grad phi_i . b_q
    dK = -3.0 * (Gb / hp.ap.a[:, None, :])[:, :, None, :] * e.Wphi.transpose(0, 2, 1)[:, None, :, :]
    return e.chain(dK)


def upwinding_terms(u: Upwinding) -> tuple[list, list]:
    h = u.heat
    if h.degree != 1:
        raise ValueError("algebraic upwinding needs P1 temperatures (and the P1 pressure that advects them)")
    region = Region(h.region)
    res = [CellResidual(h.T, None, None, region=region, element=lambda ctx: upwinding_residual(u, ctx))]
    jac = [CellJacobian(h.T, h.T, region=region, element=lambda ctx: upwinding_TT(u, ctx))]
    if h.flow is not None:
        jac.append(CellJacobian(h.T, h.flow.p, region=region, element=lambda ctx: upwinding_Tp(u, ctx)))
    if h.aperture is not None:
        jac += h.aperture.element_jacobians(h.T, lambda ctx: upwinding_aperture(u, ctx), region)
    return res, jac
