"""Fracture heat transport with leakoff into a permeable matrix (the theory manual
sections 4-7 and 11; manual, verification).

* ``rigid_fracture``: Scene 1 of the paper: cold water through a rigid
  fracture with leakoff into a permeable matrix (1D or isotropic leakoff).
* ``leakoff_heat``: a uniform leakoff fraction m, outlet temperature against
  the Laplace-domain solution of manual, verification.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass

import numpy as np

from petthm.discretisation import probes
from petthm.discretisation.assembly import FieldScale
from petthm.discretisation.constraints import Dirichlet
from petthm.errors import InputError
from petthm.io.output import on_root
from petthm.mesh import generate as meshing
from petthm.params import CELSIUS, MESH, PHYSICS, param
from petthm.physics import materials as mt
from petthm.physics.builders import ModelBuilder
from petthm.physics.kernels import wells as wl
from petthm.physics.monitors import Balances, FractureWells, Worst, hit
from petthm.scenes.base import Monitor, Scene, Setup, TimeDefaults, constant, constant_in_time
from petthm.scenes.fractured import (
    SCENE1_WELLS,
    FirstLayer,
    WellsMonitor,
    balances_of,
    far_sides,
    first_layer,
    first_layer_param,
    heat_wells_monitor,
    rate_pressure_scale,
    rigid_fracture_physics,
    strip_with_fracture,
    transmissivity,
)
from petthm.scenes.lauwerier import SCENE1_ROCK
from petthm.solvers.options import direct_solver_defaults

FRACTURE_HEAT = mt.group("Fracture", ("fracture_aperture",) + mt.FRACTURE_HEAT)


# -- rigid_fracture (Scene 1) ---------------------------------------------------------------------------
@dataclass(frozen=True)
class Scene1Params:
    """Scene 1 of the paper: rigid fracture in a permeable matrix (rigid_fracture)"""
    scene1_length: float = param(100.0, "m", "fracture length (injector at x = 0, producer at x = L)",
                                 lo=0.0, lo_open=True, kind=MESH)
    scene1_margin: float = param(150.0, "m", "rock beyond the fracture in every direction", lo=0.0,
                                 lo_open=True, kind=MESH)
    scene1_fracture_size: float = param(1.0, "m", "mesh size at the fracture", lo=0.0, lo_open=True,
                                        kind=MESH)
    scene1_layer: FirstLayer = first_layer_param("thm_scene1_layer", 0.0, "a graded unstructured mesh",
                                                 "the first output time (the profile at 1e8 s)")
    scene1_layer_growth: float = param(1.3, "-", "thickness ratio of successive layers", lo=1.0, hi=3.0,
                                       kind=MESH)


class _Scene1Monitor(Monitor):
    """Wells, leakoff fraction, Tf's range, balances; the Tf profile at 1e8 s."""

    carried = ("base.worst", "profile")
    files = ("profile_1e8.json",)

    def __init__(self, scene, base: WellsMonitor):
        self.scene, self.base = scene, base
        self.profile, self.last = None, {}

    def __call__(self, problem, t, X=None):
        p = self.scene.p
        out = self.base(problem, t, X)
        out["leakoff_fraction"] = 1.0 - out["production_rate"] / p.injection_rate if p.injection_rate else 0.0
        if hit(t, (1e8,)) is not None:
            comm = problem.dm.comm
            x = probes.gather_root(comm, problem.disc.field_node_coordinates("Tf")[:, 0])
            v = probes.gather_root(comm, problem.field_values("Tf", X, t)[:, 0] - CELSIUS)
            if x is not None:
                order = np.argsort(x)
                self.profile = {"x": x[order].tolist(), "Tf": v[order].tolist()}
        self.last = out
        return out

    def report(self, problem, t):
        out = {"balance_max": self.base.worst.as_dict(),
               "production_temperature_final": self.last.get("production_temperature"),
               "permeability": list(self.scene.p.rock_permeability)}
        if self.profile is not None:
            path = os.path.join(self.scene.output_dir, "profile_1e8.json")

            def write():
                with open(path, "w") as f:
                    json.dump(self.profile, f)
            on_root(problem.dm.comm, write, path)
            out["profile_file"] = os.path.basename(path)
        return out


