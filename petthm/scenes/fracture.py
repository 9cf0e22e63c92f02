"""Fracture flow and heat scenes with a rigid rock (issue 3; physics.md
sections 4-9 and 11, verification.md sections 1-3).

* ``fracture_flow_patch``: steady cubic-law flow along a fracture cutting
  the domain, pressure fixed at both ends: linear, exact for P1 and P2.
* ``radial_flow``: point injector at the centre of a buried disc fracture,
  pressure fixed on its rim: p = p_R + Q/(2 pi T_h) ln(R/r).
* ``leakoff_1d``: fracture pressure raised by dp at t = 0, 1D diffusion into
  the matrix on both sides: cumulative leakoff 4 dp S L sqrt(c t / pi).
* ``lauwerier``: cold water through a fracture in impermeable hot rock,
  compared with Lauwerier's solution (verification.md section 1).
* ``rigid_fracture``: Scene 1 of the paper: the same with a permeable matrix
  (1D or isotropic leakoff).

Fracture fields ``pf``, ``Tf`` live on the - faces of the cohesive cells; the
matrix fields ``pm``, ``Tm`` on the split mesh.  The interface conditions
pm = pf and (``equilibrium`` exchange) Tm = Tf on both faces are imposed by
tying the matrix nodes on the walls to the fracture unknowns (docs/fracture.md).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import erfc

from .. import meshing
from ..assembly import FieldScale
from ..balance import BalanceMonitor, Conserved
from ..errors import InputError
from ..fields import FieldSpec
from ..fluid import Viscosity
from ..fracture import FRACTURE_BC, TIP_BC
from ..kernels import contact as ct
from ..kernels import transport as tr
from ..kernels import wells
from ..model import Model
from ..params import CELSIUS, param
from ..solver import Dirichlet
from .base import HeatMaterial, Scene, TimeDefaults, register, with_defaults


# -- parameters ------------------------------------------------------------------------
@dataclass(frozen=True)
class FluidFlow:
    """Fluid flow properties (physics.md sections 4, 5 and 8)"""
    fluid_viscosity: str = param("1e-3", "Pa s", "viscosity: a number, or 'water' for mu(T)")
    fluid_compressibility: float = param(4.5e-10, "1/Pa", "fluid compressibility c_f", lo=0.0)
    fluid_thermal_expansion: float = param(2.07e-4, "1/K", "fluid volumetric thermal expansion beta_f", lo=0.0)


@dataclass(frozen=True)
class HeatExchange:
    """Wall heat exchange between the fracture fluid and the rock (physics.md section 7)"""
    fracture_heat_exchange: str = param("equilibrium", "-",
                                        "wall heat exchange: equilibrium, nusselt, or hw in W/(m2 K)")


@dataclass(frozen=True)
class FractureProps(HeatExchange):
    """Fracture (rigid: fixed aperture)"""
    fracture_aperture: float = param(1e-3, "m", "hydraulic aperture a0", lo=0.0, lo_open=True)


@dataclass(frozen=True)
class Wells:
    """Wells and initial state (physics.md section 9)"""
    injection_rate: float = param(1e-4, "m3/s", "injection rate Q (per metre in 2D)", lo=0.0)
    injection_temperature: float = param(20.0, "degC", "injected water temperature")
    production_pressure: float = param(0.0, "Pa", "producer well pressure")
    initial_temperature: float = param(100.0, "degC", "initial rock and fluid temperature T0")
    initial_pressure: float = param(0.0, "Pa", "initial pressure p0")
    well_radius: float = param(0.1, "m", "well radius r_w (producer well index)", lo=0.0, lo_open=True)


Rock1 = with_defaults(HeatMaterial, rock_density=2820.0, rock_heat_capacity=1170.0,
                      rock_conductivity=2.88)

NUSSELT = 7.54


def _max():
    from mpi4py import MPI
    return MPI.MAX


def _viscosity(fl: FluidFlow) -> Viscosity:
    try:
        return Viscosity.parse(fl.fluid_viscosity)
    except ValueError:
        raise InputError(f"option -thm_fluid_viscosity = {fl.fluid_viscosity} is not a number > 0 "
                         "or 'water'") from None


def exchange_coefficient(he: HeatExchange, aperture: float, fluid_conductivity: float):
    """None for 'equilibrium', else hw (W/(m2 K)): Nu lambda_f / (2 a) or the given number."""
    mode = he.fracture_heat_exchange.strip().lower()
    if mode == "equilibrium":
        return None
    if mode == "nusselt":
        return NUSSELT * fluid_conductivity / (2 * aperture)
    try:
        hw = float(mode)
    except ValueError:
        hw = -1.0
    if not hw > 0:
        raise InputError(f"option -thm_fracture_heat_exchange = {he.fracture_heat_exchange} is not "
                         "equilibrium, nusselt or a number > 0 (W/(m2 K))")
    return hw


class FractureScene(Scene):
    """Shared set-up of the rigid-fracture scenes."""
    fractured = True
    flow_dim = 1                     # dimension of the flow in the fracture (for the well index)
    # sparse direct solves: these coupled, advection-dominated fracture-matrix
    # systems defeat GMRES + GAMG (hundreds of iterations, failed steps)
    direct_solve = True

    def reference_aperture(self) -> float:
        """The fracture's aperture (rigid), or its initial aperture (deformable)."""
        return self[FractureProps].fracture_aperture

    def fracture_model(self, mesh, degree, *, heat: bool, permeability=None, matrix_storage=0.0,
                       matrix_thermal_storage=0.0, rock_conductivity=None, aperture=None,
                       lumped: bool = False) -> Model:
        """Fields, terms and ties: pf (+ Tf, Tm with ``heat``; + pm with a
        ``permeability`` tensor).  ``aperture``: a ``contact.Aperture`` (a
        deformable fracture; the caller adds u and lam), else the fixed
        ``reference_aperture``.  ``lumped`` (P1): the rock's heat capacity and
        the wall exchange by row-sum lumping."""
        fl, m = self[FluidFlow], self.material
        mu = _viscosity(fl)
        a = self.reference_aperture()
        unit = 1.0 if aperture is not None else a          # coefficients per unit aperture, or times a
        d = mesh.dim
        fields = [FieldSpec("pf", 1, degree, "fracture")]
        res, jac, ties = [], [], {}
        Tf = "Tf" if heat else None
        frac_flow = tr.Flow("fracture", "pf", Tf, unit * fl.fluid_compressibility, unit ** 3 / 12 * np.eye(d), mu,
                            unit * fl.fluid_thermal_expansion if heat else 0.0, aperture=aperture)
        r, j = tr.flow_terms(frac_flow)
        res, jac = res + r, jac + j
        matrix_flow = None
        if permeability is not None:
            fields.append(FieldSpec("pm", 1, degree, "matrix"))
            ties["pm"] = "pf"
            matrix_flow = tr.Flow("matrix", "pm", "Tm" if heat else None, matrix_storage, permeability, mu,
                                  matrix_thermal_storage if heat else 0.0)
            r, j = tr.flow_terms(matrix_flow)
            res, jac = res + r, jac + j
        if heat:
            fields += [FieldSpec("Tf", 1, degree, "fracture"), FieldSpec("Tm", 1, degree, "matrix")]
            hw = exchange_coefficient(self[HeatExchange], a, m.fluid_conductivity)
            if hw is not None and aperture is not None and self[HeatExchange].fracture_heat_exchange.strip().lower() \
                    == "nusselt":
                hw = tr.ApertureExchange(NUSSELT * m.fluid_conductivity / 2, aperture)   # hw = Nu lambda_f / (2 a)
            if hw is None:
                ties["Tm"] = "Tf"
            else:
                if permeability is not None:
                    raise InputError("option -thm_fracture_heat_exchange: only 'equilibrium' is implemented "
                                     "with a permeable matrix (the heat carried by leakoff needs the wall flux)")
                r, j = tr.exchange_terms("Tf", ("Tm-", "Tm+"), hw, lumped=lumped)
                res, jac = res + r, jac + j
            frac_heat = tr.Heat("fracture", "Tf", unit * m.fluid_rho_c, unit * m.fluid_conductivity, m.fluid_rho_c,
                                frac_flow, degree, True, aperture=aperture)
            r, j = tr.heat_terms(frac_heat)
            res, jac = res + r, jac + j
            lam = m.conductivity if rock_conductivity is None else rock_conductivity
            mat_heat = tr.Heat("matrix", "Tm", m.rho_c, lam, m.fluid_rho_c, matrix_flow, degree, True, lumped=lumped)
            r, j = tr.heat_terms(mat_heat)
            res, jac = res + r, jac + j
        self._flows = (frac_flow, matrix_flow)
        return Model(fields, res, jac, ties=ties)

    @property
    def material(self):
        return next(v for k, v in self.p.items() if issubclass(k, HeatMaterial))

    def balances(self, heat: bool) -> list[Conserved]:
        """Fluid volume and (with heat) energy balances of physics.md section 7.

        The stored amounts are integrated relative to the initial pressure and
        temperature (constants drop out of the change, and the subtraction of
        two large integrals would lose digits); enthalpy fluxes are in kelvin."""
        frac_flow, matrix_flow = self._flows
        m = self.material
        w = next((v for k, v in self.p.items() if issubclass(k, Wells)), Wells())
        p0, T0 = w.initial_pressure, w.initial_temperature + CELSIUS

        a_ref = self.reference_aperture()

        def aperture(ctx):
            ap = frac_flow.aperture
            return ap.law.aperture(ctx.value(ap.mech.lam)[..., 0], ct.opening(ap.mech, ctx))

        def vol(fl):
            def f(ctx):
                s = fl.storage * (ctx.value(fl.p)[..., 0] - p0)
                if fl.T is not None and fl.thermal_storage:
                    s = s - fl.thermal_storage * (ctx.value(fl.T)[..., 0] - T0)
                if fl.aperture is not None:          # (a - a_ref) + a (c_f dp - beta_f dT)
                    a = aperture(ctx)
                    s = a - a_ref + a * s
                return s
            return f
        storage = {"fracture": vol(frac_flow)}
        if matrix_flow is not None:
            storage["matrix"] = vol(matrix_flow)
        out = [Conserved("mass", ("pf", "pm"), "pf", storage)]
        if heat:
            def frac_energy(ctx):
                Tf = ctx.value("Tf")[..., 0]
                if frac_flow.aperture is None:
                    return a_ref * m.fluid_rho_c * (Tf - T0)
                a = aperture(ctx)                    # a (T - T0) + T0 (a - a_ref): the change of a T
                return m.fluid_rho_c * (a * (Tf - T0) + T0 * (a - a_ref))
            out.append(Conserved("energy", ("Tf", "Tm"), "Tf", {
                "fracture": frac_energy,
                "matrix": lambda ctx: m.rho_c * (ctx.value("Tm")[..., 0] - T0)}))
        return out

    def well_terms(self, mesh, injector_at, producer_at, heat: bool, share: float = 1.0):
        """Injector and producer (``share``: the part of each well in the model, 1/2 on a symmetry plane).
        The producer's well index uses the reference aperture and the viscosity at T0."""
        w = self[Wells]
        mu = _viscosity(self[FluidFlow])
        T_res = w.initial_temperature + CELSIUS
        Th = self.reference_aperture() ** 3 / (12 * mu.mu(T_res))
        surf = mesh.fracture
        h = float(surf.h.min()) if surf.ncells else np.inf
        h = mesh.dm.comm.tompi4py().allreduce(h, op=_min())
        rho_c = self.material.fluid_rho_c
        T = "Tf" if heat else None
        out = []
        if injector_at is not None:
            out.append(wells.injector(injector_at, share * w.injection_rate, rho_c,
                                      w.injection_temperature + CELSIUS, T=T))
        if producer_at is not None:
            PI = share * wells.well_index(float(Th), h, w.well_radius, self.flow_dim)
            out.append(wells.producer(producer_at, w.production_pressure, PI, rho_c, T=T))
        self.wells = out
        return out

    def well_monitors(self, problem, t, X, injector_at, producer_at, heat: bool) -> dict:
        out = {}
        if injector_at is not None:
            out["injection_pressure"] = problem.point_value("pf", injector_at, X, t)
        if producer_at is not None:
            prod = next(p for p in self.wells if p.name == "producer")
            pp = problem.point_value("pf", producer_at, X, t)
            vals = {"pf": pp}
            if heat:
                vals["Tf"] = problem.point_value("Tf", producer_at, X, t)
                out["production_temperature"] = vals["Tf"] - CELSIUS
            out["production_rate"] = prod.residual(vals, t)["pf"]
            out["production_pressure_node"] = pp
        return out

    def balance_monitors(self, problem, t, X) -> dict:
        if getattr(self, "_balance", None) is None or self._balance.problem is not problem:
            self._balance = BalanceMonitor(problem, self.balances(self._heat))
        out = self._balance(t, X)
        for k in ("mass_balance", "energy_balance"):
            if k in out:
                v = abs(out[k])
                self._worst[k] = v if v != v else max(self._worst.get(k, 0.0), v)   # NaN: not evaluated
        return out


