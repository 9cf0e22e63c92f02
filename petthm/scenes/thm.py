"""Coupled THM scenes with a deformable fracture (theory manual, "Equations: rock deformation",
7-11).

* ``penny_impermeable``: Scene 2 of the paper.  A horizontal penny fracture
  (R = 100 m) in impermeable rock; cold water injected 50 m left of the
  centre and produced at constant pressure 50 m right of it.  Fields u, pf,
  Tf, Tm and the contact traction lam (no pm).  The cooled rock contracts,
  the contact traction falls and the aperture a = ac(lam) + max(g, 0) rises.

The model is the half y >= 0 (the wells lie on the symmetry plane y = 0 and
carry half their rate).  Tm = Tf on the fracture walls ("equilibrium", the
default), or the walls exchange heat with hw = Nu lambda_f / (2 a) at the
local aperture ("nusselt": local thermal non-equilibrium, the paper's model;
manual, Scene 2).  The strain heating of section 6 is an option
(-thm_thermomechanical_heating, off by default as section 6 allows); the
rock has no pores.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, replace

import numpy as np

from petthm.discretisation import probes
from petthm.discretisation.assembly import FieldScale
from petthm.discretisation.constraints import Dirichlet
from petthm.discretisation.fields import Domain
from petthm.errors import InputError
from petthm.io.output import on_root
from petthm.mesh import generate as meshing
from petthm.params import CELSIUS, DISCRETISATION, MESH, PHYSICS, param
from petthm.physics import materials as mt
from petthm.physics.builders import ModelBuilder
from petthm.physics.monitors import FractureWells, contact_node_checks, fracture_vertices
from petthm.scenes.base import (
    Monitor,
    Scene,
    Setup,
    TimeDefaults,
    constant,
    constant_in_time,
    tip_tractions,
    zero,
)
from petthm.scenes.contact import (
    OPEN_TRACTION,
    contact_block_recipe,
    contact_solver_defaults,
    fracture_normal,
)
from petthm.scenes.fractured import (
    ClosedUnderStress,
    FirstLayer,
    WellsMonitor,
    first_layer,
    first_layer_param,
    heat_wells_monitor,
    rate_pressure_scale,
    transmissivity,
)
from petthm.scenes.friction import slip_columns
from petthm.solvers.recipes import closed_fracture_recipe


@dataclass(frozen=True)
class Scene2Params:
    """Scene 2 of the paper: deformable penny fracture in impermeable rock (penny_impermeable)"""
    scene2_radius: float = param(100.0, "m", "fracture radius R", lo=0.0, lo_open=True, kind=MESH)
    scene2_well_offset: float = param(50.0, "m", "distance of each well from the centre (< R)", lo=0.0,
                                      lo_open=True, kind=MESH)
    scene2_box: float = param(3.0, "-", "domain half-size / R (the rock beyond the fracture)", lo=1.5,
                              kind=MESH)
    scene2_fracture_size: float = param(10.0, "m", "mesh size on the fracture", lo=0.0, lo_open=True,
                                        kind=MESH)
    scene2_well_size: float = param(5.0, "m", "mesh size at the wells", lo=0.0, lo_open=True, kind=MESH)
    scene2_layer: FirstLayer = first_layer_param("thm_scene2_layer", 0.5, "unstructured tetrahedra",
                                                 "the first output time (1e3 s: 0.0185 m in granite)")
    scene2_layer_growth: float = param(1.5, "-", "thickness ratio of successive layers", lo=1.0, hi=3.0,
                                       kind=MESH)
    scene2_lumped_heat: bool = param(True, "-", "row-sum lumping of the rock heat capacity and the wall "
                                     "exchange (keeps Tf and Tm within [Tinj, T0] on thin layers)",
                                     kind=DISCRETISATION)
    scene2_tip_traction: str = param("insitu", "-", "lam at the fracture front: insitu (its initial value) "
                                     "or zero", choices=("insitu", "zero"), kind=PHYSICS)


#: a Tf more than this fraction of [Tinj, T0] outside it is reported as a warning
TF_BOUNDS_WARNING = 0.05
#: the half model y >= 0 holds half of each well
HALF = 0.5


class _Scene2Monitor(Monitor):
    """Wells, contact and aperture at the injector, the aperture identity
    a = a0 - lam/Kn where closed, Tf's range, balances; the fracture maps."""

    carried = ("base.worst",)
    files = ("fracture_final.npz",)

    def __init__(self, scene, base: WellsMonitor, law):
        self.scene, self.base, self.law = scene, base, law
        self.state, self.last, self._regular = None, {}, None

    def __call__(self, problem, t, X=None):
        sc = self.scene
        comm = problem.dm.comm
        inj = sc.wells_at()[0]
        out = self.base(problem, t, X)
        x, g, lam = fracture_vertices(problem, X, t)
        a = self.law.aperture(lam, g)
        out["lam_injector"], out["aperture_injector"] = probes.nearest(comm, x, inj, (lam, a))
        closed = lam > OPEN_TRACTION * sc.lam0
        # where closed, a = a0 - lam/Kn exactly: the complementarity leaves no positive opening there
        ident = np.abs(a - self.law.closure_aperture(lam)[0])[closed]
        out["aperture_identity"] = probes.global_max(comm, ident, empty=0.0) / sc.initial_aperture()
        out["aperture_max"] = probes.global_max(comm, a, empty=0.0)
        out["lam_min"] = probes.global_min(comm, lam)
        out["nodes_open"] = probes.global_count(comm, ~closed)
        opening, second = contact_node_checks(problem, OPEN_TRACTION * sc.lam0, X, t)
        out["closed_opening"] = probes.global_max(comm, [opening]) / sc.initial_aperture()
        out.update(slip_columns(problem, X, t) if problem.model.friction_law is not None else
                   {"slip_max": np.nan, "slipping_area": np.nan})
        out["lam_roughness"] = np.nan if second is None else \
            probes.global_max(comm, second[self.regular_cells(problem)], empty=0.0) / sc.lam0
        self.base.worst.update("aperture_identity", out["aperture_identity"])
        v = problem.field_values("Tf", X, t)[:, 0] - CELSIUS
        self.state = (x, g, lam, a, v)
        self.last = out
        return out

    def regular_cells(self, problem) -> np.ndarray:
        """The fracture cells away from the singular points of lam: no vertex
        on the front (lam prescribed there) or within two well sizes of a
        well (the log singularity of the pressure)."""
        if self._regular is None:
            surf = problem.disc.regions[Domain.FRACTURE]
            x = surf.mesh.vertex_coords[surf.cell_vertices]                 # (nc, nv, d)
            p = self.scene.p
            far = np.ones(len(x), dtype=bool)
            for w in self.scene.wells_at():
                far &= np.linalg.norm(x - np.asarray(w), axis=2).min(axis=1) > 2 * p.scene2_well_size
            inside = np.linalg.norm(x[..., :2], axis=2).max(axis=1) < p.scene2_radius * (1 - 1e-9)
            self._regular = far & inside
        return self._regular

    def write_fracture_maps(self, problem, path):
        """The last monitored state on the fracture (model half y >= 0), for the
        paper's Fig. 5: ``vertices`` (x, y, opening, lam, aperture) and ``Tf``
        (x, y, Tf in degC) at the fracture nodes, in one .npz (rank 0 writes)."""
        comm = problem.dm.comm
        x, g, lam, a, v = self.state
        xT = problem.disc.field_node_coordinates("Tf")
        rows = probes.gather_root(comm, np.column_stack([x[:, 0], x[:, 1], g, lam, a]) if len(x)
                                  else np.zeros((0, 5)))
        rowsT = probes.gather_root(comm,
                                   np.column_stack([xT[:, 0], xT[:, 1], v]) if len(v) else np.zeros((0, 3)))
        on_root(comm, lambda: np.savez(path, vertices=rows, Tf=rowsT), path)

    def report(self, problem, t):
        out = {"balance_max": self.base.worst.as_dict(), **{k: self.last.get(k) for k in (
            "injection_pressure", "production_temperature", "lam_injector", "aperture_injector")}}
        path = os.path.join(self.scene.output_dir, "fracture_final.npz")
        self.write_fracture_maps(problem, path)
        out["fracture_maps"] = os.path.basename(path)
        return out


