"""Poroelastic verification scenes (theory manual, "Equations: rock deformation";
manual, verification).

* ``terzaghi``: 1D consolidation of a column (plane strain, lateral and base
  rollers, a load sigma0 on the drained top at t = 0+, impermeable base),
  started from the undrained state and compared with the series solution.
* ``mandel``: Mandel's problem on the quarter domain, pressure against the
  series solution of Cheng & Detournay (1988) incl. the Mandel-Cryer effect.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from petthm.discretisation import probes
from petthm.discretisation.assembly import FieldScale
from petthm.discretisation.constraints import Dirichlet
from petthm.discretisation.model import MATRIX
from petthm.mesh import generate as meshing
from petthm.params import DISCRETISATION, MESH, PHYSICS, param
from petthm.physics import materials as mt
from petthm.physics.builders import ModelBuilder
from petthm.physics.kernels import poroelastic as pe
from petthm.physics.monitors import hit
from petthm.scenes.base import Monitor, Scene, Setup, TimeDefaults, zero
from petthm.solvers.options import direct_solver_defaults
from petthm.solvers.recipes import PMG_P1_NOT_AGGRESSIVE, glued
from petthm.verification.analytic import series_sum

#: the poroelastic rock and fluid (the manual's verification rock set R)
POROUS_ROCK = mt.group("Poroelastic rock and fluid", mt.ELASTIC + (
    "rock_biot_coefficient", "rock_porosity", "rock_permeability", "fluid_compressibility",
    "fluid_viscosity"),
    rock_porosity=0.1)


def constrained_modulus(p) -> float:
    """M_d = K + 4G/3."""
    return p.bulk_modulus + 4 * p.shear_modulus / 3


def consolidation(p) -> float:
    """c = (k/mu) M M_d / (K_u + 4G/3), K_u = K + alpha^2 M, written with S = 1/M
    so that S = 0 (incompressible fluid and grains) is allowed."""
    S, a = p.storage, p.rock_biot_coefficient
    Md = constrained_modulus(p)
    return p.isotropic_permeability() / p.fluid_viscosity.value * Md / (S * Md + a * a)


def undrained_factor(p) -> float:
    """1 / (M_d + alpha^2 M) written with S: S / (S M_d + alpha^2)."""
    S, a = p.storage, p.rock_biot_coefficient
    return S / (S * constrained_modulus(p) + a * a)


def biot_model(p, mesh, degree: int, pressure_degree: int, stabilisation: float = 0.0):
    """u and pm of Biot's poroelasticity (the builder of both scenes)."""
    b = ModelBuilder(p, mesh.dim)
    b.elasticity(degree, biot=True)
    b.matrix_flow(pressure_degree, permeability=p.isotropic_permeability() * np.eye(mesh.dim),
                  storage=p.storage)
    if stabilisation:
        b.biot_stabilisation(stabilisation)
    return b.build()


@dataclass(frozen=True)
class TerzaghiParams:
    """Terzaghi consolidation column (terzaghi)"""
    terzaghi_height: float = param(10.0, "m", "column height L", lo=0.0, lo_open=True, kind=MESH)
    terzaghi_width: float = param(1.0, "m", "column width", lo=0.0, lo_open=True, kind=MESH)
    terzaghi_dim: int = param(2, "-", "space dimension (3: a square column, rollers on its four sides)",
                              choices=(2, 3), kind=MESH)
    terzaghi_load: float = param(1e6, "Pa", "compressive load sigma0 on the top", lo=0.0, lo_open=True,
                                 kind=PHYSICS)
    terzaghi_pressure_degree: int = param(1, "-", "degree of pm (1: Taylor-Hood with P2 u)", choices=(1, 2),
                                          kind=DISCRETISATION)
    biot_stabilization: float = param(0.0, "-", "factor of the pressure stabilisation h^2/(4(lambda+2G)) "
                                      "(0: off; 1: Aguilar et al. 2008)", lo=0.0, kind=DISCRETISATION)
    terzaghi_start: str = param("undrained", "-", "initial state: undrained (the t = 0+ solution) or rest "
                                "(u = 0, p = 0; the load makes the first step undrained)",
                                choices=("undrained", "rest"), kind=PHYSICS)


def _terms(n=400):
    return (2 * np.arange(n) + 1) * np.pi / 2