def _min():
    from mpi4py import MPI
    return MPI.MIN


def far_sides(width: float, axis: int = 1):
    """Boundary predicate of the two far sides x[axis] = 0 and 2 W of a strip."""
    return lambda x: np.isclose(x[:, axis], 0.0) | np.isclose(x[:, axis], 2 * width)


def strip_with_fracture(path, length, width, size, fracture_size):
    """[0, L] x [0, 2W] with a fracture along y = W cutting both ends, graded toward it."""
    fr = [meshing.Fracture("segment", p0=(0.0, width), p1=(length, width), size=fracture_size)]
    return meshing.box_with_fractures(path, [length, 2 * width], size, fr, grading_distance=0.5 * width)


# -- fracture_flow_patch ------------------------------------------------------------------
@dataclass(frozen=True)
class PatchParams:
    """Linear pressure along a fracture cutting the domain (fracture_flow_patch)"""
    patch_dim: int = param(2, "-", "space dimension", choices=(2, 3))
    patch_length: float = param(100.0, "m", "fracture length (domain length in x)", lo=0.0, lo_open=True)
    patch_inlet_pressure: float = param(1.2e5, "Pa", "pressure at x = 0")
    patch_outlet_pressure: float = param(0.0, "Pa", "pressure at x = L")


@register
class FractureFlowPatch(FractureScene):
    name = "fracture_flow_patch"
    description = "steady cubic-law flow along a fracture: linear pressure, exact for P1 and P2"
    parameter_sets = (with_defaults(FluidFlow, fluid_compressibility=0.0), FractureProps, HeatMaterial,
                      PatchParams)
    time = TimeDefaults(final_time=1.0, dt_initial=1.0, mesh_size=20.0)
    history_columns = ("pressure_error", "flux_error", "mass_balance")
    _heat = False

    def boundaries(self):
        L = self[PatchParams].patch_length
        return {"x0": lambda x: np.isclose(x[:, 0], 0.0), "x1": lambda x: np.isclose(x[:, 0], L)}

    def generate_mesh(self, path, size):
        p = self[PatchParams]
        L = p.patch_length
        if p.patch_dim == 2:
            fr = [meshing.Fracture("segment", p0=(0.0, 0.37 * L), p1=(L, 0.37 * L))]
            return meshing.box_with_fractures(path, [L, L], size, fr)
        fr = [meshing.Fracture("rectangle", center=(0.5 * L, 0.5 * L, 0.43 * L), half=(0.5 * L, 0.3 * L))]
        return meshing.box_with_fractures(path, [L, L, L], size, fr)

    def exact(self, x):
        p = self[PatchParams]
        return p.patch_inlet_pressure + (p.patch_outlet_pressure - p.patch_inlet_pressure) * x[:, 0] / p.patch_length

    def build(self, mesh, degree):
        p = self[PatchParams]
        self._worst = {}
        model = self.fracture_model(mesh, degree, heat=False)
        bcs = [Dirichlet("pf", b, lambda x, t: self.exact(x)) for b in ("x0", "x1")]
        dp = abs(p.patch_inlet_pressure - p.patch_outlet_pressure) or 1.0
        scales = {"pf": FieldScale(dp, p.patch_outlet_pressure)}
        return model, bcs, scales, {"pf": lambda x: np.full(len(x), p.patch_outlet_pressure)}

    def _errors(self, problem, t, X=None):
        p = self[PatchParams]
        dp = abs(p.patch_inlet_pressure - p.patch_outlet_pressure)
        err = problem.max_nodal_error("pf", self.exact, X, t)
        # outflow at x = L: the consistent reaction of the Dirichlet condition
        fl = self._flows[0]
        width = 1.0 if p.patch_dim == 2 else 0.6 * p.patch_length
        q_exact = fl.permeability[0, 0] / fl.viscosity.value * dp / p.patch_length * width
        rl = self._balance.last_residual if getattr(self, "_balance", None) else None
        if rl is None:
            return err / dp, None
        q_out = -problem.reaction(rl, ("pf",), ("x1",))
        return err / dp, abs(q_out - q_exact) / q_exact

    def monitors(self, problem, t, X=None):
        out = self.balance_monitors(problem, t, X)
        pe, fe = self._errors(problem, t, X)
        out.update({"pressure_error": pe, "flux_error": fe if fe is not None else ""})
        self._last = (pe, fe)
        return out

    def report(self, problem, t):
        pe, fe = self._last
        return {"error": {"pf_max_rel": pe, "flux_rel": fe}, "balance_max": self._worst}


