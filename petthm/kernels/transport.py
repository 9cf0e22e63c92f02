"""Fluid flow and heat transport on one region (matrix cells or fracture faces).

The same kernels serve the matrix (physics.md sections 5-6, rigid rock) and
the fracture (sections 4 and 7); only the coefficients differ.  A
deformable fracture (``aperture``: kernels/contact.Aperture) scales them by
the local aperture a(lam, g); its storage gains da/dt and its stored energy
capacity a T (see ``Flow`` and ``Heat``).  With mobility M(T) = 1/mu(T) and a constant "permeability" tensor K
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
R = C Tdot + b . grad T - L lap T,
tau = ((2|b|/h_p)^2 + 9 (4 L/h_p^2)^2)^(-1/2), h_p = h/p.  The fracture's
wall exchange hw (T - Tm) is left out of R: it is a coupling to the rock,
and where it dominates (hw = Nu lambda_f / (2a) is about 1e4 W/m2/K, the
Damkoehler number hw h / |b| is 1e2-1e3) its SUPG term
tau (b . grad w) hw (T - Tm) has off-diagonal entries of the size of the
exchange itself and no sign, and Tf left [Tinj, T0] by 12-19 % in Scene 2.
Without it the scheme is streamline upwinding of the advection-conduction
operator with the (lumped) exchange as a source: Tf stays in the bounds,
at the price of consistency O(tau hw (T - Tm)) in the exchange layer,
which no mesh resolves there (its thickness rho_f C_f q / hw is a few mm).  With w = 1 the
SUPG term vanishes, so it does not disturb the balance.  Every Jacobian
block is exact (tests/test_fracture_physics.py checks them against finite
differences).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import partial
from typing import Optional

import numpy as np

from ..fluid import Viscosity
from ..model import CellJacobian, CellResidual


@dataclass(frozen=True)
class Flow:
    """Flow coefficients of one region (see the module docstring).  With an
    ``aperture`` (a deformable fracture, ``contact.Aperture``) the storage,
    thermal storage and permeability are per unit aperture: S = a storage,
    B = a thermal_storage, K = a^3 permeability, and da/dt joins the storage."""
    region: str
    p: str                          # pressure field
    T: Optional[str]                # temperature field of mu(T) and B (None: isothermal)
    storage: float                  # S
    permeability: np.ndarray        # K (d, d)
    viscosity: Viscosity = field(default_factory=Viscosity)
    thermal_storage: float = 0.0    # B
    aperture: Optional[object] = None


@dataclass(frozen=True)
class Heat:
    """Heat-transport coefficients of one region.  With an ``aperture`` the
    capacity and conductivity are per unit aperture (C = a capacity,
    L = a conductivity) and the stored energy's rate gains capacity T da/dt."""
    region: str
    T: str
    capacity: float                 # C
    conductivity: object            # L: a number, or a (d, d) tensor (no advection then)
    fluid_rho_c: float = 0.0        # rho_f C_f (0: no advection)
    flow: Optional[Flow] = None     # the flow that advects heat
    degree: int = 2
    supg: bool = True
    aperture: Optional[object] = None
    lumped: bool = False            # capacity term by row-sum lumping (P1, no aperture)


@dataclass(frozen=True)
class ApertureExchange:
    """Wall heat-transfer coefficient hw = K / a of a deformable fracture
    (physics.md section 7: K = Nu lambda_f / 2)."""
    K: float
    aperture: object

    def value(self, ctx):
        return self.K / self.aperture.state(ctx).a

    def derivative(self, ctx):
        """d hw / d a."""
        return -self.K / self.aperture.state(ctx).a ** 2


def _hw(hw, ctx):
    """A wall coefficient: a number, or per point (``ApertureExchange``)."""
    return hw.value(ctx) if isinstance(hw, ApertureExchange) else hw


# -- helpers ----------------------------------------------------------------------
def _g0(v):
    """A per-point coefficient (nc, nq) or a number as a g0 block (.., .., 1, 1)."""
    return np.asarray(v)[..., None, None] if np.ndim(v) else np.full((1, 1, 1, 1), v)


def _aperture(obj, ctx):
    """The aperture state of a deformable fracture, or None."""
    return None if obj.aperture is None else obj.aperture.state(ctx)


def _mobility(fl: Flow, ctx):
    """(M, dM/dT) at the quadrature points, (nc, nq)."""
    if fl.T is None or not fl.viscosity.water:
        m = 1.0 / fl.viscosity.value
        return np.full(ctx.shape, m), np.zeros(ctx.shape)
    return fl.viscosity.mobility(ctx.value(fl.T)[..., 0])


