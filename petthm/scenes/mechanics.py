"""Elastic and thermo-elastic verification scenes (theory manual, "Equations: rock deformation" and
6; manual, verification).

* ``gravity_column``: an elastic column under its own weight (body force):
  quadratic settlement, exact for P2.
* ``thermal_stress``: cooling of a laterally constrained half-space:
  temperature, lateral stress and surface displacement against the 1D
  solution.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from petthm.discretisation import probes
from petthm.discretisation.assembly import FieldScale
from petthm.discretisation.constraints import Dirichlet
from petthm.discretisation.model import MATRIX
from petthm.mesh import generate as meshing
from petthm.params import CELSIUS, MESH, param
from petthm.physics import materials as mt
from petthm.physics.builders import ModelBuilder
from petthm.physics.kernels import poroelastic as pe
from petthm.physics.monitors import hit
from petthm.scenes.base import Monitor, Scene, Setup, TimeDefaults, constant, constant_in_time, zero
from petthm.solvers.options import direct_solver_defaults


# ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class GravityParams:
    """Elastic column under its own weight (gravity_column)"""
    gravity_height: float = param(100.0, "m", "column height H", lo=0.0, lo_open=True, kind=MESH)
    gravity_width: float = param(10.0, "m", "column width", lo=0.0, lo_open=True, kind=MESH)


class _GravityMonitor(Monitor):
    def __init__(self, scene):
        self.scene, self.last = scene, {}

    def __call__(self, problem, t, X=None):
        sc = self.scene
        H = sc.p.gravity_height
        top = float(sc.exact_uy(np.array([H]))[0])
        err = probes.max_nodal_error(problem, "u", lambda x: sc.exact_uy(x[:, 1]), X, t, component=1)
        self.last = {"u_top": probes.point_value(problem, "u", (0.0, H), X, t, component=1),
                     "u_top_exact": top,
                     "u_max_error": err / abs(top)}
        return self.last

    def report(self, problem, t):
        return {"error": {"u_max_rel": self.last["u_max_error"]}}


class GravityColumn(Scene):
    """-div sigma = F with F = (0, -rho g): bottom fixed, sides on rollers,
    top free.  u_y = -rho g / (lambda + 2G) (H y - y^2/2) is quadratic, so P2
    reproduces it to round-off (a patch test of the body force)."""
    name = "gravity_column"
    dimension = 2
    description = "elastic column under its own weight (body force): quadratic settlement, exact for P2"
    parameters = (mt.group("Rock", mt.ELASTIC + ("rock_density", "gravity")), GravityParams)
    time = TimeDefaults(final_time=1.0, dt_initial=1.0, mesh_size=5.0)
    history_columns = ("u_top", "u_top_exact", "u_max_error")

    def boundaries(self):
        p = self.p
        return {"bottom": lambda x: np.isclose(x[:, 1], 0.0),
                "sides": lambda x: np.isclose(x[:, 0], 0.0) | np.isclose(x[:, 0], p.gravity_width)}

    def generate_mesh(self, path, size):
        p = self.p
        return meshing.box(path, [p.gravity_width, p.gravity_height], size)

    def exact_uy(self, y):
        p = self.p
        el = pe.Elastic(p.rock_youngs_modulus, p.rock_poisson_ratio, 2)
        return -p.rock_density * p.gravity / (el.lame + 2 * el.shear) * (p.gravity_height * y - 0.5 * y ** 2)

    def build(self, mesh, degree):
        p = self.p
        b = ModelBuilder(p, mesh.dim)
        b.elasticity(degree, body_force=(0.0, -p.rock_density * p.gravity))
        bcs = [Dirichlet("u", "bottom", lambda x, t: np.zeros((len(x), 2))),
               Dirichlet("u", "sides", zero, components=(0,))]
        scale = abs(float(self.exact_uy(np.array([p.gravity_height]))[0])) or 1.0
        return Setup(b.build(), bcs, {"u": FieldScale(scale)}, {}, _GravityMonitor(self))

    solver_defaults = staticmethod(direct_solver_defaults)


# ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class ThermalStressParams:
    """Cooling of a laterally constrained half-space (thermal_stress; manual, verification)"""
    thermal_depth: float = param(60.0, "m", "depth of the column (> 4 sqrt(kappa t_final))", lo=0.0,
                                 lo_open=True, kind=MESH)
    thermal_width: float = param(1.0, "m", "width of the column", lo=0.0, lo_open=True, kind=MESH)
    thermal_surface_size: float = param(0.1, "m", "mesh size at the surface", lo=0.0, lo_open=True, kind=MESH)


class _ThermalStressMonitor(Monitor):
    carried = ("errors",)

    def __init__(self, scene, elastic):
        self.scene, self.elastic = scene, elastic
        self.errors = {}

    def errors_at(self, problem, t, X=None):
        sc, p = self.scene, self.scene.p
        dT = abs(p.surface_temperature - p.initial_temperature)
        eT = probes.max_nodal_error(problem, "Tm", lambda x: p.T0 + sc.dT_exact(x, t), X, t) / dT
        xl, _ = problem.local_arrays(X or problem.X, t)
        asm = problem.region(MATRIX)
        s_ref = abs(sc.stress_exact(np.zeros((1, 2)), t)[0])
        num = asm.integrate(xl,
                            lambda ctx: (pe.stress(self.elastic,
                                                   ctx)[..., 1, 1] - sc.stress_exact(ctx.x, t)) ** 2,
                            t)
        area = asm.integrate(xl, lambda ctx: np.ones(ctx.shape), t)
        return eT, float(np.sqrt(num / area)) / s_ref

    def __call__(self, problem, t, X=None):
        sc = self.scene
        ux = probes.point_value(problem, "u", (0.0, 0.0), X, t, component=0)
        out = {"surface_displacement": ux, "surface_displacement_exact": sc.surface_exact(t)}
        th = hit(t, sc.TIMES)
        if th is not None:
            eT, es = self.errors_at(problem, t, X)
            out.update({"T_error": eT, "stress_error": es})
            self.errors[th] = (eT, es, abs(ux - out["surface_displacement_exact"]) /
                               abs(out["surface_displacement_exact"]))
        return out

    def report(self, problem, t):
        err = {}
        for th, (eT, es, eu) in sorted(self.errors.items()):
            err.update({f"T_max_rel_t{th:g}": eT, f"stress_l2_rel_t{th:g}": es, f"surface_u_rel_t{th:g}": eu})
        return {"error": err}


class ThermalStress(Scene):
    name = "thermal_stress"
    dimension = 2
    description = ("1D cooling with constrained lateral strain (manual, verification): T, lateral stress, "
                   "surface motion")
    parameters = (mt.group("Rock", mt.ELASTIC + mt.ROCK_HEAT + ("rock_thermal_expansion",)),
                  mt.group("Temperatures", ("initial_temperature", "surface_temperature")),
                  mt.group("Coupling", ("thermomechanical_heating",)),
                  ThermalStressParams)
    time = TimeDefaults(final_time=1e8, dt_initial=10.0, dt_growth=1.02, dt_max=1e6, mesh_size=5.0,
                        output_interval=50)
    history_columns = ("surface_displacement", "surface_displacement_exact", "T_error", "stress_error")
    TIMES = (1e6, 1e7, 1e8)

    def boundaries(self):
        p = self.p
        return {"surface": lambda x: np.isclose(x[:, 0], 0.0),
                "bottom": lambda x: np.isclose(x[:, 0], p.thermal_depth),
                "sides": lambda x: np.isclose(x[:, 1], 0.0) | np.isclose(x[:, 1], p.thermal_width)}

    def generate_mesh(self, path, size):
        p = self.p
        return meshing.box(path, [p.thermal_depth, p.thermal_width], size,
                           grading=meshing.Grading(axis=0, size_min=p.thermal_surface_size,
                                                   distance=0.5 * p.thermal_depth))

    def kappa(self):
        p = self.p
        return p.rock_conductivity / (p.rock_density * p.rock_heat_capacity)

    def dT_exact(self, x, t):
        from petthm.verification.analytic import erfc
        p = self.p
        dTs = p.surface_temperature - p.initial_temperature
        return dTs * erfc(x[..., 0] / (2 * np.sqrt(self.kappa() * t))) if t > 0 else 0.0 * x[..., 0]

    def stress_exact(self, x, t):
        p = self.p
        return -p.rock_youngs_modulus * p.rock_thermal_expansion * self.dT_exact(
            x, t) / (3 * (1 - p.rock_poisson_ratio))

    def surface_exact(self, t):
        """Surface displacement u_x(0) (x is depth, positive down): -int eps_xx dx."""
        p = self.p
        nu, b = p.rock_poisson_ratio, p.rock_thermal_expansion
        dTs = p.surface_temperature - p.initial_temperature
        return -b * (1 + nu) / (3 * (1 - nu)) * dTs * 2 * np.sqrt(self.kappa() * t / np.pi)

    def hit_times(self):
        return list(self.TIMES)

    def build(self, mesh, degree):
        p = self.p
        T0, Ts = p.T0, p.surface_temperature + CELSIUS
        b = ModelBuilder(p, mesh.dim)
        el = b.elasticity(degree, thermal=True)
        b.matrix_heat(degree, capacity=p.rock_density * p.rock_heat_capacity,
                      conductivity=p.rock_conductivity)
        bcs = [Dirichlet("u", "sides", zero, components=(1,)),
               Dirichlet("u", "bottom", zero, components=(0,)),
               Dirichlet("Tm", "surface", constant_in_time(Ts))]
        scale_u = abs(self.surface_exact(self.time.final_time)) or 1.0
        scales = {"u": FieldScale(scale_u), "Tm": FieldScale(abs(T0 - Ts) or 1.0, T0)}
        init = {"u": lambda x: np.zeros((len(x), mesh.dim)), "Tm": constant(T0)}
        return Setup(b.build(), bcs, scales, init, _ThermalStressMonitor(self, el))

    # GMRES + GAMG does not handle the u-T saddle point
    solver_defaults = staticmethod(direct_solver_defaults)
