"""Analytical reference solutions that need more than a closed form.

``talbot``: numerical inverse Laplace transform (fixed Talbot contour,
Abate & Valko 2004), vectorised over the contour nodes.
``leakoff_outlet_temperature``: manual, verification, fracture heat
transport with a uniform leakoff fraction m (matrix advection on or off).
``lauwerier_temperature``: manual, verification.
``erfc``: the complementary error function over arrays, from the C
library's (``math.erfc``): the scenes that need only it do not import
scipy.special (0.06 s of a small run's start, manual, performance).
``increasing_root``: the root of a function that changes sign once on each
of several brackets, by bisection vectorised over the brackets.
``series_sum``: a Fourier series over many points, term by term (the
Terzaghi and Mandel references, manual, verification).
"""
from __future__ import annotations

import math

import numpy as np

erfc = np.vectorize(math.erfc, otypes=[float])

#: a series term below this fraction of the largest coefficient is below round-off of the sum
NEGLIGIBLE_TERM = 1e-17


def series_sum(x, frequencies, coefficients, f) -> np.ndarray:
    """sum_k coefficients[k] f(x frequencies[k]) over points ``x`` of any
    shape, one term at a time (memory of ``x`` only, not of points x terms:
    the outer product took 4.5 GB in a 45 k-unknown 3D Terzaghi column),
    skipping the terms whose coefficient is negligible (the decayed terms of
    a diffusion series at later times)."""
    c = np.asarray(coefficients, dtype=float)
    smallest = NEGLIGIBLE_TERM * np.abs(c).max()
    out = np.zeros(np.shape(x))
    for w, k in zip(c, frequencies, strict=False):
        if abs(w) > smallest:
            out += w * f(x * k)
    return out


def increasing_root(f, lo, hi, iterations: int = 80) -> np.ndarray:
    """x in [lo, hi] (arrays, one bracket each) with f(x) = 0, where f (vectorised)
    is negative at lo and positive at hi and changes sign once in between:
    ``iterations`` bisections (80 halve a bracket of width pi/2 below 1e-24,
    past double precision: the result is the last representable midpoint)."""
    lo, hi = np.array(lo, dtype=float), np.array(hi, dtype=float)
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        positive = f(mid) > 0
        hi = np.where(positive, mid, hi)
        lo = np.where(positive, lo, mid)
    return 0.5 * (lo + hi)


def lauwerier_temperature(x, t, q, aperture, rho_c, conductivity, fluid_rho_c, T0, Ti):
    """Lauwerier (1955) fracture temperature (manual, verification):
    T0 + (Ti - T0) erfc(lambda x / (rho_f c_f q sqrt(kappa (t - t_d)))) U(t - t_d),
    t_d = a x / q, kappa = lambda / (rho C); q per metre of fracture height.
    q = 0 (a shut-in): nothing enters, the state at rest T0 everywhere."""
    x = np.asarray(x, dtype=float)
    if q == 0:
        return np.full(np.broadcast_shapes(x.shape, np.shape(t)), T0, dtype=float)
    kappa = conductivity / rho_c
    td = aperture * x / q
    tt = np.maximum(t - td, 1e-300)
    arg = conductivity * x / (fluid_rho_c * q * np.sqrt(kappa * tt))
    return np.where(t > td, T0 + (Ti - T0) * erfc(arg), T0)


def talbot(F, t: float, M: int = 32) -> float:
    """f(t) from its Laplace transform F(s) (F vectorised over complex s)."""
    r = 2.0 * M / (5.0 * t)
    theta = np.arange(1, M) * np.pi / M
    cot = 1.0 / np.tan(theta)
    s = r * theta * (cot + 1j)
    sigma = theta + (theta * cot - 1.0) * cot
    terms = np.exp(t * s) * F(s) * (1.0 + 1j * sigma)
    return float(r / M * (0.5 * np.real(F(np.array([r + 0j]))[0] * np.exp(r * t)) + np.sum(np.real(terms))))


def leakoff_outlet_temperature(x, t, *, q0, m, L, fluid_rho_c, rock_rho_c, rock_conductivity, T0, Tinj,
                               advection=True):
    """Fracture temperature at x (manual, verification): leakoff velocity
    v_L = m q0 / (2 L) through each face, matrix heat capacity C_m = rock_rho_c.

    Laplace domain: r(s) = [P - sqrt(P^2 + 4 lambda C_m s)] / (2 lambda), P = rho_f c_f v_L,
    theta_f = (Tinj - T0)/s (1 - m x/L)^(-lambda r / (rho_f c_f v_L)).
    Without matrix advection P = 0 (then the closed form with x_eff holds).
    q0 = 0 (a shut-in): nothing enters, the state at rest T0."""
    if t <= 0 or q0 == 0:
        return T0
    vL = m * q0 / (2 * L)
    P = fluid_rho_c * vL if advection else 0.0
    lam, Cm = rock_conductivity, rock_rho_c

    def F(s):
        r = (P - np.sqrt(P * P + 4 * lam * Cm * s)) / (2 * lam)
        return (Tinj - T0) / s * np.exp(-lam * r / (fluid_rho_c * vL) * np.log(1 - m * x / L))
    return T0 + talbot(F, t)
