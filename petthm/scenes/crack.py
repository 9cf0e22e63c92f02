"""Crack scenes of the fracture mechanics (theory manual, "Equations: rock deformation",
manual, verification): a buried crack in elastic rock, half model in
plane strain, its faces loaded by the fluid pressure and the contact
traction ``lam`` (the shared pieces are in ``contact.py``).

* ``partial_opening``: a buried crack under compression whose central part
  is pressurised above the closure stress: an open centre and a closed rim.
* ``fracture_inflation``: water injected at the centre of a closed crack.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from petthm.discretisation import probes
from petthm.discretisation.assembly import FieldScale
from petthm.discretisation.constraints import Dirichlet
from petthm.discretisation.model import FRACTURE
from petthm.errors import InputError
from petthm.params import MESH, PHYSICS, param, with_defaults
from petthm.physics import materials as mt
from petthm.physics.builders import ModelBuilder
from petthm.physics.kernels import contact as ct
from petthm.physics.monitors import fracture_vertices
from petthm.scenes.base import Monitor, Scene, Setup, TimeDefaults, constant, tip_tractions, zero
from petthm.scenes.contact import (
    OPEN_TRACTION,
    contact_solver_defaults,
    crack_half_model,
    fracture_normal,
    mechanics_model,
)
from petthm.solvers.recipes import SSLS_CRACK_GAMG, glued


# -- partial_opening ---------------------------------------------------------------------
@dataclass(frozen=True)
class PartialOpeningParams:
    """Crack under compression with a pressurised centre (partial_opening)"""
    partial_half_length: float = param(50.0, "m", "crack half-length c (2D half model)", lo=0.0, lo_open=True,
                                       kind=MESH)
    partial_peak_pressure: float = param(12e6, "Pa", "pressure reached at the end in |x| < b (> sigma_n)",
                                         kind=PHYSICS)
    partial_radius: float = param(0.5, "-", "b / c: half-width of the pressurised centre", lo=0.0, hi=1.0,
                                  lo_open=True, kind=PHYSICS)
    partial_box: float = param(20.0, "-", "domain half-size / c", lo=2.0, kind=MESH)
    partial_crack_size: float = param(0.025, "-", "mesh size on the crack / c", lo=1e-4, hi=1.0, kind=MESH)


#: in-situ normal stress sigma_n and initial fluid pressure p0 (< sigma_n, kept outside |x| < b)
PARTIAL_LOADS = mt.group("In-situ stress and initial pressure", ("insitu_stress", "initial_pressure"),
                         insitu_stress="10e6", initial_pressure=5e6)


class _ProfileMonitor(Monitor):
    """The opening and lam along the crack: the end of the open zone, the
    centre opening, the open vertices."""

    def __init__(self, scene):
        self.scene = scene
        self.last, self.profile = {}, None

    def crack_profile(self, problem, X=None, t=0.0):
        """(x, opening, lam) at every crack vertex, sorted by x (all ranks)."""
        comm = problem.dm.comm
        x, g, lam = fracture_vertices(problem, X, t)
        x, g, lam = (probes.gather_all(comm, a) for a in (x[:, 0], g, lam))
        x, k = np.unique(x, return_index=True)
        return x, g[k], lam[k]

    def __call__(self, problem, t, X=None):
        x, g, lam = self.crack_profile(problem, X, t)
        is_open = lam <= OPEN_TRACTION * self.scene.normal_stress()
        # end of the open zone: the first closed vertex beyond the centre
        closed = np.flatnonzero(~is_open & (x > 0))
        x_open = float(x[closed[0]]) if len(closed) else float(x[-1])
        self.last = {"open_length": x_open, "opening_centre": float(g[0]), "lam_max": float(lam.max()),
                     "nodes_open": int(is_open.sum())}
        self.profile = (x, g, lam)
        return self.last

    def report(self, problem, t):
        x, g, lam = self.profile
        return dict(self.last, profile={"x": x.tolist(), "opening": g.tolist(), "lam": lam.tolist()})


class _CrackScene(Scene):
    """The half model of a 2D crack of half-length c under compression."""

    def boundaries(self):
        p = self.p
        L = p.partial_box * p.partial_half_length
        return {"sym_x": lambda x: np.isclose(x[:, 0], 0.0),
                "far": lambda x: np.isclose(x[:, 0], L) | np.isclose(np.abs(x[:, 1]), L)}

    def generate_mesh(self, path, size):
        p = self.p
        c = p.partial_half_length
        L = p.partial_box * c
        edge = [(p.partial_radius * c, 0.0)]          # a vertex where the pressure jumps
        return crack_half_model(path, c, L, p.partial_crack_size * c, size, edge)

    def normal_stress(self) -> float:
        return self.p.normal_stress(fracture_normal(2))

    def crack_bcs(self, model):
        return [Dirichlet("u", "far", lambda x, t: np.zeros((len(x), 2))),
                Dirichlet("u", "sym_x", zero, components=(0,))] + tip_tractions(model, zero, {"sym_x": 0})

    def solver_defaults(self, comm):
        return contact_solver_defaults(comm)

    def block_recipe(self, snes_type):
        """With ``vinewtonssls``, GAMG's graph threshold 0.05 on the finest
        level of the glued elasticity (``recipes.SSLS_CRACK_GAMG``)."""
        return glued(SSLS_CRACK_GAMG) if snes_type == "vinewtonssls" else {}


class PartialOpening(_CrackScene):
    name = "partial_opening"
    dimension = 2
    description = "crack under compression, centre pressurised above closure: open centre, closed rim"
    parameters = (mt.group("Rock", mt.ELASTIC), mt.group("Contact", mt.CONTACT, **mt.FRICTIONLESS),
                  PARTIAL_LOADS, PartialOpeningParams)
    time = TimeDefaults(final_time=1.0, dt_initial=0.1, mesh_size=0.0)
    history_columns = ("open_length", "opening_centre", "lam_max", "nodes_open")

    def pressure(self, x, t):
        p = self.p
        ramp = min(t / self.final_time, 1.0)
        inside = np.abs(x[..., 0]) < p.partial_radius * p.partial_half_length
        return p.initial_pressure + inside * ramp * (p.partial_peak_pressure - p.initial_pressure)

    def build(self, mesh, degree):
        p = self.p
        if mesh.dim != 2:
            raise InputError("partial_opening is a 2D scene (the mesh is 3D)")
        sn = self.normal_stress()
        if not p.initial_pressure < sn < p.partial_peak_pressure:
            raise InputError(
                "options -thm_initial_pressure < -thm_insitu_stress < -thm_partial_peak_pressure "
                             "are required (closed, then partly open)")
        E, nu, c = p.rock_youngs_modulus, p.rock_poisson_ratio, p.partial_half_length
        w_ref = 4 * (1 - nu ** 2) * (p.partial_peak_pressure - sn) / E * c
        model, _ = mechanics_model(p, mesh, degree, self.pressure, sn, w_ref)
        scales = {"u": FieldScale(w_ref), "lam": FieldScale(sn)}
        return Setup(model, self.crack_bcs(model), scales, {"lam": constant(sn - p.initial_pressure)},
                     _ProfileMonitor(self))


# -- fracture_inflation --------------------------------------------------------------------
class _InflationMonitor(_ProfileMonitor):
    """Injection pressure, centre opening, open vertices and the volume
    balance: int a over the crack against the injected volume (relative to
    it; with none, Q = 0, relative to the crack's initial fluid volume)."""

    carried = ("a0",)

    def __init__(self, scene, mech, law):
        super().__init__(scene)
        self.mech, self.law = mech, law
        self.a0 = None

    def fluid_volume(self, problem, X, t):
        """int a over the crack (m2 per metre, half model)."""
        xl, _ = problem.local_arrays(X or problem.X, t)

        def a(ctx):
            lam = ctx.value("lam")[..., 0]
            return self.law.aperture(lam, ct.opening(self.mech, ctx))
        return problem.region(FRACTURE).integrate(xl, a, t)

    def __call__(self, problem, t, X=None):
        out = super().__call__(problem, t, X)
        vol = self.fluid_volume(problem, X, t)
        if self.a0 is None:
            self.a0 = vol
        injected = self.scene.p.injection_rate * t
        ref = injected if injected > 0 else self.a0
        out = {"injection_pressure": probes.point_value(problem, "pf", (0.0, 0.0), X, t),
               "opening_centre": out["opening_centre"], "nodes_open": out["nodes_open"],
               "volume_balance": (vol - self.a0 - injected) / ref if t > 0 else 0.0}
        self.last = dict(self.last, **out)
        return out

    def report(self, problem, t):
        return dict(self.last, error={"volume_balance": self.last.get("volume_balance")})


class FractureInflation(_CrackScene):
    name = "fracture_inflation"
    dimension = 2
    description = "water injected at the centre of a closed crack: aperture from contact and opening, da/dt"
    parameters = (mt.group("Rock", mt.ELASTIC),
                  mt.group("Fracture", mt.JOINT + mt.CONTACT, fracture_aperture=0.6e-3, **mt.FRICTIONLESS),
                  PARTIAL_LOADS,
                  mt.group("Fluid and injection",
                           ("fluid_viscosity", "fluid_compressibility", "injection_rate"),
                           fluid_compressibility=0.0, injection_rate=1e-5),
                  with_defaults(PartialOpeningParams, partial_crack_size=0.05))
    time = TimeDefaults(final_time=2000.0, dt_initial=10.0, dt_growth=1.1, dt_max=100.0, mesh_size=0.0)
    history_columns = ("injection_pressure", "opening_centre", "nodes_open", "volume_balance")

    def build(self, mesh, degree):
        from petthm.physics.kernels import wells
        p = self.p
        if mesh.dim != 2:
            raise InputError("fracture_inflation is a 2D scene (the mesh is 3D)")
        sn = self.normal_stress()
        if not p.initial_pressure < sn:
            raise InputError("option -thm_initial_pressure must be below -thm_insitu_stress (closed)")
        w_ref = 4 * (1 - p.rock_poisson_ratio ** 2) * sn / p.rock_youngs_modulus * p.partial_half_length
        b = ModelBuilder(p, 2)
        b.elasticity(degree)
        mech = b.contact(normal_stress=sn, u_scale=w_ref)
        b.deformable(mech)
        b.fracture_flow(degree, reference_aperture=p.fracture_aperture)
        b.wells([wells.injector((0.0, 0.0), p.injection_rate, 0.0, None, T=None)])
        scales = {"u": FieldScale(w_ref), "lam": FieldScale(sn), "pf": FieldScale(sn, p.initial_pressure)}
        init = {"lam": constant(sn - p.initial_pressure), "pf": constant(p.initial_pressure)}
        model = b.build()
        return Setup(model, self.crack_bcs(model), scales, init,
                     _InflationMonitor(self, mech, b.aperture.law))
