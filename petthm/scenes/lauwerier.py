"""``lauwerier``: cold water through a fracture in impermeable hot rock,
compared with Lauwerier's solution (theory manual, "Equations: fracture flow";
manual, verification): 2D (plane strain, H = 1 m, point wells) or a 3D
slab of height H with line wells.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from petthm.discretisation import probes
from petthm.discretisation.assembly import FieldScale
from petthm.discretisation.constraints import Dirichlet
from petthm.errors import InputError
from petthm.mesh import generate as meshing
from petthm.params import CELSIUS, MESH, PHYSICS, param
from petthm.physics import materials as mt
from petthm.physics.builders import ModelBuilder
from petthm.physics.kernels import wells as wl
from petthm.physics.monitors import FractureWells, hit
from petthm.scenes.base import Monitor, Scene, Setup, TimeDefaults, constant, constant_in_time
from petthm.scenes.fractured import (
    SCENE1_WELLS,
    FirstLayer,
    WellsMonitor,
    far_sides,
    first_layer,
    first_layer_param,
    heat_wells_monitor,
    rate_pressure_scale,
    rigid_fracture_physics,
    strip_with_fracture,
    transmissivity,
)
from petthm.solvers.options import direct_solver_defaults
from petthm.verification.analytic import lauwerier_temperature


@dataclass(frozen=True)
class LauwerierParams:
    """Fracture in impermeable hot rock (lauwerier; manual, verification)"""
    lauwerier_length: float = param(100.0, "m", "fracture length L (injector at x = 0, producer at x = L)",
                                    lo=0.0, lo_open=True, kind=MESH)
    lauwerier_width: float = param(0.0, "m", "rock on each side of the fracture (0: the larger of 60 m "
                                   "and 4 sqrt(kappa t_final); a width below 4 sqrt(kappa t_final), where "
                                   "the rock's far side would feel the cooling, is refused)", lo=0.0,
                                   kind=MESH)
    lauwerier_fracture_size: float = param(0.5, "m", "mesh size at the fracture", lo=0.0, lo_open=True,
                                           kind=MESH)
    lauwerier_layer: FirstLayer = first_layer_param("thm_lauwerier_layer", 0.0, "a graded unstructured mesh",
                                                    "the start of the outlet error's range (1e4 s)")
    lauwerier_layer_growth: float = param(1.3, "-", "thickness ratio of successive layers", lo=1.0, hi=3.0,
                                          kind=MESH)
    lauwerier_dim: int = param(2, "-", "2: plane strain (H = 1 m); 3: a slab of height H with line wells",
                               choices=(2, 3), kind=MESH)
    lauwerier_height: float = param(1.0, "m", "slab height H (3D; Q is the slab's total rate)",
                                    lo=0.0, lo_open=True, kind=MESH)
    lauwerier_rock_conduction: str = param("full", "-", "full, or normal: conduction in the rock only "
                                           "normal to the fracture (the analytical solution's assumption)",
                                           choices=("full", "normal"), kind=PHYSICS)


#: the rock of Scene 1 (manual, "The paper's scenes")
SCENE1_ROCK = dict(rock_density=2820.0, rock_heat_capacity=1170.0, rock_conductivity=2.88)


class SlabWells:
    """Line injector at x = 0 and line producer at x = L of the 3D slab: one
    point term per fracture node on each line, weighted with the consistent
    nodal weights of a uniform line density."""

    def __init__(self, scene):
        self.scene = scene
        self.terms, self.lines = [], None

    def line_nodes(self, mesh, degree, x_line):
        """The fracture nodes on the well line x = x_line, sorted by y, with
        the consistent nodal weights of a uniform line density (sum = H)."""
        surf = mesh.fracture
        pts = [mesh.vertex_coords[surf.cell_vertices.ravel()]]
        if degree == 2:
            pts.append(mesh.edge_midpoints()[surf.cell_edges.ravel() - mesh.estart])
        X = np.concatenate(pts)
        X = X[np.abs(X[:, 0] - x_line) < 1e-9 * self.scene.p.lauwerier_length]
        X = probes.gather_all(mesh.dm.comm, X)
        X = X[np.argsort(X[:, 1])]
        X = X[np.concatenate([[True], np.diff(X[:, 1]) > 1e-12])]
        y = X[:, 1]
        w = np.zeros(len(y))
        step = 2 if degree == 2 else 1
        for k in range(0, len(y) - 1, step):          # elements [y_k, y_k+step]
            h = y[k + step] - y[k]
            if degree == 2:
                w[k] += h / 6
                w[k + 1] += 2 * h / 3
                w[k + 2] += h / 6
            else:
                w[k] += h / 2
                w[k + 1] += h / 2
        return X, w

    def make(self, mesh, degree):
        p = self.scene.p
        PI_line = wl.well_index(transmissivity(p, p.fracture_aperture, p.T0), 0.0, p.well_radius,
                                1)  # per metre
        Xi, wi = self.line_nodes(mesh, degree, 0.0)
        Xp, wp = self.line_nodes(mesh, degree, p.lauwerier_length)
        H = p.lauwerier_height
        self.terms = [wl.injector(tuple(x), p.injection_rate * c / H, p.fluid_rho_c, p.T_inj,
                                  name=f"injector_{i}")
                      for i, (x, c) in enumerate(zip(Xi, wi, strict=False))]
        self.terms += [wl.producer(tuple(x), p.production_pressure, PI_line * c, p.fluid_rho_c,
                                   name=f"producer_{i}")
                       for i, (x, c) in enumerate(zip(Xp, wp, strict=False))]
        self.lines = (Xi, wi, Xp, wp)
        return self.terms

    def __call__(self, problem, t, X=None):
        """Injection pressure: mean over the inlet line; production: rate and the
        flow-weighted temperature of the outlet line."""
        Xi, wi, Xp, wp = self.lines
        pin = [probes.point_value(problem, "pf", x, X, t) for x in Xi]
        qs, Ts = [], []
        for term, x in zip([w for w in self.terms if w.name.startswith("producer")], Xp, strict=False):
            v = {"pf": probes.point_value(problem, "pf", x, X, t),
                 "Tf": probes.point_value(problem, "Tf", x, X, t)}
            qs.append(term.residual(v, t)["pf"])
            Ts.append(v["Tf"])
        qs, Ts = np.array(qs), np.array(Ts)
        # the produced water's mixed temperature; with nothing produced (t = 0, a shut-in) the line's mean
        Tp = np.dot(qs, Ts) / qs.sum() if qs.sum() > 0 else np.dot(wp, Ts) / wp.sum()
        return {"injection_pressure": float(np.dot(pin, wi) / wi.sum()), "production_rate": float(qs.sum()),
                "production_temperature": float(Tp) - CELSIUS}


#: the outlet error is reported as its maximum from each of these times on (s):
#: 1e4 s, from when the outlet temperature has moved (the whole meaningful
#: range, as the peer comparison scores it), and 1e6 s (the earlier metric)
OUTLET_ERROR_FROM = (1e4, 1e6)


class _LauwerierMonitor(Monitor):
    """Outlet error every step (its maximum over t >= 1e4 s and over
    t >= 1e6 s), the profile error at the profile times, Tf's range, balances."""

    carried = ("base.worst", "outlet", "profile", "steps_scored")

    def __init__(self, scene, base: WellsMonitor):
        self.scene, self.base = scene, base
        self.outlet, self.profile = {t0: 0.0 for t0 in OUTLET_ERROR_FROM}, {}
        self.steps_scored = {t0: 0 for t0 in OUTLET_ERROR_FROM}

    def fracture_error(self, problem, t, X=None):
        """Max over fracture nodes of |Tf - T_exact| / (T0 - Tinj)."""
        p = self.scene.p
        v = problem.field_values("Tf", X, t)[:, 0]
        x = problem.disc.field_node_coordinates("Tf")[:, 0]
        dT = abs(p.initial_temperature - p.injection_temperature)
        return probes.global_max(problem.dm.comm, np.abs(v - self.scene.exact(x, t)) / dT, empty=0.0)

    def __call__(self, problem, t, X=None):
        p, sc = self.scene.p, self.scene
        out = self.base(problem, t, X)
        dT = abs(p.initial_temperature - p.injection_temperature)
        prod = sc.wells_at()[1]
        ex = float(sc.exact(np.array([prod[0]]), t)[0]) - CELSIUS
        out["outlet_error"] = abs(out["production_temperature"] - ex) / dT
        for t0 in OUTLET_ERROR_FROM:
            if t >= t0 * (1 - 1e-12):
                self.outlet[t0] = max(self.outlet[t0], out["outlet_error"])
                self.steps_scored[t0] += 1
        e = self.fracture_error(problem, t, X)
        th = hit(t, sc.profile_times)
        if th is not None:
            self.profile[th] = e
        return out

    def report(self, problem, t):
        err = {f"outlet_max_rel_t_ge_{t0:.0e}".replace("e+0", "e"): self.outlet[t0] if self.steps_scored[t0]
               else None for t0 in OUTLET_ERROR_FROM}
        err.update({f"profile_max_rel_t{th:g}": v for th, v in sorted(self.profile.items())})
        return {"error": err, "balance_max": self.base.worst.as_dict(),
                "heat_exchange": str(self.scene.p.fracture_heat_exchange)}


