"""Scene 3 of the paper (manual, "The paper's scenes"): a deformable inclined
fracture in a permeable, thermo-poro-elastic rock with matrix wells.

* ``inclined_penny``: a disc fracture (R = 200 m) dipping 30 degrees,
  centred at the origin, strike along y; every field: u (Biot, thermal
  strain), lam (contact), pf (cubic law with da/dt), pm (Darcy with Biot
  storage), Tf and Tm (advection-conduction); leakoff by the tie pm = pf on
  the walls and the equilibrium exchange Tm = Tf there (the heat that
  leakoff carries is the wall flux of the tied nodes); mu(T) of water.  A
  vertical injector and producer 300 m apart on the strike line through the
  centre, their lowest 20 m perforated just above the fracture (not
  connected to it: ``-thm_scene3_well_standoff``), inject and produce
  0.005 m3/s (``petthm.physics.matrixwells``).  ``-thm_scene3_case`` 1|2|3 sets
  the defaults of T0 and the in-situ stress (the paper's three cases).

The box [-L, L]^3 (L = ``-thm_scene3_box`` R) has rollers on its faces
and the initial pressure and temperature there.  manual, Scene 3 gives the
reasons for what the paper leaves open.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from petthm import params as P
from petthm.discretisation import probes
from petthm.discretisation.assembly import FieldScale
from petthm.discretisation.constraints import Dirichlet
from petthm.errors import InputError
from petthm.mesh import generate as meshing
from petthm.mesh import layered as layeredmesh
from petthm.mesh.plex import Interior
from petthm.params import DISCRETISATION, MESH, PHYSICS, param
from petthm.physics import materials as mt
from petthm.physics.builders import WATER_ENERGY_SCHEMES, ModelBuilder, heat_scheme
from petthm.physics.materials import Parameters
from petthm.physics.matrixwells import MatrixWells, Perforation
from petthm.physics.monitors import Worst, contact_node_checks, contact_node_fields
from petthm.scenes.base import (
    Monitor,
    Scene,
    Setup,
    TimeDefaults,
    constant,
    constant_in_time,
    tip_tractions,
)
from petthm.scenes.contact import OPEN_TRACTION, contact_block_recipe, contact_solver_defaults
from petthm.scenes.fractured import (
    ClosedUnderStress,
    FirstLayer,
    balances_of,
    first_layer,
    first_layer_param,
)
from petthm.scenes.friction import slip_columns
from petthm.solvers.recipes import flow_heat_first_recipe

#: (T0 in degC, compressive in-situ stress in Pa) of the paper's cases 1, 2, 3
CASES = {1: (80.0, 60e6), 2: (250.0, 60e6), 3: (250.0, 75e6)}
YEAR = 365.25 * 86400.0
#: the degree of Tf and Tm (P1 whatever -thm_fe_degree gives u)
TEMPERATURE_DEGREE = 1
#: an aperture this much above its initial value counts as raised (the affected area)
RAISED = 0.10


@dataclass(frozen=True)
class Scene3Params:
    """Scene 3 of the paper: deformable inclined fracture, permeable rock, matrix wells (inclined_penny)"""
    scene3_case: int = param(1, "-", "the paper's case: 1 (T0 80 degC, 60 MPa), 2 (250 degC, 60 MPa), "
                             "3 (250 degC, 75 MPa); sets the defaults of -thm_initial_temperature and "
                             "-thm_insitu_stress", choices=(1, 2, 3), kind=PHYSICS)
    scene3_radius: float = param(200.0, "m", "fracture radius R", lo=0.0, lo_open=True, kind=MESH)
    scene3_dip: float = param(30.0, "deg", "fracture dip (rotation about the y axis)", lo=0.0, hi=80.0,
                              kind=MESH)
    scene3_box: float = param(3.0, "-", "domain half-size / R", lo=1.5, kind=MESH)
    scene3_well_spacing: float = param(300.0, "m", "distance between the wells (on the strike line y "
                                       "through the fracture's centre, symmetric about it)", lo=0.0,
                                       lo_open=True, kind=MESH)
    scene3_perforation: float = param(20.0, "m", "perforated length at the bottom of each well", lo=0.0,
                                      lo_open=True, kind=MESH)
    scene3_well_standoff: float = param(10.0, "m", "vertical distance from the fracture up to the bottom "
                                        "of each perforation (the wells do not reach the fracture)",
                                        lo=0.0, lo_open=True, kind=MESH)
    scene3_fracture_size: float = param(20.0, "m", "mesh size on the fracture", lo=0.0, lo_open=True,
                                        kind=MESH)
    scene3_well_size: float = param(5.0, "m", "mesh size along the perforations", lo=0.0, lo_open=True,
                                    kind=MESH)
    scene3_layer: FirstLayer = first_layer_param("thm_scene3_layer", 0.0, "unstructured tetrahedra",
                                                 "the first output time (10 years)")
    scene3_layer_growth: float = param(1.5, "-", "thickness ratio of successive layers", lo=1.0, hi=3.0,
                                       lo_open=True, kind=MESH)
    scene3_far_pressure: str = param("fixed", "-", "the box faces: fixed (pm = p0, fluid crosses them) or "
                                     "closed (no flow: all the produced water comes from the rock and the "
                                     "injector)", choices=("fixed", "closed"), kind=PHYSICS)
    scene3_lumped_heat: bool = param(True, "-", "row-sum lumping of the heat capacities (keeps Tf and Tm "
                                     "closer to [Tinj, T0] where the mesh does not resolve the fronts)",
                                     kind=DISCRETISATION)


WELLS3 = mt.group("Wells, in-situ and initial state", mt.WELLS + (
    "production_rate", "insitu_stress", "initial_pressure", "initial_temperature"),
    injection_rate=0.005, production_rate=0.005, production_pressure=20e6, initial_pressure=20e6)


class _Scene3Monitor(Monitor):
    """Wells, the fracture's aperture, contact and temperature, balances."""

    carried = ("worst", "peak")

    def __init__(self, scene, wells: MatrixWells, balances, worst, law):
        self.scene, self.wells, self.balances, self.worst = scene, wells, balances, worst
        self.law = law
        self.last, self.peak = {}, (0.0, 0.0)

    def __call__(self, problem, t, X=None):
        sc = self.scene
        comm = problem.dm.comm
        out = self.wells(problem, t, X)
        f = contact_node_fields(problem, X, t)
        lam = problem.field_values("lam", X, t)[:, 0]
        a, a0 = f["aperture"], sc.initial_aperture()
        x = problem.disc.field_node_coordinates("lam")
        rise = a - a0
        k = int(np.argmax(rise)) if len(rise) else -1
        best = probes.global_max(comm, rise, empty=-np.inf)
        where = np.zeros(3)
        if k >= 0 and rise[k] == best:
            where = x[k]
        owner = probes.global_min(comm, [comm.rank if k >= 0 and rise[k] == best else comm.size])
        where = probes.mpi(comm).bcast(where, root=int(owner))
        out["aperture_increase_max"] = best
        out["aperture_increase_ratio"] = best / a0
        out.update({f"aperture_increase_{c}": float(v) for c, v in zip("xyz", where, strict=False)})
        out["raised_area"] = probes.global_sum(comm, float(np.sum(f["weight"][rise > RAISED * a0])))
        closed = lam > OPEN_TRACTION * sc.lam0
        ident = np.abs(a - self.law.closure_aperture(lam)[0])[closed]
        out["aperture_identity"] = probes.global_max(comm, ident, empty=0.0) / a0
        out["lam_min"] = probes.global_min(comm, lam)
        out["nodes_open"] = probes.global_count(comm, ~closed & self.owned(problem))
        opening, _ = contact_node_checks(problem, OPEN_TRACTION * sc.lam0, X, t)
        out["closed_opening"] = probes.global_max(comm, [opening]) / a0
        out.update(slip_columns(problem, fields=f) if problem.model.friction_law is not None else
                   {"slip_max": np.nan, "slipping_area": np.nan})
        out.update(self.balances(problem, t, X))
        self.worst.update("aperture_identity", out["aperture_identity"])
        if best > self.peak[1]:
            self.peak = (t, best)
        self.last = out
        return out

    def owned(self, problem) -> np.ndarray:
        """The lam nodes this rank owns (each node counted once over the
        ranks; the front's constrained nodes are never open)."""
        disc = problem.disc
        g = disc.global_index[disc.field_local_dofs("lam")[:, 0]]
        lo, hi = disc.ownership_range()
        return (g >= lo) & (g < hi)

    def stop_reason(self):
        p = self.last.get("production_pressure")
        if self.scene.p.production_rate > 0 and p is not None and p < 0:
            return (f"the producer's pressure fell to {p:.4g} Pa: the rate -thm_production_rate = "
                    f"{self.scene.p.production_rate:g} m3/s cannot be produced from this rock; lower it, "
                    "or set it to 0 to produce at -thm_production_pressure")
        return None

    def report(self, problem, t):
        keys = ("injection_pressure", "production_pressure", "production_temperature",
                "aperture_increase_max",
                "aperture_increase_ratio", "raised_area", "lam_min")
        return {"balance_max": self.worst.as_dict(), **{k: self.last.get(k) for k in keys},
                "aperture_increase_peak": {"time": self.peak[0], "years": self.peak[0] / YEAR,
                                           "value": self.peak[1]},
                "case": self.scene.p.scene3_case, "lam0": self.scene.lam0,
                "initial_aperture": self.scene.initial_aperture()}