class _TerzaghiMonitor(Monitor):
    """Settlement and base pressure every step; the relative L2 error of pm at
    the verification times T_v = c t / L^2 (the series is costly); the
    largest pressure outside [0, p0]."""

    carried = ("errors", "overshoot")

    def __init__(self, scene):
        self.scene = scene
        self.errors, self.overshoot = {}, 0.0

    def __call__(self, problem, t, X=None):
        sc, p = self.scene, self.scene.p
        pmin, pmax = probes.field_range(problem, "pm", X, t)
        # pressure outside [0, p0] (the undrained pressure bounds the solution), relative to the load
        over = max(pmax - sc.p0(), -pmin, 0.0) / p.terzaghi_load if t > 0 else 0.0
        self.overshoot = max(self.overshoot, over)
        top, base = sc.point(p.terzaghi_height), sc.point(0.0)
        settlement = -probes.point_value(problem, "u", top, X, t, component=1)
        out = {"settlement": settlement, "settlement_exact": sc.exact_settlement(t), "p_overshoot": over,
               "p_base": probes.point_value(problem, "pm", base, X, t),
               "p_base_exact": float(sc.exact_p(np.array([base]), t)[0]) if t > 0 else sc.p0()}
        th = hit(t, sc.hit_times())
        if th is not None:
            xl, _ = problem.local_arrays(X or problem.X, t)
            e = problem.region(MATRIX).error_norms(xl, "pm", sc.exact_p, sc.exact_grad_p, t)
            out["p_l2_rel"] = e["l2_rel"]
            tv = sc.TV[sc.hit_times().index(th)]
            self.errors[tv] = (e["l2_rel"],
                               abs(settlement - out["settlement_exact"]) / out["settlement_exact"])
        return out

    def report(self, problem, t):
        err = {}
        for tv, (ep, es) in sorted(self.errors.items()):
            err[f"p_l2_rel_Tv{tv:g}"] = ep
            err[f"settlement_rel_Tv{tv:g}"] = es
        return {"error": err, "t_c": self.scene.t_c(), "p0": self.scene.p0(),
                "p_overshoot_max_rel_load": self.overshoot}


class Terzaghi(Scene):
    name = "terzaghi"
    description = "1D consolidation (manual, verification): pressure and settlement vs the series solution"
    parameters = (POROUS_ROCK, TerzaghiParams)
    time = TimeDefaults(final_time=1300.0, dt_initial=0.0648, dt_growth=1.05, dt_max=2.0, mesh_size=0.5)
    history_columns = ("settlement", "settlement_exact", "p_base", "p_base_exact", "p_l2_rel", "p_overshoot")
    TV = (0.01, 0.1, 0.5, 1.0)

    def block_recipe(self, snes_type):
        """The p-multigrid's P1 level without GAMG's aggressive coarsening
        (``recipes.PMG_P1_NOT_AGGRESSIVE``): item 9's weak scaling 1.11x
        against 1.41x over 1-8 ranks; to 2 t_c on three levels 8.6 / 8.8 /
        9.6 against 10.1 / 11.1 / 12.4 Krylov iterations per Newton
        iteration (manual, solver guide).  P1 u has no p-multigrid, so
        nothing is proposed there."""
        return glued(PMG_P1_NOT_AGGRESSIVE) if self.run.fe_degree == 2 else {}

    def boundaries(self):
        p = self.p
        w = p.terzaghi_width
        out = {"top": lambda x: np.isclose(x[:, 1], p.terzaghi_height),
               "base": lambda x: np.isclose(x[:, 1], 0.0),
               "sides": lambda x: np.isclose(x[:, 0], 0.0) | np.isclose(x[:, 0], w)}
        if p.terzaghi_dim == 3:
            out["front_back"] = lambda x: np.isclose(x[:, 2], 0.0) | np.isclose(x[:, 2], w)
        return out

    def generate_mesh(self, path, size):
        p = self.p
        lengths = [p.terzaghi_width, p.terzaghi_height] + [p.terzaghi_width] * (p.terzaghi_dim - 2)
        return meshing.box(path, lengths, size, structured=True)

    def point(self, y: float) -> tuple:
        """The point at height y on the column's axis x = 0 (z = 0)."""
        return (0.0, y) + (0.0,) * (self.p.terzaghi_dim - 2)

    # -- reference solution ----------------------------------------------------------
    def t_c(self):
        return self.p.terzaghi_height ** 2 / consolidation(self.p)

    def p0(self):
        """alpha M sigma0 / (M_d + alpha^2 M) = alpha sigma0 / (S M_d + alpha^2)."""
        p = self.p
        a = p.rock_biot_coefficient
        return a * p.terzaghi_load / (p.storage * constrained_modulus(p) + a * a) if a > 0 else 0.0

    def exact_p(self, x, t):
        L = self.p.terzaghi_height
        z = L - x[..., 1]
        lam = _terms()
        Tv = t / self.t_c()
        e = np.exp(-lam ** 2 * Tv) * 2 / lam
        return self.p0() * series_sum(z / L, lam, e, np.sin)

    def exact_grad_p(self, x, t):
        L = self.p.terzaghi_height
        z = L - x[..., 1]
        lam = _terms()
        e = np.exp(-lam ** 2 * t / self.t_c()) * 2 / L
        dpdz = self.p0() * series_sum(z / L, lam, e, np.cos)
        grad = np.zeros(dpdz.shape + (x.shape[-1],))
        grad[..., 1] = -dpdz
        return grad

    def exact_settlement(self, t):
        p = self.p
        s0 = p.terzaghi_load * p.terzaghi_height * undrained_factor(p)
        sinf = p.terzaghi_load * p.terzaghi_height / constrained_modulus(p)
        lam = _terms()
        U = 1 - np.sum(2 / lam ** 2 * np.exp(-lam ** 2 * t / self.t_c()))
        return s0 + (sinf - s0) * U

    def hit_times(self):
        return [tv * self.t_c() for tv in self.TV]

    # -- model -------------------------------------------------------------------------
    def build(self, mesh, degree):
        p = self.p
        model = biot_model(p, mesh, degree, p.terzaghi_pressure_degree, p.biot_stabilization)
        load = np.zeros(mesh.dim)
        load[1] = -p.terzaghi_load
        model.facets.append(pe.traction("u", "top", lambda x, t: load))
        bcs = [Dirichlet("u", "sides", zero, components=(0,)), Dirichlet("u", "base", zero, components=(1,)),
               Dirichlet("pm", "top", zero)]
        if mesh.dim == 3:
            bcs.append(Dirichlet("u", "front_back", zero, components=(2,)))
        s_inf = p.terzaghi_load * p.terzaghi_height / constrained_modulus(p)
        scales = {"u": FieldScale(s_inf), "pm": FieldScale(self.p0())}
        # undrained state at t = 0+: uniform p0 and uniform vertical strain
        eps = -p.terzaghi_load * undrained_factor(p)
        rest = p.terzaghi_start == "rest"
        init = {"u": lambda x: np.column_stack([np.zeros(len(x)), (0.0 if rest else eps) * x[:, 1]] +
                                               [np.zeros(len(x))] * (mesh.dim - 2)),
                "pm": lambda x: np.full(len(x), 0.0 if rest else self.p0())}
        return Setup(model, bcs, scales, init, _TerzaghiMonitor(self))

    # GMRES + GAMG does not handle the u-p saddle point
    solver_defaults = staticmethod(direct_solver_defaults)


# ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class MandelParams:
    """Mandel's problem, quarter domain (mandel; manual, verification)"""
    mandel_a: float = param(10.0, "m", "half-width a (drained sides at x = +-a)", lo=0.0, lo_open=True,
                            kind=MESH)
    mandel_b: float = param(10.0, "m", "half-height b (rigid plates at y = +-b)", lo=0.0, lo_open=True,
                            kind=MESH)
    mandel_force: float = param(1e7, "N/m", "force F per unit length on each plate (mean stress F/a)",
                                lo=0.0, lo_open=True, kind=PHYSICS)
    mandel_pressure_degree: int = param(1, "-", "degree of pm (1: Taylor-Hood with P2 u)", choices=(1, 2),
                                        kind=DISCRETISATION)


class _MandelMonitor(Monitor):
    """Centre pressure, its peak, the plate force (the consistent reaction),
    the largest nodal pressure error at the verification times."""

    carried = ("errors", "peak", "force_error")

    def __init__(self, scene):
        self.scene = scene
        self.errors, self.peak, self.force_error = {}, (0.0, 0.0), None

    def __call__(self, problem, t, X=None):
        sc = self.scene
        pc = probes.point_value(problem, "pm", (0.0, 0.0), X, t)
        ex = float(sc.exact_p(np.array([[0.0, 0.0]]), t)[0]) if t > 0 else sc.p0()
        if pc > self.peak[0]:
            self.peak = (pc, t)
        # the force the prescribed plate displacement needs (the consistent reaction
        # of the u_y rows on y = b; the momentum rows have no time derivative) must stay F
        xl, _ = problem.local_arrays(X or problem.X, t)
        force = -problem.reaction(problem.local_residual(xl, np.zeros_like(xl), t), ("u",), ("yb",))
        F = sc.p.mandel_force
        out = {"p_centre": pc, "p_centre_exact": ex, "plate_force_rel_error": abs(force - F) / F}
        if t > 0:
            self.force_error = max(self.force_error or 0.0, out["plate_force_rel_error"])
        th = hit(t, sc.hit_times())
        if th is not None:
            e = probes.max_nodal_error(problem, "pm", lambda x: sc.exact_p(x, t), X, t) / sc.p0()
            out["p_max_error"] = e
            self.errors[sc.TAU[sc.hit_times().index(th)]] = e
        return out

    def report(self, problem, t):
        sc = self.scene
        tau = np.linspace(0.02, 0.1, 400)
        pk = max(float(sc.exact_p(np.array([[0.0, 0.0]]), s * sc.t_ref())[0]) for s in tau)
        err = {f"p_max_rel_tau{k:g}": v for k, v in sorted(self.errors.items())}
        err["p_max_rel"] = max(self.errors.values()) if self.errors else None
        err["mandel_cryer_peak_rel_p0"] = abs(self.peak[0] - pk) / sc.p0()
        err["plate_force_max_rel"] = self.force_error
        return {"error": err, "peak_p_over_p0": self.peak[0] / sc.p0(), "peak_exact_over_p0": pk / sc.p0(),
                "peak_time_tau": self.peak[1] / sc.t_ref(), "p0": sc.p0()}


