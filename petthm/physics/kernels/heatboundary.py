"""The boundary terms of the heat equations (theory manual, "Boundary and
initial conditions"): the enthalpy that the fluid carries across a boundary
without a temperature condition (a prescribed velocity's outflow, a
prescribed Darcy flux's water), a conductive inflow and a heat loss."""
from __future__ import annotations

from collections.abc import Callable

import numpy as np

from petthm.discretisation.model import FacetTerm
from petthm.physics.kernels.heat import Heat, PointFunction


def outflow_term(h: Heat, boundary: str) -> FacetTerm:
    """The enthalpy the fluid carries out through a boundary part without a
    temperature condition: int_out w max(b . n, 0) T (the conservative form's
    natural condition is zero total flux; a prescribed velocity only)."""
    if h.velocity is None:
        raise ValueError("an advective outflow boundary needs a prescribed velocity")

    def bn(ctx):
        v = np.broadcast_to(h.velocity(ctx.x, ctx.t), ctx.shape + (ctx.dim,))
        return np.maximum(h.fluid_rho_c * np.einsum("cqa,cqa->cq", v, ctx.n), 0.0)

    def f0(ctx):
        return bn(ctx)[..., None] * (ctx.value(h.T) - h.reference_temperature)

    def g0(ctx):
        return bn(ctx)[..., None, None]
    return FacetTerm(h.T, boundary, f0, g0)


def water_flux_term(T: str, fluid_rho_c: float, boundary: str, outward_flux: Callable) -> FacetTerm:
    """The enthalpy of the water that a prescribed Darcy flux carries across
    a boundary part without a temperature condition: int w rho_f C_f q_n T,
    q_n = ``outward_flux(ctx)`` (m/s, (nc, nq)); the water leaves, or enters,
    at the boundary's own temperature.  The advection of the flow's
    conservative form has no boundary term (its natural condition is no
    flow): without this term the water would cross the boundary without
    its energy.  T in kelvin, as the advection's (no reference temperature
    with a flow)."""
    def f0(ctx):
        return fluid_rho_c * outward_flux(ctx)[..., None] * ctx.value(T)

    def g0(ctx):
        return fluid_rho_c * outward_flux(ctx)[..., None, None]
    return FacetTerm(T, boundary, f0, g0)


def neumann(name: str, boundary: str, inflow: PointFunction) -> FacetTerm:
    """Prescribed conductive heat inflow q_N (W/m2) through a boundary part."""
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
