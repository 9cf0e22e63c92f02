"""Fluid flow on one region (matrix cells or fracture faces): the theory manual
sections 4 and 5 (rigid rock; the Biot term is kernels/poroelastic.py).

The same kernels serve the matrix and the fracture; only the coefficients
differ.  A deformable fracture (``aperture``: kernels/contact.Aperture)
scales them by the local aperture a(lam, g) and its storage gains da/dt.
With mobility M(T) = 1/mu(T) and a constant "permeability" tensor K (the
matrix permeability k_m, or a^3/12 I on the fracture), for the unknown p::

    S dp/dt - B dT/dt + div q = s,        q = -M(T) K (grad p - rho_f g)

Matrix: S = phi c_f + (alpha - phi)/K_s, B = phi beta_f.  Fracture:
S = a c_f, B = a beta_f, and grad is the tangential gradient.  Weak form
(w a test function)::

    int w (S pdot - B Tdot) + grad w . M K grad p

A deformable fracture stores the water content a (1 + s) per unit area,
s = c_f (p - p0) - beta_f (T - T0) (the reference state p0, T0 of the
flow), and its storage term is backward Euler's exact quotient of that
content, (a (1 + s) - a_old (1 + s_old)) / dt = adot (1 + s) + a sdot
- adot sdot dt: the fluid volume balance telescopes from step to step
(the stored amount of ``monitors.fracture_balances``).

Every Jacobian block is exact (tests check them against finite differences).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial

import numpy as np

from petthm.discretisation.model import CellJacobian, CellResidual, Domain, Region
from petthm.physics.fluid import Viscosity
from petthm.physics.kernels.regional import Regional, at, regional


@dataclass(frozen=True)
class Flow:
    """Flow coefficients of one region (see the module docstring).  With an
    ``aperture`` (a deformable fracture, ``contact.Aperture``) the storage,
    thermal storage and permeability are per unit aperture: S = a storage,
    B = a thermal_storage, K = a^3 permeability, and da/dt joins the storage.
    S, B and K may be ``Regional`` (kernels/regional.py) on the rock."""
    region: Domain
    p: str                          # pressure field
    T: str | None                # temperature field of mu(T) and B (None: isothermal)
    storage: float | Regional       # S
    permeability: np.ndarray | Regional        # K (d, d)
    viscosity: Viscosity = field(default_factory=Viscosity)
    thermal_storage: float | Regional = 0.0    # B
    aperture: object | None = None
    source: Callable | None = None   # s(x, t): a volume (area, on the fracture) source, 1/s
    reference_pressure: float = 0.0      # p0 of a deformable fracture's content a (1 + s)
    reference_temperature: float = 0.0   # T0 (K) of it
    gravity: tuple = ()             # rho_f g (N/m3, a vector): q = -M K (grad p - rho_f g)


# -- helpers ----------------------------------------------------------------------
def g0_block(v):
    """A per-point coefficient (nc, nq) or a number as a g0 block (.., .., 1, 1)."""
    return np.asarray(v)[..., None, None] if np.ndim(v) else np.full((1, 1, 1, 1), v)


def aperture_state(obj, ctx):
    """The aperture state of a deformable fracture, or None."""
    return None if obj.aperture is None else obj.aperture.state(ctx)


def mobility(fl: Flow, ctx):
    """(M, dM/dT) at the quadrature points, (nc, nq)."""
    if fl.T is None or not fl.viscosity.water:
        m = 1.0 / fl.viscosity.value
        return np.full(ctx.shape, m), np.zeros(ctx.shape)
    return fl.viscosity.mobility(ctx.value(fl.T)[..., 0])


def unit_darcy(fl: Flow, ctx):
    """K (grad p - rho_f g) (nc, nq, d), K without a deformable fracture's a^3;
    on a fracture, the part of rho_f g along it (grad p is tangential there)."""
    fl = at(fl, ctx)
    drive = ctx.grad(fl.p)[:, :, 0, :]
    if fl.gravity:
        g = np.asarray(fl.gravity, dtype=float)
        if fl.region is Domain.FRACTURE:
            n = ctx.normals
            g = g - (n @ g)[..., None] * n
        drive = drive - g
    return drive @ np.swapaxes(fl.permeability, -1, -2)


def permeability_grad_p(fl: Flow, ctx):
    """K (grad p - rho_f g) (nc, nq, d), K including a^3 in a deformable fracture."""
    q, ap = unit_darcy(fl, ctx), aperture_state(fl, ctx)
    return q if ap is None else (ap.a ** 3)[..., None] * q


def _storages(fl: Flow, ctx):
    """(S, B): numbers, or per point in a deformable fracture."""
    fl = at(fl, ctx)
    ap = aperture_state(fl, ctx)
    return (fl.storage, fl.thermal_storage) if ap is None else (fl.storage * ap.a, fl.thermal_storage * ap.a)


# -- flow -------------------------------------------------------------------------
def storage_rate(fl: Flow, ctx):
    """S dp/dt - B dT/dt - s (nc, nq): the fluid stored per unit volume (area)
    and time, less the source (without the da/dt of a deformable fracture)."""
    S, B = _storages(fl, ctx)
    r = S * ctx.dot(fl.p)[..., 0]
    if fl.T is not None and fl.thermal_storage:
        r = r - B * ctx.dot(fl.T)[..., 0]
    if fl.source is not None:
        r = r - np.broadcast_to(fl.source(ctx.x, ctx.t), ctx.shape)
    return r


def increment_product(ctx, adot, sdot):
    """da ds / dt = adot sdot / shift: what a sdot + s adot at the new time
    exceeds the backward-Euler quotient (a s - a_old s_old) / dt by (0 without a step)."""
    return adot * sdot / ctx.shift if ctx.shift > 0 else np.zeros_like(adot)


def compressed_content(fl: Flow, ctx):
    """(s, sdot) of a deformable fracture's content a (1 + s) (the module docstring), (nc, nq)."""
    fl = at(fl, ctx)
    s = fl.storage * (ctx.value(fl.p)[..., 0] - fl.reference_pressure)
    sdot = fl.storage * ctx.dot(fl.p)[..., 0]
    if fl.T is not None and fl.thermal_storage:
        s = s - fl.thermal_storage * (ctx.value(fl.T)[..., 0] - fl.reference_temperature)
        sdot = sdot - fl.thermal_storage * ctx.dot(fl.T)[..., 0]
    return s, sdot


