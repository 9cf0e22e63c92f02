"""Thermo-poro-elastic deformation of the matrix (theory manual, "Equations: rock deformation") and the
Biot term of the matrix flow equation (section 5).

    -div sigma = F,   sigma = C : eps(u) - alpha (p - p0) I - K beta_s (T - T0) I

(tension positive; the in-situ stress sigma0 is in equilibrium and left out:
u is the displacement from the in-situ state, whose pressure p0 and
temperature T0 may vary with position).  Weak form:

    int grad w : sigma - int w . F - int_N w . t = 0

(F a constant body force, ``Elastic.body_force``: e.g. the rock's weight).

Flow: alpha d(div u)/dt is added to the matrix flow residual (the rest of
section 5 is ``flow.Flow`` with storage S = 1/M = phi c_f + (alpha - phi)/K_s).
In 2D the equations are those of plane strain (the same formulas with d = 2).
Heat (``heating_terms``): the thermo-mechanical terms of section 6,
beta_s K T d(div u)/dt - phi beta_f T dp/dt, in the matrix heat equation.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import numpy as np

from petthm.discretisation.model import (
    MATRIX,
    CellJacobian,
    CellResidual,
    FacetTerm,
    Region,
    Side,
    Trace,
)
from petthm.physics.kernels.regional import Regional, at, regional


@dataclass(frozen=True)
class Elastic:
    """Drained isotropic elasticity with Biot and thermal coupling.  The
    moduli, the Biot coefficient and the expansion may be ``Regional``
    (kernels/regional.py): the kernels see the values of each batch's
    region; the derived moduli below are then those of one region."""
    youngs_modulus: float | Regional
    poisson_ratio: float | Regional
    dim: int
    u: str = "u"
    p: str | None = None           # pore pressure field (Biot coupling)
    biot: float | Regional = 0.0
    p_ref: float | Callable = 0.0     # p0: a number or a function of position (points (n, d) -> (n,))
    T: str | None = None           # temperature field (thermal strain)
    thermal_expansion: float | Regional = 0.0    # volumetric beta_s
    T_ref: float | Callable = 0.0     # T0 (K): likewise
    body_force: tuple = ()            # F (N/m3), constant: -div sigma = F
    region: Region = MATRIX

    @property
    def shear(self) -> float:
        return self.youngs_modulus / (2 * (1 + self.poisson_ratio))

    @property
    def lame(self) -> float:
        E, nu = self.youngs_modulus, self.poisson_ratio
        return E * nu / ((1 + nu) * (1 - 2 * nu))

    @property
    def bulk(self) -> float:
        return self.youngs_modulus / (3 * (1 - 2 * self.poisson_ratio))

    def stiffness(self) -> np.ndarray:
        """C[a, e, b, f] = lambda d_ae d_bf + G (d_ab d_ef + d_af d_eb)."""
        I = np.eye(self.dim)
        return self.lame * np.einsum("ae,bf->aebf", I, I) + self.shear * (
            np.einsum("ab,ef->aebf", I, I) + np.einsum("af,eb->aebf", I, I))


def stress(el: Elastic, ctx):
    """sigma (nc, nq, d, d), tension positive."""
    return _stress_of(el, ctx, ctx.grad(el.u), el.p, el.T)


def wall_stress(el: Elastic, side: Side, ctx, gradient):
    """sigma (nc, nq, d, d) on the rock's face on ``side`` of the fracture,
    at the fracture's points (``ctx`` of a fracture region): from the
    displacement gradient ``gradient`` (nc, nq, d, d) there and pm and Tm on
    that face."""
    return _stress_of(el, ctx, gradient, el.p and Trace(el.p, side), el.T and Trace(el.T, side))


def at_points(reference, ctx):
    """A reference value of the in-situ state at the quadrature points: the
    number itself, or a function of position evaluated there (nc, nq)."""
    if not callable(reference):
        return reference
    x = ctx.x
    return np.asarray(reference(x.reshape(-1, x.shape[-1])), dtype=float).reshape(x.shape[:-1])


def _stress_of(el: Elastic, ctx, G, p, T):
    """sigma from the displacement gradient G (nc, nq, d, d) and the pressure
    and temperature references ``p``, ``T`` (None: not coupled), with the
    moduli of the batch's region."""
    el = at(el, ctx)
    eps = 0.5 * (G + np.swapaxes(G, 2, 3))
    iso = el.lame * np.trace(eps, axis1=2, axis2=3)
    if p is not None and el.biot:
        iso = iso - el.biot * (ctx.value(p)[..., 0] - at_points(el.p_ref, ctx))
    if T is not None and el.thermal_expansion:
        iso = iso - el.bulk * el.thermal_expansion * (ctx.value(T)[..., 0] - at_points(el.T_ref, ctx))
    return 2 * el.shear * eps + iso[..., None, None] * np.eye(el.dim)


