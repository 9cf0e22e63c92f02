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
from dataclasses import dataclass, replace

import numpy as np

from petthm.discretisation.model import CellJacobian, CellResidual, Region
from petthm.physics.kernels.flow import increment_product, water_content, water_content_rate
from petthm.physics.kernels.regional import at, regional


@dataclass(frozen=True)
class Upwinding:
    """The discrete upwinding of one region's heat transport (``heat.Heat``,
    P1, advected); ``point(heat, ctx)`` gives its data at the quadrature
    points (``heat.heat_point``: the Darcy flux b, the mobility, the aperture).
    ``limiter``: the flux correction that gives back the diffusion d_ij where
    the solution is smooth (``kernels/limiter.py``; None: plain upwinding)."""
    heat: object
    point: Callable
    limiter: object | None = None


class _Element:
    """k, d and what their derivatives need, on a batch of cells; ``limited``:
    d_ij times the limiter's 1 - alpha_ij of the cells (held fixed in the
    derivatives: kernels/limiter.py)."""

    def __init__(self, u: Upwinding, ctx, limited: bool = True):
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
        self.T = T
        self.dT = T[:, :, None] - T[:, None, :]                                # T_i - T_j
        self.keep = None
        if limited and u.limiter is not None:
            self.keep = ctx.cell_values(u.limiter.keep)                        # 1 - alpha_ij
            self.D = self.D * self.keep

    def chain(self, dK):
        """sum_j (T_i - T_j) dd_ij/dx_k for dk_ij/dx_k = dK[c, i, j, k...]."""
        dKt = np.swapaxes(dK, 1, 2)
        sel = self.s1.reshape(self.s1.shape + (1,) * (dK.ndim - 3))
        sel2 = self.s2.reshape(sel.shape)
        dT = self.dT if self.keep is None else self.dT * self.keep
        dT = dT.reshape(sel.shape)
        return (dT * (np.where(sel, dK, 0.0) + np.where(sel2, dKt, 0.0))).sum(axis=2)


def _element(u: Upwinding, ctx) -> _Element:
    return ctx.cached(("upwinding", id(u)), lambda: _Element(u, ctx))


def upwinding_diffusion(u: Upwinding, ctx):
    """The upwinding's d_ij and T_i - T_j on the cells, unlimited (nc, nb, nb):
    what the limiter corrects."""
    e = _Element(at(u, ctx), ctx, limited=False)
    return e.D, e.dT, e.T


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
    pre = u.limiter
    res = [CellResidual(h.T, None, None, region=region, element=regional(upwinding_residual, u), prepare=pre)]
    jac = [CellJacobian(h.T, h.T, region=region, element=regional(upwinding_TT, u), prepare=pre)]
    if h.flow is not None:
        jac.append(CellJacobian(h.T, h.flow.p, region=region, element=regional(upwinding_Tp, u), prepare=pre))
    if h.aperture is not None:
        jac += [replace(j, prepare=pre) for j in
                h.aperture.element_jacobians(h.T, regional(upwinding_aperture, u), region)]
    return res, jac


# -- the energy of the stored water ------------------------------------------------------
@dataclass(frozen=True)
class StoredWater:
    """The energy rho_f C_f m T of the water a region stores, m the flow's
    water content (``flow.water_content``), in nodal form (theory manual,
    "Discrete bounds")::

        r_i += rho_f C_f (m_i dT_i/dt + mdot_i T_i - mdot_i dT_i/dt / shift),
        m_i = int phi_i m,   mdot_i = int phi_i mdot,

    backward Euler's exact quotient of rho_f C_f m_i T_i (the energy
    balance telescopes).  mdot_i is the storage term of the flow's row i
    (the same quadrature rule), so that the Galerkin advection's row sum,
    which the flow's mass balance makes -rho_f C_f mdot_i T_i (the water
    stored, counted as heat in kelvin), cancels against mdot_i T_i: no
    source proportional to the temperature remains, and the upwinded
    operator is local-extremum-diminishing.  ``biot``: (u, alpha), the
    water the rock's volume change alpha div u stores; ``aperture``: a
    deformable fracture, whose content a (1 + s) replaces its capacity a rho_f C_f."""
    heat: object
    flow: object
    biot: tuple = ()


