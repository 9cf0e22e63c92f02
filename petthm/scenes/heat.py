"""Heat-transport verification scenes (theory manual, "Equations: rock heat"; manual, verification, 8),
all on the production path of the rock heat equation (kernels/heat.Heat,
conservative form with SUPG).

* ``heat_mms``: manufactured solution T = T_ref + A (1 + t/t_ref) g(x) on the
  unit square/cube with Dirichlet, Neumann and Robin sides and a uniform
  advection velocity; affine in t, so backward Euler adds no time error and
  the reported L2/H1 errors are purely spatial.  The Neumann and Robin sides
  are outflow sides: the fluid carries its enthalpy out there
  (``heatboundary.outflow_term``) and q_N, h (T - T_ext) are the conductive
  fluxes.
* ``heat_erfc``: 1D conduction into a half-space after a step change of the
  surface temperature, T = T0 + (Ts - T0) erfc(z / (2 sqrt(kappa t))), on a
  strip graded toward the surface.
* ``heat_advection``: a cold front advected through a channel at cell Peclet
  number >= 100 with SUPG; reports the over/undershoot.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from petthm.discretisation import probes
from petthm.discretisation.assembly import FieldScale
from petthm.discretisation.constraints import Dirichlet
from petthm.discretisation.model import MATRIX
from petthm.mesh import generate as meshing
from petthm.params import CELSIUS, MESH, PHYSICS, param
from petthm.physics import materials as mt
from petthm.physics.builders import ModelBuilder
from petthm.physics.kernels import heatboundary as hb
from petthm.scenes.base import Monitor, Scene, Setup, TimeDefaults, constant, constant_in_time, face
from petthm.solvers.options import direct_solver_defaults

FIELD = "Tm"
ROCK_AND_FLUID_HEAT = mt.ROCK_HEAT + ("rock_porosity",) + mt.FLUID_HEAT


# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class MMSParams:
    """Manufactured-solution set-up (heat_mms)"""
    mms_dim: int = param(2, "-", "space dimension", choices=(2, 3), kind=MESH)
    mms_velocity: tuple = param((1.0, 0.5, 0.25), "m/s", "uniform Darcy velocity vx,vy[,vz]", kind=PHYSICS)
    mms_robin_coefficient: float = param(2.0, "W/(m2 K)", "h of the Robin side y=1", lo=0.0, lo_open=True,
                                         kind=PHYSICS)
    mms_amplitude: float = param(10.0, "K", "amplitude A of the manufactured field", lo=0.0, lo_open=True,
                                 kind=PHYSICS)


class _ErrorNorms(Monitor):
    """L2 and H1 errors of Tm against the exact solution at the end."""

    def __init__(self, scene):
        self.scene = scene

    def report(self, problem, t):
        sc = self.scene
        e = problem.region(MATRIX).error_norms(problem.local_arrays(problem.X, t)[0], FIELD,
                                               sc.exact, sc.exact_grad, t)
        mesh = problem.disc.mesh
        return {"error": {"Tm_l2_rel": e["l2_rel"], "Tm_h1_rel": e["h1_rel"], "Tm_l2": e["l2"],
                          "Tm_h1": e["h1"]},
                "h_max": probes.global_max(mesh.dm.comm, mesh.h, empty=0.0)}


class HeatMMS(Scene):
    name = "heat_mms"
    description = "manufactured solution for transient advection-diffusion (2D/3D, P1/P2)"
    parameters = (mt.group("Rock and fluid heat", ROCK_AND_FLUID_HEAT, rock_density=1.0,
                           rock_heat_capacity=1.0,
                           rock_conductivity=1.0, fluid_density=1.0, fluid_heat_capacity=1.0),
                  mt.group("Discretisation", mt.HEAT_DISCRETISATION),
                  MMSParams)
    time = TimeDefaults(final_time=1.0, dt_initial=0.25, mesh_size=0.125)
    t_ref = 1.0
    T_ref = 300.0

    def boundaries(self):
        d = self.p.mms_dim
        parts = {"x0": face(0, 0.0), "x1": face(0, 1.0), "y0": face(1, 0.0), "y1": face(1, 1.0)}
        if d == 3:
            parts.update(z0=face(2, 0.0), z1=face(2, 1.0))
        return parts

    def generate_mesh(self, path, size):
        return meshing.box(path, [1.0] * self.p.mms_dim, size, structured=True)

    # exact solution ------------------------------------------------------------
    def _g(self, x):
        g = np.sin(np.pi * x[..., 0]) * np.cos(np.pi * x[..., 1]) + x[..., 0] * x[..., 1]
        if x.shape[-1] == 3:
            g = g * np.cos(0.5 * np.pi * x[..., 2]) + x[..., 2] ** 2
        return g

    def _grad_g(self, x):
        sx, cx = np.sin(np.pi * x[..., 0]), np.cos(np.pi * x[..., 0])
        sy, cy = np.sin(np.pi * x[..., 1]), np.cos(np.pi * x[..., 1])
        gx = np.pi * cx * cy + x[..., 1]
        gy = -np.pi * sx * sy + x[..., 0]
        if x.shape[-1] == 2:
            return np.stack([gx, gy], axis=-1)
        cz, sz = np.cos(0.5 * np.pi * x[..., 2]), np.sin(0.5 * np.pi * x[..., 2])
        g2 = sx * cy + x[..., 0] * x[..., 1]
        return np.stack([gx * cz, gy * cz, -0.5 * np.pi * sz * g2 + 2 * x[..., 2]], axis=-1)

    def _lap_g(self, x):
        s2 = np.sin(np.pi * x[..., 0]) * np.cos(np.pi * x[..., 1])
        if x.shape[-1] == 2:
            return -2 * np.pi ** 2 * s2
        cz = np.cos(0.5 * np.pi * x[..., 2])
        g2 = s2 + x[..., 0] * x[..., 1]
        return -2 * np.pi ** 2 * s2 * cz - 0.25 * np.pi ** 2 * g2 * cz + 2.0

    def exact(self, x, t):
        return self.T_ref + self.p.mms_amplitude * (1 + t / self.t_ref) * self._g(x)

    def exact_grad(self, x, t):
        return self.p.mms_amplitude * (1 + t / self.t_ref) * self._grad_g(x)

    def _velocity(self, x, t):
        return np.asarray(self.p.mms_velocity[:x.shape[-1]], dtype=float)

    def _source(self, x, t):
        p, A = self.p, self.p.mms_amplitude
        dTdt = A / self.t_ref * self._g(x)
        adv = np.einsum("...a,a->...", self.exact_grad(x, t), self._velocity(x, t))
        lap = A * (1 + t / self.t_ref) * self._lap_g(x)
        return p.rho_c * dTdt + p.fluid_rho_c * adv - p.conductivity * lap

    def build(self, mesh, degree):
        p = self.p
        b = ModelBuilder(p, mesh.dim)
        heat = b.matrix_heat(degree, velocity=self._velocity, source=self._source,
                             reference_temperature=self.T_ref)
        h, lam = p.mms_robin_coefficient, p.conductivity

        def inflow(x, t):    # q_N = lambda grad T . n on x = 1 (n = +x)
            return lam * self.exact_grad(x, t)[..., 0]

        def t_ext(x, t):     # -lambda grad T . n = h (T - T_ext) on y = 1 (n = +y)
            return self.exact(x, t) + lam * self.exact_grad(x, t)[..., 1] / h

        model = b.build()
        model.facets += [hb.neumann(FIELD, "x1", inflow), hb.robin(FIELD, "y1", h, t_ext),
                         hb.outflow_term(heat, "x1"), hb.outflow_term(heat, "y1")]
        dir_parts = ["x0", "y0"] + (["z0", "z1"] if p.mms_dim == 3 else [])
        rate = lambda x, t: p.mms_amplitude / self.t_ref * self._g(x)  # noqa: E731
        dirichlet = [Dirichlet(FIELD, part, self.exact, rate) for part in dir_parts]
        scales = {FIELD: FieldScale(scale=p.mms_amplitude, offset=self.T_ref)}
        return Setup(model, dirichlet, scales, {FIELD: lambda x: self.exact(x, 0.0)}, _ErrorNorms(self))


# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class ErfcParams:
    """Half-space conduction after a surface temperature step (heat_erfc)"""
    erfc_depth: float = param(10.0, "m", "depth of the strip (insulated at the far end)", lo=0.0,
                              lo_open=True, kind=MESH)
    erfc_width: float = param(0.5, "m", "width of the strip", lo=0.0, lo_open=True, kind=MESH)
    erfc_surface_size: float = param(0.02, "m", "mesh size at the surface", lo=0.0, lo_open=True, kind=MESH)


class _ErfcMonitor(Monitor):
    def __init__(self, scene):
        self.scene = scene

    def error(self, problem, t):
        p = self.scene.p
        err = probes.max_nodal_error(problem, FIELD, lambda x: self.scene.exact(x, t), t=t)
        return err / abs(p.initial_temperature - p.surface_temperature)

    def __call__(self, problem, t, X=None):
        T = problem.field_values(FIELD, t=t)[:, 0]
        x = problem.disc.field_node_coordinates(FIELD)
        out = {}
        for z in (0.5, 1.0, 2.0):
            out[f"T_z{z:g}"] = probes.nearest(problem.dm.comm, x, (z, 0.0), [T - CELSIUS], ord=1)[0]
        out["error_max"] = self.error(problem, t)
        return out

    def report(self, problem, t):
        return {"error": {"Tm_max_rel": self.error(problem, t)}}


class HeatErfc(Scene):
    name = "heat_erfc"
    dimension = 2
    description = "1D transient conduction into a half-space (manual, verification), graded mesh"
    water_pressure = 1e6                # Pa gauge (no pressure field; liquid up to 184 degC)
    parameters = (mt.group("Rock and fluid heat", ROCK_AND_FLUID_HEAT),
                  mt.group("Initial and surface temperature", ("initial_temperature", "surface_temperature")),
                  ErfcParams)
    time = TimeDefaults(final_time=1e6, dt_initial=10.0, dt_growth=1.01, dt_max=1e4,
                        output_interval=50, mesh_size=0.25)
    history_columns = ("T_z0.5", "T_z1", "T_z2", "error_max")

    def boundaries(self):
        return {"surface": face(0, 0.0)}

    def generate_mesh(self, path, size):
        p = self.p
        return meshing.box(path, [p.erfc_depth, p.erfc_width], size,
                           grading=meshing.Grading(axis=0, size_min=p.erfc_surface_size,
                                                   distance=0.5 * p.erfc_depth))

    def exact(self, x, t):
        p = self.p
        kappa = p.conductivity / p.rho_c
        T0, Ts = p.T0, p.surface_temperature + CELSIUS
        z = x[..., 0]
        if t <= 0:
            return np.full(z.shape, T0)
        from petthm.verification.analytic import erfc
        return T0 + (Ts - T0) * erfc(z / (2 * np.sqrt(kappa * t)))

    def build(self, mesh, degree):
        p = self.p
        b = ModelBuilder(p, mesh.dim)
        b.matrix_heat(degree)
        Ts, T0 = p.surface_temperature + CELSIUS, p.T0
        dirichlet = [Dirichlet(FIELD, "surface", constant_in_time(Ts))]
        scales = {FIELD: FieldScale(scale=abs(T0 - Ts) or 1.0, offset=T0)}
        return Setup(b.build(), dirichlet, scales, {FIELD: constant(T0)}, _ErfcMonitor(self))


# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class AdvectionParams:
    """Advection-dominated front in a channel (heat_advection)"""
    advection_velocity: tuple = param((1e-5, 0.0), "m/s",
                                      "uniform Darcy velocity vx,vy (inflow only through x = 0)",
                                      kind=PHYSICS)
    advection_length: float = param(100.0, "m", "channel length", lo=0.0, lo_open=True, kind=MESH)
    advection_height: float = param(20.0, "m", "channel height", lo=0.0, lo_open=True, kind=MESH)


class _PecletMonitor(Monitor):
    """The mesh's cell Peclet number (the front's range: run/ranges.py)."""

    def __init__(self, scene):
        self.scene = scene

    def __call__(self, problem, t, X=None):
        return {"cell_peclet": self.scene.cell_peclet(problem.disc.mesh)}

    def report(self, problem, t):
        return {"cell_peclet_min": self.scene.cell_peclet(problem.disc.mesh)}


class HeatAdvection(Scene):
    name = "heat_advection"
    dimension = 2
    description = "cold front advected at cell Peclet >= 100 (SUPG boundedness check)"
    water_pressure = 1e6                # Pa gauge: liquid at the 100 degC start
    parameters = (mt.group("Rock and fluid heat", ROCK_AND_FLUID_HEAT, rock_conductivity=0.1,
                           fluid_conductivity=0.0),
                  mt.group("Temperatures", ("initial_temperature", "injection_temperature"),
                           initial_temperature=100.0),
                  mt.group("Discretisation", mt.HEAT_DISCRETISATION),
                  AdvectionParams)
    time = TimeDefaults(final_time=1.0e7, dt_initial=2e5, output_interval=5, mesh_size=2.5)
    history_columns = ("cell_peclet",)
    # an advection-dominated, nonsymmetric system: algebraic multigrid (the
    # default) needed up to 2000 Krylov iterations per solve; a direct solve
    # of this 2D case takes one (manual, verification: heat)
    solver_defaults = staticmethod(direct_solver_defaults)

    def boundaries(self):
        return {"inlet": face(0, 0.0), "outlet": face(0, self.p.advection_length)}

    def generate_mesh(self, path, size):
        p = self.p
        return meshing.box(path, [p.advection_length, p.advection_height], size)

    def _velocity(self, x, t):
        return np.asarray(self.p.advection_velocity[:2], dtype=float)

    def build(self, mesh, degree):
        p = self.p
        b = ModelBuilder(p, mesh.dim)
        heat = b.matrix_heat(degree, velocity=self._velocity, reference_temperature=p.T0)
        model = b.build()
        model.facets.append(hb.outflow_term(heat, "outlet"))
        Ti, T0 = p.T_inj, p.T0
        dirichlet = [Dirichlet(FIELD, "inlet", constant_in_time(Ti))]
        scales = {FIELD: FieldScale(scale=abs(T0 - Ti), offset=T0)}
        return Setup(model, dirichlet, scales, {FIELD: constant(T0)}, _PecletMonitor(self))

    def cell_peclet(self, mesh):
        p = self.p
        w = p.fluid_rho_c / p.rho_c * np.linalg.norm(p.advection_velocity)
        kappa = p.conductivity / p.rho_c
        return w * probes.global_min(mesh.dm.comm, mesh.h) / (2 * kappa)