def _body_f0(el: Elastic, ctx):
    """-F: the body force's part of int grad w : sigma - int w . F."""
    return np.broadcast_to(-np.asarray(el.body_force, dtype=float), ctx.shape + (el.dim,))


def _g3_uu(el: Elastic, ctx):
    return el.stiffness()[None, None]


def _g2_coupling(coef: float, dim: int):
    return (-coef * np.eye(dim))[None, None, :, :, None]


def _g2_biot(el: Elastic, ctx):
    """d sigma/d p: -alpha I."""
    return _g2_coupling(el.biot, el.dim)


def _g2_thermal(el: Elastic, ctx):
    """d sigma/d T: -K beta_s I."""
    return _g2_coupling(el.bulk * el.thermal_expansion, el.dim)


def _biot_f0(el: Elastic, ctx):
    """alpha d(div u)/dt in the flow equation."""
    Gdot = _grad_dot(ctx, el.u)
    return el.biot * np.trace(Gdot, axis1=2, axis2=3)[..., None]


def _grad_dot(ctx, name):
    """Gradient of the time derivative of a field (nc, nq, m, d)."""
    return ctx.grad_dot(name)


def _biot_g1(el: Elastic, ctx):
    return (el.biot * ctx.shift * np.eye(el.dim))[None, None, None]


def elastic_terms(el: Elastic) -> tuple[list, list]:
    """Momentum balance of ``el.u`` and the Biot term of the flow equation."""
    res = [CellResidual(el.u, partial(_body_f0, el) if el.body_force else None, regional(stress, el),
                        region=el.region)]
    jac = [CellJacobian(el.u, el.u, g3=regional(_g3_uu, el), region=el.region, constant=True)]
    if el.p is not None and el.biot:
        jac.append(CellJacobian(el.u, el.p, g2=regional(_g2_biot, el), region=el.region, constant=True))
        res.append(CellResidual(el.p, regional(_biot_f0, el), None, region=el.region))
        jac.append(CellJacobian(el.p, el.u, g1=regional(_biot_g1, el), region=el.region))
    if el.T is not None and el.thermal_expansion:
        jac.append(CellJacobian(el.u, el.T, g2=regional(_g2_thermal, el), region=el.region, constant=True))
    return res, jac


def _heating_rate(el: Elastic, p: str | None, porosity_expansion, ctx):
    """beta_s K d(div u)/dt - phi beta_f dp/dt at the points (nc, nq), 1/s."""
    el, porosity_expansion = at(el, ctx), at(porosity_expansion, ctx)
    r = el.bulk * el.thermal_expansion * np.trace(_grad_dot(ctx, el.u), axis1=2, axis2=3)
    if porosity_expansion and p is not None:
        r = r - porosity_expansion * ctx.dot(p)[..., 0]
    return r


def heating_power(el: Elastic, T: str, p: str | None = None, porosity_expansion=0.0):
    """The heating of ``heating_terms`` as a power density (W/m3, positive
    where it heats): ``power(ctx)`` at the points (nc, nq), from the state's
    temperature (K) and rates."""
    rate = partial(_heating_rate, el, p, porosity_expansion if p is not None else 0.0)

    def power(ctx):
        return -ctx.value(T)[..., 0] * rate(ctx)
    return power