class RigidFracture(Scene):
    name = "rigid_fracture"
    dimension = 2
    description = "Scene 1: cold water through a rigid fracture with leakoff into a permeable matrix (2D)"
    parameters = (mt.group("Fluid", mt.FLUID_FLOW + mt.FLUID_HEAT, fluid_viscosity="water"),
                  mt.group("Rock", mt.ROCK_HEAT + ("rock_porosity", "rock_permeability"), rock_porosity=0.1,
                           rock_permeability=(0.0, 1e-14), **SCENE1_ROCK),
                  FRACTURE_HEAT,
                  SCENE1_WELLS, Scene1Params)
    time = TimeDefaults(final_time=1e9, dt_initial=100.0, dt_growth=1.05, dt_max=5e6, mesh_size=25.0,
                        output_interval=25)
    history_columns = ("injection_pressure", "production_temperature", "production_rate", "leakoff_fraction",
                       "mass_balance", "energy_balance")

    def permeability(self, dim):
        """The matrix permeability tensor ('0,k': 1D leakoff normal to the
        fracture), or None for an impermeable matrix (no pm)."""
        K = self.p.permeability(dim)
        return None if not K.any() else K

    def boundaries(self):
        p = self.p
        L, M = p.scene1_length, p.scene1_margin
        return {"far": lambda x: np.isclose(x[:, 0], -M) | np.isclose(x[:, 0], L + M) |
                np.isclose(x[:, 1], -M) | np.isclose(x[:, 1], M)}

    def generate_mesh(self, path, size):
        p = self.p
        L, M = p.scene1_length, p.scene1_margin
        if p.scene1_layer.layered:
            layer = first_layer(self, p.scene1_layer)
            return meshing.layered_box_with_segment(path, (-M, L + M), M, (0.0, L), size,
                                                    p.scene1_fracture_size, layer,
                                                    p.scene1_layer_growth, 0.5 * M)
        fr = [meshing.Fracture("segment", p0=(0.0, 0.0), p1=(L, 0.0), size=p.scene1_fracture_size)]
        return meshing.box_with_fractures(path, [L + 2 * M, 2 * M], size, fr, grading_distance=0.5 * M,
                                          origin=(-M, -M), wells=self.wells_at())

    def wells_at(self):
        return (0.0, 0.0), (self.p.scene1_length, 0.0)

    def hit_times(self):
        return [1e8]

    def build(self, mesh, degree):
        p = self.p
        K = self.permeability(mesh.dim)
        b = ModelBuilder(p, mesh.dim)
        rigid_fracture_physics(b, degree, heat=True, permeability=K,
                               matrix_storage=p.rock_porosity * p.fluid_compressibility,
                               matrix_thermal_storage=p.rock_porosity * p.fluid_thermal_expansion)
        wells = FractureWells(*self.wells_at(), heat=True)
        b.wells(wells.make(p, mesh, transmissivity(p, p.fracture_aperture, p.T0)))
        base = heat_wells_monitor(b, wells)
        T0, Ti, p0 = p.T0, p.T_inj, p.initial_pressure
        bcs = [Dirichlet("Tm", "far", constant_in_time(T0))]
        if K is not None:
            bcs.append(Dirichlet("pm", "far", constant_in_time(p0)))
        Th = p.fracture_aperture ** 3 / 12 / p.fluid_viscosity.mu(Ti)
        dp = rate_pressure_scale(float(p.injection_rate * p.scene1_length / Th), p0, p.production_pressure)
        sp, sT = FieldScale(dp, p.production_pressure), FieldScale(abs(T0 - Ti) or 1.0, T0)
        scales = {"pf": sp, "Tf": sT, "Tm": FieldScale(sT.scale, sT.offset)}
        init = {"pf": constant(p0), "Tf": constant(T0), "Tm": constant(T0)}
        if K is not None:
            scales["pm"] = FieldScale(sp.scale, sp.offset)
            init["pm"] = constant(p0)
        return Setup(b.build(), bcs, scales, init, _Scene1Monitor(self, base))

    solver_defaults = staticmethod(direct_solver_defaults)


# -- leakoff_heat (manual, verification) -------------------------------------------------------
@dataclass(frozen=True)
class LeakoffHeatParams:
    """Fracture heat transport with a uniform leakoff fraction m (leakoff_heat; manual, verification)"""
    leakoff_fraction: float = param(0.25, "-", "fraction m of the injected rate lost over the fracture",
                                    lo=0.0, hi=1.0, lo_open=True, kind=PHYSICS)
    leakoff_heat_length: float = param(100.0, "m", "fracture length L", lo=0.0, lo_open=True, kind=MESH)
    leakoff_heat_width: float = param(60.0, "m", "matrix on each side (pressure p_W there)", lo=0.0,
                                      lo_open=True, kind=MESH)
    leakoff_heat_fracture_size: float = param(0.5, "m", "mesh size at the fracture", lo=0.0, lo_open=True,
                                              kind=MESH)


class _LeakoffHeatMonitor(Monitor):
    carried = ("worst", "errors")

    def __init__(self, scene, wells, balances: Balances, worst: Worst):
        self.scene, self.wells, self.balances, self.worst = scene, wells, balances, worst
        self.errors = {}

    def __call__(self, problem, t, X=None):
        p, sc = self.scene.p, self.scene
        inj, prod = sc.wells_at()
        out = {"injection_pressure": probes.point_value(problem, "pf", inj, X, t),
               "production_temperature": probes.point_value(problem, "Tf", prod, X, t) - CELSIUS,
               "production_rate": self.wells[1].residual({"pf": 0.0, "Tf": 0.0}, t)["pf"]}
        out.update(self.balances(problem, t, X))
        rl = self.balances.last_residual
        out["leakoff_rate"] = -problem.reaction(rl, ("pm",), ("far",)) if rl is not None else 0.0
        ex = sc.exact_outlet(t)
        out["outlet_error"] = abs(out["production_temperature"] - ex) / abs(p.initial_temperature -
                                                                           p.injection_temperature)
        th = hit(t, sc.hit_times())
        if th is not None:
            self.errors[th] = out["outlet_error"]
        return out

    def report(self, problem, t):
        err = {f"outlet_rel_t{th:g}": e for th, e in sorted(self.errors.items())}
        err["outlet_max_rel"] = max(self.errors.values()) if self.errors else None
        return {"error": err, "balance_max": self.worst.as_dict()}


