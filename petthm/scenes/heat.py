"""Heat-transport verification scenes (physics.md section 6; verification.md 7a, 8).

* ``heat_mms``: manufactured solution T = T_ref + A (1 + t/t_ref) g(x) on the
  unit square/cube with Dirichlet, Neumann and Robin sides and a uniform
  advection velocity; affine in t, so backward Euler adds no time error and
  the reported L2/H1 errors are purely spatial.
* ``heat_erfc``: 1D conduction into a half-space after a step change of the
  surface temperature, T = T0 + (Ts - T0) erfc(z / (2 sqrt(kappa t))), on a
  strip graded toward the surface.
* ``heat_advection``: a cold front advected through a channel at cell Peclet
  number >= 100 with SUPG; reports the over/undershoot.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import erfc

from .. import meshing
from ..assembly import FieldScale
from ..kernels import heat
from ..params import CELSIUS, param
from ..solver import Dirichlet
from .base import HeatMaterial, Scene, TimeDefaults, register, with_defaults

FIELD = "Tm"


def _face(axis, value):
    return lambda x: np.isclose(x[:, axis], value, atol=1e-9)


# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class MMSParams:
    """Manufactured-solution set-up (heat_mms)"""
    mms_dim: int = param(2, "-", "space dimension", choices=(2, 3))
    mms_velocity: tuple = param((1.0, 0.5, 0.25), "m/s", "uniform Darcy velocity vx,vy[,vz]")
    mms_robin_coefficient: float = param(2.0, "W/(m2 K)", "h of the Robin side y=1", lo=0.0, lo_open=True)
    mms_amplitude: float = param(10.0, "K", "amplitude A of the manufactured field", lo=0.0, lo_open=True)


MMSMaterial = with_defaults(HeatMaterial, rock_density=1.0, rock_heat_capacity=1.0,
                            rock_conductivity=1.0, fluid_density=1.0, fluid_heat_capacity=1.0)


@register
class HeatMMS(Scene):
    name = "heat_mms"
    description = "manufactured solution for transient advection-diffusion (2D/3D, P1/P2)"
    parameter_sets = (MMSMaterial, MMSParams)
    time = TimeDefaults(final_time=1.0, dt_initial=0.25, mesh_size=0.125)
    t_ref = 1.0
    T_ref = 300.0

    def boundaries(self):
        d = self[MMSParams].mms_dim
        parts = {"x0": _face(0, 0.0), "x1": _face(0, 1.0), "y0": _face(1, 0.0), "y1": _face(1, 1.0)}
        if d == 3:
            parts.update(z0=_face(2, 0.0), z1=_face(2, 1.0))
        return parts

    def generate_mesh(self, path, size):
        return meshing.box(path, [1.0] * self[MMSParams].mms_dim, size, structured=True)

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
        A = self[MMSParams].mms_amplitude
        return self.T_ref + A * (1 + t / self.t_ref) * self._g(x)

    def exact_grad(self, x, t):
        A = self[MMSParams].mms_amplitude
        return A * (1 + t / self.t_ref) * self._grad_g(x)

    def _velocity(self, x, t):
        d = x.shape[-1]
        return np.asarray(self[MMSParams].mms_velocity[:d], dtype=float)

    def _source(self, x, t):
        m, A = self[MMSMaterial], self[MMSParams].mms_amplitude
        dTdt = A / self.t_ref * self._g(x)
        adv = np.einsum("...a,a->...", self.exact_grad(x, t), self._velocity(x, t))
        lap = A * (1 + t / self.t_ref) * self._lap_g(x)
        return m.rho_c * dTdt + m.fluid_rho_c * adv - m.conductivity * lap

    def build(self, mesh, degree):
        m, mp = self[MMSMaterial], self[MMSParams]
        c = heat.HeatCoefficients(m.rho_c, m.conductivity, m.fluid_rho_c, self._velocity,
                                  self._source, supg=True, degree=degree)
        h = mp.mms_robin_coefficient
        lam = m.conductivity

        def inflow(x, t):    # q_N = lambda grad T . n on x = 1 (n = +x)
            return lam * self.exact_grad(x, t)[..., 0]

        def t_ext(x, t):     # -lambda grad T . n = h (T - T_ext) on y = 1 (n = +y)
            return self.exact(x, t) + lam * self.exact_grad(x, t)[..., 1] / h

        facets = [heat.neumann(FIELD, "x1", inflow), heat.robin(FIELD, "y1", h, t_ext)]
        model = heat.heat_model(c, FIELD, facets)
        dir_parts = ["x0", "y0"] + (["z0", "z1"] if mp.mms_dim == 3 else [])
        rate = lambda x, t: mp.mms_amplitude / self.t_ref * self._g(x)  # noqa: E731
        dirichlet = [Dirichlet(FIELD, b, self.exact, rate) for b in dir_parts]
        scales = {FIELD: FieldScale(scale=mp.mms_amplitude, offset=self.T_ref)}
        return model, dirichlet, scales, {FIELD: lambda x: self.exact(x, 0.0)}

    def report(self, problem, t):
        e = problem.asm.error_norms(problem.local_arrays(problem.X, t)[0], FIELD,
                                    self.exact, self.exact_grad, t)
        hmax = problem.disc.mesh.dm.comm.tompi4py().allreduce(
            float(problem.disc.mesh.h.max()) if problem.disc.mesh.ncells else 0.0, op=_max())
        return {"error": {"Tm_l2_rel": e["l2_rel"], "Tm_h1_rel": e["h1_rel"],
                          "Tm_l2": e["l2"], "Tm_h1": e["h1"]}, "h_max": hmax}


def _max():
    from mpi4py import MPI
    return MPI.MAX


# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class ErfcParams:
    """Half-space conduction after a surface temperature step (heat_erfc)"""
    initial_temperature: float = param(80.0, "degC", "initial rock temperature T0")
    surface_temperature: float = param(20.0, "degC", "surface temperature Ts for t > 0")
    erfc_depth: float = param(10.0, "m", "depth of the strip (insulated at the far end)", lo=0.0, lo_open=True)
    erfc_width: float = param(0.5, "m", "width of the strip", lo=0.0, lo_open=True)
    erfc_surface_size: float = param(0.02, "m", "mesh size at the surface", lo=0.0, lo_open=True)


@register
class HeatErfc(Scene):
    name = "heat_erfc"
    description = "1D transient conduction into a half-space (verification.md 7a), graded mesh"
    parameter_sets = (HeatMaterial, ErfcParams)
    time = TimeDefaults(final_time=1e6, dt_initial=10.0, dt_growth=1.01, dt_max=1e4,
                        output_interval=50, mesh_size=0.25)
    history_columns = ("T_z0.5", "T_z1", "T_z2", "error_max")

    def boundaries(self):
        return {"surface": _face(0, 0.0)}

    def generate_mesh(self, path, size):
        p = self[ErfcParams]
        return meshing.box(path, [p.erfc_depth, p.erfc_width], size,
                           grading=meshing.Grading(axis=0, size_min=p.erfc_surface_size,
                                                   distance=0.5 * p.erfc_depth))

    def exact(self, x, t):
        p, m = self[ErfcParams], self[HeatMaterial]
        kappa = m.conductivity / m.rho_c
        T0, Ts = p.initial_temperature + CELSIUS, p.surface_temperature + CELSIUS
        z = x[..., 0]
        if t <= 0:
            return np.full(z.shape, T0)
        return T0 + (Ts - T0) * erfc(z / (2 * np.sqrt(kappa * t)))

    def build(self, mesh, degree):
        p, m = self[ErfcParams], self[HeatMaterial]
        c = heat.HeatCoefficients(m.rho_c, m.conductivity, degree=degree)
        Ts = p.surface_temperature + CELSIUS
        T0 = p.initial_temperature + CELSIUS
        model = heat.heat_model(c, FIELD)
        dirichlet = [Dirichlet(FIELD, "surface", lambda x, t: np.full(len(x), Ts))]
        scales = {FIELD: FieldScale(scale=abs(T0 - Ts) or 1.0, offset=T0)}
        return model, dirichlet, scales, {FIELD: lambda x: np.full(len(x), T0)}

    def _nodal_error(self, problem, t):
        p = self[ErfcParams]
        err = problem.max_nodal_error(FIELD, lambda x: self.exact(x, t), t=t)
        return err / abs(p.initial_temperature - p.surface_temperature)

    def monitors(self, problem, t, X=None):
        T = problem.field_values(FIELD, t=t)[:, 0]
        x = problem.disc.field_node_coordinates(FIELD)
        out = {}
        comm = problem.disc.mesh.dm.comm.tompi4py()
        for z in (0.5, 1.0, 2.0):
            d = np.abs(x[:, 0] - z) + np.abs(x[:, 1])
            k = int(np.argmin(d)) if len(d) else 0
            best = comm.allreduce((float(d[k]) if len(d) else np.inf, float(T[k] - CELSIUS) if len(d) else 0.0),
                                  op=_minloc())
            out[f"T_z{z:g}"] = best[1]
        out["error_max"] = self._nodal_error(problem, t)
        return out

    def report(self, problem, t):
        return {"error": {"Tm_max_rel": self._nodal_error(problem, t)}}


def _minloc():
    from mpi4py import MPI
    return MPI.MIN


# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class AdvectionParams:
    """Advection-dominated front in a channel (heat_advection)"""
    initial_temperature: float = param(100.0, "degC", "initial temperature T0")
    injection_temperature: float = param(20.0, "degC", "inflow temperature Tinj")
    advection_velocity: tuple = param((1e-5, 0.0), "m/s", "uniform Darcy velocity vx,vy (inflow only through x = 0)")
    advection_length: float = param(100.0, "m", "channel length", lo=0.0, lo_open=True)
    advection_height: float = param(20.0, "m", "channel height", lo=0.0, lo_open=True)
    supg: bool = param(True, "-", "SUPG stabilisation")


AdvMaterial = with_defaults(HeatMaterial, rock_conductivity=0.1, fluid_conductivity=0.0)


@register
class HeatAdvection(Scene):
    name = "heat_advection"
    description = "cold front advected at cell Peclet >= 100 (SUPG boundedness check)"
    parameter_sets = (AdvMaterial, AdvectionParams)
    time = TimeDefaults(final_time=1.0e7, dt_initial=2e5, output_interval=5, mesh_size=2.5)
    history_columns = ("T_min", "T_max", "overshoot", "cell_peclet")

    def boundaries(self):
        return {"inlet": _face(0, 0.0)}

    def generate_mesh(self, path, size):
        p = self[AdvectionParams]
        return meshing.box(path, [p.advection_length, p.advection_height], size)

    def _velocity(self, x, t):
        return np.asarray(self[AdvectionParams].advection_velocity[:2], dtype=float)

    def build(self, mesh, degree):
        p, m = self[AdvectionParams], self[AdvMaterial]
        c = heat.HeatCoefficients(m.rho_c, m.conductivity, m.fluid_rho_c, self._velocity,
                                  supg=p.supg, degree=degree)
        Ti, T0 = p.injection_temperature + CELSIUS, p.initial_temperature + CELSIUS
        model = heat.heat_model(c, FIELD)
        dirichlet = [Dirichlet(FIELD, "inlet", lambda x, t: np.full(len(x), Ti))]
        scales = {FIELD: FieldScale(scale=abs(T0 - Ti), offset=T0)}
        self._extremes = [np.inf, -np.inf]
        return model, dirichlet, scales, {FIELD: lambda x: np.full(len(x), T0)}

    def cell_peclet(self, mesh):
        p, m = self[AdvectionParams], self[AdvMaterial]
        w = m.fluid_rho_c / m.rho_c * np.linalg.norm(p.advection_velocity)
        kappa = m.conductivity / m.rho_c
        hmin = mesh.dm.comm.tompi4py().allreduce(float(mesh.h.min()) if mesh.ncells else np.inf, op=_minloc())
        return w * hmin / (2 * kappa)

    def monitors(self, problem, t, X=None):
        p = self[AdvectionParams]
        T = problem.field_values(FIELD, t=t)[:, 0] - CELSIUS
        comm = problem.disc.mesh.dm.comm.tompi4py()
        tmin = comm.allreduce(float(T.min()) if len(T) else np.inf, op=_minloc())
        tmax = comm.allreduce(float(T.max()) if len(T) else -np.inf, op=_max())
        self._extremes = [min(self._extremes[0], tmin), max(self._extremes[1], tmax)]
        lo, hi = sorted((p.injection_temperature, p.initial_temperature))
        over = max(tmax - hi, lo - tmin, 0.0) / (hi - lo)
        return {"T_min": tmin, "T_max": tmax, "overshoot": over,
                "cell_peclet": self.cell_peclet(problem.disc.mesh)}

    def report(self, problem, t):
        p = self[AdvectionParams]
        lo, hi = sorted((p.injection_temperature, p.initial_temperature))
        tmin, tmax = self._extremes
        return {"overshoot_rel": max(tmax - hi, lo - tmin, 0.0) / (hi - lo),
                "T_min_all_steps": tmin, "T_max_all_steps": tmax,
                "cell_peclet_min": self.cell_peclet(problem.disc.mesh)}
