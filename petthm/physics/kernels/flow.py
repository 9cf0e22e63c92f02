"""Fluid flow on one region (matrix cells or fracture faces): the theory manual
sections 4 and 5 (rigid rock; the Biot term is kernels/poroelastic.py).

The same kernels serve the matrix and the fracture; only the coefficients
differ.  A deformable fracture (``aperture``: kernels/contact.Aperture)
scales them by the local aperture a(lam, g) and its storage gains da/dt.
With mobility M(T) = 1/mu(T) and a constant "permeability" tensor K (the
matrix permeability k_m, or a^3/12 I on the fracture), for the unknown p::

    S dp/dt - B dT/dt + div q = s,        q = -M(T) K grad p

Matrix: S = phi c_f + (alpha - phi)/K_s, B = phi beta_f.  Fracture:
S = a c_f, B = a beta_f, and grad is the tangential gradient.  Weak form
(w a test function)::

    int w (S pdot - B Tdot) + grad w . M K grad p

Every Jacobian block is exact (tests check them against finite differences).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial

import numpy as np

from petthm.discretisation.model import CellJacobian, CellResidual, Domain, Region
from petthm.physics.fluid import Viscosity


@dataclass(frozen=True)
class Flow:
    """Flow coefficients of one region (see the module docstring).  With an
    ``aperture`` (a deformable fracture, ``contact.Aperture``) the storage,
    thermal storage and permeability are per unit aperture: S = a storage,
    B = a thermal_storage, K = a^3 permeability, and da/dt joins the storage."""
    region: Domain
    p: str                          # pressure field
    T: str | None                # temperature field of mu(T) and B (None: isothermal)
    storage: float                  # S
    permeability: np.ndarray        # K (d, d)
    viscosity: Viscosity = field(default_factory=Viscosity)
    thermal_storage: float = 0.0    # B
    aperture: object | None = None
    source: Callable | None = None   # s(x, t): a volume (area, on the fracture) source, 1/s


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
    return ctx.grad(fl.p)[:, :, 0, :] @ np.swapaxes(fl.permeability, -1, -2)


def permeability_grad_p(fl: Flow, ctx):
    """K grad p (nc, nq, d), K including a^3 in a deformable fracture."""
    q, ap = unit_darcy(fl, ctx), aperture_state(fl, ctx)
    return q if ap is None else (ap.a ** 3)[..., None] * q


def _storages(fl: Flow, ctx):
    """(S, B): numbers, or per point in a deformable fracture."""
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


def flow_f0(fl: Flow, ctx):
    r = storage_rate(fl, ctx)
    if fl.aperture is not None:
        r = r + aperture_state(fl, ctx).adot
    return r[..., None]


def flow_f1(fl: Flow, ctx):
    M, _ = mobility(fl, ctx)
    return (M[..., None] * permeability_grad_p(fl, ctx))[:, :, None, :]


def flow_g0_pp(fl: Flow, ctx):
    return g0_block(_storages(fl, ctx)[0] * ctx.shift)


def flow_g3_pp(fl: Flow, ctx):
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
    """d f0/d a (with da/dt): shift + storage pdot - thermal_storage Tdot."""
    s = ctx.shift + fl.storage * ctx.dot(fl.p)[..., 0]
    if fl.T is not None and fl.thermal_storage:
        s = s - fl.thermal_storage * ctx.dot(fl.T)[..., 0]
    return s


def flow_s1_aperture(fl: Flow, ctx):
    """d f1/d a = 3 a^2 M K_unit grad p (nc, nq, d)."""
    M, _ = mobility(fl, ctx)
    return (3 * aperture_state(fl, ctx).a ** 2 * M)[..., None] * unit_darcy(fl, ctx)


def flow_terms(fl: Flow) -> tuple[list, list]:
    """Residual and Jacobian registrations of a flow equation."""
    res = [CellResidual(fl.p, partial(flow_f0, fl), partial(flow_f1, fl), region=Region(fl.region))]
    jac = [CellJacobian(fl.p, fl.p, g0=partial(flow_g0_pp, fl) if fl.storage else None,
                        g3=partial(flow_g3_pp, fl), region=Region(fl.region))]
    if fl.T is not None and (fl.thermal_storage or fl.viscosity.water):
        jac.append(CellJacobian(fl.p, fl.T,
                                g0=partial(flow_g0_pT, fl) if fl.thermal_storage else None,
                                g2=partial(flow_g2_pT, fl) if fl.viscosity.water else None,
                                region=Region(fl.region)))
    if fl.aperture is not None:
        jac += fl.aperture.jacobians(fl.p, partial(flow_s0_aperture, fl), partial(flow_s1_aperture, fl))
    return res, jac
