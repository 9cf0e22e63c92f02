"""A manufactured solution of the fully coupled THM system with a fracture
(manual, verification), and its sources, generated with sympy.

The domain is the unit square or cube; the fracture Gamma is the plane
zeta = 1/2 of the last coordinate zeta (y in 2D, z in 3D) and crosses the
whole domain (no tips).  xi are the other coordinates.  The fields are
affine in t, so backward Euler adds no time error:

* fracture pressure and temperature pf(xi, t), Tf(xi, t);
* matrix pressure pm = pf + s (zeta - 1/2) g(xi, t) + sin(pi (zeta - 1/2)) c(xi, t),
  s = sign(zeta - 1/2): continuous across Gamma (pm = pf on the walls, the
  tie of ``builders.leakoff``) with a kink, so the leakoff is not zero;
  Tm = Tf + ... the same construction (the ``equilibrium`` wall exchange);
* u = u_s(x, t) +- (w(xi, t)/2) e_zeta: the opening is w >= 0.1
  (``open``: lam = 0), or u is continuous and the contact traction is a
  manufactured lam(xi, t) > 0 (``closed``: a = a0 - lam/Kn).

The sources are the simulator's own strong form (theory manual, "Equations: rock deformation"
as the kernels implement them; the docstrings there):

* rock, on each half: f_u = -div sigma, sigma = C:eps - alpha (pm - p0) I
  - K beta_s (Tm - T0) I;  f_p = S dpm/dt - B dTm/dt + alpha d(div u)/dt
  + div q, q = -k/mu(Tm) grad pm;  f_T = C_m dTm/dt + div(rho_f C_f q Tm
  - lambda_m grad Tm) (+ Tm (beta_s K d(div u)/dt - phi beta_f dpm/dt) with
  the thermo-mechanical heating of section 6);
* fracture (the stored energy's rate form; backward Euler's quotient
  differs from it by terms of the step: ``fracture_sources``):
  g_pf = d/dt (a (1 + c_f (pf - p0) - beta_f (Tf - T0))) + div qf + q_L,
  qf = -a^3/(12 mu(Tf)) grad pf, q_L = sum over the halves of q . n_out
  (n_out from Gamma into the half: the leakoff the matrix rows of the
  tied wall nodes carry); g_Tf = rho_f C_f (a dTf/dt + Tf da/dt)
  + div(rho_f C_f qf Tf - a lambda_f grad Tf) + sum (rho_f C_f q Tm
  - lambda_m grad Tm) . n_out (the conservative form's wall flux);
* the faces: sigma nu = -P nu + h on each half's face (nu its outward
  normal, P = pf + lam + sigma0_nn): h is applied as a load.

Every function returned takes (x (..., d), t) and evaluates with numpy
(``sympy.lambdify``); a volume function picks the half from zeta.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

#: the halves: +1 above the fracture (zeta > 1/2), -1 below
HALVES = (1, -1)


@dataclass(frozen=True)
class Coefficients:
    """The coefficients of the operator (SI; the scene's parameters)."""
    dim: int
    E: float
    nu: float
    alpha: float                # Biot coefficient
    p_ref: float                # p0 of the Biot stress
    beta_s: float               # rock volumetric thermal expansion
    T_ref: float                # T0 of the thermal stress (K)
    storage: float              # S
    thermal_storage: float      # B = phi beta_f
    k: float                    # isotropic permeability
    viscosity: object           # fluid.Viscosity
    C_m: float                  # (rho C)m
    lam_m: float                # lambda_m
    rho_c_f: float              # rho_f C_f
    lam_f: float                # lambda_f
    c_f: float
    beta_f: float
    a0: float
    Kn: float
    sigma0_nn: float            # in-situ normal stress on the fracture, tension positive
    heating: bool = False       # the thermo-mechanical heating of section 6
    porosity: float = 0.0
    water_energy: bool = False  # the stored energy counts the water's content (upwind, limited schemes)

    @property
    def bulk(self) -> float:
        return self.E / (3 * (1 - 2 * self.nu))


@dataclass(frozen=True)
class Amplitudes:
    """Sizes of the manufactured fields."""
    pressure: float = 1.0
    temperature: float = 20.0
    displacement: float = 0.05
    opening: float = 0.1            # w in [opening, 2 opening] for t in [0, 1]
    traction: float = 0.1           # lam in [traction/2, 9 traction/4] for t in [0, 1] (closed)


class CoupledSolution:
    """The exact fields and the sources (see the module docstring).
    ``closed``: the contact regime (u continuous, lam > 0)."""

    def __init__(self, c: Coefficients, closed: bool = False, amp: Amplitudes = Amplitudes()):
        import sympy as sp
        self.c, self.closed, self.amp, self.sp = c, closed, amp, sp
        d = c.dim
        self.X = sp.symbols("x y z")[:d]
        self.t = sp.Symbol("t")
        X, t = self.X, self.t
        x = X[0]
        y = X[1] if d == 3 else sp.Float(0.3)        # 2D: the functions of the slice y = 0.3
        zeta = X[-1]
        pi = sp.pi
        P, T, U = amp.pressure, amp.temperature, amp.displacement
        self.pf = c.p_ref + P * (1 + t / 2) * (1 + sp.sin(1.3 * pi * x + 0.4) * sp.cos(0.9 * pi * y + 0.2)
                                               / 2)
        self.Tf = c.T_ref + T * (1 + t / 2) * (1 + sp.cos(1.1 * pi * x + 0.3) * sp.sin(0.8 * pi * y + 0.5)
                                               / 2)
        kink_p = P * (1 + t) * sp.cos(0.5 * pi * x) * (1 + y) / 2
        bulge_p = P * (1 + t / 3) * sp.sin(0.7 * pi * x + 0.2) * sp.cos(0.6 * pi * y) / 2
        kink_T = T * (1 + t) * sp.sin(0.6 * pi * x + 0.3) * (1 + y) / 4
        bulge_T = T * (1 + t / 4) * sp.cos(0.9 * pi * x) * sp.cos(0.5 * pi * y + 0.1) / 4
        dz = zeta - sp.Rational(1, 2)
        wave = sp.sin(pi * dz)
        us = [U * (1 + t) * sp.sin(pi * x + 0.3) * sp.cos(0.8 * pi * y) * sp.cos(0.7 * pi * zeta),
              U * (1 + t / 2) * sp.cos(0.9 * pi * x) * sp.sin(pi * y + 0.2) * sp.sin(0.6 * pi * zeta + 0.4),
              U * (1 + 2 * t) * sp.sin(0.8 * pi * x + 0.1) * sp.cos(0.7 * pi * y + 0.3)
              * sp.cos(0.9 * pi * zeta)]
        us = us[:d - 1] + [us[2]]
        if closed:
            self.w = sp.Integer(0)
            self.lam = amp.traction * (1 + t / 2) * (1 + sp.cos(pi * x) * sp.sin(pi * y + 0.3) / 2)
            self.a = c.a0 - self.lam / c.Kn
        else:
            self.w = amp.opening * (1 + t * (1 + sp.sin(pi * x) * sp.sin(pi * y + 0.2)) / 2)
            self.lam = sp.Integer(0)
            self.a = c.a0 + self.w
        self.half = {}
        for s in HALVES:
            pm = self.pf + s * dz * kink_p + wave * bulge_p
            Tm = self.Tf + s * dz * kink_T + wave * bulge_T
            u = sp.Matrix(us) + sp.Matrix([0] * (d - 1) + [s * self.w / 2])
            self.half[s] = {"u": u, "pm": pm, "Tm": Tm}
        self._sources()

    # -- symbolic calculus ------------------------------------------------------------
    def grad(self, f):
        return self.sp.Matrix([self.sp.diff(f, xi) for xi in self.X])

    def div(self, v):
        return sum(self.sp.diff(v[i], xi) for i, xi in enumerate(self.X))

    def stress(self, s):
        """sigma on a half (tension positive)."""
        sp, c, h = self.sp, self.c, self.half[s]
        d = c.dim
        G = h["u"].jacobian(self.X)
        eps = (G + G.T) / 2
        lame = c.E * c.nu / ((1 + c.nu) * (1 - 2 * c.nu))
        mu = c.E / (2 * (1 + c.nu))
        iso = lame * eps.trace() - c.alpha * (h["pm"] - c.p_ref) - c.bulk * c.beta_s * (h["Tm"] - c.T_ref)
        return 2 * mu * eps + iso * sp.eye(d)

    def mobility(self, T):
        return 1 / self.c.viscosity.symbolic(T)

    def darcy(self, s):
        """q = -k/mu(Tm) grad pm on a half."""
        h = self.half[s]
        return -self.c.k * self.mobility(h["Tm"]) * self.grad(h["pm"])

    def on_fracture(self, f):
        return f.subs(self.X[-1], self.sp.Rational(1, 2))

    def _sources(self) -> None:
        sp, c, t = self.sp, self.c, self.t
        d = c.dim
        e = sp.Matrix([0] * (d - 1) + [1])
        self.f_u, self.f_p, self.f_T, self.sigma, self.h = {}, {}, {}, {}, {}
        self.Tm_increment = {s: 0 for s in HALVES}
        q_L, wall_heat = 0, 0
        P = self.pf + self.lam + c.sigma0_nn
        for s in HALVES:
            h = self.half[s]
            sig = self.stress(s)
            self.sigma[s] = sig
            self.f_u[s] = -sp.Matrix([self.div(sig.row(i)) for i in range(d)])
            q = self.darcy(s)
            divu_t = sp.diff(self.div(h["u"]), t)
            self.f_p[s] = (c.storage * sp.diff(h["pm"], t) - c.thermal_storage * sp.diff(h["Tm"], t)
                           + c.alpha * divu_t + self.div(q))
            flux = c.rho_c_f * q * h["Tm"] - c.lam_m * self.grad(h["Tm"])
            fT = c.C_m * sp.diff(h["Tm"], t) + self.div(flux)
            if c.water_energy:
                m = (c.storage * (h["pm"] - c.p_ref) - c.thermal_storage * (h["Tm"] - c.T_ref)
                     + c.alpha * self.div(h["u"]))
                fT += c.rho_c_f * sp.diff(m * h["Tm"], t)
                self.Tm_increment[s] = c.rho_c_f * sp.diff(m, t) * sp.diff(h["Tm"], t)
            if c.heating:
                fT += h["Tm"] * (c.beta_s * c.bulk * divu_t - c.porosity * c.beta_f * sp.diff(h["pm"], t))
            self.f_T[s] = fT
            n_out = s * e                                  # from Gamma into the half
            q_L += self.on_fracture(q.dot(n_out))
            wall_heat += self.on_fracture(flux.dot(n_out))
            nu = -n_out                                    # the half's outward normal on Gamma
            self.h[s] = self.on_fracture(sig * nu + P * nu)
        a = self.a
        Xt = self.X[:-1]
        grad_t = lambda f: sp.Matrix([sp.diff(f, xi) for xi in Xt])       # noqa: E731
        div_t = lambda v: sum(sp.diff(v[i], xi) for i, xi in enumerate(Xt))  # noqa: E731
        qf = -a ** 3 / 12 * self.mobility(self.Tf) * grad_t(self.pf)
        self.content = a * (1 + c.c_f * (self.pf - c.p_ref) - c.beta_f * (self.Tf - c.T_ref))
        self.g_pf = sp.diff(self.content, t) + div_t(qf) + q_L
        self.stored = self.content if c.water_energy else a      # energy: rho_f C_f stored Tf
        self.g_Tf = (c.rho_c_f * sp.diff(self.stored * self.Tf, t)
                     + div_t(c.rho_c_f * qf * self.Tf - a * c.lam_f * grad_t(self.Tf)) + wall_heat)

    # -- numpy functions ----------------------------------------------------------------
    def _lambdify(self, expr) -> Callable:
        """A numpy function f(x (..., d), t) -> (...) of a scalar expression."""
        f = self.sp.lambdify(list(self.X) + [self.t], expr, modules="numpy", cse=True)

        def fn(x, t):
            x = np.asarray(x, dtype=float)
            out = f(*np.moveaxis(x, -1, 0), t)
            return np.broadcast_to(np.asarray(out, dtype=float), x.shape[:-1]).copy()
        return fn

    def _vector(self, expr) -> Callable:
        """A numpy function of a sympy Matrix (its entries, flattened row by row)."""
        fns = [self._lambdify(v) for v in list(expr)]
        shape = tuple(expr.shape) if expr.shape[1] > 1 else (expr.shape[0],)

        def fn(x, t):
            return np.stack([f(x, t) for f in fns], axis=-1).reshape(np.shape(x)[:-1] + shape)
        return fn

    def _halves(self, exprs: dict) -> Callable:
        """A function of x that takes the + half's expression above Gamma, the - half's below
        (decided by ``inside``, a point of the node's side, where given: the copies of a node on Gamma)."""
        fns = {s: (self._vector(e) if hasattr(e, "shape") else self._lambdify(e)) for s, e in exprs.items()}

        def fn(x, t, inside=None):
            x = np.asarray(x, dtype=float)
            up = (x if inside is None else np.asarray(inside))[..., -1] > 0.5
            a, b = fns[1](x, t), fns[-1](x, t)
            return np.where(up.reshape(up.shape + (1,) * (a.ndim - up.ndim)), a, b)
        return fn

    def value(self, name: str) -> Callable:
        """The exact field ``name`` (u, pm, Tm, pf, Tf, lam) as f(x, t)."""
        if name in ("pf", "Tf", "lam"):
            return self._lambdify(getattr(self, name))
        return self._halves({s: self.half[s][name] for s in HALVES})

    def rate(self, name: str) -> Callable:
        """d/dt of the exact field."""
        sp = self.sp
        if name in ("pf", "Tf", "lam"):
            return self._lambdify(sp.diff(getattr(self, name), self.t))
        return self._halves({s: sp.diff(self.half[s][name], self.t) for s in HALVES})

    def gradient(self, name: str) -> Callable:
        """Its gradient: (..., d) for a scalar, (..., d, d) [component, direction] for u;
        on the fracture the tangential gradient (zeta component 0)."""
        if name in ("pf", "Tf", "lam"):
            g = self.grad(getattr(self, name))
            return self._vector(g)
        if name == "u":
            return self._halves({s: self.half[s]["u"].jacobian(self.X) for s in HALVES})
        return self._halves({s: self.grad(self.half[s][name]) for s in HALVES})

    def stress_function(self) -> Callable:
        """sigma(x, t) (..., d, d) on either half (lateral traction data)."""
        return self._halves(self.sigma)

    def volume_sources(self) -> dict:
        """{'u': f_u (..., d), 'pm': f_p, 'Tm': f_T, 'Tm_increment': rho_f C_f
        dm/dt dTm/dt}: with ``water_energy`` the stored energy rho_f C_f m Tm
        of the water content m = S (pm - p0) - B (Tm - T0) + alpha div u, whose
        backward-Euler quotient differs from its rate by a term of the step
        (as the fracture's, ``fracture_sources``; 0 without it)."""
        return {"u": self._halves(self.f_u), "pm": self._halves(self.f_p), "Tm": self._halves(self.f_T),
                "Tm_increment": self._halves(self.Tm_increment)}

    def fracture_sources(self) -> dict:
        """{'pf': g_pf, 'Tf': g_Tf, 'pf_increment': da/dt ds/dt, 'Tf_step':
        a function (x, t, dt) of the difference between the rate and backward
        Euler's quotient of the stored energy E = rho_f C_f A Tf, A = a (with
        ``water_energy``: the content a (1 + s)): dE/dt - (E(t) - E(t - dt))/dt.
        The stored energy of a step is that quotient (kernels/heat.py,
        kernels/transport.py: it telescopes), so the source of a step dt is
        g_Tf minus it; E is cubic in t with the content, quadratic without.
        Likewise the content a (1 + s) of the fracture flow (kernels/flow.py),
        s = c_f (pf - p0) - beta_f (Tf - T0), quadratic in t: its quotient is
        its rate less dt da/dt ds/dt."""
        sp, t, c = self.sp, self.t, self.c
        sdot = c.c_f * sp.diff(self.pf, t) - c.beta_f * sp.diff(self.Tf, t)
        energy = c.rho_c_f * self.stored * self.Tf
        E, Et = self._lambdify(energy), self._lambdify(sp.diff(energy, t))

        def step(x, t, dt):
            return Et(x, t) - (E(x, t) - E(x, t - dt)) / dt
        return {"pf": self._lambdify(self.g_pf), "Tf": self._lambdify(self.g_Tf),
                "pf_increment": self._lambdify(sp.diff(self.a, t) * sdot), "Tf_step": step}

    def face_load(self, half: int) -> Callable:
        """h of a half (..., d): sigma nu + P nu on its face."""
        return self._vector(self.h[half])

    def aperture(self) -> Callable:
        """a(xi, t), the manufactured hydraulic aperture."""
        return self._lambdify(self.a)

    def leakoff(self) -> Callable:
        """q_L(xi, t) (a check of the construction: not zero)."""
        e = self.sp.Matrix([0] * (self.c.dim - 1) + [1])
        return self._lambdify(sum(self.on_fracture(self.darcy(s).dot(s * e)) for s in HALVES))