def heating_terms(el: Elastic, T: str, p: str | None = None,
                  porosity_expansion=0.0) -> tuple[list, list]:
    """Thermo-mechanical heating of theory manual, "Equations: rock heat" in the heat equation of ``T``:

        + beta_s K T d(div u)/dt - phi beta_f T dp/dt

    (T in kelvin; compression heats, expansion and pressure rise of the pore
    fluid cool).  ``porosity_expansion`` is phi beta_f (0 or no ``p``: the
    strain term only; a number or ``Regional``).  Exact Jacobians with
    respect to T, u and p."""
    pe = porosity_expansion if p is not None else 0.0
    rate = partial(_heating_rate, el, p, pe)

    def f0(ctx):
        return (ctx.value(T)[..., 0] * rate(ctx))[..., None]

    def g0_TT(ctx):
        return rate(ctx)[..., None, None]

    def g1_Tu(ctx):
        e = at(el, ctx)
        bK = e.bulk * e.thermal_expansion
        return (bK * ctx.shift * ctx.value(T)[..., 0])[..., None, None,
                                                       None] * np.eye(el.dim)[None, None, None]

    def g0_Tp(ctx):
        return (-at(pe, ctx) * ctx.shift * ctx.value(T)[..., 0])[..., None, None]
    res = [CellResidual(T, f0, None, region=el.region)]
    jac = [CellJacobian(T, T, g0=g0_TT, region=el.region), CellJacobian(T, el.u, g1=g1_Tu, region=el.region)]
    if pe:
        jac.append(CellJacobian(T, p, g0=g0_Tp, region=el.region))
    return res, jac


def traction(u: str, boundary: str, t_of_x) -> FacetTerm:
    """Prescribed traction t (Pa, vector) on a boundary part: residual -int w . t."""
    def f0(ctx):
        return -np.broadcast_to(t_of_x(ctx.x, ctx.t), ctx.shape + (ctx.dim,))
    return FacetTerm(u, boundary, f0, None)


def fixed_stress_terms(el: Elastic, p: str) -> list[CellJacobian]:
    """The fixed-stress approximation of the pressure Schur complement
    (a preconditioner block, not part of the Jacobian):

        S = A_pp - A_pu A_uu^-1 A_up  ~  A_pp + shift alpha^2 / K_dr M_p,

    A_pu = shift alpha (q, div du) (section 5), A_up = -alpha (div w, dp)
    (section 2), K_dr = lambda + 2 G / d the drained bulk modulus of the
    d-dimensional body (Kim, Tchelepi & Juanes 2011; the fixed-stress
    split's stabilisation with the physical choice of its constant), with
    each region's moduli."""
    def g0(ctx):
        e = at(el, ctx)
        beta = e.biot ** 2 / (e.lame + 2.0 * e.shear / e.dim)
        return np.full(ctx.shape, beta * ctx.shift)[..., None, None]
    return [CellJacobian(p, p, g0=g0, region=el.region)]


def pressure_stabilisation_terms(el: Elastic, p: str, factor: float = 1.0) -> tuple[list, list]:
    """Flow-equation perturbation tau int grad q . grad(dp/dt), tau = factor h^2 / (4 (lambda + 2G))
    (Aguilar, Gaspar, Lisbona & Rodrigo 2008): removes the non-physical pressure
    oscillations of the first steps when dt << h^2 / c; consistent to O(h^2)."""
    def tau0(ctx):
        e = at(el, ctx)
        return factor / (4 * (e.lame + 2 * e.shear))

    def f1(ctx):
        return tau0(ctx) * ctx.h[:, :, None, None] ** 2 * _grad_dot(ctx, p)

    def g3(ctx):
        t = tau0(ctx) * ctx.h[:, 0] ** 2 * ctx.shift
        return (t[:, None, None] * np.eye(el.dim))[:, None, None, :, None, :]
    return ([CellResidual(p, None, f1, region=el.region)],
            [CellJacobian(p, p, g3=g3, region=el.region)])