class _Water:
    def __init__(self, w: StoredWater, ctx):
        h, fl = w.heat, w.flow
        self.Wphi = ctx.weights[:, :, None] * ctx.basis(h.T)[None]                 # (nc, nq, nb)
        m, self.dm_dp, self.dm_dT, self.dm_da = water_content(fl, ctx)
        mdot = water_content_rate(fl, ctx)
        if w.biot:
            u, alpha = w.biot
            m = m + alpha * np.trace(ctx.grad(u), axis1=2, axis2=3)
            mdot = mdot + alpha * np.trace(ctx.grad_dot(u), axis1=2, axis2=3)
        self.m = np.einsum("cqi,cq->ci", self.Wphi, np.broadcast_to(m, ctx.shape))
        self.mdot = np.einsum("cqi,cq->ci", self.Wphi, np.broadcast_to(mdot, ctx.shape))
        self.T = ctx.nodal(h.T)[..., 0]
        self.Tdot = ctx.nodal_rate(h.T)[..., 0]
        self.c = h.fluid_rho_c

    def value_block(self, ctx, dm, trial):
        """c shift T_i int phi_i dm psi_k: the Jacobian through m's dependence dm on a trial value."""
        B = np.einsum("cqi,cq,qk->cik", self.Wphi, np.broadcast_to(dm, ctx.shape), ctx.basis(trial))
        return self.c * ctx.shift * self.T[:, :, None] * B


def _water(w: StoredWater, ctx) -> _Water:
    return ctx.cached(("stored water", id(w)), lambda: _Water(w, ctx))


def stored_water_residual(w: StoredWater, ctx):
    e = _water(w, ctx)
    return (e.c * (e.m * e.Tdot + e.mdot * e.T - increment_product(ctx, e.mdot, e.Tdot)))[..., None]


def stored_water_TT(w: StoredWater, ctx):
    """d/dT_k of c (m_i T_i)^. : c shift (m_i delta_ik + T_i dm_i/dT_k)."""
    e = _water(w, ctx)
    nc, _, nb = e.Wphi.shape
    A = e.value_block(ctx, e.dm_dT, w.heat.T) if w.flow.T == w.heat.T else np.zeros((nc, nb, nb))
    idx = np.arange(A.shape[1])
    A[:, idx, idx] += e.c * ctx.shift * e.m
    return A[:, None, None]


def stored_water_Tp(w: StoredWater, ctx):
    e = _water(w, ctx)
    return e.value_block(ctx, e.dm_dp, w.flow.p)[:, None, None]


def stored_water_Tu(w: StoredWater, ctx):
    """Through alpha div u: c shift T_i int phi_i alpha d(psi_k)/dx_j, (nc, 1, d, nb, nbu)."""
    e = _water(w, ctx)
    u, alpha = w.biot
    G = ctx.basis_gradients_at_points(u)                                           # (nc, nq|1, nbu, d)
    B = np.einsum("cqi,cqka->caik", e.Wphi, np.broadcast_to(G, (G.shape[0], e.Wphi.shape[1]) + G.shape[2:]))
    return (e.c * ctx.shift * alpha * e.T[:, None, :, None] * B)[:, None]


def stored_water_aperture(w: StoredWater, ctx):
    """d r_i / d a_q (nc, nb, nq): c shift T_i W_q phi_i(q) (1 + s_q)."""
    e = _water(w, ctx)
    return e.c * ctx.shift * e.T[:, :, None] * (e.Wphi * e.dm_da[:, :, None]).transpose(0, 2, 1)


def stored_water_terms(w: StoredWater) -> tuple[list, list]:
    h, fl = w.heat, w.flow
    region = Region(h.region)
    res = [CellResidual(h.T, None, None, region=region, element=regional(stored_water_residual, w))]
    jac = [CellJacobian(h.T, h.T, region=region, element=regional(stored_water_TT, w)),
           CellJacobian(h.T, fl.p, region=region, element=regional(stored_water_Tp, w))]
    if w.biot:
        jac.append(CellJacobian(h.T, w.biot[0], region=region, element=regional(stored_water_Tu, w)))
    if fl.aperture is not None:
        jac += fl.aperture.element_jacobians(h.T, regional(stored_water_aperture, w), region)
    return res, jac
