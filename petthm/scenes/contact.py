"""Fracture mechanics scenes (issue 4; physics.md sections 2-3,
verification.md sections 4-5): elastic rock with fracture faces loaded by a
prescribed fluid pressure and the contact traction ``lam``.

* ``sneddon``: a pressurised open crack in an (almost) infinite solid: the
  penny crack (3D, quarter model) or the plane-strain Griffith crack (2D,
  half model), compared with Sneddon's opening.
* ``contact_patch``: a fracture cutting the whole domain, closed by a
  compressive load on the top face and opened by a fluid pressure p < sigma:
  uniform lam = sigma - p, zero opening, aperture a0 - lam/Kn.
* ``partial_opening``: a buried crack under compression whose central part
  is pressurised above the closure stress: an open centre and a closed rim.

The contact is solved by SNES's VI Newton (``vinewtonrsls`` by default) with
the bound lam >= 0 (kernels/contact.py).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import meshing
from ..assembly import FieldScale
from ..errors import InputError
from ..fields import FieldSpec
from ..fracture import TIP_BC
from ..kernels import contact as ct
from ..kernels import poroelastic as pe
from ..kernels import transport as tr
from ..fluid import Viscosity
from ..model import Model
from ..params import param
from ..solver import Dirichlet
from .base import Scene, TimeDefaults, register, with_defaults
from .fracture import _max


# -- parameters ------------------------------------------------------------------------
@dataclass(frozen=True)
class ElasticRock:
    """Elastic rock (physics.md section 2; the rock of Scene 2)"""
    rock_youngs_modulus: float = param(37.5e9, "Pa", "drained Young's modulus E", lo=0.0, lo_open=True)
    rock_poisson_ratio: float = param(0.25, "-", "drained Poisson ratio nu", lo=0.0, hi=0.4999)


@dataclass(frozen=True)
class Joint:
    """Fracture normal stiffness and aperture (physics.md section 3)"""
    joint_stiffness: float = param(1e11, "Pa/m", "normal joint stiffness Kn", lo=0.0, lo_open=True)
    joint_aperture: float = param(0.6e-3, "m", "aperture a0 at zero contact traction", lo=0.0, lo_open=True)
    joint_residual_fraction: float = param(1e-3, "-", "residual aperture ares / a0", lo=0.0, hi=1.0)

    def law(self) -> ct.JointLaw:
        return ct.JointLaw(self.joint_aperture, self.joint_stiffness,
                           self.joint_residual_fraction * self.joint_aperture)


#: a vertex counts as open where lam is below this fraction of the stress scale
OPEN_TRACTION = 1e-9
#: shift of the contact function relative to the displacement scale (kernels/contact.py)
GAP_TOLERANCE = 1e-12


def zero(x, t):
    return np.zeros(len(x))


def _gather(comm, a: np.ndarray) -> np.ndarray:
    parts = comm.allgather(a)
    return np.concatenate(parts) if parts else a


def crack_half_model(path, c, L, crack_size, size=0.0, vertices=()):
    """[0, L] x [-L, L] with a crack from (0, 0) to (c, 0) (the half model of a
    crack of length 2c, symmetric about x = 0), mesh size ``crack_size`` on the
    crack growing by a third of the distance to ``size`` (default L/10);
    ``vertices``: extra mesh vertices on the crack."""
    size = size or L / 10
    fr = [meshing.Fracture("segment", p0=(0.0, 0.0), p1=(c, 0.0), size=crack_size)]
    return meshing.box_with_fractures(path, [L, 2 * L], size, fr, grading_distance=3 * size, origin=(0.0, -L),
                                      wells=list(vertices), well_size=crack_size)


class MechanicsScene(Scene):
    """Shared set-up: elastic rock, faces loaded by a prescribed pressure, contact."""
    fractured = True
    direct_solve = True

    def solver_defaults(self, comm):
        # snes_atol 1e-12: one more Newton step (an iterative refinement) where
        # the LU is less accurate than MUMPS (PETSc's own LU with reordering)
        return dict(super().solver_defaults(comm), snes_type="vinewtonrsls", snes_atol="1e-12")

    def mechanics_model(self, mesh, degree, pressure, normal_stress: float, u_scale: float) -> Model:
        """Fields u (``degree``) and lam (P1 on the fracture), the elastic
        terms, the face loads and the contact rows; lam >= 0."""
        r = self[ElasticRock]
        d = mesh.dim
        el = pe.Elastic(r.rock_youngs_modulus, r.rock_poisson_ratio, d)
        self.mech = ct.FractureMechanics(d, pressure=pressure, insitu_normal_stress=-normal_stress,
                                         gap_tolerance=GAP_TOLERANCE * u_scale)
        res, jac = pe.elastic_terms(el)
        fr, fj = ct.fracture_mechanics_terms(self.mech)
        fields = [FieldSpec("u", d, degree), FieldSpec("lam", 1, 1, "fracture")]
        return Model(fields, res + fr, jac + fj, bounds={"lam": (0.0, None)})

    def opening_nodes(self, problem, X=None, t=0.0):
        """(coordinates, opening g, lam) at the vertices of the fracture's - faces
        on this rank (each vertex once)."""
        disc, surf = problem.disc, problem.disc.regions["fracture"]
        xl, _ = problem.local_arrays(X or problem.X, t)
        sc, d = problem.scales["u"], surf.dim
        nv = surf.rdim + 1
        nc = surf.ncells
        um = xl[disc.region_dofs("fracture", "u-")[:, :nv * d]].reshape(nc, nv, d)
        up = xl[disc.region_dofs("fracture", "u+")[:, :nv * d]].reshape(nc, nv, d)
        g = np.einsum("cva,ca->cv", up - um, surf.normals) * sc.scale
        lam = xl[disc.region_dofs("fracture", "lam")[:, :nv]] * problem.scales["lam"].scale
        verts, first = np.unique(surf.cell_vertices.ravel(), return_index=True)
        x = surf.mesh.vertex_coords[verts]
        return x, g.ravel()[first], lam.ravel()[first]


# -- sneddon ---------------------------------------------------------------------------
@dataclass(frozen=True)
class SneddonParams:
    """Pressurised crack in an infinite solid (sneddon; verification.md section 4)"""
    sneddon_dim: int = param(3, "-", "3: penny crack (quarter model), 2: Griffith crack (half model)",
                             choices=(2, 3))
    sneddon_radius: float = param(100.0, "m", "crack radius R (3D) or half-length c (2D)", lo=0.0, lo_open=True)
    sneddon_net_pressure: float = param(1e6, "Pa", "net pressure p - sigma_n", lo=0.0, lo_open=True)
    sneddon_normal_stress: float = param(0.0, "Pa", "in-situ normal stress sigma_n (compressive)", lo=0.0)
    sneddon_box: float = param(20.0, "-", "domain half-size / R", lo=2.0)
    sneddon_crack_size: float = param(0.05, "-", "mesh size on the crack / R", lo=1e-4, hi=1.0)


@register
class Sneddon(MechanicsScene):
    name = "sneddon"
    description = "pressurised penny (3D) or Griffith (2D) crack: opening against Sneddon's solution"
    parameter_sets = (ElasticRock, Joint, SneddonParams)
    time = TimeDefaults(final_time=1.0, dt_initial=1.0, mesh_size=0.0)
    history_columns = ("opening_centre", "centre_error", "opening_l2_error", "lam_max")

    @property
    def L(self):
        p = self[SneddonParams]
        return p.sneddon_box * p.sneddon_radius

    def boundaries(self):
        L, d = self.L, self[SneddonParams].sneddon_dim
        out = {"sym_x": lambda x: np.isclose(x[:, 0], 0.0)}
        if d == 3:
            out["sym_y"] = lambda x: np.isclose(x[:, 1], 0.0)
            out["far"] = lambda x: np.isclose(x[:, 0], L) | np.isclose(x[:, 1], L) | np.isclose(np.abs(x[:, 2]), L)
        else:
            out["far"] = lambda x: np.isclose(x[:, 0], L) | np.isclose(np.abs(x[:, 1]), L)
        return out

    def generate_mesh(self, path, size):
        p = self[SneddonParams]
        R, L = p.sneddon_radius, self.L
        hf = p.sneddon_crack_size * R
        if p.sneddon_dim == 2:
            return crack_half_model(path, R, L, hf, size)
        size = size or L / 10
        fr = [meshing.Fracture("disc", center=(0.0, 0.0, 0.0), radius=R, size=hf)]
        return meshing.box_with_fractures(path, [L, L, 2 * L], size, fr, grading_distance=3 * size,
                                          origin=(0.0, 0.0, -L))

    def exact_opening(self, r):
        """Sneddon's total opening w(r) (verification.md section 4)."""
        p, rock = self[SneddonParams], self[ElasticRock]
        E, nu, R, pn = rock.rock_youngs_modulus, rock.rock_poisson_ratio, p.sneddon_radius, p.sneddon_net_pressure
        s = np.sqrt(np.clip(1 - (r / R) ** 2, 0.0, None))
        if p.sneddon_dim == 3:
            return 8 * (1 - nu ** 2) * pn * R / (np.pi * E) * s
        return 4 * (1 - nu ** 2) * pn / E * R * s

    def _radius(self, x):
        return np.linalg.norm(x[..., :2], axis=-1) if self[SneddonParams].sneddon_dim == 3 else np.abs(x[..., 0])

    def build(self, mesh, degree):
        p = self[SneddonParams]
        if mesh.dim != p.sneddon_dim:
            raise InputError(f"option -thm_sneddon_dim = {p.sneddon_dim} but the mesh is {mesh.dim}D")
        sn = p.sneddon_normal_stress
        w0 = float(self.exact_opening(np.zeros(1))[0])
        model = self.mechanics_model(mesh, degree, lambda x, t: sn + p.sneddon_net_pressure, sn, w0)
        d = mesh.dim
        bcs = [Dirichlet("u", "far", lambda x, t: np.zeros((len(x), d))),
               Dirichlet("u", "sym_x", zero, components=(0,)),
               Dirichlet("lam", TIP_BC, zero)]
        if d == 3:
            bcs.append(Dirichlet("u", "sym_y", zero, components=(1,)))
        scales = {"u": FieldScale(w0), "lam": FieldScale(p.sneddon_net_pressure + sn)}
        return model, bcs, scales, {}

    def errors(self, problem, t, X=None) -> dict:
        """Opening at the centre and the relative L2 error of the opening over r < 0.95 R."""
        comm = problem.dm.comm.tompi4py()
        x, g, lam = self.opening_nodes(problem, X, t)
        r = self._radius(x)
        best = comm.allreduce((float(r.min()), float(g[np.argmin(r)])) if len(r) else (np.inf, 0.0),
                              op=_minloc())
        w0 = float(self.exact_opening(np.zeros(1))[0])
        R = self[SneddonParams].sneddon_radius
        xl, _ = problem.local_arrays(X or problem.X, t)
        asm = problem.region("fracture")

        def sq_err(ctx):
            inside = self._radius(ctx.x) < 0.95 * R
            return inside * (ct.opening(self.mech, ctx) - self.exact_opening(self._radius(ctx.x))) ** 2

        def sq_exact(ctx):
            inside = self._radius(ctx.x) < 0.95 * R
            return inside * self.exact_opening(self._radius(ctx.x)) ** 2
        l2 = np.sqrt(asm.integrate(xl, sq_err, t) / asm.integrate(xl, sq_exact, t))
        lam_max = comm.allreduce(float(lam.max()) if len(lam) else 0.0, op=_max())
        return {"opening_centre": best[1], "centre_error": abs(best[1] - w0) / w0,
                "opening_l2_error": float(l2), "lam_max": lam_max}

    def monitors(self, problem, t, X=None):
        self._last = self.errors(problem, t, X) if t > 0 else {}
        return self._last

    def report(self, problem, t):
        e = getattr(self, "_last", {})
        return {"error": {k: e.get(k) for k in ("centre_error", "opening_l2_error")},
                "opening_centre": e.get("opening_centre"),
                "opening_centre_exact": float(self.exact_opening(np.zeros(1))[0])}