# -- radial_flow ------------------------------------------------------------------------------
@dataclass(frozen=True)
class RadialParams:
    """Point injector at the centre of a disc fracture, pressure fixed on the rim (radial_flow)"""
    radial_radius: float = param(100.0, "m", "disc radius R", lo=0.0, lo_open=True)
    radial_well_size: float = param(1.0, "m", "mesh size at the well", lo=0.0, lo_open=True)
    radial_rim_pressure: float = param(0.0, "Pa", "pressure p_R on the rim")


@register
class RadialFlow(FractureScene):
    name = "radial_flow"
    description = "point injector in a disc fracture: p = p_R + Q/(2 pi T_h) ln(R/r) (verification.md 3b)"
    parameter_sets = (with_defaults(FluidFlow, fluid_compressibility=0.0),
                      with_defaults(FractureProps, fracture_aperture=2e-4), HeatMaterial,
                      with_defaults(Wells, injection_rate=1e-3), RadialParams)
    time = TimeDefaults(final_time=1.0, dt_initial=1.0, mesh_size=25.0)
    history_columns = ("injection_pressure", "error_5h", "mass_balance")
    flow_dim = 2
    _heat = False

    def generate_mesh(self, path, size):
        p = self[RadialParams]
        R = p.radial_radius
        c = (1.5 * R, 1.5 * R, 1.5 * R)
        fr = [meshing.Fracture("disc", center=c, radius=R, size=min(size, R / 8))]
        return meshing.box_with_fractures(path, [3 * R] * 3, 2 * size, fr, grading_distance=R,
                                          wells=[c], well_size=p.radial_well_size)

    def centre(self):
        return np.full(3, 1.5 * self[RadialParams].radial_radius)

    def exact(self, x):
        p, w = self[RadialParams], self[Wells]
        Th = self[FractureProps].fracture_aperture ** 3 / (12 * _viscosity(self[FluidFlow]).value)
        r = np.linalg.norm(x - self.centre()[None, :], axis=1)
        return p.radial_rim_pressure + w.injection_rate / (2 * np.pi * Th) * np.log(p.radial_radius / np.maximum(r, 1e-300))

    def build(self, mesh, degree):
        p = self[RadialParams]
        self._worst = {}
        model = self.fracture_model(mesh, degree, heat=False)
        model.points.extend(self.well_terms(mesh, tuple(self.centre()), None, heat=False))
        bcs = [Dirichlet("pf", TIP_BC, lambda x, t: np.full(len(x), p.radial_rim_pressure))]
        ref = float(self.exact(self.centre()[None, :] + [[p.radial_radius / 100, 0, 0]])[0]) - p.radial_rim_pressure
        scales = {"pf": FieldScale(ref, p.radial_rim_pressure)}
        return model, bcs, scales, {"pf": lambda x: np.full(len(x), p.radial_rim_pressure)}

    def _error(self, problem, t, X=None):
        """Max |p - p_exact| over fracture nodes at r >= 5 h_well, relative to
        the largest pressure rise p_exact - p_R among them (verification.md 3b)."""
        p = self[RadialParams]
        comm = problem.dm.comm.tompi4py()
        v = problem.field_values("pf", X, t)[:, 0]
        x = problem.disc.field_node_coordinates("pf")
        r = np.linalg.norm(x - self.centre()[None, :], axis=1)
        sel = r >= 5 * p.radial_well_size
        ex = self.exact(x[sel])
        e = comm.allreduce(float(np.max(np.abs(v[sel] - ex))) if sel.any() else 0.0, op=_max())
        rise = comm.allreduce(float(np.max(ex - p.radial_rim_pressure)) if sel.any() else 0.0, op=_max())
        return e / rise

    def monitors(self, problem, t, X=None):
        out = {"injection_pressure": problem.point_value("pf", tuple(self.centre()), X, t),
               "error_5h": self._error(problem, t, X)}
        out.update(self.balance_monitors(problem, t, X))
        return out

    def report(self, problem, t):
        return {"error": {"pf_rel_beyond_5h": self._error(problem, t)}, "balance_max": self._worst}