def _unit_Kgradp(fl: Flow, ctx):
    return np.einsum("ab,cqb->cqa", fl.permeability, ctx.grad(fl.p)[:, :, 0, :])


def _Kgradp(fl: Flow, ctx):
    """K grad p (nc, nq, d), K including a^3 in a deformable fracture."""
    q, ap = _unit_Kgradp(fl, ctx), _aperture(fl, ctx)
    return q if ap is None else (ap.a ** 3)[..., None] * q


def _storages(fl: Flow, ctx):
    """(S, B): numbers, or per point in a deformable fracture."""
    ap = _aperture(fl, ctx)
    return (fl.storage, fl.thermal_storage) if ap is None else (fl.storage * ap.a, fl.thermal_storage * ap.a)


# -- flow -------------------------------------------------------------------------
def flow_f0(fl: Flow, ctx):
    S, B = _storages(fl, ctx)
    r = S * ctx.dot(fl.p)[..., 0]
    if fl.T is not None and fl.thermal_storage:
        r = r - B * ctx.dot(fl.T)[..., 0]
    if fl.aperture is not None:
        r = r + _aperture(fl, ctx).adot
    return r[..., None]


def flow_f1(fl: Flow, ctx):
    M, _ = _mobility(fl, ctx)
    return (M[..., None] * _Kgradp(fl, ctx))[:, :, None, :]


def flow_g0_pp(fl: Flow, ctx):
    return _g0(_storages(fl, ctx)[0] * ctx.shift)


def flow_g3_pp(fl: Flow, ctx):
    M, _ = _mobility(fl, ctx)
    ap = _aperture(fl, ctx)
    if ap is None and (fl.T is None or not fl.viscosity.water):
        return (M[0, 0] * fl.permeability)[None, None, None, :, None, :]
    coef = M if ap is None else M * ap.a ** 3
    return (coef[:, :, None, None] * fl.permeability)[:, :, None, :, None, :]


def flow_g0_pT(fl: Flow, ctx):
    return _g0(-_storages(fl, ctx)[1] * ctx.shift)


def flow_g2_pT(fl: Flow, ctx):
    _, dM = _mobility(fl, ctx)
    return (dM[..., None] * _Kgradp(fl, ctx))[:, :, None, :, None]


def flow_s0_aperture(fl: Flow, ctx):
    """d f0/d a (with da/dt): shift + storage pdot - thermal_storage Tdot."""
    s = ctx.shift + fl.storage * ctx.dot(fl.p)[..., 0]
    if fl.T is not None and fl.thermal_storage:
        s = s - fl.thermal_storage * ctx.dot(fl.T)[..., 0]
    return s


def flow_s1_aperture(fl: Flow, ctx):
    """d f1/d a = 3 a^2 M K_unit grad p (nc, nq, d)."""
    M, _ = _mobility(fl, ctx)
    return (3 * _aperture(fl, ctx).a ** 2 * M)[..., None] * _unit_Kgradp(fl, ctx)


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
    if fl.aperture is not None:
        jac += fl.aperture.jacobians(fl.p, partial(flow_s0_aperture, fl), partial(flow_s1_aperture, fl))
    return res, jac


# -- heat -------------------------------------------------------------------------
class _HeatPoint:
    """Everything the heat residual and its derivatives need at the quadrature points."""

    def __init__(self, h: Heat, ctx):
        self.h = h
        T = h.T
        self.gT = ctx.grad(T)[:, :, 0, :]                           # (nc, nq, d)
        self.Tv = ctx.value(T)[..., 0]
        self.ap = _aperture(h, ctx)
        a = 1.0 if self.ap is None else self.ap.a
        self.C, self.L = h.capacity * a, h.conductivity * a         # numbers or (nc, nq)
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
            self.B1 = 144.0 / hp ** 4                                      # B0 = B1 L^2
            bb = np.einsum("cqa,cqa->cq", self.b, self.b)
            self.tau = 1.0 / np.sqrt(self.A * bb + self.B1 * self.L ** 2) if h.supg else np.zeros_like(bb)
            R = self.C * ctx.dot(T)[..., 0] + np.einsum("cqa,cqa->cq", self.b, self.gT)
            if h.degree > 1:
                self.lapT = ctx.lap(T)[..., 0]
                R = R - self.L * self.lapT
            self.R = R
        self.d = d

    def dZ_db(self):
        """dZ_a/db_c of Z = tau R b: (nc, nq, a, c)."""
        tau, R, b = self.tau, self.R, self.b
        eye = np.eye(self.d)[None, None]
        return (-(tau ** 3 * self.A * R)[..., None, None] * b[..., :, None] * b[..., None, :]
                + tau[..., None, None] * b[..., :, None] * self.gT[..., None, :]
                + (tau * R)[..., None, None] * eye)