def _minloc():
    from mpi4py import MPI
    return MPI.MINLOC


# -- contact_patch -----------------------------------------------------------------------
@dataclass(frozen=True)
class ContactPatchParams:
    """Closed fracture across the domain under compression (contact_patch; verification.md section 5)"""
    contact_dim: int = param(3, "-", "space dimension", choices=(2, 3))
    contact_size: float = param(10.0, "m", "domain width and height", lo=0.0, lo_open=True)
    contact_normal_stress: float = param(60e6, "Pa", "compressive normal stress sigma at the end", lo=0.0, lo_open=True)
    contact_pressure: float = param(20e6, "Pa", "fracture fluid pressure p at the end (< sigma)", lo=0.0)
    contact_insitu_fraction: float = param(0.5, "-", "fraction of sigma and p present in the in-situ "
                                           "state; the rest is ramped up over the run", lo=0.0, hi=1.0, lo_open=True)


@register
class ContactPatch(MechanicsScene):
    name = "contact_patch"
    description = "closed fracture under compression and fluid pressure: lam = sigma - p, zero opening"
    parameter_sets = (ElasticRock, Joint, ContactPatchParams)
    time = TimeDefaults(final_time=1.0, dt_initial=0.25, mesh_size=2.5)
    history_columns = ("lam_error", "opening_max", "aperture_error", "aperture_mean")

    def boundaries(self):
        p = self[ContactPatchParams]
        W, d = p.contact_size, p.contact_dim
        out = {"bottom": lambda x: np.isclose(x[:, -1], 0.0), "top": lambda x: np.isclose(x[:, -1], W)}
        for k in range(d - 1):
            out[f"side{k}"] = (lambda k: lambda x: np.isclose(x[:, k], 0.0) | np.isclose(x[:, k], W))(k)
        return out

    def generate_mesh(self, path, size):
        p = self[ContactPatchParams]
        W = p.contact_size
        if p.contact_dim == 2:
            fr = [meshing.Fracture("segment", p0=(-W, 0.5 * W), p1=(2 * W, 0.5 * W))]
        else:
            fr = [meshing.Fracture("rectangle", center=(0.5 * W, 0.5 * W, 0.5 * W), half=(1.5 * W, 1.5 * W))]
        return meshing.box_with_fractures(path, [W] * p.contact_dim, size, fr)

    def ramp(self, t):
        """Fraction of the final sigma and p applied at time t."""
        f = self[ContactPatchParams].contact_insitu_fraction
        return f + (1 - f) * min(t / self.time_final, 1.0)

    def exact_lam(self, t):
        p = self[ContactPatchParams]
        return (p.contact_normal_stress - p.contact_pressure) * self.ramp(t)

    def build(self, mesh, degree):
        p = self[ContactPatchParams]
        if mesh.dim != p.contact_dim:
            raise InputError(f"option -thm_contact_dim = {p.contact_dim} but the mesh is {mesh.dim}D")
        if not p.contact_pressure < p.contact_normal_stress:
            raise InputError(f"option -thm_contact_pressure = {p.contact_pressure:g} must be below "
                             f"-thm_contact_normal_stress = {p.contact_normal_stress:g} (a closed fracture)")
        self.time_final = self.run.final_time or self.time.final_time
        self._worst = {}
        f, d, sigma = p.contact_insitu_fraction, mesh.dim, p.contact_normal_stress
        rock = self[ElasticRock]
        el = pe.Elastic(rock.rock_youngs_modulus, rock.rock_poisson_ratio, d)
        u_scale = sigma * p.contact_size / (el.lame + 2 * el.shear)
        model = self.mechanics_model(mesh, degree, lambda x, t: p.contact_pressure * self.ramp(t),
                                     f * sigma, u_scale)
        top = np.zeros(d)
        top[-1] = -1.0
        model.facets.append(pe.traction("u", "top", lambda x, t: top * sigma * (self.ramp(t) - f)))
        bcs = [Dirichlet("u", "bottom", zero, components=(d - 1,))]
        bcs += [Dirichlet("u", f"side{k}", zero, components=(k,)) for k in range(d - 1)]
        scales = {"u": FieldScale(u_scale), "lam": FieldScale(sigma)}
        lam0 = self.exact_lam(0.0)
        return model, bcs, scales, {"lam": lambda x: np.full(len(x), lam0)}

    def errors(self, problem, t, X=None) -> dict:
        comm = problem.dm.comm.tompi4py()
        law = self[Joint].law()
        _, g, lam = self.opening_nodes(problem, X, t)
        ex = self.exact_lam(t)
        a = law.aperture(lam, g)
        a_ex = law.aperture(np.array([ex]), 0.0)[0]
        local = [float(np.abs(lam - ex).max()) if len(lam) else 0.0, float(np.abs(g).max()) if len(g) else 0.0,
                 float(np.abs(a - a_ex).max()) if len(a) else 0.0]
        worst = np.empty(3)
        comm.Allreduce(np.array(local), worst, op=_max())
        n = comm.allreduce(len(a))
        return {"lam_error": worst[0] / ex, "opening_max": worst[1], "aperture_error": worst[2] / a_ex,
                "aperture_mean": comm.allreduce(float(a.sum())) / max(n, 1)}

    def monitors(self, problem, t, X=None):
        self._last = self.errors(problem, t, X)
        for k in ("lam_error", "opening_max", "aperture_error"):
            self._worst[k] = max(self._worst.get(k, 0.0), self._last[k])
        return self._last

    def report(self, problem, t):
        return {"error": dict(self._worst), "aperture_mean": self._last["aperture_mean"],
                "lam_exact": self.exact_lam(t)}