# -- leakoff_1d ------------------------------------------------------------------------------------
@dataclass(frozen=True)
class LeakoffParams:
    """Fracture pressure step, 1D diffusion into the matrix on both sides (leakoff_1d)"""
    leakoff_length: float = param(10.0, "m", "fracture length (domain length in x)", lo=0.0, lo_open=True)
    leakoff_width: float = param(60.0, "m", "matrix on each side of the fracture", lo=0.0, lo_open=True)
    leakoff_pressure_step: float = param(1e6, "Pa", "fracture overpressure dp for t > 0", lo=0.0, lo_open=True)
    leakoff_storage: float = param(1e-9, "1/Pa", "matrix storage S", lo=0.0, lo_open=True)
    leakoff_fracture_size: float = param(0.05, "m", "mesh size at the fracture", lo=0.0, lo_open=True)


@dataclass(frozen=True)
class LeakoffPerm:
    """Matrix permeability (leakoff_1d)"""
    rock_permeability: float = param(1e-15, "m2", "matrix permeability k_m", lo=0.0, lo_open=True)


@register
class Leakoff1D(FractureScene):
    name = "leakoff_1d"
    description = "fracture pressure step: cumulative leakoff 4 dp S L sqrt(c t/pi) (both faces)"
    parameter_sets = (FluidFlow, FractureProps, with_defaults(HeatMaterial), with_defaults(Wells, initial_pressure=0.0),
                      LeakoffParams, LeakoffPerm)
    time = TimeDefaults(final_time=1e5, dt_initial=1.0, dt_growth=1.05, dt_max=2e3, mesh_size=5.0)
    history_columns = ("leakoff_rate", "leakoff_volume", "leakoff_stored", "leakoff_exact", "leakoff_error",
                       "mass_balance")
    _heat = False

    def boundaries(self):
        return {"far": far_sides(self[LeakoffParams].leakoff_width)}

    def generate_mesh(self, path, size):
        p = self[LeakoffParams]
        return strip_with_fracture(path, p.leakoff_length, p.leakoff_width, size, p.leakoff_fracture_size)

    def diffusivity(self):
        mu = _viscosity(self[FluidFlow]).value
        return self[LeakoffPerm].rock_permeability / (mu * self[LeakoffParams].leakoff_storage)

    def exact_volume(self, t):
        """Both faces: 2 x L x 2 dp S sqrt(c t / pi)."""
        p = self[LeakoffParams]
        return 4 * p.leakoff_pressure_step * p.leakoff_storage * p.leakoff_length * \
            math.sqrt(self.diffusivity() * t / math.pi)

    def hit_times(self):
        return [1e3, 1e4, 1e5]

    def build(self, mesh, degree):
        p, w = self[LeakoffParams], self[Wells]
        self._worst, self._samples = {}, {}
        k = self[LeakoffPerm].rock_permeability
        model = self.fracture_model(mesh, degree, heat=False, permeability=k * np.eye(mesh.dim),
                                    matrix_storage=p.leakoff_storage)
        p0, p1 = w.initial_pressure, w.initial_pressure + p.leakoff_pressure_step
        bcs = [Dirichlet("pf", FRACTURE_BC, lambda x, t: np.full(len(x), p1)),
               Dirichlet("pm", "far", lambda x, t: np.full(len(x), p0))]
        sc = FieldScale(p.leakoff_pressure_step, p0)
        scales = {"pf": sc, "pm": FieldScale(sc.scale, sc.offset)}
        init = {"pf": lambda x: np.full(len(x), p1), "pm": lambda x: np.full(len(x), p0)}
        return model, bcs, scales, init

    def _volume(self, problem, t, X=None):
        """Leaked volume = stored matrix volume S (pm - p0) + volume lost at the far sides."""
        p, w = self[LeakoffParams], self[Wells]
        xl, _ = problem.local_arrays(X or problem.X, t)
        return problem.region("matrix").integrate(
            xl, lambda ctx: p.leakoff_storage * (ctx.value("pm")[..., 0] - w.initial_pressure), t)

    def monitors(self, problem, t, X=None):
        """Leakoff rate = inflow through the fracture's pressure condition (the
        consistent reaction); volume = its backward-Euler time integral."""
        out = self.balance_monitors(problem, t, X)
        rl = self._balance.last_residual
        rate = problem.reaction(rl, ("pf", "pm"), boundaries=(FRACTURE_BC,)) if rl is not None else 0.0
        prev_t, prev_V = getattr(self, "_cum", (t, 0.0))
        V = prev_V + (t - prev_t) * rate
        self._cum = (t, V)
        ex = self.exact_volume(t)
        out.update({"leakoff_rate": rate, "leakoff_volume": V, "leakoff_stored": self._volume(problem, t, X),
                    "leakoff_exact": ex, "leakoff_error": abs(V - ex) / ex if ex > 0 else 0.0})
        for th in self.hit_times():
            if abs(t - th) <= 1e-9 * th:
                self._samples[th] = out["leakoff_error"]
        return out

    def report(self, problem, t):
        return {"error": {f"leakoff_rel_t{th:g}": e for th, e in sorted(self._samples.items())},
                "balance_max": self._worst}


