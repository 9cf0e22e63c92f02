"""Poroelastic verification scenes (issue 4; verification.md section 6).

* ``terzaghi``: 1D consolidation of a column (plane strain, lateral and base
  rollers, a load sigma0 on the drained top at t = 0+, impermeable base),
  started from the undrained state and compared with the series solution.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import meshing
from ..assembly import FieldScale
from ..fields import FieldSpec
from ..fluid import Viscosity
from ..kernels import poroelastic as pe
from ..kernels import transport as tr
from ..model import Model
from ..params import param
from ..solver import Dirichlet
from .base import Scene, TimeDefaults, register


@dataclass(frozen=True)
class PoroRock:
    """Poroelastic rock and fluid (physics.md sections 2 and 5; verification.md rock set R)"""
    rock_youngs_modulus: float = param(37.5e9, "Pa", "drained Young's modulus E", lo=0.0, lo_open=True)
    rock_poisson_ratio: float = param(0.25, "-", "drained Poisson ratio nu", lo=0.0, hi=0.4999)
    rock_biot_coefficient: float = param(0.8, "-", "Biot coefficient alpha", lo=0.0, hi=1.0)
    rock_porosity: float = param(0.1, "-", "porosity phi", lo=0.0, hi=1.0)
    rock_permeability: float = param(1e-14, "m2", "permeability k", lo=0.0, lo_open=True)
    fluid_compressibility: float = param(4.5e-10, "1/Pa", "fluid compressibility c_f", lo=0.0)
    fluid_viscosity: float = param(1e-3, "Pa s", "fluid viscosity mu", lo=0.0, lo_open=True)

    @property
    def K(self):
        return self.rock_youngs_modulus / (3 * (1 - 2 * self.rock_poisson_ratio))

    @property
    def G(self):
        return self.rock_youngs_modulus / (2 * (1 + self.rock_poisson_ratio))

    @property
    def storage(self):
        """1/M = phi c_f + (alpha - phi)/K_s, K_s = K/(1 - alpha) (alpha = 1: K_s infinite)."""
        a, phi = self.rock_biot_coefficient, self.rock_porosity
        return phi * self.fluid_compressibility + (a - phi) * (1 - a) / self.K

    @property
    def M_d(self):
        return self.K + 4 * self.G / 3

    def consolidation(self):
        """c = (k/mu) M M_d / (K_u + 4G/3), K_u = K + alpha^2 M, written with S = 1/M
        so that S = 0 (incompressible fluid and grains) is allowed."""
        S, a = self.storage, self.rock_biot_coefficient
        return self.rock_permeability / self.fluid_viscosity * self.M_d / (S * (self.K + 4 * self.G / 3) + a * a)

    def undrained_factor(self):
        """1 / (M_d + alpha^2 M) written with S: S / (S M_d + alpha^2)."""
        S, a = self.storage, self.rock_biot_coefficient
        return S / (S * self.M_d + a * a)


@dataclass(frozen=True)
class TerzaghiParams:
    """Terzaghi consolidation column (terzaghi)"""
    terzaghi_height: float = param(10.0, "m", "column height L", lo=0.0, lo_open=True)
    terzaghi_width: float = param(1.0, "m", "column width", lo=0.0, lo_open=True)
    terzaghi_load: float = param(1e6, "Pa", "compressive load sigma0 on the top", lo=0.0, lo_open=True)
    terzaghi_pressure_degree: int = param(1, "-", "degree of pm (1: Taylor-Hood with P2 u)", choices=(1, 2))
    biot_stabilization: float = param(0.0, "-", "factor of the pressure stabilisation h^2/(4(lambda+2G)) "
                                      "(0: off; 1: Aguilar et al. 2008)", lo=0.0)
    terzaghi_start: str = param("undrained", "-", "initial state: undrained (the t = 0+ solution) or rest "
                                "(u = 0, p = 0; the load makes the first step undrained)",
                                choices=("undrained", "rest"))


def _terms(n=400):
    return (2 * np.arange(n) + 1) * np.pi / 2


@register
class Terzaghi(Scene):
    direct_solve = True             # GMRES + GAMG does not handle the u-p/u-T saddle point
    name = "terzaghi"
    description = "1D consolidation (verification.md 6a): pressure and settlement vs the series solution"
    parameter_sets = (PoroRock, TerzaghiParams)
    time = TimeDefaults(final_time=1300.0, dt_initial=0.0648, dt_growth=1.05, dt_max=2.0, mesh_size=0.5)
    history_columns = ("settlement", "settlement_exact", "p_base", "p_base_exact", "p_l2_rel", "p_overshoot")
    TV = (0.01, 0.1, 0.5, 1.0)

    def boundaries(self):
        p = self[TerzaghiParams]
        return {"top": lambda x: np.isclose(x[:, 1], p.terzaghi_height),
                "base": lambda x: np.isclose(x[:, 1], 0.0),
                "sides": lambda x: np.isclose(x[:, 0], 0.0) | np.isclose(x[:, 0], p.terzaghi_width)}

    def generate_mesh(self, path, size):
        p = self[TerzaghiParams]
        return meshing.box(path, [p.terzaghi_width, p.terzaghi_height], size, structured=True)

    # -- reference solution ----------------------------------------------------------
    def t_c(self):
        return self[TerzaghiParams].terzaghi_height ** 2 / self[PoroRock].consolidation()

    def p0(self):
        """alpha M sigma0 / (M_d + alpha^2 M) = alpha sigma0 / (S M_d + alpha^2)."""
        r, s0 = self[PoroRock], self[TerzaghiParams].terzaghi_load
        a = r.rock_biot_coefficient
        return a * s0 / (r.storage * r.M_d + a * a) if a > 0 else 0.0

    def exact_p(self, x, t):
        L = self[TerzaghiParams].terzaghi_height
        z = L - x[..., 1]
        lam = _terms()
        Tv = t / self.t_c()
        e = np.exp(-lam ** 2 * Tv) * 2 / lam
        return self.p0() * np.sum(np.sin(np.multiply.outer(z, lam) / L) * e, axis=-1)

    def exact_grad_p(self, x, t):
        L = self[TerzaghiParams].terzaghi_height
        z = L - x[..., 1]
        lam = _terms()
        e = np.exp(-lam ** 2 * t / self.t_c()) * 2 / L
        dpdz = self.p0() * np.sum(np.cos(np.multiply.outer(z, lam) / L) * e, axis=-1)
        return np.stack([np.zeros_like(dpdz), -dpdz], axis=-1)

    def exact_settlement(self, t):
        r, p = self[PoroRock], self[TerzaghiParams]
        s0 = p.terzaghi_load * p.terzaghi_height * r.undrained_factor()
        sinf = p.terzaghi_load * p.terzaghi_height / r.M_d
        lam = _terms()
        U = 1 - np.sum(2 / lam ** 2 * np.exp(-lam ** 2 * t / self.t_c()))
        return s0 + (sinf - s0) * U

    def hit_times(self):
        return [tv * self.t_c() for tv in self.TV]

    # -- model -------------------------------------------------------------------------
    def build(self, mesh, degree):
        r, p = self[PoroRock], self[TerzaghiParams]
        d = mesh.dim
        el = pe.Elastic(r.rock_youngs_modulus, r.rock_poisson_ratio, d, p="pm",
                        biot=r.rock_biot_coefficient)
        flow = tr.Flow("matrix", "pm", None, r.storage, r.rock_permeability * np.eye(d),
                       Viscosity(r.fluid_viscosity))
        res, jac = pe.elastic_terms(el)
        fr, fj = tr.flow_terms(flow)
        if p.biot_stabilization:
            sr, sj = pe.pressure_stabilisation_terms(el, "pm", p.biot_stabilization)
            fr, fj = fr + sr, fj + sj
        load = pe.traction("u", "top", lambda x, t: np.array([0.0, -p.terzaghi_load]))
        model = Model([FieldSpec("u", d, degree), FieldSpec("pm", 1, p.terzaghi_pressure_degree)],
                      res + fr, jac + fj, [load])
        zero = lambda x, t: np.zeros(len(x))  # noqa: E731
        bcs = [Dirichlet("u", "sides", zero, components=(0,)), Dirichlet("u", "base", zero, components=(1,)),
               Dirichlet("pm", "top", zero)]
        s_inf = p.terzaghi_load * p.terzaghi_height / r.M_d
        scales = {"u": FieldScale(s_inf), "pm": FieldScale(self.p0())}
        # undrained state at t = 0+: uniform p0 and uniform vertical strain
        eps = -p.terzaghi_load * r.undrained_factor()
        rest = p.terzaghi_start == "rest"
        init = {"u": lambda x: np.column_stack([np.zeros(len(x)), (0.0 if rest else eps) * x[:, 1]]),
                "pm": lambda x: np.full(len(x), 0.0 if rest else self.p0())}
        self._errors = {}
        return model, bcs, scales, init

    def _settlement(self, problem, t, X=None):
        L = self[TerzaghiParams].terzaghi_height
        return -problem.point_value("u", (0.0, L), X, t, component=1)

    def monitors(self, problem, t, X=None):
        """Settlement and base pressure every step; the relative L2 error of pm at
        the verification times T_v = c t / L^2 in ``TV`` (the series is costly)."""
        v = problem.field_values("pm", X, t)[:, 0]
        from mpi4py import MPI
        pmax = problem.dm.comm.tompi4py().allreduce(float(v.max()) if len(v) else -np.inf, op=MPI.MAX)
        pmin = problem.dm.comm.tompi4py().allreduce(float(v.min()) if len(v) else np.inf, op=MPI.MIN)
        load = self[TerzaghiParams].terzaghi_load
        # pressure outside [0, p0] (the undrained pressure bounds the solution), relative to the load
        over = max(pmax - self.p0(), -pmin, 0.0) / load if t > 0 else 0.0
        self._overshoot = max(getattr(self, "_overshoot", 0.0), over)
        out = {"settlement": self._settlement(problem, t, X), "settlement_exact": self.exact_settlement(t),
               "p_overshoot": over,
               "p_base": problem.point_value("pm", (0.0, 0.0), X, t),
               "p_base_exact": float(self.exact_p(np.array([[0.0, 0.0]]), t)[0]) if t > 0 else self.p0()}
        for tv, th in zip(self.TV, self.hit_times()):
            if abs(t - th) <= 1e-9 * th:
                xl, _ = problem.local_arrays(X or problem.X, t)
                e = problem.asm.error_norms(xl, "pm", self.exact_p, self.exact_grad_p, t)
                out["p_l2_rel"] = e["l2_rel"]
                self._errors[tv] = (e["l2_rel"], abs(out["settlement"] - out["settlement_exact"]) /
                                    out["settlement_exact"])
        return out

    def report(self, problem, t):
        err = {}
        for tv, (ep, es) in sorted(self._errors.items()):
            err[f"p_l2_rel_Tv{tv:g}"] = ep
            err[f"settlement_rel_Tv{tv:g}"] = es
        return {"error": err, "t_c": self.t_c(), "p0": self.p0(),
                "p_overshoot_max_rel_load": getattr(self, "_overshoot", 0.0)}


# ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class MandelParams:
    """Mandel's problem, quarter domain (mandel; verification.md 6b)"""
    mandel_a: float = param(10.0, "m", "half-width a (drained sides at x = +-a)", lo=0.0, lo_open=True)
    mandel_b: float = param(10.0, "m", "half-height b (rigid plates at y = +-b)", lo=0.0, lo_open=True)
    mandel_force: float = param(1e7, "N/m", "force F per unit length on each plate (mean stress F/a)",
                                lo=0.0, lo_open=True)
    mandel_pressure_degree: int = param(1, "-", "degree of pm (1: Taylor-Hood with P2 u)", choices=(1, 2))