class InclinedPenny(ClosedUnderStress, Scene):
    name = "inclined_penny"
    dimension = 3
    description = ("Scene 3: cold water between matrix wells past a deformable inclined fracture in "
                   "permeable thermo-poro-elastic rock (3D, all fields)")
    parameters = (mt.group("Rock", mt.ELASTIC + mt.ROCK_HEAT + (
        "rock_biot_coefficient", "rock_porosity", "rock_permeability", "rock_thermal_expansion"),
        rock_youngs_modulus=20e9, rock_poisson_ratio=0.2, rock_biot_coefficient=0.8, rock_porosity=0.1,
        rock_permeability=(1e-14,)),
        mt.group("Fluid", mt.FLUID_FLOW + mt.FLUID_HEAT, fluid_viscosity="water"),
        mt.group("Fracture", mt.JOINT + mt.CONTACT + mt.FRACTURE_HEAT, fracture_aperture=0.6e-3,
                 **mt.FRICTIONLESS),
        WELLS3,
        mt.group("Coupling", ("thermomechanical_heating",)),
        Scene3Params)
    time = TimeDefaults(final_time=30 * YEAR, dt_initial=86400.0, dt_growth=1.1, dt_max=0.2 * YEAR,
                        mesh_size=0.0, output_interval=10)
    history_columns = ("injection_pressure", "injection_rate", "production_pressure", "production_rate",
                       "production_temperature",
                       "aperture_increase_max", "aperture_increase_ratio", "aperture_increase_x",
                       "aperture_increase_y", "aperture_increase_z", "raised_area", "lam_min", "nodes_open",
                       "aperture_identity", "closed_opening", "slip_max", "slipping_area",
                       "mass_balance", "energy_balance")

    @classmethod
    def read(cls, run):
        """The parameters, with T0 and the in-situ stress of ``-thm_scene3_case`` as their defaults."""
        T0, sigma = CASES[P.read(Scene3Params).scene3_case]
        groups = [P.with_defaults(g, initial_temperature=T0, insitu_stress=f"{sigma:g}")
                  for g in cls.parameters]
        return cls(run, P.read_all(groups, base=Parameters))

    def solver_defaults(self, comm):
        # a fresh factorisation every Newton iteration: mu(T), the advection and the contact set change
        # the Jacobian too much for a lagged one (GMRES hit 50 iterations on the coarse mesh)
        return contact_solver_defaults(comm)

    def block_recipe(self, snes_type):
        """The flow and heat fields {pm, pf, Tf, Tm} as one split before the
        mechanics, by GMRES to 1e-3 on ILU(0), and the glued elasticity by
        CG on its cycle (``recipes.flow_heat_first_recipe``; manual, solver
        guide).  Block Gauss-Seidel over five splits drops the coupling among
        the flow and heat fields, which makes 56 % of the Krylov count on
        coarse Scene 3's finest level; the one split keeps it.  The
        heat comes before the mechanics: the rock's thermal stress
        loads u, and the heat balances do not contain u.  Four steps after
        2 years, case 2, one run after the other beside a second run: coarse level 3
        (P1 u, 70 677 unknowns) 5.6 against 71.5 Krylov iterations per
        Newton iteration, KSPSolve 11.9 against 64.5 s; the default mesh
        (P2 u, 119 862 unknowns) 6.0 against 49.8, 57.7 against 98.0 s.

        Six CG iterations with P1 u (four with P2 u): the elasticity's error
        is what is left of the count.  Coarse levels 1-3 to 2 years: 2.8 /
        3.5 / 4.1 Krylov iterations per Newton iteration with six (1.46x over
        28x the unknowns), 2.9 / 3.8 / 4.9 with four, at the same cost
        (11.6 against 11.3 s); on the default mesh six cost 11 % more time
        (64.0 against 57.7 s) for 5.6 against 6.0.

        One Chebyshev step on the P2 level of the glued elasticity's
        p-multigrid (three elsewhere): that level's products are most of a
        Krylov iteration's cost here.

        Newton to a scaled residual of 1e-9 (``contact_block_recipe``).  At
        0.2-year steps the second
        Newton iteration reaches 4e-10, and a third one changed the reported
        quantities by at most 2e-9 of their values (case 2 at 7 years, four
        steps, side by side: injection pressure 1.4e-10, production
        temperature 6e-11, max aperture increase 2e-9; mass balance 3.0e-8
        either way, energy balance 5e-11 against 5e-14) for 28 % of the
        time (92.5 s against 127.8 s; 563 against 781 Krylov iterations).

        With the bound-preserving heat transport (``limited``, ``upwind``)
        Newton goes to 1e-10 and a linear solve to 1e-12: a step is accepted
        at the first iterate below the tolerance, and the balances follow
        that residual (case 3 continued from 29.8 years, six steps: mass and
        energy balances 7.6e-9 to 1.8e-8 per step with 1e-9, at most 4.3e-11
        with 1e-10; 6 against 5 Newton and 48-57 against 35-43 Krylov
        iterations per step; production temperature within 3e-7 K; theory
        manual, discretisation)."""
        recipe = {**contact_block_recipe(), **flow_heat_first_recipe(self.run.fe_degree)}
        if heat_scheme(self.p, TEMPERATURE_DEGREE) in WATER_ENERGY_SCHEMES:
            recipe.update(snes_atol="1e-10", ksp_atol="1e-12")
        return recipe

    def hit_times(self):
        """10, 20 and 30 years (the paper's Figs. 8-10), where the fields are written."""
        return [y * YEAR for y in (10, 20, 30) if y * YEAR <= self.final_time * (1 + 1e-12)]

    # -- geometry -------------------------------------------------------------------------
    @property
    def L(self) -> float:
        return self.p.scene3_box * self.p.scene3_radius

    def normal(self) -> np.ndarray:
        """The fracture's unit normal: e_z rotated by the dip about y."""
        d = math.radians(self.p.scene3_dip)
        return np.array([math.sin(d), 0.0, math.cos(d)])

    def perforations(self) -> tuple[Perforation, Perforation]:
        """Injector at y = -s/2, producer at y = +s/2 (x = 0, where the
        fracture plane is at z = 0); each perforated from the standoff above
        the fracture up by the perforated length."""
        p = self.p
        y = p.scene3_well_spacing / 2
        z0 = p.scene3_well_standoff
        z1 = z0 + p.scene3_perforation
        return (Perforation("injector", (0.0, -y, z0), (0.0, -y, z1)),
                Perforation("producer", (0.0, y, z0), (0.0, y, z1)))

    def boundaries(self):
        L = self.L
        out = {f"{s}{c}": (lambda x, a=a, v=v: np.isclose(x[:, a], v))
               for a, c in enumerate("xyz") for s, v in (("lo_", -L), ("hi_", L))}
        out["injector"] = Interior(self.perforations()[0].contains)      # Tm = T_inj on its interval
        return out

    def generate_mesh(self, path, size):
        p = self.p
        L = self.L
        if p.scene3_layer.layered:
            layer = first_layer(self, p.scene3_layer)
            return self._layered_mesh(path, size or L / 4, layer)
        fr = [meshing.Fracture("disc", center=(0.0, 0.0, 0.0), radius=p.scene3_radius, dip=p.scene3_dip,
                               strike=1, size=p.scene3_fracture_size)]
        return meshing.box_with_fractures(path, [2 * L] * 3, size or L / 4, fr, grading_distance=L,
                                          origin=(-L, -L, -L), well_size=p.scene3_well_size,
                                          well_lines=[w.segment() for w in self.perforations()])

    def _layered_mesh(self, path, size, layer):
        """Layers parallel to the fracture (``layeredmesh``), the first ``layer``
        m thick, the perforations' ends on layer boundaries."""
        p = self.p
        L = self.L
        zone = 0.5 * L * (1.0 - math.tan(math.radians(p.scene3_dip)))
        top = p.scene3_well_standoff + p.scene3_perforation
        if p.scene3_dip >= 45.0 or top >= zone:
            raise InputError(f"option -thm_scene3_layer = {p.scene3_layer}: the layered mesh needs "
                             f"-thm_scene3_dip < 45 (got {p.scene3_dip:g}) and the perforations' tops "
                             f"({top:g} m above the fracture) below {zone:.4g} m (half the rock above "
                             "the fracture's lowest point); use -thm_scene3_layer 0 or a larger "
                             "-thm_scene3_box")
        across = zone * math.cos(math.radians(p.scene3_dip))
        if layer >= 0.5 * across:
            raise InputError(f"option -thm_scene3_layer = {layer:g} m: the first layer must be "
                             f"thinner than half the layered zone across the fracture ({0.5 * across:.4g} m)")
        wells = [tuple(w.bottom[:2]) for w in self.perforations()]
        return layeredmesh.layered_box_with_inclined_disc(
            path, L, p.scene3_radius, p.scene3_dip, size, p.scene3_fracture_size, layer,
            p.scene3_layer_growth, wells=wells, well_size=p.scene3_well_size,
            well_heights=(p.scene3_well_standoff, top))

    # -- model ------------------------------------------------------------------------------
    def check(self, mesh):
        p = self.p
        self.check_closed_start()
        half = p.scene3_well_spacing / 2
        top = p.scene3_well_standoff + p.scene3_perforation
        if half >= self.L or top >= self.L:
            raise InputError(f"options -thm_scene3_well_spacing = {p.scene3_well_spacing:g} / "
                             f"-thm_scene3_well_standoff + -thm_scene3_perforation = {top:g}: the wells must "
                             f"lie inside the box (half-size {self.L:g} m)")

    def pressure_scale(self) -> float:
        """Q mu(Tinj) / (2 pi k l_p): the pressure change a line well makes
        (Pa), at least 1e-3 of lam0 (no injection)."""
        p = self.p
        k = float(np.max(p.permeability(3)))
        dp = p.injection_rate * p.fluid_viscosity.mu(p.T_inj) / (2 * np.pi * k * p.scene3_perforation)
        return float(max(dp, 1e-3 * self.lam0))

    def build(self, mesh, degree):
        self.check(mesh)
        p = self.p
        T0, Ti, p0 = p.T0, p.T_inj, p.initial_pressure
        R = p.scene3_radius
        u_scale = max(p.rock_thermal_expansion * abs(T0 - Ti) * R / 3, 1e-6 * R)
        a_ref = self.initial_aperture()
        K = p.permeability(3)
        b = ModelBuilder(p, 3)
        b.elasticity(degree, biot=True, thermal=True)
        mech = b.contact(normal_stress=self.normal_stress, u_scale=u_scale)
        b.deformable(mech)
        b.fracture_flow(1, reference_aperture=a_ref, heat=True)     # lam follows u; pf, pm, Tf, Tm: P1
        b.matrix_flow(1, permeability=K, storage=p.storage,
                      thermal_storage=p.rock_porosity * p.fluid_thermal_expansion, heat=True)
        b.leakoff()
        b.fracture_heat(TEMPERATURE_DEGREE, reference_aperture=a_ref, lumped=p.scene3_lumped_heat)
        b.matrix_heat(TEMPERATURE_DEGREE, lumped=p.scene3_lumped_heat)
        inj, prod = self.perforations()
        wells = MatrixWells(inj, prod, p.injection_rate, Ti, p.production_rate or None, p.production_pressure,
                            p.fluid_rho_c)
        b.wells(wells.make(mesh, float(np.max(K)), float(p.fluid_viscosity.mu(T0)), p.well_radius))
        worst = Worst()
        balances = balances_of(b, a_ref, p0, True, worst)
        model = b.build()
        bcs = [Dirichlet("u", f"{s}{c}", lambda x, t: np.zeros(len(x)), components=(a,))
               for a, c in enumerate("xyz") for s in ("lo_", "hi_")]
        bcs += tip_tractions(model, constant_in_time(self.lam0))
        far = [f"{s}{c}" for c in "xyz" for s in ("lo_", "hi_")]
        bcs += [Dirichlet("Tm", f, constant_in_time(T0)) for f in far]
        if p.injection_rate > 0:        # shut in (Q = 0), the injector holds no cold water: Tm stays free
            bcs.append(Dirichlet("Tm", "injector", constant_in_time(Ti)))
        if p.scene3_far_pressure == "fixed":
            bcs += [Dirichlet("pm", f, constant_in_time(p0)) for f in far]
        sp, sT = FieldScale(self.pressure_scale(), p0), FieldScale(abs(T0 - Ti) or 1.0, T0)
        scales = {"u": FieldScale(u_scale), "lam": FieldScale(self.lam0), "pf": sp,
                  "pm": FieldScale(sp.scale, sp.offset), "Tf": sT, "Tm": FieldScale(sT.scale, sT.offset)}
        init = {"lam": constant(self.lam0), "pf": constant(p0), "pm": constant(p0), "Tf": constant(T0),
                "Tm": constant(T0)}
        monitor = _Scene3Monitor(self, wells, balances, worst, b.aperture.law)
        return Setup(model, bcs, scales, init, monitor)