def lauwerier_temperature(x, t, q, aperture, rho_c, conductivity, fluid_rho_c, T0, Ti):
    """Lauwerier (1955) fracture temperature (verification.md section 1):
    T0 + (Ti - T0) erfc(lambda x / (rho_f c_f q sqrt(kappa (t - t_d)))) U(t - t_d),
    t_d = a x / q, kappa = lambda / (rho C); q per metre of fracture height."""
    x = np.asarray(x, dtype=float)
    kappa = conductivity / rho_c
    td = aperture * x / q
    tt = np.maximum(t - td, 1e-300)
    arg = conductivity * x / (fluid_rho_c * q * np.sqrt(kappa * tt))
    return np.where(t > td, T0 + (Ti - T0) * erfc(arg), T0)


# -- lauwerier ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class LauwerierParams:
    """Fracture in impermeable hot rock (lauwerier; verification.md section 1)"""
    lauwerier_length: float = param(100.0, "m", "fracture length L (injector at x = 0, producer at x = L)",
                                    lo=0.0, lo_open=True)
    lauwerier_width: float = param(60.0, "m", "rock on each side of the fracture", lo=0.0, lo_open=True)
    lauwerier_fracture_size: float = param(0.5, "m", "mesh size at the fracture", lo=0.0, lo_open=True)
    lauwerier_dim: int = param(2, "-", "2: plane strain (H = 1 m); 3: a slab of height H with line wells",
                               choices=(2, 3))
    lauwerier_height: float = param(1.0, "m", "slab height H (3D; Q is the slab's total rate)",
                                    lo=0.0, lo_open=True)
    lauwerier_rock_conduction: str = param("full", "-", "full, or normal: conduction in the rock only "
                                           "normal to the fracture (the analytical solution's assumption)",
                                           choices=("full", "normal"))


