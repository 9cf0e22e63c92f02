"""Fluid flow and heat transport on one region (matrix cells or fracture faces).

The same kernels serve the matrix (physics.md sections 5-6, rigid rock) and
the fracture (sections 4 and 7, fixed aperture); only the coefficients
differ.  With mobility M(T) = 1/mu(T) and a constant "permeability" tensor K
(the matrix permeability k_m, or a^3/12 I on the fracture):

flow (unknown p)::

    S dp/dt - B dT/dt + div q = 0,        q = -M(T) K grad p

heat (unknown T), in conservative form with the fluid's enthalpy flux
b T, b = rho_f C_f q::

    C dT/dt + div(b T - L grad T) = 0

Matrix: S = phi c_f + (alpha - phi)/K_s, B = phi beta_f, C = (rho C)_m,
L = lambda_m.  Fracture: S = a c_f, B = a beta_f, C = a rho_f C_f,
L = a lambda_f, and grad is the tangential gradient.

Weak forms (w a test function)::

    int w (S pdot - B Tdot) + grad w . M K grad p
    int w C Tdot - grad w . (b T - L grad T) + sum_e int tau (b . grad w) R

The conservative heat form makes the discrete energy balance exact: with
w = 1 every flux term cancels, so the stored-energy change equals the
enthalpy brought in by wells and boundaries (physics.md section 7).  It
differs from the advective form of section 7 by T (S pdot - B Tdot), the
fluid's storage rate times T, which vanishes for an incompressible fluid.
SUPG (Brooks & Hughes 1982) uses the residual of the advective form,
R = C Tdot + b . grad T - L lap T (+ the wall exchange on the fracture),
tau = ((2|b|/h_p)^2 + 9 (4 L/h_p^2)^2)^(-1/2), h_p = h/p.  With w = 1 the
SUPG term vanishes, so it does not disturb the balance.  Every Jacobian
block is exact (tests/test_fracture_physics.py checks them against finite
differences).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import partial
from typing import Optional

import numpy as np

from ..fluid import Viscosity
from ..model import CellJacobian, CellResidual


@dataclass(frozen=True)
class Flow:
    """Flow coefficients of one region (see the module docstring)."""
    region: str
    p: str                          # pressure field
    T: Optional[str]                # temperature field of mu(T) and B (None: isothermal)
    storage: float                  # S
    permeability: np.ndarray        # K (d, d)
    viscosity: Viscosity = field(default_factory=Viscosity)
    thermal_storage: float = 0.0    # B


@dataclass(frozen=True)
class Heat:
    """Heat-transport coefficients of one region."""
    region: str
    T: str
    capacity: float                 # C
    conductivity: object            # L: a number, or a (d, d) tensor (no advection then)
    fluid_rho_c: float = 0.0        # rho_f C_f (0: no advection)
    flow: Optional[Flow] = None     # the flow that advects heat
    degree: int = 2
    supg: bool = True
    exchange: tuple = ()            # (hw, trace name) pairs: R += hw (T - T_trace) (fracture)


# -- helpers ----------------------------------------------------------------------
def _mobility(fl: Flow, ctx):
    """(M, dM/dT) at the quadrature points, (nc, nq)."""
    if fl.T is None or not fl.viscosity.water:
        m = 1.0 / fl.viscosity.value
        return np.full(ctx.shape, m), np.zeros(ctx.shape)
    return fl.viscosity.mobility(ctx.value(fl.T)[..., 0])


def _Kgradp(fl: Flow, ctx):
    return np.einsum("ab,cqb->cqa", fl.permeability, ctx.grad(fl.p)[:, :, 0, :])


# -- flow -------------------------------------------------------------------------
def flow_f0(fl: Flow, ctx):
    r = fl.storage * ctx.dot(fl.p)
    if fl.T is not None and fl.thermal_storage:
        r = r - fl.thermal_storage * ctx.dot(fl.T)
    return r


def flow_f1(fl: Flow, ctx):
    M, _ = _mobility(fl, ctx)
    return (M[..., None] * _Kgradp(fl, ctx))[:, :, None, :]


def flow_g0_pp(fl: Flow, ctx):
    return np.full((1, 1, 1, 1), fl.storage * ctx.shift)


def flow_g3_pp(fl: Flow, ctx):
    M, _ = _mobility(fl, ctx)
    if fl.T is None or not fl.viscosity.water:
        return (M[0, 0] * fl.permeability)[None, None, None, :, None, :]
    return (M[:, :, None, None] * fl.permeability)[:, :, None, :, None, :]


def flow_g0_pT(fl: Flow, ctx):
    return np.full((1, 1, 1, 1), -fl.thermal_storage * ctx.shift)


def flow_g2_pT(fl: Flow, ctx):
    _, dM = _mobility(fl, ctx)
    return (dM[..., None] * _Kgradp(fl, ctx))[:, :, None, :, None]


def flow_terms(fl: Flow) -> tuple[list, list]:
    """Residual and Jacobian registrations of a flow equation."""
    res = [CellResidual(fl.p, partial(flow_f0, fl), partial(flow_f1, fl), region=fl.region)]
    jac = [CellJacobian(fl.p, fl.p, g0=partial(flow_g0_pp, fl) if fl.storage else None,
                        g3=partial(flow_g3_pp, fl), region=fl.region)]
    if fl.T is not None and (fl.thermal_storage or fl.viscosity.water):
        jac.append(CellJacobian(fl.p, fl.T,
                                g0=partial(flow_g0_pT, fl) if fl.thermal_storage else None,
                                g2=partial(flow_g2_pT, fl) if fl.viscosity.water else None,
                                region=fl.region))
    return res, jac


# -- heat -------------------------------------------------------------------------
class _HeatPoint:
    """Everything the heat residual and its derivatives need at the quadrature points."""

    def __init__(self, h: Heat, ctx):
        self.h = h
        T = h.T
        self.gT = ctx.grad(T)[:, :, 0, :]                           # (nc, nq, d)
        self.Tv = ctx.value(T)[..., 0]
        self.advect = h.flow is not None and h.fluid_rho_c != 0.0
        d = ctx.dim
        if self.advect:
            M, dM = _mobility(h.flow, ctx)
            self.M, self.dM = M, dM
            self.b = -h.fluid_rho_c * M[..., None] * _Kgradp(h.flow, ctx)     # (nc, nq, d)
            # m = (db/dT)/b componentwise factor: b depends on T through M(T)
            self.m = dM / M if h.flow.T == T else np.zeros_like(M)
            hp = ctx.h / h.degree
            self.A = 4.0 / hp ** 2
            B0 = 9.0 * (4.0 * h.conductivity / hp ** 2) ** 2
            bb = np.einsum("cqa,cqa->cq", self.b, self.b)
            self.tau = 1.0 / np.sqrt(self.A * bb + B0) if h.supg else np.zeros_like(bb)
            R = h.capacity * ctx.dot(T)[..., 0] + np.einsum("cqa,cqa->cq", self.b, self.gT)
            if h.degree > 1:
                R = R - h.conductivity * ctx.lap(T)[..., 0]
            for hw, trace in h.exchange:
                R = R + hw * (self.Tv - ctx.value(trace)[..., 0])
            self.R = R
        self.d = d

    def dZ_db(self):
        """dZ_a/db_c of Z = tau R b: (nc, nq, a, c)."""
        tau, R, b = self.tau, self.R, self.b
        eye = np.eye(self.d)[None, None]
        return (-(tau ** 3 * self.A * R)[..., None, None] * b[..., :, None] * b[..., None, :]
                + tau[..., None, None] * b[..., :, None] * self.gT[..., None, :]
                + (tau * R)[..., None, None] * eye)


def _conduction(h: Heat, gT):
    L = h.conductivity
    return L * gT if np.isscalar(L) else np.einsum("ab,cqb->cqa", L, gT)


def heat_f0(h: Heat, ctx):
    r = h.capacity * ctx.dot(h.T)[..., 0]
    return r[..., None]


def heat_f1(h: Heat, ctx):
    hp = _HeatPoint(h, ctx)
    f1 = _conduction(h, hp.gT)
    if hp.advect:
        f1 = f1 - hp.b * hp.Tv[..., None]
        if h.supg:
            f1 = f1 + (hp.tau * hp.R)[..., None] * hp.b
    return f1[:, :, None, :]


def heat_g0_TT(h: Heat, ctx):
    return np.full((1, 1, 1, 1), h.capacity * ctx.shift)


def heat_g2_TT(h: Heat, ctx):
    hp = _HeatPoint(h, ctx)
    b, m = hp.b, hp.m[..., None]
    g = -b * (1.0 + hp.Tv[..., None] * m)                   # d(-b T)/dT
    if h.supg:
        extra = h.capacity * ctx.shift + sum(hw for hw, _ in h.exchange)
        g = g + (hp.tau * extra)[..., None] * b
        g = g + np.einsum("nqac,nqc->nqa", hp.dZ_db(), b * m)
    return g[:, :, None, :, None]


def heat_g3_TT(h: Heat, ctx):
    d = ctx.dim
    L = h.conductivity
    g = (L * np.eye(d) if np.isscalar(L) else np.asarray(L))[None, None]
    if h.supg:
        hp = _HeatPoint(h, ctx)
        g = g + hp.tau[..., None, None] * hp.b[..., :, None] * hp.b[..., None, :]
    return g[:, :, None, :, None, :]


def heat_g2lap_TT(h: Heat, ctx):
    hp = _HeatPoint(h, ctx)
    return (-h.conductivity * hp.tau[..., None] * hp.b)[:, :, None, :, None]


def heat_g3_Tp(h: Heat, ctx):
    """d f1/d grad p = (-T I + dZ/db) db/dgrad p, db/dgrad p = -rho_f C_f M K."""
    hp = _HeatPoint(h, ctx)
    dbdg = -h.fluid_rho_c * hp.M[..., None, None] * h.flow.permeability[None, None]
    D = -hp.Tv[..., None, None] * np.eye(hp.d)[None, None]
    if h.supg:
        D = D + hp.dZ_db()
    return np.einsum("nqac,nqce->nqae", D, dbdg)[:, :, None, :, None, :]


def heat_g2_exchange(h: Heat, hw: float, ctx):
    """SUPG part of d f1/d T_trace: -tau hw b."""
    hp = _HeatPoint(h, ctx)
    return (-hw * hp.tau[..., None] * hp.b)[:, :, None, :, None]


def heat_terms(h: Heat) -> tuple[list, list]:
    advect = h.flow is not None and h.fluid_rho_c != 0.0
    if advect and not np.isscalar(h.conductivity):
        raise ValueError("a conductivity tensor is only supported without advection")
    supg = advect and h.supg
    hh = h if advect else Heat(h.region, h.T, h.capacity, h.conductivity, 0.0, None, h.degree, False,
                               h.exchange)
    res = [CellResidual(h.T, partial(heat_f0, hh), partial(heat_f1, hh), region=h.region)]
    jac = [CellJacobian(h.T, h.T, g0=partial(heat_g0_TT, hh) if h.capacity else None,
                        g2=partial(heat_g2_TT, hh) if advect else None,
                        g3=partial(heat_g3_TT, hh),
                        g2_lap=partial(heat_g2lap_TT, hh) if supg and h.degree > 1 else None,
                        region=h.region)]
    if advect:
        jac.append(CellJacobian(h.T, h.flow.p, g3=partial(heat_g3_Tp, hh), region=h.region))
        if supg:
            for hw, trace in h.exchange:
                jac.append(CellJacobian(h.T, trace, g2=partial(heat_g2_exchange, hh, hw), region=h.region))
    return res, jac


# -- wall heat exchange (fracture region) ----------------------------------------------
def exchange_terms(Tf: str, traces: tuple, hw: float) -> tuple[list, list]:
    """q_h = hw (Tf - Tm_s) on each face s (physics.md section 7): a sink in the
    fracture heat equation and the equal source in the matrix heat equation
    (test functions of the traces ``Tm-``/``Tm+``)."""
    def f0_f(ctx):
        return hw * sum(ctx.value(Tf) - ctx.value(s) for s in traces)

    def f0_m(s, ctx):
        return hw * (ctx.value(s) - ctx.value(Tf))

    def const(v, ctx):
        return np.full((1, 1, 1, 1), v)
    res = [CellResidual(Tf, f0_f, None, region="fracture")]
    res += [CellResidual(s, partial(f0_m, s), None, region="fracture") for s in traces]
    jac = [CellJacobian(Tf, Tf, g0=partial(const, hw * len(traces)), region="fracture")]
    for s in traces:
        jac += [CellJacobian(Tf, s, g0=partial(const, -hw), region="fracture"),
                CellJacobian(s, Tf, g0=partial(const, -hw), region="fracture"),
                CellJacobian(s, s, g0=partial(const, hw), region="fracture")]
    return res, jac