# -- partial_opening ---------------------------------------------------------------------
@dataclass(frozen=True)
class PartialOpeningParams:
    """Crack under compression with a pressurised centre (partial_opening)"""
    partial_half_length: float = param(50.0, "m", "crack half-length c (2D half model)", lo=0.0, lo_open=True)
    partial_normal_stress: float = param(10e6, "Pa", "in-situ compressive normal stress sigma_n", lo=0.0, lo_open=True)
    partial_pressure: float = param(5e6, "Pa", "initial fluid pressure p0 (< sigma_n), kept outside |x| < b")
    partial_peak_pressure: float = param(12e6, "Pa", "pressure reached at the end in |x| < b (> sigma_n)")
    partial_radius: float = param(0.5, "-", "b / c: half-width of the pressurised centre", lo=0.0, hi=1.0, lo_open=True)
    partial_box: float = param(20.0, "-", "domain half-size / c", lo=2.0)
    partial_crack_size: float = param(0.025, "-", "mesh size on the crack / c", lo=1e-4, hi=1.0)


@register
class PartialOpening(MechanicsScene):
    name = "partial_opening"
    description = "crack under compression, centre pressurised above closure: open centre, closed rim"
    parameter_sets = (ElasticRock, Joint, PartialOpeningParams)
    time = TimeDefaults(final_time=1.0, dt_initial=0.1, mesh_size=0.0)
    history_columns = ("open_length", "opening_centre", "lam_max", "nodes_open")

    def boundaries(self):
        p = self[PartialOpeningParams]
        L = p.partial_box * p.partial_half_length
        return {"sym_x": lambda x: np.isclose(x[:, 0], 0.0),
                "far": lambda x: np.isclose(x[:, 0], L) | np.isclose(np.abs(x[:, 1]), L)}

    def generate_mesh(self, path, size):
        p = self[PartialOpeningParams]
        c = p.partial_half_length
        L = p.partial_box * c
        edge = [(p.partial_radius * c, 0.0)]          # a vertex where the pressure jumps
        return crack_half_model(path, c, L, p.partial_crack_size * c, size, edge)

    def pressure(self, x, t):
        p = self[PartialOpeningParams]
        ramp = min(t / self.time_final, 1.0)
        inside = np.abs(x[..., 0]) < p.partial_radius * p.partial_half_length
        return p.partial_pressure + inside * ramp * (p.partial_peak_pressure - p.partial_pressure)

    def build(self, mesh, degree):
        p = self[PartialOpeningParams]
        if mesh.dim != 2:
            raise InputError("partial_opening is a 2D scene (the mesh is 3D)")
        if not p.partial_pressure < p.partial_normal_stress < p.partial_peak_pressure:
            raise InputError("options -thm_partial_pressure < -thm_partial_normal_stress < "
                             "-thm_partial_peak_pressure are required (closed, then partly open)")
        self.time_final = self.run.final_time or self.time.final_time
        rock = self[ElasticRock]
        E, nu, c = rock.rock_youngs_modulus, rock.rock_poisson_ratio, p.partial_half_length
        w_ref = 4 * (1 - nu ** 2) * (p.partial_peak_pressure - p.partial_normal_stress) / E * c
        model = self.mechanics_model(mesh, degree, self.pressure, p.partial_normal_stress, w_ref)
        bcs = [Dirichlet("u", "far", lambda x, t: np.zeros((len(x), 2))),
               Dirichlet("u", "sym_x", zero, components=(0,)),
               Dirichlet("lam", TIP_BC, zero)]
        scales = {"u": FieldScale(w_ref), "lam": FieldScale(p.partial_normal_stress)}
        lam0 = p.partial_normal_stress - p.partial_pressure
        return model, bcs, scales, {"lam": lambda x: np.full(len(x), lam0)}

    def profile(self, problem, X=None, t=0.0):
        """(x, opening, lam) at every crack vertex, sorted by x (all ranks)."""
        comm = problem.dm.comm.tompi4py()
        x, g, lam = self.opening_nodes(problem, X, t)
        x, g, lam = (_gather(comm, a) for a in (x[:, 0], g, lam))
        x, k = np.unique(x, return_index=True)
        return x, g[k], lam[k]

    def monitors(self, problem, t, X=None):
        x, g, lam = self.profile(problem, X, t)
        is_open = lam <= OPEN_TRACTION * self[PartialOpeningParams].partial_normal_stress
        # end of the open zone: the first closed vertex beyond the centre
        closed = np.flatnonzero(~is_open & (x > 0))
        x_open = float(x[closed[0]]) if len(closed) else float(x[-1])
        self._last = {"open_length": x_open, "opening_centre": float(g[0]), "lam_max": float(lam.max()),
                      "nodes_open": int(is_open.sum())}
        self._profile = (x, g, lam)
        return self._last

    def report(self, problem, t):
        x, g, lam = self._profile
        return dict(self._last, profile={"x": x.tolist(), "opening": g.tolist(), "lam": lam.tolist()})