class PennyImpermeable(ClosedUnderStress, Scene):
    name = "penny_impermeable"
    dimension = 3
    description = ("Scene 2: cold water through a deformable penny fracture with contact in impermeable "
                   "rock (3D)")
    parameters = (mt.group("Rock", mt.ELASTIC + mt.ROCK_HEAT + ("rock_porosity", "rock_thermal_expansion")),
                  mt.group("Fluid", mt.FLUID_FLOW + mt.FLUID_HEAT, fluid_viscosity="water"),
                  mt.group("Fracture", mt.JOINT + mt.CONTACT + mt.FRACTURE_HEAT,
                           fracture_aperture=0.6e-3, **mt.FRICTIONLESS),
                  mt.group("Wells, in-situ and initial state", mt.WELLS + (
                      "insitu_stress", "initial_pressure", "initial_temperature"),
                      injection_rate=1e-3, initial_pressure=20e6, production_pressure=20e6),
                  mt.group("Coupling", ("thermomechanical_heating",)),
                  Scene2Params)
    time = TimeDefaults(final_time=1e9, dt_initial=1e3, dt_growth=1.2, dt_max=2e7, mesh_size=0.0,
                        output_interval=10)
    history_columns = ("injection_pressure", "production_temperature", "production_rate", "lam_injector",
                       "aperture_injector", "aperture_max", "lam_min", "nodes_open", "aperture_identity",
                       "closed_opening", "lam_roughness", "slip_max", "slipping_area",
                       "mass_balance", "energy_balance")
    def solver_defaults(self, comm):
        # one LU per time step: the later Newton iterations of a step reuse it
        # as GMRES's preconditioner (the factorisation dominates the run time)
        return dict(contact_solver_defaults(comm), snes_lag_preconditioner="10")

    def block_recipe(self, snes_type):
        """``contact_block_recipe``: level 1 to 1e9 s, side by side
        (manual, solver guide): 217 against 314 Newton iterations, 19 123
        against 25 628 Krylov, 147 against 193 s; injection pressure,
        production temperature, lam and aperture at the injector equal to
        2e-12 relative, mass balance 5.4e-7 either way.  The mechanics,
        then {pf, Tf, Tm} as one split, the glued elasticity by four CG
        iterations on its cycle (BoomerAMG with P1 u where PETSc has hypre)
        (``recipes.closed_fracture_recipe``)."""
        return {**contact_block_recipe(), **closed_fracture_recipe(self.run.fe_degree)}

    # -- geometry -----------------------------------------------------------------------
    @property
    def L(self):
        return self.p.scene2_box * self.p.scene2_radius

    def wells_at(self):
        d = self.p.scene2_well_offset
        return (-d, 0.0, 0.0), (d, 0.0, 0.0)

    def boundaries(self):
        L = self.L
        return {"sym_y": lambda x: np.isclose(x[:, 1], 0.0),
                "far_x": lambda x: np.isclose(np.abs(x[:, 0]), L),
                "far_y": lambda x: np.isclose(x[:, 1], L),
                "far_z": lambda x: np.isclose(np.abs(x[:, 2]), L)}

    def generate_mesh(self, path, size):
        p = self.p
        L = self.L
        size = size or L / 4
        if p.scene2_layer.layered:
            layer = first_layer(self, p.scene2_layer)
            return meshing.layered_half_box_with_disc(path, L, p.scene2_radius, size, p.scene2_fracture_size,
                                                      layer, p.scene2_layer_growth,
                                                      list(self.wells_at()),
                                                      p.scene2_well_size)
        fr = [meshing.Fracture("disc", center=(0.0, 0.0, 0.0), radius=p.scene2_radius,
                               size=p.scene2_fracture_size)]
        return meshing.box_with_fractures(path, [2 * L, L, 2 * L], size, fr, grading_distance=L,
                                          origin=(-L, 0.0, -L), wells=list(self.wells_at()),
                                          well_size=p.scene2_well_size)

    def hit_times(self):
        return [10.0 ** k for k in range(3, 10) if 10.0 ** k <= self.final_time]

    # -- model ----------------------------------------------------------------------------
    def normal(self) -> np.ndarray:
        return fracture_normal(3)

    def check(self, mesh):
        p = self.p
        self.check_closed_start()
        if not p.scene2_well_offset < p.scene2_radius:
            raise InputError(f"option -thm_scene2_well_offset = {p.scene2_well_offset:g} must be below "
                             f"-thm_scene2_radius = {p.scene2_radius:g} (wells on the fracture)")

    def build(self, mesh, degree):
        self.check(mesh)
        p = self.p
        T0, Ti = p.T0, p.T_inj
        u_scale = max(p.rock_thermal_expansion * abs(T0 - Ti) * p.scene2_radius / 3, 1e-6 * p.scene2_radius)
        a_ref = self.initial_aperture()
        b = ModelBuilder(p, 3)
        b.elasticity(degree, thermal=True)
        mech = b.contact(normal_stress=self.normal_stress, u_scale=u_scale)
        b.deformable(mech)
        b.fracture_flow(1, reference_aperture=a_ref, heat=True)         # lam, pf, Tf, Tm: always P1
        b.fracture_heat(1, reference_aperture=a_ref, lumped=p.scene2_lumped_heat)
        b.matrix_heat(1, lumped=p.scene2_lumped_heat)
        # the producer's well index: the line formula 2 T / r_w (flow_dim 1), the scene's documented choice
        wells = FractureWells(*self.wells_at(), heat=True, share=HALF, flow_dim=1)
        b.wells(wells.make(p, mesh, transmissivity(p, a_ref, T0)))
        b.model.ranges["Tf"] = replace(b.temperature_ranges()["Tf"], warn_above=TF_BOUNDS_WARNING,
                                       hint="; refine the fracture mesh or use "
                                            "-thm_fracture_heat_exchange equilibrium")
        base = heat_wells_monitor(b, wells, a_ref)
        lam_tip = self.lam0 if p.scene2_tip_traction == "insitu" else 0.0
        bcs = [Dirichlet("u", "sym_y", zero, components=(1,)),
               Dirichlet("u", "far_x", zero, components=(0,)),
               Dirichlet("u", "far_y", zero, components=(1,)),
               Dirichlet("u", "far_z", zero, components=(2,))]
        bcs += tip_tractions(b.model, constant_in_time(lam_tip), {"sym_y": 1})
        bcs += [Dirichlet("Tm", f, constant_in_time(T0)) for f in ("far_x", "far_y", "far_z")]
        mu = p.fluid_viscosity
        dp = rate_pressure_scale(float(p.injection_rate * 12 * mu.mu(Ti) / (2 * np.pi * a_ref ** 3)
                                       * np.log(2 * p.scene2_well_offset / p.well_radius)),
                                 p.initial_pressure, p.production_pressure)
        sT = FieldScale(abs(T0 - Ti) or 1.0, T0)
        scales = {"u": FieldScale(u_scale), "lam": FieldScale(self.lam0),
                  "pf": FieldScale(dp, p.initial_pressure),
                  "Tf": sT, "Tm": FieldScale(sT.scale, sT.offset)}
        init = {"lam": constant(self.lam0), "pf": constant(p.initial_pressure), "Tf": constant(T0),
                "Tm": constant(T0)}
        return Setup(b.build(), bcs, scales, init, _Scene2Monitor(self, base, b.aperture.law))
