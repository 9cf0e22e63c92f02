"""Wells on a fracture (theory manual, "Equations: wells") as terms at one fracture node.

* Injector: volume rate Q (m3/s; per metre out of plane in 2D) into the
  fracture flow equation and the enthalpy rate rho_f C_f Q T_inj into the
  fracture heat equation (the "injected enthalpy flux" form of section 9).
* Producer at a prescribed well pressure p_w through a well index PI:
  Q_p = PI (p_f - p_w) leaves the flow equation and carries rho_f C_f Q_p T_f
  out of the heat equation.  This is the standard reservoir-simulation
  well model (Peaceman 1978): the node pressure is the grid pressure around
  the well, not the bottom-hole pressure; ``well_index`` gives PI.

Both are exactly conservative: the energy that leaves with the produced
fluid is the term the heat equation loses, so the discrete energy balance
(``petthm.physics.balance``) closes to the solver tolerance.
"""
from __future__ import annotations

import math

from petthm.discretisation.model import PointTerm


def injector(point, rate: float, rho_c: float, T_inj: float | None, p: str = "pf",
             T: str | None = "Tf", name: str = "injector") -> PointTerm:
    fields = (p,) + ((T,) if T else ())

    def residual(v, t):
        r = {p: -rate}
        if T:
            r[T] = -rho_c * rate * T_inj
        return r
    return PointTerm(name, tuple(point), fields, residual, lambda v, t: {})


def producer(point, pressure: float, index: float, rho_c: float, p: str = "pf",
             T: str | None = "Tf", name: str = "producer") -> PointTerm:
    fields = (p,) + ((T,) if T else ())

    def residual(v, t):
        q = index * (v[p] - pressure)
        r = {p: q}
        if T:
            r[T] = rho_c * q * v[T]
        return r

    def jacobian(v, t):
        j = {(p, p): index}
        if T:
            q = index * (v[p] - pressure)
            j.update({(T, p): rho_c * index * v[T], (T, T): rho_c * q})
        return j
    return PointTerm(name, tuple(point), fields, residual, jacobian)


def well_index(transmissivity: float, h: float, well_radius: float, flow_dim: int) -> float:
    """PI (m3/(s Pa)) of a well node for a fracture of transmissivity a^3/(12 mu)
    (m3/(Pa s)) and element size h around the node.

    flow_dim 2 (a disc-like fracture in 3D): Peaceman's radial inflow,
    PI = 2 pi T / ln(r_e / r_w), r_e = 0.2 h (Peaceman's equivalent radius,
    floored at 2 r_w).  flow_dim 1 (a line fracture in 2D): the node is
    reached from both sides over the distance r_w, PI = 2 T / r_w.
    """
    if flow_dim == 1:
        return 2.0 * transmissivity / well_radius
    re = max(0.2 * h, 2.0 * well_radius)
    return 2.0 * math.pi * transmissivity / math.log(re / well_radius)


def rate_producer(point, rate: float, rho_c: float, p: str = "pf", T: str | None = "Tf",
                  name: str = "producer") -> PointTerm:
    """A producer at a prescribed rate Q_p (m3/s) that carries rho_f C_f Q_p T_f out."""
    fields = (p,) + ((T,) if T else ())

    def residual(v, t):
        r = {p: rate}
        if T:
            r[T] = rho_c * rate * v[T]
        return r

    def jacobian(v, t):
        return {(T, T): rho_c * rate} if T else {}
    return PointTerm(name, tuple(point), fields, residual, jacobian)