@register
class Lauwerier(FractureScene):
    name = "lauwerier"
    description = "cold water through a fracture in impermeable rock vs Lauwerier (2D, H = 1 m)"
    parameter_sets = (FluidFlow, FractureProps, Rock1, Wells, LauwerierParams)
    time = TimeDefaults(final_time=1e8, dt_initial=100.0, dt_growth=1.05, dt_max=1e6, mesh_size=10.0,
                        output_interval=20)
    history_columns = ("injection_pressure", "production_temperature", "production_rate", "outlet_error",
                       "Tf_min", "Tf_max", "mass_balance", "energy_balance")
    _heat = True
    profile_times = (1e7, 1e8)

    def boundaries(self):
        p = self[LauwerierParams]
        return {"far": far_sides(p.lauwerier_width, p.lauwerier_dim - 1)}   # normal axis: y (2D), z (3D)

    def generate_mesh(self, path, size):
        p = self[LauwerierParams]
        L, W, H = p.lauwerier_length, p.lauwerier_width, p.lauwerier_height
        if p.lauwerier_dim == 2:
            return strip_with_fracture(path, L, W, size, p.lauwerier_fracture_size)
        fr = [meshing.Fracture("rectangle", center=(0.5 * L, 0.5 * H, W), half=(0.5 * L, 0.5 * H),
                               size=p.lauwerier_fracture_size)]
        return meshing.box_with_fractures(path, [L, H, 2 * W], size, fr, grading_distance=0.5 * W)

    def wells_at(self):
        p = self[LauwerierParams]
        return (0.0, p.lauwerier_width), (p.lauwerier_length, p.lauwerier_width)

    def line_nodes(self, mesh, degree, x_line):
        """The fracture nodes on the well line x = x_line (3D slab), sorted by y, with
        the consistent nodal weights of a uniform line density (sum = H)."""
        surf, comm = mesh.fracture, mesh.dm.comm.tompi4py()
        pts = [mesh.vertex_coords[surf.cell_vertices.ravel()]]
        if degree == 2:
            pts.append(mesh.edge_midpoints()[surf.cell_edges.ravel() - mesh.estart])
        X = np.concatenate(pts)
        X = X[np.abs(X[:, 0] - x_line) < 1e-9 * self[LauwerierParams].lauwerier_length]
        X = np.concatenate(comm.allgather(X))
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

    def slab_wells(self, mesh, degree):
        """Line injector at x = 0 and line producer at x = L (3D slab)."""
        p, w, fp = self[LauwerierParams], self[Wells], self[FractureProps]
        rho_c = self.material.fluid_rho_c
        mu = _viscosity(self[FluidFlow])
        Th = fp.fracture_aperture ** 3 / (12 * mu.mu(w.initial_temperature + CELSIUS))
        PI_line = wells.well_index(float(Th), 0.0, w.well_radius, 1)          # per metre of line
        Xi, wi = self.line_nodes(mesh, degree, 0.0)
        Xp, wp = self.line_nodes(mesh, degree, p.lauwerier_length)
        H = p.lauwerier_height
        out = [wells.injector(tuple(x), w.injection_rate * c / H, rho_c, w.injection_temperature + CELSIUS,
                              name=f"injector_{i}") for i, (x, c) in enumerate(zip(Xi, wi))]
        out += [wells.producer(tuple(x), w.production_pressure, PI_line * c, rho_c, name=f"producer_{i}")
                for i, (x, c) in enumerate(zip(Xp, wp))]
        self.wells = out
        self._slab = (Xi, wi, Xp, wp)
        return out

    def slab_monitors(self, problem, t, X):
        """Injection pressure: mean over the inlet line; production: rate and the
        flow-weighted temperature of the outlet line."""
        Xi, wi, Xp, wp = self._slab
        pin = [problem.point_value("pf", x, X, t) for x in Xi]
        qs, Ts = [], []
        for term, x in zip([w for w in self.wells if w.name.startswith("producer")], Xp):
            v = {"pf": problem.point_value("pf", x, X, t), "Tf": problem.point_value("Tf", x, X, t)}
            qs.append(term.residual(v, t)["pf"])
            Ts.append(v["Tf"])
        qs, Ts = np.array(qs), np.array(Ts)
        return {"injection_pressure": float(np.dot(pin, wi) / wi.sum()), "production_rate": float(qs.sum()),
                "production_temperature": float(np.dot(qs, Ts) / qs.sum()) - CELSIUS}

    def exact(self, x, t):
        """Lauwerier's T_f(x, t) in kelvin (with the transit delay t_d = a x / q)."""
        w, m, fp = self[Wells], self[Rock1], self[FractureProps]
        lp = self[LauwerierParams]
        q = w.injection_rate / (lp.lauwerier_height if lp.lauwerier_dim == 3 else 1.0)
        return lauwerier_temperature(x, t, q, fp.fracture_aperture, m.rho_c, m.conductivity, m.fluid_rho_c,
                                     w.initial_temperature + CELSIUS, w.injection_temperature + CELSIUS)

    def hit_times(self):
        return [1e6, 1e7, 1e8]

    def build(self, mesh, degree):
        w = self[Wells]
        self._worst, self._profile, self._outlet = {}, {}, []
        lp = self[LauwerierParams]
        lam = None
        if lp.lauwerier_rock_conduction == "normal":       # only across the fracture
            lam = np.zeros((mesh.dim, mesh.dim))
            lam[mesh.dim - 1, mesh.dim - 1] = self.material.conductivity
        model = self.fracture_model(mesh, degree, heat=True, rock_conductivity=lam)
        if self[LauwerierParams].lauwerier_dim == 3:
            model.points.extend(self.slab_wells(mesh, degree))
        else:
            inj, prod = self.wells_at()
            model.points.extend(self.well_terms(mesh, inj, prod, heat=True))
        T0, Ti = w.initial_temperature + CELSIUS, w.injection_temperature + CELSIUS
        bcs = [Dirichlet("Tm", "far", lambda x, t: np.full(len(x), T0))]
        Th = self[FractureProps].fracture_aperture ** 3 / 12 / _viscosity(self[FluidFlow]).mu(Ti)
        Th = Th * self[LauwerierParams].lauwerier_height if self[LauwerierParams].lauwerier_dim == 3 else Th
        dp = float(w.injection_rate * self[LauwerierParams].lauwerier_length / Th)
        sT = FieldScale(abs(T0 - Ti) or 1.0, T0)
        scales = {"pf": FieldScale(dp, w.production_pressure), "Tf": sT, "Tm": FieldScale(sT.scale, sT.offset)}
        p_init = lambda x: np.full(len(x), w.initial_pressure)  # noqa: E731
        T_init = lambda x: np.full(len(x), T0)  # noqa: E731
        return model, bcs, scales, {"pf": p_init, "Tf": T_init, "Tm": T_init}

    def _fracture_error(self, problem, t, X=None):
        """Max over fracture nodes of |Tf - T_exact| / (T0 - Tinj), and Tf's range."""
        w = self[Wells]
        comm = problem.dm.comm.tompi4py()
        v = problem.field_values("Tf", X, t)[:, 0]
        x = problem.disc.field_node_coordinates("Tf")[:, 0]
        dT = abs(w.initial_temperature - w.injection_temperature)
        e = float(np.abs(v - self.exact(x, t)).max()) / dT if len(v) else 0.0
        lo = comm.allreduce(float(v.min()) if len(v) else np.inf, op=_min()) - CELSIUS
        hi = comm.allreduce(float(v.max()) if len(v) else -np.inf, op=_max()) - CELSIUS
        return comm.allreduce(e, op=_max()), lo, hi

    def monitors(self, problem, t, X=None):
        w = self[Wells]
        inj, prod = self.wells_at()
        if self[LauwerierParams].lauwerier_dim == 3:
            out = self.slab_monitors(problem, t, X)
        else:
            out = self.well_monitors(problem, t, X, inj, prod, heat=True)
        dT = abs(w.initial_temperature - w.injection_temperature)
        ex = float(self.exact(np.array([prod[0]]), t)[0]) - CELSIUS
        out["outlet_error"] = abs(out["production_temperature"] - ex) / dT
        if t >= 1e6 * (1 - 1e-12):
            self._outlet.append(out["outlet_error"])
        e, lo, hi = self._fracture_error(problem, t, X)
        out.update({"Tf_min": lo, "Tf_max": hi})
        bound = max(lo < min(w.injection_temperature, w.initial_temperature) and
                    (min(w.injection_temperature, w.initial_temperature) - lo) / dT or 0.0,
                    hi > max(w.injection_temperature, w.initial_temperature) and
                    (hi - max(w.injection_temperature, w.initial_temperature)) / dT or 0.0)
        self._worst["Tf_bounds_violation"] = max(self._worst.get("Tf_bounds_violation", 0.0), bound)
        for th in self.profile_times:
            if abs(t - th) <= 1e-9 * th:
                self._profile[th] = e
        out.update(self.balance_monitors(problem, t, X))
        return out

    def report(self, problem, t):
        err = {"outlet_max_rel_t_ge_1e6": max(self._outlet) if self._outlet else None}
        err.update({f"profile_max_rel_t{th:g}": v for th, v in sorted(self._profile.items())})
        return {"error": err, "balance_max": self._worst,
                "heat_exchange": self[FractureProps].fracture_heat_exchange}