class Mandel(Scene):
    name = "mandel"
    dimension = 2
    description = "Mandel's problem (manual, verification): pressure incl. the Mandel-Cryer overshoot"
    parameters = (POROUS_ROCK, MandelParams)
    time = TimeDefaults(final_time=700.0, dt_initial=0.0648, dt_growth=1.05, dt_max=1.3, mesh_size=0.5)
    history_columns = ("p_centre", "p_centre_exact", "p_max_error", "plate_force_rel_error")
    TAU = (0.01, 0.05, 0.1, 0.2, 0.5, 1.0)

    def __init__(self, run, p):
        super().__init__(run, p)
        self.alpha_n = self.roots()

    def boundaries(self):
        p = self.p
        return {"x0": lambda x: np.isclose(x[:, 0], 0.0), "y0": lambda x: np.isclose(x[:, 1], 0.0),
                "xa": lambda x: np.isclose(x[:, 0], p.mandel_a),
                "yb": lambda x: np.isclose(x[:, 1], p.mandel_b)}

    def generate_mesh(self, path, size):
        p = self.p
        return meshing.box(path, [p.mandel_a, p.mandel_b], size, structured=True)

    # -- reference (Cheng & Detournay 1988) -------------------------------------------
    def _constants(self):
        p = self.p
        S, al = p.storage, p.rock_biot_coefficient
        Ku_S = S * p.bulk_modulus + al * al                   # S K_u
        B = al / Ku_S
        nu, G = p.rock_poisson_ratio, p.shear_modulus
        nu_u = (3 * Ku_S - 2 * G * S) / (2 * (3 * Ku_S + G * S))
        return B, nu, nu_u, G, consolidation(p)

    def roots(self, n=200):
        """The first n roots of tan(x) = k x, k = (1 - nu)/(nu_u - nu) > 1: one
        in each (i pi, i pi + pi/2), where tan x - k x goes from < 0 to +inf."""
        from petthm.verification.analytic import increasing_root
        B, nu, nu_u, G, c = self._constants()
        k = (1 - nu) / (nu_u - nu)
        i = np.arange(n)
        lo = np.where(i > 0, i * np.pi + 1e-12, 1e-9)
        return increasing_root(lambda x: np.tan(x) - k * x, lo, i * np.pi + np.pi / 2 - 1e-12)

    def t_ref(self):
        return self.p.mandel_a ** 2 / self._constants()[4]

    def p0(self):
        B, nu, nu_u, G, c = self._constants()
        p = self.p
        return p.mandel_force * B * (1 + nu_u) / (3 * p.mandel_a)

    def _series(self, t):
        an = self.alpha_n
        return an, np.exp(-an ** 2 * t / self.t_ref())

    def exact_p(self, x, t):
        a = self.p.mandel_a
        an, e = self._series(t)
        w = np.sin(an) / (an - np.sin(an) * np.cos(an)) * e
        return 2 * self.p0() * (series_sum(x[..., 0] / a, an, w, np.cos) - np.sum(np.cos(an) * w))

    def _uy_factor(self, t, rate=False):
        """u_y / y (or its time derivative)."""
        B, nu, nu_u, G, c = self._constants()
        p = self.p
        F, a = p.mandel_force, p.mandel_a
        an, e = self._series(t)
        s = np.sin(an) * np.cos(an) / (an - np.sin(an) * np.cos(an))
        if rate:
            return F * (1 - nu_u) / (G * a) * np.sum(s * e * (-an ** 2 / self.t_ref()))
        return -F * (1 - nu) / (2 * G * a) + F * (1 - nu_u) / (G * a) * np.sum(s * e)

    def hit_times(self):
        return [tau * self.t_ref() for tau in self.TAU]

    def build(self, mesh, degree):
        p = self.p
        model = biot_model(p, mesh, degree, p.mandel_pressure_degree)
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
        return Setup(model, bcs, scales, init, _MandelMonitor(self))

    # GMRES + GAMG does not handle the u-p saddle point
    solver_defaults = staticmethod(direct_solver_defaults)