class Lauwerier(Scene):
    name = "lauwerier"
    description = "cold water through a fracture in impermeable rock vs Lauwerier (2D, H = 1 m)"
    parameters = (mt.group("Fluid", mt.FLUID_FLOW + mt.FLUID_HEAT),
                  mt.group("Rock", mt.ROCK_HEAT + ("rock_porosity",), **SCENE1_ROCK),
                  mt.group("Fracture", ("fracture_aperture",) + mt.FRACTURE_HEAT),
                  SCENE1_WELLS, LauwerierParams)
    time = TimeDefaults(final_time=1e8, dt_initial=100.0, dt_growth=1.05, dt_max=1e6, mesh_size=10.0,
                        output_interval=20)
    history_columns = ("injection_pressure", "production_temperature", "production_rate", "outlet_error",
                       "mass_balance", "energy_balance")
    profile_times = (1e7, 1e8)

    def __init__(self, run, p):
        super().__init__(run, p)
        self.width = self.checked_width()

    def checked_width(self) -> float:
        """The rock width each side: wide enough that the far side stays at T0
        until the end (4 sqrt(kappa t): erfc(2) = 0.5 % of the cooling there)."""
        p = self.p
        need = 4.0 * np.sqrt(p.conductivity / p.rho_c * self.final_time)
        if not p.lauwerier_width:
            return max(60.0, float(np.ceil(need)))
        if p.lauwerier_width < need:
            raise InputError(f"option -thm_lauwerier_width = {p.lauwerier_width:g} m: the cooling reaches "
                             f"the far side of the rock by the end time {self.final_time:g} s; it must be >= "
                             f"4 sqrt(kappa t) = {need:.3g} m (or 0 for a width that fits)")
        return p.lauwerier_width

    def boundaries(self):
        p = self.p
        return {"far": far_sides(self.width, p.lauwerier_dim - 1)}   # normal axis: y (2D), z (3D)

    def generate_mesh(self, path, size):
        p = self.p
        L, W, H = p.lauwerier_length, self.width, p.lauwerier_height
        if p.lauwerier_layer.layered:
            layer = first_layer(self, p.lauwerier_layer)
            return meshing.layered_slab_with_fracture(path, (L,) if p.lauwerier_dim == 2 else (L, H), W,
                                                      p.lauwerier_fracture_size, layer,
                                                      p.lauwerier_layer_growth)
        if p.lauwerier_dim == 2:
            return strip_with_fracture(path, L, W, size, p.lauwerier_fracture_size)
        fr = [meshing.Fracture("rectangle", center=(0.5 * L, 0.5 * H, W), half=(0.5 * L, 0.5 * H),
                               size=p.lauwerier_fracture_size)]
        return meshing.box_with_fractures(path, [L, H, 2 * W], size, fr, grading_distance=0.5 * W)

    def wells_at(self):
        p = self.p
        return (0.0, self.width), (p.lauwerier_length, self.width)

    def exact(self, x, t):
        """Lauwerier's T_f(x, t) in kelvin (with the transit delay t_d = a x / q)."""
        p = self.p
        q = p.injection_rate / (p.lauwerier_height if p.lauwerier_dim == 3 else 1.0)
        return lauwerier_temperature(x, t, q, p.fracture_aperture, p.rho_c, p.conductivity, p.fluid_rho_c,
                                     p.T0, p.T_inj)

    def hit_times(self):
        return [1e6, 1e7, 1e8]

    def first_output_time(self):
        """The outlet error is counted from 1e4 s on."""
        return OUTLET_ERROR_FROM[0]

    def build(self, mesh, degree):
        p = self.p
        lam = None
        if p.lauwerier_rock_conduction == "normal":       # only across the fracture
            lam = np.zeros((mesh.dim, mesh.dim))
            lam[mesh.dim - 1, mesh.dim - 1] = p.conductivity
        b = ModelBuilder(p, mesh.dim)
        rigid_fracture_physics(b, degree, heat=True, rock_conductivity=lam)
        if p.lauwerier_dim == 3:
            wells = SlabWells(self)
            b.wells(wells.make(mesh, degree))
        else:
            wells = FractureWells(*self.wells_at(), heat=True)
            b.wells(wells.make(p, mesh, transmissivity(p, p.fracture_aperture, p.T0)))
        base = heat_wells_monitor(b, wells)
        T0, Ti = p.T0, p.T_inj
        bcs = [Dirichlet("Tm", "far", constant_in_time(T0))]
        Th = p.fracture_aperture ** 3 / 12 / p.fluid_viscosity.mu(Ti)
        Th = Th * p.lauwerier_height if p.lauwerier_dim == 3 else Th
        dp = rate_pressure_scale(float(p.injection_rate * p.lauwerier_length / Th), p.initial_pressure,
                                 p.production_pressure)
        sT = FieldScale(abs(T0 - Ti) or 1.0, T0)
        scales = {"pf": FieldScale(dp, p.production_pressure), "Tf": sT,
                  "Tm": FieldScale(sT.scale, sT.offset)}
        init = {"pf": constant(p.initial_pressure), "Tf": constant(T0), "Tm": constant(T0)}
        return Setup(b.build(), bcs, scales, init, _LauwerierMonitor(self, base))

    solver_defaults = staticmethod(direct_solver_defaults)