# -- rigid_fracture (Scene 1) ---------------------------------------------------------------------------
@dataclass(frozen=True)
class Scene1Params:
    """Scene 1 of the paper: rigid fracture in a permeable matrix (rigid_fracture)"""
    rock_permeability: tuple = param((0.0, 1e-14), "m2",
                                     "matrix permeability: k (isotropic) or kxx,kyy (0,k: '1D leakoff', "
                                     "normal to the fracture); 0 = impermeable (no pm)", lo=0.0)
    scene1_length: float = param(100.0, "m", "fracture length (injector at x = 0, producer at x = L)",
                                 lo=0.0, lo_open=True)
    scene1_margin: float = param(150.0, "m", "rock beyond the fracture in every direction", lo=0.0, lo_open=True)
    scene1_fracture_size: float = param(1.0, "m", "mesh size at the fracture", lo=0.0, lo_open=True)


Rock1Porous = with_defaults(Rock1, rock_porosity=0.1)


@register
class RigidFracture(FractureScene):
    name = "rigid_fracture"
    description = "Scene 1: cold water through a rigid fracture with leakoff into a permeable matrix (2D)"
    parameter_sets = (with_defaults(FluidFlow, fluid_viscosity="water"), FractureProps, Rock1Porous, Wells,
                      Scene1Params)
    time = TimeDefaults(final_time=1e9, dt_initial=100.0, dt_growth=1.05, dt_max=5e6, mesh_size=25.0,
                        output_interval=25)
    history_columns = ("injection_pressure", "production_temperature", "production_rate", "leakoff_fraction",
                       "Tf_min", "Tf_max", "mass_balance", "energy_balance")
    _heat = True

    def permeability(self, dim):
        k = self[Scene1Params].rock_permeability
        if len(k) == 1:
            K = k[0] * np.eye(dim)
        elif len(k) == dim:
            K = np.diag(k)
        else:
            raise InputError(f"option -thm_rock_permeability takes 1 or {dim} values, got {len(k)}")
        return None if not K.any() else K

    def boundaries(self):
        p = self[Scene1Params]
        L, M = p.scene1_length, p.scene1_margin
        return {"far": lambda x: np.isclose(x[:, 0], -M) | np.isclose(x[:, 0], L + M) |
                np.isclose(x[:, 1], -M) | np.isclose(x[:, 1], M)}

    def generate_mesh(self, path, size):
        p = self[Scene1Params]
        L, M = p.scene1_length, p.scene1_margin
        fr = [meshing.Fracture("segment", p0=(0.0, 0.0), p1=(L, 0.0), size=p.scene1_fracture_size)]
        return meshing.box_with_fractures(path, [L + 2 * M, 2 * M], size, fr, grading_distance=0.5 * M,
                                          origin=(-M, -M))

    def wells_at(self):
        return (0.0, 0.0), (self[Scene1Params].scene1_length, 0.0)

    def hit_times(self):
        return [1e8]

    def build(self, mesh, degree):
        w, fl = self[Wells], self[FluidFlow]
        m = self.material
        self._worst, self._profile = {}, None
        K = self.permeability(mesh.dim)
        model = self.fracture_model(mesh, degree, heat=True, permeability=K,
                                    matrix_storage=m.rock_porosity * fl.fluid_compressibility,
                                    matrix_thermal_storage=m.rock_porosity * fl.fluid_thermal_expansion)
        inj, prod = self.wells_at()
        model.points.extend(self.well_terms(mesh, inj, prod, heat=True))
        T0, Ti = w.initial_temperature + CELSIUS, w.injection_temperature + CELSIUS
        p0 = w.initial_pressure
        bcs = [Dirichlet("Tm", "far", lambda x, t: np.full(len(x), T0))]
        if K is not None:
            bcs.append(Dirichlet("pm", "far", lambda x, t: np.full(len(x), p0)))
        Th = self[FractureProps].fracture_aperture ** 3 / 12 / _viscosity(fl).mu(Ti)
        dp = float(w.injection_rate * self[Scene1Params].scene1_length / Th)
        sp, sT = FieldScale(dp, w.production_pressure), FieldScale(abs(T0 - Ti) or 1.0, T0)
        scales = {"pf": sp, "Tf": sT, "Tm": FieldScale(sT.scale, sT.offset)}
        init = {"pf": lambda x: np.full(len(x), p0), "Tf": lambda x: np.full(len(x), T0),
                "Tm": lambda x: np.full(len(x), T0)}
        if K is not None:
            scales["pm"] = FieldScale(sp.scale, sp.offset)
            init["pm"] = lambda x: np.full(len(x), p0)
        return model, bcs, scales, init

    def monitors(self, problem, t, X=None):
        w = self[Wells]
        inj, prod = self.wells_at()
        out = self.well_monitors(problem, t, X, inj, prod, heat=True)
        out["leakoff_fraction"] = 1.0 - out["production_rate"] / w.injection_rate if w.injection_rate else 0.0
        v = problem.field_values("Tf", X, t)[:, 0] - CELSIUS
        comm = problem.dm.comm.tompi4py()
        lo = comm.allreduce(float(v.min()) if len(v) else np.inf, op=_min())
        hi = comm.allreduce(float(v.max()) if len(v) else -np.inf, op=_max())
        out.update({"Tf_min": lo, "Tf_max": hi})
        dT = abs(w.initial_temperature - w.injection_temperature)
        viol = max(0.0, min(w.injection_temperature, w.initial_temperature) - lo,
                   hi - max(w.injection_temperature, w.initial_temperature)) / dT
        self._worst["Tf_bounds_violation"] = max(self._worst.get("Tf_bounds_violation", 0.0), viol)
        if abs(t - 1e8) <= 1e-9 * 1e8:
            x = problem.disc.field_node_coordinates("Tf")[:, 0]
            xs = comm.gather(x, root=0)
            vs = comm.gather(v, root=0)
            if comm.rank == 0:
                xa, va = np.concatenate(xs), np.concatenate(vs)
                order = np.argsort(xa)
                self._profile = {"x": xa[order].tolist(), "Tf": va[order].tolist()}
        out.update(self.balance_monitors(problem, t, X))
        self._last = out
        return out

    def report(self, problem, t):
        out = {"balance_max": self._worst, "production_temperature_final": self._last.get("production_temperature"),
               "permeability": list(self[Scene1Params].rock_permeability)}
        if self._profile is not None:
            import json
            import os
            path = os.path.join(self.run.output_dir or os.path.join("output", self.name), "profile_1e8.json")
            with open(path, "w") as f:
                json.dump(self._profile, f)
            out["profile_file"] = os.path.basename(path)
        return out


