"""The full coupled manufactured solution (manual, verification):
every field of Scene 3 at once (u, pm, Tm, pf, Tf, and lam), made with the
same builders as ``inclined_penny`` (Biot with thermal strain, the contact
face loads, the deformable aperture, the cubic law with da/dt, leakoff by
the tie pm = pf, the equilibrium wall exchange Tm = Tf, mu(T), advection
with SUPG), plus the manufactured sources of ``petthm.verification.manufactured``.

* ``coupled_mms``: the unit square or cube cut by the fracture zeta = 1/2
  (no tips); ``-thm_coupled_mms_state open`` (opening w >= 0.05, lam = 0,
  a = a0 + w) or ``closed`` (u continuous, lam > 0, a = a0 - lam/Kn);
  every field of degree ``-thm_fe_degree``.  Boundary data: u on the
  faces zeta = 0 and 1, the exact traction on the others (their nodes on
  Gamma are split, and a Dirichlet value is a function of position only);
  pm and Tm on every face, pf and Tf on the fracture's edges.  The fields
  are affine in t: the reported L2 and H1 errors at the final time are
  purely spatial.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from functools import partial

import numpy as np

from petthm.discretisation import probes
from petthm.discretisation.assembly import FieldScale
from petthm.discretisation.constraints import Dirichlet
from petthm.discretisation.model import FRACTURE, MATRIX, CellResidual, Side, Trace
from petthm.errors import InputError
from petthm.mesh import generate as meshing
from petthm.params import DISCRETISATION, MESH, PHYSICS, param
from petthm.physics import materials as mt
from petthm.physics.builders import WATER_ENERGY_SCHEMES, ModelBuilder, heat_scheme
from petthm.physics.kernels import poroelastic as pe
from petthm.physics.monitors import recovered_traction
from petthm.scenes.base import Monitor, Scene, Setup, TimeDefaults, face, on_sides
from petthm.scenes.contact import contact_block_recipe, contact_solver_defaults
from petthm.solvers.recipes import flow_heat_first_recipe
from petthm.verification.manufactured import HALVES, Amplitudes, Coefficients, CoupledSolution

MATRIX_FIELDS = ("u", "pm", "Tm")
FRACTURE_FIELDS = ("pf", "Tf")


@dataclass(frozen=True)
class CoupledMMSParams:
    """The full coupled manufactured solution (coupled_mms; manual, verification)"""
    coupled_mms_dim: int = param(2, "-", "space dimension", choices=(2, 3), kind=MESH)
    coupled_mms_state: str = param("open", "-", "the fracture: open (lam = 0, a = a0 + opening) or closed "
                                   "(u continuous, lam > 0, a = a0 - lam/Kn)", choices=("open", "closed"),
                                   kind=PHYSICS)
    coupled_mms_supg: bool = param(True, "-", "SUPG in both heat equations, as every scene uses it (off: "
                                   "the Galerkin form, to separate the stabilisation's consistency error)",
                                   kind=DISCRETISATION)


def coefficients(p, dim: int, water_energy: bool = False) -> Coefficients:
    """The operator's coefficients from the scene's parameters (``water_energy``:
    the heat transport's stored energy counts the water's content)."""
    return Coefficients(
        dim=dim, E=p.rock_youngs_modulus, nu=p.rock_poisson_ratio, alpha=p.rock_biot_coefficient,
        p_ref=p.initial_pressure, beta_s=p.rock_thermal_expansion, T_ref=p.T0, storage=p.storage,
        thermal_storage=p.rock_porosity * p.fluid_thermal_expansion, k=p.isotropic_permeability(),
        viscosity=p.fluid_viscosity, C_m=p.rho_c, lam_m=p.conductivity, rho_c_f=p.fluid_rho_c,
        lam_f=p.fluid_conductivity, c_f=p.fluid_compressibility, beta_f=p.fluid_thermal_expansion,
        a0=p.fracture_aperture, Kn=p.fracture_normal_stiffness, sigma0_nn=-p.insitu_stress.normal(
            np.eye(dim)[-1]), heating=bool(p.thermomechanical_heating), porosity=p.rock_porosity,
        water_energy=water_energy)


def _error_entries(name: str, e: dict) -> dict:
    return {f"{name}_l2": e["l2"], f"{name}_h1": e["h1"], f"{name}_l2_rel": e["l2_rel"],
            f"{name}_h1_rel": e["h1_rel"]}


class _ErrorNorms(Monitor):
    """L2 and H1-seminorm errors of every field at the end (relative to the
    exact field's norms; T relative to T - T0), and their worst over the run."""

    def __init__(self, scene, solution: CoupledSolution, fields):
        self.scene, self.m, self.fields = scene, solution, fields

    def errors(self, problem, t) -> dict:
        xl = problem.local_arrays(problem.X, t)[0]
        out = {}
        T0 = self.scene.p.T0
        for name in self.fields:
            region = FRACTURE if name in FRACTURE_FIELDS + ("lam",) else MATRIX
            exact = self.m.value(name)
            if name in ("Tm", "Tf"):     # relative to the temperature change, not to T in kelvin
                ref = problem.region(region).error_norms(xl, name, lambda x, t, f=exact: f(x, t) - T0,
                                                         self.m.gradient(name), t)
                e = problem.region(region).error_norms(xl, name, exact, self.m.gradient(name), t)
                e["l2_rel"] = e["l2"] / ref["l2_exact"]
            else:
                e = problem.region(region).error_norms(xl, name, exact, self.m.gradient(name), t)
            out.update(_error_entries(name, e))
        if "lam" in self.fields:
            out.update(_error_entries("lam_recovered", self.recovered_errors(problem, t)))
        return out

    def recovered_errors(self, problem, t) -> dict:
        """The errors of the traction recovered from the rock's stress
        (``monitors.recovered_traction``) as a field on lam's nodes."""
        recovered = recovered_traction(problem, t=t)
        xl = problem.local_arrays(problem.X, t)[0].copy()
        sc = problem.scales["lam"]
        xl[problem.disc.field_local_dofs("lam")[:, 0]] = (recovered - sc.offset) / sc.scale
        return problem.region(FRACTURE).error_norms(xl, "lam", self.m.value("lam"), self.m.gradient("lam"), t)

    def __call__(self, problem, t, X=None):
        e = self.errors(problem, t)
        return {f"{n}_l2_rel": e[f"{n}_l2_rel"] for n in self.fields}

    def report(self, problem, t):
        mesh = problem.disc.mesh
        return {"error": self.errors(problem, t), "h_max": probes.global_max(mesh.dm.comm, mesh.h, empty=0.0),
                "state": self.scene.p.coupled_mms_state}


class CoupledMMS(Scene):
    name = "coupled_mms"
    description = ("manufactured solution of every coupled field (u, pm, Tm, pf, Tf, lam) with a "
                   "fracture across the unit square/cube (2D/3D, P1/P2)")
    parameters = (
        mt.group("Rock", mt.ELASTIC + mt.ROCK_HEAT + (
            "rock_biot_coefficient", "rock_porosity", "rock_permeability", "rock_thermal_expansion"),
            rock_youngs_modulus=10.0, rock_poisson_ratio=0.25, rock_biot_coefficient=0.8, rock_porosity=0.2,
            rock_permeability=(1e-3,), rock_thermal_expansion=0.01, rock_density=1.0, rock_heat_capacity=1.0,
            rock_conductivity=1.0),
        mt.group("Fluid", mt.FLUID_FLOW + mt.FLUID_HEAT, fluid_viscosity="water", fluid_compressibility=0.5,
                 fluid_thermal_expansion=0.01, fluid_density=1.0, fluid_heat_capacity=1.0,
                 fluid_conductivity=1.0),
        mt.group("Fracture", mt.JOINT + mt.CONTACT + mt.FRACTURE_HEAT, fracture_aperture=0.2,
                 fracture_normal_stiffness=2.0,
                 **mt.FRICTIONLESS),
        mt.group("State", ("initial_temperature", "initial_pressure", "insitu_stress",
                           "thermomechanical_heating"), initial_temperature=50.0, insitu_stress="1"),
        CoupledMMSParams)
    time = TimeDefaults(final_time=1.0, dt_initial=0.5, mesh_size=0.25)
    history_columns = tuple(f"{n}_l2_rel" for n in ("u", "lam", "pf", "pm", "Tf", "Tm"))

    @property
    def closed(self) -> bool:
        return self.p.coupled_mms_state == "closed"

    def sides(self) -> tuple[str, ...]:
        """The boundary parts across which the fracture runs (the last coordinate is its normal)."""
        return ("x0", "x1") if self.p.coupled_mms_dim == 2 else ("x0", "x1", "y0", "y1")

    def boundaries(self):
        d = self.p.coupled_mms_dim
        axes = "xyz"[:d]
        return {f"{c}{v}": face(a, float(v)) for a, c in enumerate(axes) for v in (0, 1)}

    def generate_mesh(self, path, size):
        if self.p.coupled_mms_dim == 2:
            fr = [meshing.Fracture("segment", p0=(0.0, 0.5), p1=(1.0, 0.5))]
            return meshing.box_with_fractures(path, [1.0, 1.0], size, fr)
        fr = [meshing.Fracture("rectangle", center=(0.5, 0.5, 0.5), half=(0.5, 0.5))]
        return meshing.box_with_fractures(path, [1.0, 1.0, 1.0], size, fr)

    def solver_defaults(self, comm):
        # the sources are O(1e3) where T is in kelvin: an absolute floor below round-off of the residual
        return dict(contact_solver_defaults(comm), snes_rtol="1e-12", snes_atol="1e-11", snes_max_it="30")

    def block_recipe(self, snes_type):
        """Scene 3's recipe, which has the same fields (``recipes.flow_heat_first_recipe``
        and ``contact_block_recipe``).  ``BLOCK_RECIPE``'s five splits stop
        at 500 Krylov iterations in every linear solve of the first step
        (3D P1, mesh size 0.04, 60 207 unknowns, open and closed).
        With this recipe both states complete, with the direct solve's
        steps and its errors against the exact solution to six digits
        (manual, verification: coupled MMS)."""
        return {**contact_block_recipe(), **flow_heat_first_recipe(self.run.fe_degree)}

    def solution(self, dim: int, degree: int = 1) -> CoupledSolution:
        """The manufactured solution; its aperture must stay above the
        residual aperture of the joint law (a0 - lam/Kn is not clipped).  Its
        sources count the water's content in the stored energy where the
        heat transport does (upwind, limited: kernels/transport.StoredWater)."""
        p = self.p
        water = heat_scheme(p, degree, bool(p.coupled_mms_supg)) in WATER_ENERGY_SCHEMES
        m = CoupledSolution(coefficients(p, dim, water), closed=self.closed, amp=Amplitudes(opening=0.05))
        g = np.linspace(0.0, 1.0, 21)
        grid = np.meshgrid(*[g] * (dim - 1) + [np.array([0.5])], indexing="ij")
        xs = np.stack(grid, axis=-1).reshape(-1, dim)
        a_min = min(float(m.aperture()(xs, t).min()) for t in (0.0, self.final_time))
        floor = p.fracture_residual_fraction * p.fracture_aperture
        if not a_min > 2 * floor:
            raise InputError(f"options -thm_fracture_aperture = {p.fracture_aperture:g} and "
                             f"-thm_fracture_normal_stiffness = {p.fracture_normal_stiffness:g}: the "
                             f"manufactured closed aperture a0 - lam/Kn falls to {a_min:.3g} m (lam up to "
                             f"{float(m.value('lam')(xs, self.final_time).max()):.3g} Pa); it must stay "
                             "above twice the residual aperture")
        return m

    def build(self, mesh, degree):
        p, dim = self.p, mesh.dim
        m = self.solution(dim, degree)
        supg = bool(p.coupled_mms_supg)
        sources = m.volume_sources()
        b = ModelBuilder(p, dim)
        b.elasticity(degree, biot=True, thermal=True)
        mech = b.contact(normal_stress=-m.c.sigma0_nn, u_scale=0.05)
        b.deformable(mech)
        frac = m.fracture_sources()
        b.fracture_flow(degree, reference_aperture=p.fracture_aperture, heat=True, source=frac["pf"])
        b.matrix_flow(degree, permeability=p.permeability(dim), storage=p.storage,
                      thermal_storage=m.c.thermal_storage, heat=True, source=sources["pm"])
        b.leakoff()
        b.fracture_heat(degree, reference_aperture=p.fracture_aperture, supg=supg,
                        source=frac["Tf"])
        b.matrix_heat(degree, source=sources["Tm"], supg=supg)
        model = b.build()
        model.add(source_terms(m, sources, frac))
        model.recovered_traction = dataclasses.replace(model.recovered_traction,
                                                       face_load=partial(manufactured_face_load, m))
        sigma = m.stress_function()
        model.facets += [pe.traction("u", part, partial(_outward_traction, sigma, part))
                         for part in self.sides()]
        d = "xyz"[dim - 1]
        bcs = [Dirichlet("u", f"{d}{v}", m.value("u"), m.rate("u")) for v in (0, 1)]
        faces = list(self.boundaries())
        bcs += [Dirichlet(f, part, m.value(f), m.rate(f)) for f in ("pm", "Tm") for part in faces]
        bcs += [Dirichlet(f, part, m.value(f), m.rate(f)) for f in FRACTURE_FIELDS for part in self.sides()]
        scales = {"u": FieldScale(0.05), "lam": FieldScale(0.2), "pf": FieldScale(1.0, p.initial_pressure),
                  "pm": FieldScale(1.0, p.initial_pressure), "Tf": FieldScale(20.0, p.T0),
                  "Tm": FieldScale(20.0, p.T0)}
        init = {f: (lambda x, f=f: m.value(f)(x, 0.0)) for f in ("lam", "pf", "pm", "Tf", "Tm")}
        init["u"] = on_sides(lambda x, inside: m.value("u")(x, 0.0, inside))
        return Setup(model, bcs, scales, init, _ErrorNorms(self, m, ("u", "lam", "pf", "pm", "Tf", "Tm")))


def _outward_traction(sigma, part: str, x, t):
    """sigma nu on a side of the box (nu its outward normal)."""
    axis, sign = "xyz".index(part[0]), (1.0 if part[1] == "1" else -1.0)
    return sign * sigma(x, t)[..., :, axis]


def manufactured_face_load(m: CoupledSolution, side: Side, ctx):
    """h (nc, nq, d) of the half a fracture face's rock lies in: the face load
    the manufactured solution puts on the trace of u on ``side`` (the half the
    fracture normal points into is the + face)."""
    up = (side.sign * ctx.normals[..., -1] > 0)[..., None]           # this face lies above Gamma
    h = {s: m.face_load(s)(ctx.x, ctx.t) for s in HALVES}
    return np.where(up, h[1], h[-1])


def source_terms(m: CoupledSolution, sources: dict, frac: dict) -> tuple[list, list]:
    """The manufactured right-hand sides that the flow and heat builders do
    not take (-int w f): f_u on the cells, the face loads h of each half on
    the trace of u that lies in it (the half the fracture normal points into
    is the + face), and on the fracture + int w (dE/dt - backward Euler's
    quotient of E) for its stored energy E and + int w dt da/dt ds/dt (dt =
    1/shift: backward Euler's stored energy, kernels/heat.heat_f0, and water
    content, kernels/flow.flow_f0, for the step taken, also after a rejected
    step), with the water's content in the stored energy also + int w dt
    rho_f C_f dm/dt dTm/dt in the rock."""
    def volume(f, ctx):
        v = -f(ctx.x, ctx.t)
        return v if v.ndim == 3 else v[..., None]

    def face_load(side: Side, ctx):
        return -manufactured_face_load(m, side, ctx)

    def step_increment(increment, ctx):
        return (increment(ctx.x, ctx.t) / ctx.shift if ctx.shift > 0 else np.zeros(ctx.shape))[..., None]

    def step_energy(step, ctx):
        return (step(ctx.x, ctx.t, 1.0 / ctx.shift) if ctx.shift > 0 else np.zeros(ctx.shape))[..., None]
    res = [CellResidual("u", partial(volume, sources["u"]), None, region=MATRIX),
           CellResidual("Tf", partial(step_energy, frac["Tf_step"]), None, region=FRACTURE),
           CellResidual("pf", partial(step_increment, frac["pf_increment"]), None, region=FRACTURE)]
    res += [CellResidual(Trace("u", side), partial(face_load, side), None, region=FRACTURE)
            for side in (Side.PLUS, Side.MINUS)]
    if m.c.water_energy:
        res.append(CellResidual("Tm", partial(step_increment, sources["Tm_increment"]), None, region=MATRIX))
    return res, []