@register
class Mandel(Scene):
    direct_solve = True             # GMRES + GAMG does not handle the u-p/u-T saddle point
    name = "mandel"
    description = "Mandel's problem (verification.md 6b): pressure incl. the Mandel-Cryer overshoot"
    parameter_sets = (PoroRock, MandelParams)
    time = TimeDefaults(final_time=700.0, dt_initial=0.0648, dt_growth=1.05, dt_max=1.3, mesh_size=0.5)
    history_columns = ("p_centre", "p_centre_exact", "p_max_error", "plate_force_rel_error")
    TAU = (0.01, 0.05, 0.1, 0.2, 0.5, 1.0)

    def boundaries(self):
        p = self[MandelParams]
        return {"x0": lambda x: np.isclose(x[:, 0], 0.0), "y0": lambda x: np.isclose(x[:, 1], 0.0),
                "xa": lambda x: np.isclose(x[:, 0], p.mandel_a), "yb": lambda x: np.isclose(x[:, 1], p.mandel_b)}

    def generate_mesh(self, path, size):
        p = self[MandelParams]
        return meshing.box(path, [p.mandel_a, p.mandel_b], size, structured=True)

    # -- reference (Cheng & Detournay 1988) -------------------------------------------
    def _constants(self):
        r = self[PoroRock]
        S, al = r.storage, r.rock_biot_coefficient
        Ku_S = S * r.K + al * al                              # S K_u
        B = al / Ku_S
        nu, G = r.rock_poisson_ratio, r.G
        nu_u = (3 * Ku_S - 2 * G * S) / (2 * (3 * Ku_S + G * S))
        return B, nu, nu_u, G, r.consolidation()

    def roots(self, n=200):
        from scipy.optimize import brentq
        B, nu, nu_u, G, c = self._constants()
        k = (1 - nu) / (nu_u - nu)
        f = lambda x: np.tan(x) - k * x  # noqa: E731
        out = []
        for i in range(n):
            lo, hi = i * np.pi + 1e-12, i * np.pi + np.pi / 2 - 1e-12
            out.append(brentq(f, lo if i else 1e-9, hi))
        return np.array(out)

    def t_ref(self):
        return self[MandelParams].mandel_a ** 2 / self._constants()[4]

    def p0(self):
        B, nu, nu_u, G, c = self._constants()
        p = self[MandelParams]
        return p.mandel_force * B * (1 + nu_u) / (3 * p.mandel_a)

    def exact_p(self, x, t):
        a = self[MandelParams].mandel_a
        an = self._roots
        e = np.exp(-an ** 2 * t / self.t_ref())
        w = np.sin(an) / (an - np.sin(an) * np.cos(an)) * e
        return 2 * self.p0() * np.sum((np.cos(np.multiply.outer(x[..., 0], an) / a) - np.cos(an)) * w, axis=-1)

    def exact_grad_p(self, x, t):
        a = self[MandelParams].mandel_a
        an = self._roots
        e = np.exp(-an ** 2 * t / self.t_ref())
        w = np.sin(an) / (an - np.sin(an) * np.cos(an)) * e
        dpdx = 2 * self.p0() * np.sum(-np.sin(np.multiply.outer(x[..., 0], an) / a) * (an / a) * w, axis=-1)
        return np.stack([dpdx, np.zeros_like(dpdx)], axis=-1)

    def _uy_factor(self, t, rate=False):
        """u_y / y (or its time derivative)."""
        B, nu, nu_u, G, c = self._constants()
        p = self[MandelParams]
        F, a = p.mandel_force, p.mandel_a
        an = self._roots
        e = np.exp(-an ** 2 * t / self.t_ref())
        s = np.sin(an) * np.cos(an) / (an - np.sin(an) * np.cos(an))
        if rate:
            return F * (1 - nu_u) / (G * a) * np.sum(s * e * (-an ** 2 / self.t_ref()))
        return -F * (1 - nu) / (2 * G * a) + F * (1 - nu_u) / (G * a) * np.sum(s * e)

    def hit_times(self):
        return [tau * self.t_ref() for tau in self.TAU]

    def build(self, mesh, degree):
        r, p = self[PoroRock], self[MandelParams]
        self._roots = self.roots()
        d = mesh.dim
        el = pe.Elastic(r.rock_youngs_modulus, r.rock_poisson_ratio, d, p="pm", biot=r.rock_biot_coefficient)
        flow = tr.Flow("matrix", "pm", None, r.storage, r.rock_permeability * np.eye(d),
                       Viscosity(r.fluid_viscosity))
        res, jac = pe.elastic_terms(el)
        fr, fj = tr.flow_terms(flow)
        model = Model([FieldSpec("u", d, degree), FieldSpec("pm", 1, p.mandel_pressure_degree)], res + fr, jac + fj)
        zero = lambda x, t: np.zeros(len(x))  # noqa: E731
        bcs = [Dirichlet("u", "x0", zero, components=(0,)), Dirichlet("u", "y0", zero, components=(1,)),
               Dirichlet("u", "yb", lambda x, t: self._uy_factor(t) * x[:, 1],
                         lambda x, t: self._uy_factor(t, rate=True) * x[:, 1], components=(1,)),
               Dirichlet("pm", "xa", zero)]
        B, nu, nu_u, G, c = self._constants()
        F, a = p.mandel_force, p.mandel_a
        scales = {"u": FieldScale(F * p.mandel_b / (G * a)), "pm": FieldScale(self.p0())}
        init = {"u": lambda x: np.column_stack([F * nu_u * x[:, 0] / (2 * G * a),
                                                -F * (1 - nu_u) * x[:, 1] / (2 * G * a)]),
                "pm": lambda x: np.full(len(x), self.p0())}
        self._errors, self._peak = {}, (0.0, 0.0)
        return model, bcs, scales, init

    def monitors(self, problem, t, X=None):
        pc = problem.point_value("pm", (0.0, 0.0), X, t)
        ex = float(self.exact_p(np.array([[0.0, 0.0]]), t)[0]) if t > 0 else self.p0()
        if pc > self._peak[0]:
            self._peak = (pc, t)
        # the force the prescribed plate displacement needs (the consistent reaction
        # of the u_y rows on y = b; the momentum rows have no time derivative) must stay F
        xl, _ = problem.local_arrays(X or problem.X, t)
        force = -problem.reaction(problem.local_residual(xl, np.zeros_like(xl), t), ("u",), ("yb",))
        F = self[MandelParams].mandel_force
        out = {"p_centre": pc, "p_centre_exact": ex, "plate_force_rel_error": abs(force - F) / F}
        if t > 0:
            self._force_err = max(getattr(self, "_force_err", 0.0), out["plate_force_rel_error"])
        for tau, th in zip(self.TAU, self.hit_times()):
            if abs(t - th) <= 1e-9 * th:
                e = problem.max_nodal_error("pm", lambda x: self.exact_p(x, t), X, t) / self.p0()
                out["p_max_error"] = e
                self._errors[tau] = e
        return out

    def report(self, problem, t):
        tau = np.linspace(0.02, 0.1, 400)
        pk = max(float(self.exact_p(np.array([[0.0, 0.0]]), s * self.t_ref())[0]) for s in tau)
        err = {f"p_max_rel_tau{k:g}": v for k, v in sorted(self._errors.items())}
        err["p_max_rel"] = max(self._errors.values()) if self._errors else None
        err["mandel_cryer_peak_rel_p0"] = abs(self._peak[0] - pk) / self.p0()
        err["plate_force_max_rel"] = getattr(self, "_force_err", None)
        return {"error": err, "peak_p_over_p0": self._peak[0] / self.p0(), "peak_exact_over_p0": pk / self.p0(),
                "peak_time_tau": self._peak[1] / self.t_ref(), "p0": self.p0()}


# ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class GravityParams:
    """Elastic column under its own weight (gravity_column)"""
    rock_youngs_modulus: float = param(37.5e9, "Pa", "Young's modulus E", lo=0.0, lo_open=True)
    rock_poisson_ratio: float = param(0.25, "-", "Poisson ratio nu", lo=0.0, hi=0.4999)
    rock_density: float = param(2650.0, "kg/m3", "rock density rho", lo=0.0, lo_open=True)
    gravity: float = param(9.81, "m/s2", "gravitational acceleration g (downwards, -y)", lo=0.0)
    gravity_height: float = param(100.0, "m", "column height H", lo=0.0, lo_open=True)
    gravity_width: float = param(10.0, "m", "column width", lo=0.0, lo_open=True)


@register
class GravityColumn(Scene):
    """-div sigma = F with F = (0, -rho g): bottom fixed, sides on rollers,
    top free.  u_y = -rho g / (lambda + 2G) (H y - y^2/2) is quadratic, so P2
    reproduces it to round-off (a patch test of the body force)."""
    direct_solve = True
    name = "gravity_column"
    description = "elastic column under its own weight (body force): quadratic settlement, exact for P2"
    parameter_sets = (GravityParams,)
    time = TimeDefaults(final_time=1.0, dt_initial=1.0, mesh_size=5.0)
    history_columns = ("u_top", "u_top_exact", "u_max_error")

    def boundaries(self):
        p = self[GravityParams]
        return {"bottom": lambda x: np.isclose(x[:, 1], 0.0),
                "sides": lambda x: np.isclose(x[:, 0], 0.0) | np.isclose(x[:, 0], p.gravity_width)}

    def generate_mesh(self, path, size):
        p = self[GravityParams]
        return meshing.box(path, [p.gravity_width, p.gravity_height], size)

    def exact_uy(self, y):
        p = self[GravityParams]
        el = pe.Elastic(p.rock_youngs_modulus, p.rock_poisson_ratio, 2)
        return -p.rock_density * p.gravity / (el.lame + 2 * el.shear) * (p.gravity_height * y - 0.5 * y ** 2)

    def build(self, mesh, degree):
        p = self[GravityParams]
        el = pe.Elastic(p.rock_youngs_modulus, p.rock_poisson_ratio, mesh.dim,
                        body_force=(0.0, -p.rock_density * p.gravity))
        res, jac = pe.elastic_terms(el)
        model = Model([FieldSpec("u", mesh.dim, degree)], res, jac)
        zero = lambda x, t: np.zeros(len(x))  # noqa: E731
        bcs = [Dirichlet("u", "bottom", lambda x, t: np.zeros((len(x), 2))),
               Dirichlet("u", "sides", zero, components=(0,))]
        scale = abs(float(self.exact_uy(np.array([p.gravity_height]))[0])) or 1.0
        return model, bcs, {"u": FieldScale(scale)}, {}

    def monitors(self, problem, t, X=None):
        H = self[GravityParams].gravity_height
        top = float(self.exact_uy(np.array([H]))[0])
        err = problem.max_nodal_error("u", lambda x: self.exact_uy(x[:, 1]), X, t, component=1)
        self._last = {"u_top": problem.point_value("u", (0.0, H), X, t, component=1), "u_top_exact": top,
                      "u_max_error": err / abs(top)}
        return self._last

    def report(self, problem, t):
        return {"error": {"u_max_rel": self._last["u_max_error"]}}


# ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class ThermalStressParams:
    """Cooling of a laterally constrained half-space (thermal_stress; verification.md 7b)"""
    rock_youngs_modulus: float = param(37.5e9, "Pa", "drained Young's modulus E", lo=0.0, lo_open=True)
    rock_poisson_ratio: float = param(0.25, "-", "Poisson ratio nu", lo=0.0, hi=0.4999)
    rock_thermal_expansion: float = param(2.4e-5, "1/K", "volumetric thermal expansion beta_s", lo=0.0)
    rock_density: float = param(2650.0, "kg/m3", "rock density", lo=0.0, lo_open=True)
    rock_heat_capacity: float = param(800.0, "J/(kg K)", "rock heat capacity", lo=0.0, lo_open=True)
    rock_conductivity: float = param(2.9, "W/(m K)", "rock conductivity", lo=0.0, lo_open=True)
    initial_temperature: float = param(80.0, "degC", "initial temperature T0")
    surface_temperature: float = param(20.0, "degC", "surface temperature for t > 0")
    thermal_depth: float = param(60.0, "m", "depth of the column (> 4 sqrt(kappa t_final))", lo=0.0, lo_open=True)
    thermal_width: float = param(1.0, "m", "width of the column", lo=0.0, lo_open=True)
    thermal_surface_size: float = param(0.1, "m", "mesh size at the surface", lo=0.0, lo_open=True)
    thermomechanical_heating: bool = param(False, "-", "the strain heating beta_s K T d(div u)/dt of "
                                           "physics.md section 6 (the reference solution leaves it out)")