def content_rate_beyond_storage(fl: Flow, ctx):
    """adot s: what the rate of a deformable fracture's content d(a (1 + s))/dt
    = adot + a sdot + adot s has beyond adot and the storage rate a sdot (nc, nq)."""
    return aperture_state(fl, ctx).adot * compressed_content(fl, ctx)[0]


def water_content(fl: Flow, ctx):
    """(m, dm/dp, dm/dT, dm/da) at the quadrature points: the water a region
    stores per unit volume (area), whose backward-Euler rate is the storage
    term of ``flow_f0`` (without the source).  Rigid rock or fracture: the
    change S (p - p0) - B (T - T0) from the reference state; a deformable
    fracture: the whole content a (1 + s) (dm/da = 1 + s; else dm/da is None)."""
    fl = at(fl, ctx)
    if fl.aperture is None:
        m = fl.storage * (ctx.value(fl.p)[..., 0] - fl.reference_pressure)
        dT = -fl.thermal_storage if fl.T is not None else 0.0
        if fl.T is not None and fl.thermal_storage:
            m = m - fl.thermal_storage * (ctx.value(fl.T)[..., 0] - fl.reference_temperature)
        return m, fl.storage, dT, None
    a = aperture_state(fl, ctx).a
    s, _ = compressed_content(fl, ctx)
    dT = -a * fl.thermal_storage if fl.T is not None else 0.0
    return a * (1.0 + s), a * fl.storage, dT, 1.0 + s


def water_content_rate(fl: Flow, ctx):
    """The storage term of ``flow_f0`` without the source: the backward-Euler
    rate of ``water_content`` (nc, nq)."""
    r = flow_f0(fl, ctx)[..., 0]
    if fl.source is not None:
        r = r + np.broadcast_to(fl.source(ctx.x, ctx.t), ctx.shape)
    return r


def flow_f0(fl: Flow, ctx):
    r = storage_rate(fl, ctx)
    if fl.aperture is not None:
        adot = aperture_state(fl, ctx).adot
        s, sdot = compressed_content(fl, ctx)
        r = r + adot * (1.0 + s) - increment_product(ctx, adot, sdot)
    return r[..., None]


def flow_f1(fl: Flow, ctx):
    M, _ = mobility(fl, ctx)
    return (M[..., None] * permeability_grad_p(fl, ctx))[:, :, None, :]


def flow_g0_pp(fl: Flow, ctx):
    return g0_block(_storages(fl, ctx)[0] * ctx.shift)


def flow_g3_pp(fl: Flow, ctx):
    fl = at(fl, ctx)
    M, _ = mobility(fl, ctx)
    ap = aperture_state(fl, ctx)
    if ap is None and (fl.T is None or not fl.viscosity.water):
        return (M[0, 0] * fl.permeability)[None, None, None, :, None, :]
    coef = M if ap is None else M * ap.a ** 3
    return (coef[:, :, None, None] * fl.permeability)[:, :, None, :, None, :]


def flow_g0_pT(fl: Flow, ctx):
    return g0_block(-_storages(fl, ctx)[1] * ctx.shift)


def flow_g2_pT(fl: Flow, ctx):
    _, dM = mobility(fl, ctx)
    return (dM[..., None] * permeability_grad_p(fl, ctx))[:, :, None, :, None]


def flow_s0_aperture(fl: Flow, ctx):
    """d f0/d a (with da/dt = shift da): shift (1 + s) (the sdot of a sdot
    cancels against that of -adot sdot / shift)."""
    return ctx.shift * (1.0 + compressed_content(fl, ctx)[0])


def flow_s1_aperture(fl: Flow, ctx):
    """d f1/d a = 3 a^2 M K_unit grad p (nc, nq, d)."""
    M, _ = mobility(fl, ctx)
    return (3 * aperture_state(fl, ctx).a ** 2 * M)[..., None] * unit_darcy(fl, ctx)


def flow_terms(fl: Flow) -> tuple[list, list]:
    """Residual and Jacobian registrations of a flow equation."""
    res = [CellResidual(fl.p, regional(flow_f0, fl), regional(flow_f1, fl), region=Region(fl.region))]
    jac = [CellJacobian(fl.p, fl.p, g0=regional(flow_g0_pp, fl) if fl.storage else None,
                        g3=regional(flow_g3_pp, fl), region=Region(fl.region))]
    if fl.T is not None and (fl.thermal_storage or fl.viscosity.water):
        jac.append(CellJacobian(fl.p, fl.T,
                                g0=regional(flow_g0_pT, fl) if fl.thermal_storage else None,
                                g2=regional(flow_g2_pT, fl) if fl.viscosity.water else None,
                                region=Region(fl.region)))
    if fl.aperture is not None:
        jac += fl.aperture.jacobians(fl.p, partial(flow_s0_aperture, fl), partial(flow_s1_aperture, fl))
    return res, jac