class LeakoffHeat(Scene):
    name = "leakoff_heat"
    dimension = 2
    description = ("uniform leakoff fraction m: outlet temperature vs the Laplace-domain solution "
                   "(manual, verification)")
    parameters = (mt.group("Fluid", mt.FLUID_FLOW + mt.FLUID_HEAT, fluid_compressibility=0.0,
                           fluid_thermal_expansion=0.0),
                  mt.group("Rock", mt.ROCK_HEAT + ("rock_porosity", "rock_permeability"), **SCENE1_ROCK),
                  mt.group("Fracture", ("fracture_aperture",) + mt.FRACTURE_HEAT,
                           fracture_aperture=3e-3),
                  mt.group("Wells and initial state", ("injection_rate", "injection_temperature",
                                                       "initial_temperature", "initial_pressure"),
                           initial_temperature=100.0, initial_pressure=1e6),
                  LeakoffHeatParams)
    time = TimeDefaults(final_time=1e8, dt_initial=100.0, dt_growth=1.03, dt_max=5e5, mesh_size=10.0,
                        output_interval=25)
    history_columns = ("injection_pressure", "production_temperature", "production_rate", "leakoff_rate",
                       "outlet_error", "mass_balance", "energy_balance")

    def boundaries(self):
        return {"far": far_sides(self.p.leakoff_heat_width)}

    def generate_mesh(self, path, size):
        p = self.p
        return strip_with_fracture(path, p.leakoff_heat_length, p.leakoff_heat_width, size,
                                   p.leakoff_heat_fracture_size)

    def wells_at(self):
        p = self.p
        return (0.0, p.leakoff_heat_width), (p.leakoff_heat_length, p.leakoff_heat_width)

    def overpressure(self):
        """p_f - p_W giving the leakoff velocity v_L = m q0 / (2L) = k dp / (mu W)."""
        p = self.p
        vL = p.leakoff_fraction * p.injection_rate / (2 * p.leakoff_heat_length)
        return vL * p.fluid_viscosity.value * p.leakoff_heat_width / p.isotropic_permeability()

    def exact_outlet(self, t):
        from petthm.verification.analytic import leakoff_outlet_temperature
        p = self.p
        return leakoff_outlet_temperature(
            p.leakoff_heat_length, t, q0=p.injection_rate, m=p.leakoff_fraction, L=p.leakoff_heat_length,
            fluid_rho_c=p.fluid_rho_c, rock_rho_c=p.rho_c, rock_conductivity=p.conductivity,
            T0=p.initial_temperature, Tinj=p.injection_temperature, advection=True)

    def hit_times(self):
        return [1e6, 1e7, 1e8]

    def build(self, mesh, degree):
        p = self.p
        if p.rock_porosity != 0:
            raise InputError(
                "option -thm_rock_porosity: leakoff_heat needs 0 (the reference has C_m = rho_s C_s)")
        b = ModelBuilder(p, mesh.dim)
        rigid_fracture_physics(b, degree, heat=True,
                               permeability=p.isotropic_permeability() * np.eye(mesh.dim))
        inj, prod = self.wells_at()
        wells = [wl.injector(inj, p.injection_rate, p.fluid_rho_c, p.T_inj),
                 wl.rate_producer(prod, (1 - p.leakoff_fraction) * p.injection_rate, p.fluid_rho_c)]
        b.wells(wells)
        worst = Worst()
        monitor = _LeakoffHeatMonitor(self, wells,
                                      balances_of(b, p.fracture_aperture, p.initial_pressure, True,
                                                               worst), worst)
        T0, Ti = p.T0, p.T_inj
        pW, dp = p.initial_pressure, self.overpressure()
        W = p.leakoff_heat_width
        bcs = [Dirichlet("Tm", "far", constant_in_time(T0)), Dirichlet("pm", "far", constant_in_time(pW))]
        sp, sT = FieldScale(rate_pressure_scale(dp, pW), pW), FieldScale(abs(T0 - Ti), T0)
        scales = {"pf": sp, "pm": FieldScale(sp.scale, sp.offset), "Tf": sT,
                  "Tm": FieldScale(sT.scale, sT.offset)}
        steady = lambda x: pW + dp * (1 - np.abs(x[:, 1] - W) / W)  # noqa: E731
        init = {"pf": steady, "pm": steady, "Tf": constant(T0), "Tm": constant(T0)}
        return Setup(b.build(), bcs, scales, init, monitor)

    solver_defaults = staticmethod(direct_solver_defaults)
