"""Matrix heat transport: physics.md section 6 without the pressure/strain terms.

Strong form (T in K, SI units)::

    (rho C)m dT/dt + rho_f C_f v . grad T - div(lambda_m grad T) = s      in Omega
    T = T_D on Gamma_D;  -lambda grad T . n = -q_N on Gamma_N (q_N inflow);
    -lambda grad T . n = h (T - T_ext) on Gamma_R

Weak form with SUPG (Brooks & Hughes 1982), residual R of the strong form and
advective velocity w = rho_f C_f v / (rho C)m::

    int v (rho C Tdot + rho_f C_f v.grad T - s) + grad v . lambda grad T
      + sum_e int tau (w . grad v) R  - int_N v q_N + int_R v h (T - T_ext) = 0

tau = (  (2|w|/h_p)^2 + 9 (4 kappa / h_p^2)^2 )^(-1/2), kappa = lambda/(rho C),
h_p = h/p (cell size over element degree).  For P2 the Laplacian in R is
kept (consistent SUPG); for P1 it vanishes.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np

from ..model import CellJacobian, CellResidual, FacetTerm, Model
from ..fields import FieldSpec

#: f(x (nc,nq,d), t) -> array broadcastable to the quadrature points
PointFunction = Callable[[np.ndarray, float], np.ndarray]


@dataclass(frozen=True)
class HeatCoefficients:
    rho_c: float                      # (rho C)m, J/(m3 K)
    conductivity: float               # lambda_m, W/(m K)
    fluid_rho_c: float = 0.0          # rho_f C_f, J/(m3 K)
    velocity: Optional[PointFunction] = None   # Darcy velocity v, m/s
    source: Optional[PointFunction] = None     # s, W/m3
    supg: bool = True
    degree: int = 2


def _velocity(c: HeatCoefficients, ctx):
    if c.velocity is None or c.fluid_rho_c == 0.0:
        return None
    return np.broadcast_to(c.velocity(ctx.x, ctx.t), ctx.shape + (ctx.dim,))


def _tau(c: HeatCoefficients, ctx, v):
    """SUPG parameter (nc, nq) and advective velocity w (nc, nq, d)."""
    w = (c.fluid_rho_c / c.rho_c) * v
    hp = ctx.h / c.degree
    kappa = c.conductivity / c.rho_c
    wn = np.linalg.norm(w, axis=-1)
    return 1.0 / np.sqrt((2.0 * wn / hp) ** 2 + 9.0 * (4.0 * kappa / hp ** 2) ** 2), w


def _strong_residual(c, ctx, v, name):
    r = c.rho_c * ctx.dot(name)[..., 0] - c.conductivity * ctx.lap(name)[..., 0]
    if v is not None:
        r = r + c.fluid_rho_c * np.einsum("cqa,cqa->cq", v, ctx.grad(name)[:, :, 0, :])
    if c.source is not None:
        r = r - np.broadcast_to(c.source(ctx.x, ctx.t), r.shape)
    return r


def f0_T(c: HeatCoefficients, name: str, ctx):
    r = c.rho_c * ctx.dot(name)[..., 0]
    v = _velocity(c, ctx)
    if v is not None:
        r = r + c.fluid_rho_c * np.einsum("cqa,cqa->cq", v, ctx.grad(name)[:, :, 0, :])
    if c.source is not None:
        r = r - np.broadcast_to(c.source(ctx.x, ctx.t), r.shape)
    return r[..., None]


def f1_T(c: HeatCoefficients, name: str, ctx):
    f1 = c.conductivity * ctx.grad(name)
    v = _velocity(c, ctx)
    if c.supg and v is not None:
        tau, w = _tau(c, ctx, v)
        f1 = f1 + (tau * _strong_residual(c, ctx, v, name))[:, :, None, None] * w[:, :, None, :]
    return f1


def g0_TT(c, name, ctx):
    return np.full((1, 1, 1, 1), c.rho_c * ctx.shift)     # constant over the cell


def g1_TT(c, name, ctx):
    v = _velocity(c, ctx)
    return (c.fluid_rho_c * v)[:, :, None, None, :]


def g2_TT(c, name, ctx):
    tau, w = _tau(c, ctx, _velocity(c, ctx))
    return (tau[:, :, None] * w * c.rho_c * ctx.shift)[:, :, None, :, None]


def g2lap_TT(c, name, ctx):
    tau, w = _tau(c, ctx, _velocity(c, ctx))
    return (-c.conductivity * tau[:, :, None] * w)[:, :, None, :, None]


def g3_TT(c, name, ctx):
    d = ctx.dim
    g = (c.conductivity * np.eye(d))[None, None]                # constant over the cell
    v = _velocity(c, ctx)
    if c.supg and v is not None:
        tau, w = _tau(c, ctx, v)
        g = g + tau[:, :, None, None] * w[:, :, :, None] * (c.fluid_rho_c * v)[:, :, None, :]
    return g[:, :, None, :, None, :]


# -- boundary terms ----------------------------------------------------------
def neumann(name: str, boundary: str, inflow: PointFunction) -> FacetTerm:
    """Prescribed heat inflow q_N (W/m2) through a boundary part."""
    def f0(ctx):
        return -np.broadcast_to(inflow(ctx.x, ctx.t), ctx.shape)[..., None]
    return FacetTerm(name, boundary, f0, None)


def robin(name: str, boundary: str, h: float, t_ext: PointFunction) -> FacetTerm:
    """Heat loss h (T - T_ext) (W/m2) through a boundary part."""
    def f0(ctx):
        return h * (ctx.value(name) - np.broadcast_to(t_ext(ctx.x, ctx.t), ctx.shape)[..., None])

    def g0(ctx):
        return np.full((1, 1, 1, 1), h)
    return FacetTerm(name, boundary, f0, g0)


def heat_model(c: HeatCoefficients, name: str = "Tm", facets=()) -> Model:
    """Registration table of the matrix heat equation for field ``name``."""
    from functools import partial
    advect = c.velocity is not None and c.fluid_rho_c != 0.0
    jac = CellJacobian(
        name, name,
        g0=partial(g0_TT, c, name),
        g1=partial(g1_TT, c, name) if advect else None,
        g2=partial(g2_TT, c, name) if advect and c.supg else None,
        g2_lap=partial(g2lap_TT, c, name) if advect and c.supg and c.degree == 2 else None,
        g3=partial(g3_TT, c, name))
    return Model(fields=[FieldSpec(name, 1, c.degree)],
                 residuals=[CellResidual(name, partial(f0_T, c, name), partial(f1_T, c, name))],
                 jacobians=[jac], facets=list(facets))