def _conduction(hp: _HeatPoint, gT):
    L = hp.L
    if hp.ap is not None:                                            # per point (deformable fracture)
        return L[..., None] * gT
    return L * gT if np.isscalar(L) else np.einsum("ab,cqb->cqa", L, gT)


def heat_f0_capacity(h: Heat, ctx):
    """C dT/dt alone (the lumped capacity term)."""
    return (h.capacity * ctx.dot(h.T)[..., 0])[..., None]


def heat_f0(h: Heat, ctx):
    if h.lumped:
        return np.zeros(ctx.shape + (1,))
    ap = _aperture(h, ctx)
    if ap is None:
        return (h.capacity * ctx.dot(h.T)[..., 0])[..., None]
    return (h.capacity * (ap.a * ctx.dot(h.T)[..., 0] + ctx.value(h.T)[..., 0] * ap.adot))[..., None]


def heat_f1(h: Heat, ctx):
    hp = _HeatPoint(h, ctx)
    f1 = _conduction(hp, hp.gT)
    if hp.advect:
        f1 = f1 - hp.b * hp.Tv[..., None]
        if h.supg:
            f1 = f1 + (hp.tau * hp.R)[..., None] * hp.b
    return f1[:, :, None, :]


def heat_g0_TT(h: Heat, ctx):
    ap = _aperture(h, ctx)
    if ap is None:
        return _g0(h.capacity * ctx.shift)
    return _g0(h.capacity * (ap.a * ctx.shift + ap.adot))


def heat_g2_TT(h: Heat, ctx):
    hp = _HeatPoint(h, ctx)
    b, m = hp.b, hp.m[..., None]
    g = -b * (1.0 + hp.Tv[..., None] * m)                   # d(-b T)/dT
    if h.supg:
        g = g + (hp.tau * hp.C * ctx.shift)[..., None] * b
        g = g + np.einsum("nqac,nqc->nqa", hp.dZ_db(), b * m)
    return g[:, :, None, :, None]


def heat_g3_TT(h: Heat, ctx):
    d = ctx.dim
    hp = _HeatPoint(h, ctx) if (h.supg or h.aperture is not None) else None
    L = h.conductivity if hp is None else hp.L
    if h.aperture is not None:                                       # per point (deformable fracture)
        g = L[..., None, None] * np.eye(d)
    else:
        g = (L * np.eye(d) if np.isscalar(L) else np.asarray(L))[None, None]
    if h.supg:
        g = g + hp.tau[..., None, None] * hp.b[..., :, None] * hp.b[..., None, :]
    return g[:, :, None, :, None, :]


def heat_g2lap_TT(h: Heat, ctx):
    hp = _HeatPoint(h, ctx)
    return ((-hp.L * hp.tau)[..., None] * hp.b)[:, :, None, :, None]


def heat_g3_Tp(h: Heat, ctx):
    """d f1/d grad p = (-T I + dZ/db) db/dgrad p, db/dgrad p = -rho_f C_f M K."""
    hp = _HeatPoint(h, ctx)
    coef = hp.M if hp.ap is None else hp.M * hp.ap.a ** 3
    dbdg = -h.fluid_rho_c * coef[..., None, None] * h.flow.permeability[None, None]
    D = -hp.Tv[..., None, None] * np.eye(hp.d)[None, None]
    if h.supg:
        D = D + hp.dZ_db()
    return np.einsum("nqac,nqce->nqae", D, dbdg)[:, :, None, :, None, :]


def heat_s0_aperture(h: Heat, ctx):
    """d f0/d a (with da/dt): capacity (Tdot + T shift)."""
    return h.capacity * (ctx.dot(h.T)[..., 0] + ctx.value(h.T)[..., 0] * ctx.shift)


def heat_s1_aperture(h: Heat, ctx):
    """d f1/d a: conductivity grad T - (db/da) T + d(tau R b)/da, db/da = 3 b / a
    (computed as -rho_f C_f M 3 a^2 K_unit grad p), with
    dR/da = capacity Tdot + db/da . grad T - conductivity lap T and
    dtau/da = -tau^3 (A b . db/da + B1 L conductivity)."""
    hp = _HeatPoint(h, ctx)
    s = h.conductivity * hp.gT
    if hp.advect:
        db = -h.fluid_rho_c * (3 * hp.ap.a ** 2 * hp.M)[..., None] * _unit_Kgradp(h.flow, ctx)
        s = s - db * hp.Tv[..., None]
        if h.supg:
            dR = h.capacity * ctx.dot(h.T)[..., 0] + np.einsum("cqa,cqa->cq", db, hp.gT)
            if h.degree > 1:
                dR = dR - h.conductivity * hp.lapT
            dtau = -hp.tau ** 3 * (hp.A * np.einsum("cqa,cqa->cq", hp.b, db) + hp.B1 * hp.L * h.conductivity)
            s = s + (dtau * hp.R + hp.tau * dR)[..., None] * hp.b + (hp.tau * hp.R)[..., None] * db
    return s


