"""Coupled THM scenes with a deformable fracture (issue 4; physics.md
sections 2-4, 7-11).

* ``penny_impermeable``: Scene 2 of the paper.  A horizontal penny fracture
  (R = 100 m) in impermeable rock; cold water injected 50 m left of the
  centre and produced at constant pressure 50 m right of it.  Fields u, pf,
  Tf, Tm and the contact traction lam (no pm).  The cooled rock contracts,
  the contact traction falls and the aperture a = ac(lam) + max(g, 0) rises.

The model is the half y >= 0 (the wells lie on the symmetry plane y = 0 and
carry half their rate).  Tm = Tf on the fracture walls ("equilibrium", the
default), or the walls exchange heat with hw = Nu lambda_f / (2 a) at the
local aperture ("nusselt": local thermal non-equilibrium, the paper's model;
on the default mesh it overshoots in the first 1e4 s, docs/scene2.md).  The strain heating
of section 6 is an option (-thm_thermomechanical_heating, off by default as
section 6 allows); the rock has no pores.
"""
from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from .. import meshing
from ..assembly import FieldScale
from ..errors import InputError
from ..fields import FieldSpec
from ..fracture import TIP_BC
from ..kernels import contact as ct
from ..kernels import poroelastic as pe
from ..params import CELSIUS, param
from ..solver import Dirichlet
from .base import HeatMaterial, TimeDefaults, register, with_defaults
from .contact import GAP_TOLERANCE, OPEN_TRACTION, ElasticRock, Joint, MechanicsScene, zero
from .fracture import FluidFlow, FractureScene, HeatExchange, Wells, _max, _min, _viscosity


@dataclass(frozen=True)
class Scene2Params:
    """Scene 2 of the paper: deformable penny fracture in impermeable rock (penny_impermeable)"""
    scene2_radius: float = param(100.0, "m", "fracture radius R", lo=0.0, lo_open=True)
    scene2_well_offset: float = param(50.0, "m", "distance of each well from the centre (< R)", lo=0.0, lo_open=True)
    scene2_normal_stress: float = param(60e6, "Pa", "in-situ compressive stress normal to the fracture",
                                        lo=0.0, lo_open=True)
    rock_thermal_expansion: float = param(2.4e-5, "1/K", "rock volumetric thermal expansion beta_s", lo=0.0)
    scene2_box: float = param(3.0, "-", "domain half-size / R (the rock beyond the fracture)", lo=1.5)
    scene2_fracture_size: float = param(10.0, "m", "mesh size on the fracture", lo=0.0, lo_open=True)
    scene2_well_size: float = param(5.0, "m", "mesh size at the wells", lo=0.0, lo_open=True)
    scene2_layer: float = param(0.5, "m", "thickness of the first rock layer on each side of the fracture "
                                "(layered mesh, growing by -thm_scene2_layer_growth); 0: unstructured tetrahedra",
                                lo=0.0)
    scene2_layer_growth: float = param(1.5, "-", "thickness ratio of successive layers", lo=1.0, hi=3.0)
    scene2_lumped_heat: bool = param(True, "-", "row-sum lumping of the rock heat capacity and the wall "
                                     "exchange (keeps Tf and Tm within [Tinj, T0] on thin layers)")
    thermomechanical_heating: bool = param(False, "-", "the strain heating beta_s K Tm d(div u)/dt of "
                                           "physics.md section 6 (an energy source the balance leaves out)")
    scene2_tip_traction: str = param("insitu", "-", "lam at the fracture front: insitu (its initial value) "
                                     "or zero", choices=("insitu", "zero"))


#: a Tf more than this fraction of [Tinj, T0] outside it is reported as a warning
TF_BOUNDS_WARNING = 0.05

Scene2Wells = with_defaults(Wells, injection_rate=1e-3, injection_temperature=20.0, initial_temperature=80.0,
                            initial_pressure=20e6, production_pressure=20e6)