@register
class ThermalStress(Scene):
    direct_solve = True             # GMRES + GAMG does not handle the u-p/u-T saddle point
    name = "thermal_stress"
    description = "1D cooling with constrained lateral strain (verification.md 7b): T, lateral stress, surface motion"
    parameter_sets = (ThermalStressParams,)
    time = TimeDefaults(final_time=1e8, dt_initial=10.0, dt_growth=1.02, dt_max=1e6, mesh_size=5.0,
                        output_interval=50)
    history_columns = ("surface_displacement", "surface_displacement_exact", "T_error", "stress_error")
    TIMES = (1e6, 1e7, 1e8)

    def boundaries(self):
        p = self[ThermalStressParams]
        return {"surface": lambda x: np.isclose(x[:, 0], 0.0), "bottom": lambda x: np.isclose(x[:, 0], p.thermal_depth),
                "sides": lambda x: np.isclose(x[:, 1], 0.0) | np.isclose(x[:, 1], p.thermal_width)}

    def generate_mesh(self, path, size):
        p = self[ThermalStressParams]
        return meshing.box(path, [p.thermal_depth, p.thermal_width], size,
                           grading=meshing.Grading(axis=0, size_min=p.thermal_surface_size,
                                                   distance=0.5 * p.thermal_depth))

    def kappa(self):
        p = self[ThermalStressParams]
        return p.rock_conductivity / (p.rock_density * p.rock_heat_capacity)

    def dT_exact(self, x, t):
        from scipy.special import erfc
        p = self[ThermalStressParams]
        dTs = p.surface_temperature - p.initial_temperature
        return dTs * erfc(x[..., 0] / (2 * np.sqrt(self.kappa() * t))) if t > 0 else 0.0 * x[..., 0]

    def stress_exact(self, x, t):
        p = self[ThermalStressParams]
        return -p.rock_youngs_modulus * p.rock_thermal_expansion * self.dT_exact(x, t) / (3 * (1 - p.rock_poisson_ratio))

    def surface_exact(self, t):
        """Surface displacement u_x(0) (x is depth, positive down): -int eps_xx dx."""
        p = self[ThermalStressParams]
        nu, b = p.rock_poisson_ratio, p.rock_thermal_expansion
        dTs = p.surface_temperature - p.initial_temperature
        return -b * (1 + nu) / (3 * (1 - nu)) * dTs * 2 * np.sqrt(self.kappa() * t / np.pi)

    def hit_times(self):
        return list(self.TIMES)

    def build(self, mesh, degree):
        p = self[ThermalStressParams]
        T0 = p.initial_temperature + 273.15
        Ts = p.surface_temperature + 273.15
        self.el = pe.Elastic(p.rock_youngs_modulus, p.rock_poisson_ratio, mesh.dim, T="Tm",
                             thermal_expansion=p.rock_thermal_expansion, T_ref=T0)
        heat = tr.Heat("matrix", "Tm", p.rock_density * p.rock_heat_capacity, p.rock_conductivity, degree=degree)
        r1, j1 = pe.elastic_terms(self.el)
        r2, j2 = tr.heat_terms(heat)
        if p.thermomechanical_heating:
            r3, j3 = pe.heating_terms(self.el, "Tm")
            r2, j2 = r2 + r3, j2 + j3
        model = Model([FieldSpec("u", mesh.dim, degree), FieldSpec("Tm", 1, degree)], r1 + r2, j1 + j2)
        zero = lambda x, t: np.zeros(len(x))  # noqa: E731
        bcs = [Dirichlet("u", "sides", zero, components=(1,)), Dirichlet("u", "bottom", zero, components=(0,)),
               Dirichlet("Tm", "surface", lambda x, t: np.full(len(x), Ts))]
        scale_u = abs(self.surface_exact(self.time.final_time)) or 1.0
        scales = {"u": FieldScale(scale_u), "Tm": FieldScale(abs(T0 - Ts) or 1.0, T0)}
        self._errors = {}
        return model, bcs, scales, {"u": lambda x: np.zeros((len(x), mesh.dim)), "Tm": lambda x: np.full(len(x), T0)}

    def _errors_at(self, problem, t, X=None):
        p = self[ThermalStressParams]
        dT = abs(p.surface_temperature - p.initial_temperature)
        T0 = p.initial_temperature + 273.15
        eT = problem.max_nodal_error("Tm", lambda x: T0 + self.dT_exact(x, t), X, t) / dT
        xl, _ = problem.local_arrays(X or problem.X, t)
        asm = problem.asm
        s_ref = abs(self.stress_exact(np.zeros((1, 2)), t)[0])
        num = asm.integrate(xl, lambda ctx: (pe.stress(self.el, ctx)[..., 1, 1] - self.stress_exact(ctx.x, t)) ** 2, t)
        area = asm.integrate(xl, lambda ctx: np.ones(ctx.shape), t)
        return eT, float(np.sqrt(num / area)) / s_ref

    def monitors(self, problem, t, X=None):
        ux = problem.point_value("u", (0.0, 0.0), X, t, component=0)
        out = {"surface_displacement": ux, "surface_displacement_exact": self.surface_exact(t)}
        for th in self.TIMES:
            if abs(t - th) <= 1e-9 * th:
                eT, es = self._errors_at(problem, t, X)
                out.update({"T_error": eT, "stress_error": es})
                self._errors[th] = (eT, es, abs(ux - out["surface_displacement_exact"]) /
                                    abs(out["surface_displacement_exact"]))
        return out

    def report(self, problem, t):
        err = {}
        for th, (eT, es, eu) in sorted(self._errors.items()):
            err.update({f"T_max_rel_t{th:g}": eT, f"stress_l2_rel_t{th:g}": es, f"surface_u_rel_t{th:g}": eu})
        return {"error": err}