def heat_terms(h: Heat) -> tuple[list, list]:
    advect = h.flow is not None and h.fluid_rho_c != 0.0
    if advect and not np.isscalar(h.conductivity):
        raise ValueError("a conductivity tensor is only supported without advection")
    if h.aperture is not None and not np.isscalar(h.conductivity):
        raise ValueError("a deformable fracture takes a scalar conductivity")
    if h.lumped and (h.aperture is not None or h.degree != 1):
        raise ValueError("a lumped capacity needs P1 and a fixed aperture")
    supg = advect and h.supg
    hh = h if advect else replace(h, fluid_rho_c=0.0, flow=None, supg=False)
    res = [CellResidual(h.T, partial(heat_f0, hh), partial(heat_f1, hh), region=h.region)]
    if h.lumped:
        res.append(CellResidual(h.T, partial(heat_f0_capacity, hh), None, region=h.region + "@lumped"))
        jac = [CellJacobian(h.T, h.T, g0=partial(heat_g0_TT, hh), region=h.region + "@lumped")]
    else:
        jac = []
    jac += [CellJacobian(h.T, h.T, g0=partial(heat_g0_TT, hh) if h.capacity and not h.lumped else None,
                        g2=partial(heat_g2_TT, hh) if advect else None,
                        g3=partial(heat_g3_TT, hh),
                        g2_lap=partial(heat_g2lap_TT, hh) if supg and h.degree > 1 else None,
                        region=h.region)]
    if advect:
        jac.append(CellJacobian(h.T, h.flow.p, g3=partial(heat_g3_Tp, hh), region=h.region))
    if h.aperture is not None:
        jac += h.aperture.jacobians(h.T, partial(heat_s0_aperture, hh), partial(heat_s1_aperture, hh))
    return res, jac


# -- wall heat exchange (fracture region) ----------------------------------------------
def exchange_terms(Tf: str, traces: tuple, hw, lumped: bool = False) -> tuple[list, list]:
    """q_h = hw (Tf - Tm_s) on each face s (physics.md section 7): a sink in the
    fracture heat equation and the equal source in the matrix heat equation
    (test functions of the traces ``Tm-``/``Tm+``).  ``hw``: a number, or an
    ``ApertureExchange`` (hw = K/a with the local aperture; then the blocks
    with respect to lam and u+- through a as well).  ``lumped``: integrated
    with the vertex rule (row-sum lumping, P1 fields)."""
    region = "fracture@lumped" if lumped else "fracture"
    def coefficient(ctx):
        v = _hw(hw, ctx)
        return v[..., None] if np.ndim(v) else v

    def f0_f(ctx):
        return coefficient(ctx) * sum(ctx.value(Tf) - ctx.value(s) for s in traces)

    def f0_m(s, ctx):
        return coefficient(ctx) * (ctx.value(s) - ctx.value(Tf))

    def coef(v, ctx):
        return _g0(v * _hw(hw, ctx))
    res = [CellResidual(Tf, f0_f, None, region=region)]
    res += [CellResidual(s, partial(f0_m, s), None, region=region) for s in traces]
    jac = [CellJacobian(Tf, Tf, g0=partial(coef, float(len(traces))), region=region)]
    for s in traces:
        jac += [CellJacobian(Tf, s, g0=partial(coef, -1.0), region=region),
                CellJacobian(s, Tf, g0=partial(coef, -1.0), region=region),
                CellJacobian(s, s, g0=partial(coef, 1.0), region=region)]
    if isinstance(hw, ApertureExchange):
        def s0_f(ctx):
            return hw.derivative(ctx) * sum(ctx.value(Tf)[..., 0] - ctx.value(s)[..., 0] for s in traces)

        def s0_m(s, ctx):
            return hw.derivative(ctx) * (ctx.value(s)[..., 0] - ctx.value(Tf)[..., 0])
        jac += hw.aperture.jacobians(Tf, s0_f, None, region)
        for s in traces:
            jac += hw.aperture.jacobians(s, partial(s0_m, s), None, region)
    return res, jac