@register
class PennyImpermeable(MechanicsScene, FractureScene):
    name = "penny_impermeable"
    description = "Scene 2: cold water through a deformable penny fracture with contact in impermeable rock (3D)"
    parameter_sets = (ElasticRock, Joint, with_defaults(FluidFlow, fluid_viscosity="water"), HeatExchange,
                      HeatMaterial, Scene2Wells, Scene2Params)
    time = TimeDefaults(final_time=1e9, dt_initial=1e3, dt_growth=1.2, dt_max=2e7, mesh_size=0.0,
                        output_interval=10)
    history_columns = ("injection_pressure", "production_temperature", "production_rate", "lam_injector",
                       "aperture_injector", "aperture_max", "lam_min", "nodes_open", "aperture_identity",
                       "Tf_min", "Tf_max", "mass_balance", "energy_balance")
    _heat = True
    share = 0.5                           # the half model holds half of each well

    def solver_defaults(self, comm):
        # one LU per time step: the later Newton iterations of a step reuse it
        # as GMRES's preconditioner (the factorisation dominates the run time)
        return dict(super().solver_defaults(comm), snes_lag_preconditioner="10")

    # -- geometry -----------------------------------------------------------------------
    @property
    def L(self):
        p = self[Scene2Params]
        return p.scene2_box * p.scene2_radius

    def wells_at(self):
        d = self[Scene2Params].scene2_well_offset
        return (-d, 0.0, 0.0), (d, 0.0, 0.0)

    def boundaries(self):
        L = self.L
        return {"sym_y": lambda x: np.isclose(x[:, 1], 0.0),
                "far_x": lambda x: np.isclose(np.abs(x[:, 0]), L),
                "far_y": lambda x: np.isclose(x[:, 1], L),
                "far_z": lambda x: np.isclose(np.abs(x[:, 2]), L)}

    def generate_mesh(self, path, size):
        p = self[Scene2Params]
        L = self.L
        size = size or L / 4
        if p.scene2_layer > 0:
            return meshing.layered_half_box_with_disc(path, L, p.scene2_radius, size, p.scene2_fracture_size,
                                                      p.scene2_layer, p.scene2_layer_growth, list(self.wells_at()),
                                                      p.scene2_well_size)
        fr = [meshing.Fracture("disc", center=(0.0, 0.0, 0.0), radius=p.scene2_radius, size=p.scene2_fracture_size)]
        return meshing.box_with_fractures(path, [2 * L, L, 2 * L], size, fr, grading_distance=L,
                                          origin=(-L, 0.0, -L), wells=list(self.wells_at()),
                                          well_size=p.scene2_well_size)

    def hit_times(self):
        return [10.0 ** k for k in range(3, 10) if 10.0 ** k <= (self.run.final_time or self.time.final_time)]

    # -- model ----------------------------------------------------------------------------
    def reference_aperture(self) -> float:
        return float(self[Joint].law().closure_aperture(np.array([self.lam0]))[0][0])

    @property
    def lam0(self) -> float:
        return self[Scene2Params].scene2_normal_stress - self[Wells].initial_pressure

    def check(self, mesh):
        p, w = self[Scene2Params], self[Wells]
        if mesh.dim != 3:
            raise InputError("penny_impermeable is a 3D scene (the mesh is 2D)")
        if not self.lam0 > 0:
            raise InputError(f"option -thm_initial_pressure = {w.initial_pressure:g} must be below "
                             f"-thm_scene2_normal_stress = {p.scene2_normal_stress:g}: the fracture starts closed")
        if not p.scene2_well_offset < p.scene2_radius:
            raise InputError(f"option -thm_scene2_well_offset = {p.scene2_well_offset:g} must be below "
                             f"-thm_scene2_radius = {p.scene2_radius:g} (wells on the fracture)")

    def build(self, mesh, degree):
        self.check(mesh)
        p, w, rock = self[Scene2Params], self[Wells], self[ElasticRock]
        T0, Ti = w.initial_temperature + CELSIUS, w.injection_temperature + CELSIUS
        self._worst, self._final = {}, None
        el = pe.Elastic(rock.rock_youngs_modulus, rock.rock_poisson_ratio, 3, T="Tm",
                        thermal_expansion=p.rock_thermal_expansion, T_ref=T0)
        u_scale = max(p.rock_thermal_expansion * abs(T0 - Ti) * p.scene2_radius / 3, 1e-6 * p.scene2_radius)
        self.mech = ct.FractureMechanics(3, pf="pf", insitu_normal_stress=-p.scene2_normal_stress,
                                         gap_tolerance=GAP_TOLERANCE * u_scale)
        self.law = self[Joint].law()
        aperture = ct.Aperture(self.mech, self.law)
        model = self.fracture_model(mesh, 1, heat=True, aperture=aperture, lumped=p.scene2_lumped_heat)
        r1, j1 = pe.elastic_terms(el)
        r2, j2 = ct.fracture_mechanics_terms(self.mech)
        model.fields = [FieldSpec("u", 3, degree), FieldSpec("lam", 1, 1, "fracture")] + model.fields
        model.residuals += r1 + r2
        model.jacobians += j1 + j2
        if p.thermomechanical_heating:
            r3, j3 = pe.heating_terms(el, "Tm")
            model.residuals += r3
            model.jacobians += j3
        model.bounds = {"lam": (0.0, None)}
        inj, prod = self.wells_at()
        model.points.extend(self.well_terms(mesh, inj, prod, heat=True, share=self.share))
        lam_tip = self.lam0 if p.scene2_tip_traction == "insitu" else 0.0
        bcs = [Dirichlet("u", "sym_y", zero, components=(1,)),
               Dirichlet("u", "far_x", zero, components=(0,)),
               Dirichlet("u", "far_y", zero, components=(1,)),
               Dirichlet("u", "far_z", zero, components=(2,)),
               Dirichlet("lam", TIP_BC, lambda x, t: np.full(len(x), lam_tip))]
        bcs += [Dirichlet("Tm", f, lambda x, t: np.full(len(x), T0)) for f in ("far_x", "far_y", "far_z")]
        mu = _viscosity(self[FluidFlow])
        a = self.reference_aperture()
        dp = float(w.injection_rate * 12 * mu.mu(Ti) / (2 * np.pi * a ** 3) * np.log(2 * p.scene2_well_offset /
                                                                                  w.well_radius))
        sT = FieldScale(abs(T0 - Ti) or 1.0, T0)
        scales = {"u": FieldScale(u_scale), "lam": FieldScale(self.lam0), "pf": FieldScale(dp, w.initial_pressure),
                  "Tf": sT, "Tm": FieldScale(sT.scale, sT.offset)}
        init = {"lam": lambda x: np.full(len(x), self.lam0), "pf": lambda x: np.full(len(x), w.initial_pressure),
                "Tf": lambda x: np.full(len(x), T0), "Tm": lambda x: np.full(len(x), T0)}
        return model, bcs, scales, init

    # -- monitors ------------------------------------------------------------------------
    def fracture_state(self, problem, X, t):
        """(x, g, lam, a) at the fracture vertices of this rank."""
        x, g, lam = self.opening_nodes(problem, X, t)
        return x, g, lam, self.law.aperture(lam, g)

    def _at(self, comm, x, values, point):
        """Values at the fracture vertex nearest to ``point`` (all ranks)."""
        from mpi4py import MPI
        d = np.linalg.norm(x - np.asarray(point)[None], axis=1) if len(x) else np.zeros(0)
        k = int(np.argmin(d)) if len(d) else 0
        best = (float(d[k]), comm.rank) if len(d) else (np.inf, comm.rank)
        _, owner = comm.allreduce(best, op=MPI.MINLOC)
        return comm.bcast([float(v[k]) for v in values] if comm.rank == owner else None, root=owner)

    def monitors(self, problem, t, X=None):
        comm = problem.dm.comm.tompi4py()
        w = self[Wells]
        inj, prod = self.wells_at()
        out = self.well_monitors(problem, t, X, inj, prod, heat=True)
        out["production_rate"] /= self.share
        x, g, lam, a = self.fracture_state(problem, X, t)
        out["lam_injector"], out["aperture_injector"] = self._at(comm, x, (lam, a), inj)
        closed = lam > OPEN_TRACTION * self.lam0
        # where closed, a = a0 - lam/Kn exactly: the complementarity leaves no positive opening there
        ident = float(np.abs(a - self.law.closure_aperture(lam)[0])[closed].max()) if closed.any() else 0.0
        out["aperture_identity"] = comm.allreduce(ident, op=_max()) / self.reference_aperture()
        out["aperture_max"] = comm.allreduce(float(a.max()) if len(a) else 0.0, op=_max())
        out["lam_min"] = comm.allreduce(float(lam.min()) if len(lam) else np.inf, op=_min())
        out["nodes_open"] = comm.allreduce(int((~closed).sum()))
        v = problem.field_values("Tf", X, t)[:, 0] - CELSIUS
        out["Tf_min"] = comm.allreduce(float(v.min()) if len(v) else np.inf, op=_min())
        out["Tf_max"] = comm.allreduce(float(v.max()) if len(v) else -np.inf, op=_max())
        lo, hi = sorted((w.injection_temperature, w.initial_temperature))
        viol = max(0.0, lo - out["Tf_min"], out["Tf_max"] - hi) / max(hi - lo, 1e-300)
        for k, val in (("Tf_bounds_violation", viol), ("aperture_identity", out["aperture_identity"])):
            self._worst[k] = max(self._worst.get(k, 0.0), val)
        if viol > TF_BOUNDS_WARNING and not getattr(self, "_warned", False) and comm.rank == 0:
            import sys
            self._warned = True
            print(f"warning: at t = {t:.4g} s Tf = [{out['Tf_min']:.2f}, {out['Tf_max']:.2f}] degC leaves "
                  f"[{lo:g}, {hi:g}] by {100 * viol:.0f} % of the range (max in summary.json: "
                  "Tf_bounds_violation); refine the fracture mesh or use -thm_fracture_heat_exchange "
                  "equilibrium", file=sys.stderr, flush=True)
        out.update(self.balance_monitors(problem, t, X))
        self._state = (x, g, lam, a, v)
        self._last = out
        return out

    def write_fracture_maps(self, problem, path):
        """The last monitored state on the fracture (model half y >= 0), for the
        paper's Fig. 5: ``vertices`` (x, y, opening, lam, aperture) and ``Tf``
        (x, y, Tf in degC) at the fracture nodes, in one .npz (rank 0 writes)."""
        comm = problem.dm.comm.tompi4py()
        x, g, lam, a, v = self._state
        xT = problem.disc.field_node_coordinates("Tf")
        rows = comm.gather(np.column_stack([x[:, 0], x[:, 1], g, lam, a]) if len(x) else np.zeros((0, 5)), root=0)
        rowsT = comm.gather(np.column_stack([xT[:, 0], xT[:, 1], v]) if len(v) else np.zeros((0, 3)), root=0)
        if comm.rank == 0:
            np.savez(path, vertices=np.concatenate(rows), Tf=np.concatenate(rowsT))

    def report(self, problem, t):
        out = {"balance_max": self._worst, **{k: self._last.get(k) for k in (
            "injection_pressure", "production_temperature", "lam_injector", "aperture_injector")}}
        path = os.path.join(self.run.output_dir or os.path.join("output", self.name), "fracture_final.npz")
        self.write_fracture_maps(problem, path)
        out["fracture_maps"] = os.path.basename(path)
        return out