# -- fracture_inflation --------------------------------------------------------------------
@dataclass(frozen=True)
class InflationParams:
    """Fluid injected into a closed crack under compression (fracture_inflation)"""
    inflation_rate: float = param(1e-5, "m2/s", "injection rate into the half model (per metre)", lo=0.0, lo_open=True)
    inflation_compressibility: float = param(0.0, "1/Pa", "fluid compressibility c_f", lo=0.0)
    inflation_viscosity: float = param(1e-3, "Pa s", "fluid viscosity", lo=0.0, lo_open=True)


@register
class FractureInflation(PartialOpening):
    name = "fracture_inflation"
    description = "water injected at the centre of a closed crack: aperture from contact and opening, da/dt"
    parameter_sets = (ElasticRock, Joint, with_defaults(PartialOpeningParams, partial_crack_size=0.05),
                      InflationParams)
    time = TimeDefaults(final_time=2000.0, dt_initial=10.0, dt_growth=1.1, dt_max=100.0, mesh_size=0.0)
    history_columns = ("injection_pressure", "opening_centre", "nodes_open", "volume_balance")

    def build(self, mesh, degree):
        from ..kernels import wells
        p, fl = self[PartialOpeningParams], self[InflationParams]
        if mesh.dim != 2:
            raise InputError("fracture_inflation is a 2D scene (the mesh is 3D)")
        if not p.partial_pressure < p.partial_normal_stress:
            raise InputError("option -thm_partial_pressure must be below -thm_partial_normal_stress (closed)")
        rock = self[ElasticRock]
        el = pe.Elastic(rock.rock_youngs_modulus, rock.rock_poisson_ratio, 2)
        sn = p.partial_normal_stress
        w_ref = 4 * (1 - rock.rock_poisson_ratio ** 2) * sn / rock.rock_youngs_modulus * p.partial_half_length
        self.mech = ct.FractureMechanics(2, pf="pf", insitu_normal_stress=-sn, gap_tolerance=GAP_TOLERANCE * w_ref)
        self.law = self[Joint].law()
        self.flow = tr.Flow("fracture", "pf", None, fl.inflation_compressibility, np.eye(2) / 12,
                            Viscosity(fl.inflation_viscosity), aperture=ct.Aperture(self.mech, self.law))
        res, jac = pe.elastic_terms(el)
        for r, j in (ct.fracture_mechanics_terms(self.mech), tr.flow_terms(self.flow)):
            res, jac = res + r, jac + j
        fields = [FieldSpec("u", 2, degree), FieldSpec("lam", 1, 1, "fracture"), FieldSpec("pf", 1, degree, "fracture")]
        model = Model(fields, res, jac, bounds={"lam": (0.0, None)})
        model.points.append(wells.injector((0.0, 0.0), fl.inflation_rate, 0.0, None, T=None))
        bcs = [Dirichlet("u", "far", lambda x, t: np.zeros((len(x), 2))),
               Dirichlet("u", "sym_x", zero, components=(0,)),
               Dirichlet("lam", TIP_BC, zero)]
        scales = {"u": FieldScale(w_ref), "lam": FieldScale(sn), "pf": FieldScale(sn, p.partial_pressure)}
        lam0 = sn - p.partial_pressure
        self._a0 = None
        return model, bcs, scales, {"lam": lambda x: np.full(len(x), lam0),
                                    "pf": lambda x: np.full(len(x), p.partial_pressure)}

    def fluid_volume(self, problem, X, t):
        """int a over the crack (m2 per metre, half model)."""
        xl, _ = problem.local_arrays(X or problem.X, t)

        def a(ctx):
            lam = ctx.value("lam")[..., 0]
            return self.law.aperture(lam, ct.opening(self.mech, ctx))
        return problem.region("fracture").integrate(xl, a, t)

    def monitors(self, problem, t, X=None):
        out = super().monitors(problem, t, X)
        vol = self.fluid_volume(problem, X, t)
        if self._a0 is None:
            self._a0 = vol
        injected = self[InflationParams].inflation_rate * t
        out = {"injection_pressure": problem.point_value("pf", (0.0, 0.0), X, t),
               "opening_centre": out["opening_centre"], "nodes_open": out["nodes_open"],
               "volume_balance": (vol - self._a0 - injected) / injected if t > 0 else 0.0}
        self._last = dict(self._last, **out)
        return out

    def report(self, problem, t):
        return dict(self._last)