# -- leakoff_heat (verification.md section 2) -------------------------------------------------------
@dataclass(frozen=True)
class LeakoffHeatParams:
    """Fracture heat transport with a uniform leakoff fraction m (leakoff_heat; verification.md 2)"""
    leakoff_fraction: float = param(0.25, "-", "fraction m of the injected rate lost over the fracture",
                                    lo=0.0, hi=1.0, lo_open=True)
    leakoff_heat_length: float = param(100.0, "m", "fracture length L", lo=0.0, lo_open=True)
    leakoff_heat_width: float = param(60.0, "m", "matrix on each side (pressure p_W there)", lo=0.0, lo_open=True)
    leakoff_heat_fracture_size: float = param(0.5, "m", "mesh size at the fracture", lo=0.0, lo_open=True)
    leakoff_heat_permeability: float = param(1e-14, "m2", "matrix permeability", lo=0.0, lo_open=True)


@register
class LeakoffHeat(FractureScene):
    name = "leakoff_heat"
    description = "uniform leakoff fraction m: outlet temperature vs the Laplace-domain solution (verification.md 2)"
    parameter_sets = (with_defaults(FluidFlow, fluid_compressibility=0.0, fluid_thermal_expansion=0.0),
                      with_defaults(FractureProps, fracture_aperture=3e-3), Rock1, Wells, LeakoffHeatParams)
    time = TimeDefaults(final_time=1e8, dt_initial=100.0, dt_growth=1.03, dt_max=5e5, mesh_size=10.0,
                        output_interval=25)
    history_columns = ("injection_pressure", "production_temperature", "production_rate", "leakoff_rate",
                       "outlet_error", "mass_balance", "energy_balance")
    _heat = True

    def boundaries(self):
        return {"far": far_sides(self[LeakoffHeatParams].leakoff_heat_width)}

    def generate_mesh(self, path, size):
        p = self[LeakoffHeatParams]
        return strip_with_fracture(path, p.leakoff_heat_length, p.leakoff_heat_width, size,
                                   p.leakoff_heat_fracture_size)

    def wells_at(self):
        p = self[LeakoffHeatParams]
        return (0.0, p.leakoff_heat_width), (p.leakoff_heat_length, p.leakoff_heat_width)

    def overpressure(self):
        """p_f - p_W giving the leakoff velocity v_L = m q0 / (2L) = k dp / (mu W)."""
        p, w = self[LeakoffHeatParams], self[Wells]
        mu = _viscosity(self[FluidFlow]).value
        vL = p.leakoff_fraction * w.injection_rate / (2 * p.leakoff_heat_length)
        return vL * mu * p.leakoff_heat_width / p.leakoff_heat_permeability

    def exact_outlet(self, t):
        from ..analytic import leakoff_outlet_temperature
        p, w, m = self[LeakoffHeatParams], self[Wells], self[Rock1]
        return leakoff_outlet_temperature(
            p.leakoff_heat_length, t, q0=w.injection_rate, m=p.leakoff_fraction, L=p.leakoff_heat_length,
            fluid_rho_c=m.fluid_rho_c, rock_rho_c=m.rho_c, rock_conductivity=m.conductivity,
            T0=w.initial_temperature, Tinj=w.injection_temperature, advection=True)

    def hit_times(self):
        return [1e6, 1e7, 1e8]

    def build(self, mesh, degree):
        p, w = self[LeakoffHeatParams], self[Wells]
        m = self.material
        if m.rock_porosity != 0:
            raise InputError("option -thm_rock_porosity: leakoff_heat needs 0 (the reference has C_m = rho_s C_s)")
        self._worst, self._errors = {}, {}
        K = p.leakoff_heat_permeability * np.eye(mesh.dim)
        model = self.fracture_model(mesh, degree, heat=True, permeability=K)
        inj, prod = self.wells_at()
        rho_c = m.fluid_rho_c
        self.wells = [wells.injector(inj, w.injection_rate, rho_c, w.injection_temperature + CELSIUS),
                      wells.rate_producer(prod, (1 - p.leakoff_fraction) * w.injection_rate, rho_c)]
        model.points.extend(self.wells)
        T0, Ti = w.initial_temperature + CELSIUS, w.injection_temperature + CELSIUS
        pW, dp = w.initial_pressure, self.overpressure()
        W = p.leakoff_heat_width
        bcs = [Dirichlet("Tm", "far", lambda x, t: np.full(len(x), T0)),
               Dirichlet("pm", "far", lambda x, t: np.full(len(x), pW))]
        sp, sT = FieldScale(dp, pW), FieldScale(abs(T0 - Ti), T0)
        scales = {"pf": sp, "pm": FieldScale(sp.scale, sp.offset), "Tf": sT, "Tm": FieldScale(sT.scale, sT.offset)}
        steady = lambda x: pW + dp * (1 - np.abs(x[:, 1] - W) / W)  # noqa: E731
        init = {"pf": steady, "pm": steady, "Tf": lambda x: np.full(len(x), T0), "Tm": lambda x: np.full(len(x), T0)}
        return model, bcs, scales, init

    def monitors(self, problem, t, X=None):
        w = self[Wells]
        inj, prod = self.wells_at()
        out = {"injection_pressure": problem.point_value("pf", inj, X, t),
               "production_temperature": problem.point_value("Tf", prod, X, t) - CELSIUS,
               "production_rate": self.wells[1].residual({"pf": 0.0, "Tf": 0.0}, t)["pf"]}
        out.update(self.balance_monitors(problem, t, X))
        rl = self._balance.last_residual
        out["leakoff_rate"] = -problem.reaction(rl, ("pm",), ("far",)) if rl is not None else 0.0
        ex = self.exact_outlet(t)
        out["outlet_error"] = abs(out["production_temperature"] - ex) / abs(w.initial_temperature -
                                                                             w.injection_temperature)
        for th in self.hit_times():
            if abs(t - th) <= 1e-9 * th:
                self._errors[th] = out["outlet_error"]
        return out

    def report(self, problem, t):
        err = {f"outlet_rel_t{th:g}": e for th, e in sorted(self._errors.items())}
        err["outlet_max_rel"] = max(self._errors.values()) if self._errors else None
        return {"error": err, "balance_max": self._worst}
