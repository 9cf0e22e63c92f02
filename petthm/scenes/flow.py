"""Fracture flow scenes with a rigid rock (theory manual, "Equations: fracture flow",
manual, verification).

* ``fracture_flow_patch``: steady cubic-law flow along a fracture cutting
  the domain, pressure fixed at both ends: linear, exact for P1 and P2.
* ``radial_flow``: point injector at the centre of a buried disc fracture,
  pressure fixed on its rim: p = p_R + Q/(2 pi T_h) ln(R/r).
* ``leakoff_1d``: fracture pressure raised by dp at t = 0, 1D diffusion into
  the matrix on both sides: cumulative leakoff 4 dp S L sqrt(c t / pi).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from petthm.discretisation import probes
from petthm.discretisation.assembly import FieldScale
from petthm.discretisation.constraints import Dirichlet
from petthm.discretisation.model import MATRIX, Domain
from petthm.mesh import generate as meshing
from petthm.mesh.fracture import FRACTURE_BC, TIP_BC
from petthm.params import MESH, PHYSICS, param
from petthm.physics import materials as mt
from petthm.physics.builders import ModelBuilder
from petthm.physics.monitors import FractureWells, Worst, hit
from petthm.scenes.base import Monitor, Scene, Setup, TimeDefaults, constant, constant_in_time
from petthm.scenes.fractured import (
    balances_of,
    far_sides,
    rate_pressure_scale,
    rigid_fracture_physics,
    strip_with_fracture,
)
from petthm.solvers.options import direct_solver_defaults


# -- fracture_flow_patch ------------------------------------------------------------------
@dataclass(frozen=True)
class PatchParams:
    """Linear pressure along a fracture cutting the domain (fracture_flow_patch)"""
    patch_dim: int = param(2, "-", "space dimension", choices=(2, 3), kind=MESH)
    patch_length: float = param(100.0, "m", "fracture length (domain length in x)", lo=0.0, lo_open=True,
                                kind=MESH)
    patch_inlet_pressure: float = param(1.2e5, "Pa", "pressure at x = 0", kind=PHYSICS)
    patch_outlet_pressure: float = param(0.0, "Pa", "pressure at x = L", kind=PHYSICS)


class _PatchMonitor(Monitor):
    carried = ("worst",)

    def __init__(self, scene, flow, balances, worst):
        self.scene, self.flow, self.balances, self.worst = scene, flow, balances, worst
        self.last = (None, None)

    def errors(self, problem, t, X=None):
        p = self.scene.p
        dp = abs(p.patch_inlet_pressure - p.patch_outlet_pressure)
        err = probes.max_nodal_error(problem, "pf", self.scene.exact, X, t)
        # outflow at x = L: the consistent reaction of the Dirichlet condition
        width = 1.0 if p.patch_dim == 2 else 0.6 * p.patch_length
        q_exact = self.flow.permeability[0, 0] / self.flow.viscosity.value * dp / p.patch_length * width
        rl = self.balances.last_residual
        if rl is None:
            return err / dp, None
        q_out = -problem.reaction(rl, ("pf",), ("x1",))
        return err / dp, abs(q_out - q_exact) / q_exact

    def __call__(self, problem, t, X=None):
        out = self.balances(problem, t, X)
        pe, fe = self.errors(problem, t, X)
        out.update({"pressure_error": pe, "flux_error": fe if fe is not None else ""})
        self.last = (pe, fe)
        return out

    def report(self, problem, t):
        pe, fe = self.last
        return {"error": {"pf_max_rel": pe, "flux_rel": fe}, "balance_max": self.worst.as_dict()}


class FractureFlowPatch(Scene):
    name = "fracture_flow_patch"
    description = "steady cubic-law flow along a fracture: linear pressure, exact for P1 and P2"
    parameters = (mt.group("Fluid", ("fluid_viscosity", "fluid_compressibility"), fluid_compressibility=0.0),
                  mt.group("Fracture", ("fracture_aperture",)), PatchParams)
    time = TimeDefaults(final_time=1.0, dt_initial=1.0, mesh_size=20.0)
    history_columns = ("pressure_error", "flux_error", "mass_balance")

    def boundaries(self):
        L = self.p.patch_length
        return {"x0": lambda x: np.isclose(x[:, 0], 0.0), "x1": lambda x: np.isclose(x[:, 0], L)}

    def generate_mesh(self, path, size):
        p = self.p
        L = p.patch_length
        if p.patch_dim == 2:
            fr = [meshing.Fracture("segment", p0=(0.0, 0.37 * L), p1=(L, 0.37 * L))]
            return meshing.box_with_fractures(path, [L, L], size, fr)
        fr = [meshing.Fracture("rectangle", center=(0.5 * L, 0.5 * L, 0.43 * L), half=(0.5 * L, 0.3 * L))]
        return meshing.box_with_fractures(path, [L, L, L], size, fr)

    def exact(self, x):
        p = self.p
        return p.patch_inlet_pressure + (
            p.patch_outlet_pressure - p.patch_inlet_pressure) * x[:, 0] / p.patch_length

    def build(self, mesh, degree):
        p = self.p
        b = ModelBuilder(p, mesh.dim)
        rigid_fracture_physics(b, degree, heat=False)
        worst = Worst()
        monitor = _PatchMonitor(self, b.flows[Domain.FRACTURE],
                                balances_of(b, p.fracture_aperture, 0.0, False, worst), worst)
        bcs = [Dirichlet("pf", part, lambda x, t: self.exact(x)) for part in ("x0", "x1")]
        dp = abs(p.patch_inlet_pressure - p.patch_outlet_pressure) or 1.0
        scales = {"pf": FieldScale(dp, p.patch_outlet_pressure)}
        return Setup(b.build(), bcs, scales, {"pf": constant(p.patch_outlet_pressure)}, monitor)

    solver_defaults = staticmethod(direct_solver_defaults)


# -- radial_flow ------------------------------------------------------------------------------
@dataclass(frozen=True)
class RadialParams:
    """Point injector at the centre of a disc fracture, pressure fixed on the rim (radial_flow)"""
    radial_radius: float = param(100.0, "m", "disc radius R", lo=0.0, lo_open=True, kind=MESH)
    radial_well_size: float = param(1.0, "m", "mesh size at the well", lo=0.0, lo_open=True, kind=MESH)
    radial_rim_pressure: float = param(0.0, "Pa", "pressure p_R on the rim", kind=PHYSICS)


class _RadialMonitor(Monitor):
    carried = ("worst",)

    def __init__(self, scene, balances, worst):
        self.scene, self.balances, self.worst = scene, balances, worst

    def error(self, problem, t, X=None):
        """Max |p - p_exact| over fracture nodes at r >= 5 h_well, relative to
        the largest pressure rise p_exact - p_R among them (manual, verification);
        with no rise (Q = 0, a shut-in: p_exact = p_R) relative to the
        pressure scale instead."""
        p, sc = self.scene.p, self.scene
        comm = problem.dm.comm
        v = problem.field_values("pf", X, t)[:, 0]
        x = problem.disc.field_node_coordinates("pf")
        r = np.linalg.norm(x - sc.centre()[None, :], axis=1)
        sel = r >= 5 * p.radial_well_size
        ex = sc.exact(x[sel])
        e = probes.global_max(comm, np.abs(v[sel] - ex), empty=0.0)
        rise = probes.global_max(comm, ex - p.radial_rim_pressure, empty=0.0)
        return e / rise if rise > 0 else e / sc.pressure_scale()

    def __call__(self, problem, t, X=None):
        out = {"injection_pressure": probes.point_value(problem, "pf", tuple(self.scene.centre()), X, t),
               "error_5h": self.error(problem, t, X)}
        out.update(self.balances(problem, t, X))
        return out

    def report(self, problem, t):
        return {"error": {"pf_rel_beyond_5h": self.error(problem, t)}, "balance_max": self.worst.as_dict()}


class RadialFlow(Scene):
    name = "radial_flow"
    dimension = 3
    description = "point injector in a disc fracture: p = p_R + Q/(2 pi T_h) ln(R/r) (manual, verification)"
    parameters = (mt.group("Fluid", ("fluid_viscosity", "fluid_compressibility"), fluid_compressibility=0.0),
                  mt.group("Fracture", ("fracture_aperture",), fracture_aperture=2e-4),
                  mt.group("Well", ("injection_rate",), injection_rate=1e-3),
                  RadialParams)
    time = TimeDefaults(final_time=1.0, dt_initial=1.0, mesh_size=25.0)
    history_columns = ("injection_pressure", "error_5h", "mass_balance")

    def generate_mesh(self, path, size):
        p = self.p
        R = p.radial_radius
        c = (1.5 * R, 1.5 * R, 1.5 * R)
        fr = [meshing.Fracture("disc", center=c, radius=R, size=min(size, R / 8))]
        return meshing.box_with_fractures(path, [3 * R] * 3, 2 * size, fr, grading_distance=R,
                                          wells=[c], well_size=p.radial_well_size)

    def centre(self):
        return np.full(3, 1.5 * self.p.radial_radius)

    def exact(self, x):
        p = self.p
        Th = p.fracture_aperture ** 3 / (12 * p.fluid_viscosity.value)
        r = np.linalg.norm(x - self.centre()[None, :], axis=1)
        return p.radial_rim_pressure + p.injection_rate / (2 * np.pi * Th) * np.log(p.radial_radius /
                                                                                    np.maximum(r, 1e-300))

    def pressure_scale(self) -> float:
        """The rise p_exact - p_R at r = R/100 (Pa), or at Q = 0 the fallback
        of ``rate_pressure_scale``."""
        p, rim = self.p, self.p.radial_rim_pressure
        ref = float(self.exact(self.centre()[None, :] + [[p.radial_radius / 100, 0, 0]])[0]) - rim
        return rate_pressure_scale(ref, rim)

    def build(self, mesh, degree):
        p = self.p
        b = ModelBuilder(p, mesh.dim)
        rigid_fracture_physics(b, degree, heat=False)
        wells = FractureWells(tuple(self.centre()), None, heat=False, flow_dim=2)
        b.wells(wells.make(p, mesh, 0.0))
        worst = Worst()
        monitor = _RadialMonitor(self, balances_of(b, p.fracture_aperture, 0.0, False, worst), worst)
        bcs = [Dirichlet("pf", TIP_BC, constant_in_time(p.radial_rim_pressure))]
        scales = {"pf": FieldScale(self.pressure_scale(), p.radial_rim_pressure)}
        return Setup(b.build(), bcs, scales, {"pf": constant(p.radial_rim_pressure)}, monitor)

    solver_defaults = staticmethod(direct_solver_defaults)


# -- leakoff_1d ------------------------------------------------------------------------------------
@dataclass(frozen=True)
class LeakoffParams:
    """Fracture pressure step, 1D diffusion into the matrix on both sides (leakoff_1d)"""
    leakoff_length: float = param(10.0, "m", "fracture length (domain length in x)", lo=0.0, lo_open=True,
                                  kind=MESH)
    leakoff_width: float = param(60.0, "m", "matrix on each side of the fracture", lo=0.0, lo_open=True,
                                 kind=MESH)
    leakoff_pressure_step: float = param(1e6, "Pa", "fracture overpressure dp for t > 0", lo=0.0,
                                         lo_open=True, kind=PHYSICS)
    leakoff_storage: float = param(1e-9, "1/Pa", "matrix storage S", lo=0.0, lo_open=True, kind=PHYSICS)
    leakoff_fracture_size: float = param(0.05, "m", "mesh size at the fracture", lo=0.0, lo_open=True,
                                         kind=MESH)


class _LeakoffMonitor(Monitor):
    """Leakoff rate = inflow through the fracture's pressure condition (the
    consistent reaction); volume = its backward-Euler time integral."""

    carried = ("worst", "cumulative", "samples")

    def __init__(self, scene, balances, worst):
        self.scene, self.balances, self.worst = scene, balances, worst
        self.cumulative = None          # (t, V)
        self.samples = {}

    def stored(self, problem, t, X=None):
        """Leaked volume stored in the matrix: int S (pm - p0)."""
        p = self.scene.p
        xl, _ = problem.local_arrays(X or problem.X, t)
        return problem.region(MATRIX).integrate(
            xl, lambda ctx: p.leakoff_storage * (ctx.value("pm")[..., 0] - p.initial_pressure), t)

    def __call__(self, problem, t, X=None):
        out = self.balances(problem, t, X)
        rl = self.balances.last_residual
        rate = problem.reaction(rl, ("pf", "pm"), boundaries=(FRACTURE_BC,)) if rl is not None else 0.0
        prev_t, prev_V = self.cumulative or (t, 0.0)
        V = prev_V + (t - prev_t) * rate
        self.cumulative = (t, V)
        ex = self.scene.exact_volume(t)
        out.update({"leakoff_rate": rate, "leakoff_volume": V, "leakoff_stored": self.stored(problem, t, X),
                    "leakoff_exact": ex, "leakoff_error": abs(V - ex) / ex if ex > 0 else 0.0})
        th = hit(t, self.scene.hit_times())
        if th is not None:
            self.samples[th] = out["leakoff_error"]
        return out

    def report(self, problem, t):
        return {"error": {f"leakoff_rel_t{th:g}": e for th, e in sorted(self.samples.items())},
                "balance_max": self.worst.as_dict()}


class Leakoff1D(Scene):
    name = "leakoff_1d"
    dimension = 2
    description = "fracture pressure step: cumulative leakoff 4 dp S L sqrt(c t/pi) (both faces)"
    parameters = (mt.group("Fluid", ("fluid_viscosity", "fluid_compressibility")),
                  mt.group("Rock", ("rock_permeability",), rock_permeability=(1e-15,)),
                  mt.group("Fracture", ("fracture_aperture",)),
                  mt.group("Initial state", ("initial_pressure",)),
                  LeakoffParams)
    time = TimeDefaults(final_time=1e5, dt_initial=1.0, dt_growth=1.05, dt_max=2e3, mesh_size=5.0)
    history_columns = ("leakoff_rate", "leakoff_volume", "leakoff_stored", "leakoff_exact", "leakoff_error",
                       "mass_balance")

    def boundaries(self):
        return {"far": far_sides(self.p.leakoff_width)}

    def generate_mesh(self, path, size):
        p = self.p
        return strip_with_fracture(path, p.leakoff_length, p.leakoff_width, size, p.leakoff_fracture_size)

    def diffusivity(self):
        p = self.p
        return p.isotropic_permeability() / (p.fluid_viscosity.value * p.leakoff_storage)

    def exact_volume(self, t):
        """Both faces: 2 x L x 2 dp S sqrt(c t / pi)."""
        p = self.p
        return 4 * p.leakoff_pressure_step * p.leakoff_storage * p.leakoff_length * \
            math.sqrt(self.diffusivity() * t / math.pi)

    def hit_times(self):
        return [1e3, 1e4, 1e5]

    def build(self, mesh, degree):
        p = self.p
        b = ModelBuilder(p, mesh.dim)
        k = p.isotropic_permeability()
        rigid_fracture_physics(b, degree, heat=False, permeability=k * np.eye(mesh.dim),
                               matrix_storage=p.leakoff_storage)
        worst = Worst()
        monitor = _LeakoffMonitor(self, balances_of(b, p.fracture_aperture, p.initial_pressure, False, worst),
                                  worst)
        p0, p1 = p.initial_pressure, p.initial_pressure + p.leakoff_pressure_step
        bcs = [Dirichlet("pf", FRACTURE_BC, constant_in_time(p1)),
               Dirichlet("pm", "far", constant_in_time(p0))]
        sc = FieldScale(p.leakoff_pressure_step, p0)
        scales = {"pf": sc, "pm": FieldScale(sc.scale, sc.offset)}
        return Setup(b.build(), bcs, scales, {"pf": constant(p1), "pm": constant(p0)}, monitor)

    solver_defaults = staticmethod(direct_solver_defaults)
