"""Fracture mechanics scenes (theory manual, "Equations: rock deformation", the manual's verification
sections 4-5): elastic rock with fracture faces loaded by the fluid pressure
and the contact traction ``lam``.

* ``sneddon``: a pressurised open crack in an (almost) infinite solid: the
  penny crack (3D, quarter model) or the plane-strain Griffith crack (2D,
  half model), compared with Sneddon's opening; the crack's fluid pressure is
  -thm_initial_pressure, above the normal stress -thm_insitu_stress.
* ``contact_patch``: a fracture cutting the whole domain, closed by a
  compressive load sigma (-thm_insitu_stress) on the top face and opened by
  a fluid pressure p < sigma (-thm_initial_pressure): uniform lam = sigma - p,
  zero opening, aperture a0 - lam/Kn.
(The crack scenes ``partial_opening`` and ``fracture_inflation`` are in
``crack.py``.)

The contact is solved by SNES's VI Newton (``vinewtonrsls`` by default) with
the bound lam >= 0 (kernels/contact.py).  Every fracture here is normal to
the last axis (y in 2D, z in 3D).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from petthm.discretisation import probes
from petthm.discretisation.assembly import FieldScale
from petthm.discretisation.constraints import Dirichlet
from petthm.discretisation.model import FRACTURE
from petthm.errors import InputError
from petthm.mesh import generate as meshing
from petthm.params import MESH, PHYSICS, param
from petthm.physics import materials as mt
from petthm.physics.builders import ModelBuilder
from petthm.physics.kernels import contact as ct
from petthm.physics.kernels import poroelastic as pe
from petthm.physics.monitors import fracture_vertices, recovered_traction
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

#: a vertex counts as open where lam is below this fraction of the stress scale
OPEN_TRACTION = 1e-9


def fracture_normal(dim: int) -> np.ndarray:
    """The unit normal of the fractures of these scenes (the last axis)."""
    n = np.zeros(dim)
    n[-1] = 1.0
    return n


def crack_half_model(path, c, L, crack_size, size=0.0, vertices=()):
    """[0, L] x [-L, L] with a crack from (0, 0) to (c, 0) (the half model of a
    crack of length 2c, symmetric about x = 0), mesh size ``crack_size`` on the
    crack growing by a third of the distance to ``size`` (default L/10);
    ``vertices``: extra mesh vertices on the crack."""
    size = size or L / 10
    fr = [meshing.Fracture("segment", p0=(0.0, 0.0), p1=(c, 0.0), size=crack_size)]
    return meshing.box_with_fractures(path, [L, 2 * L], size, fr, grading_distance=3 * size, origin=(0.0, -L),
                                      wells=list(vertices), well_size=crack_size)


#: the contact scenes' VI Newton (the user's -snes_type wins)
VI_NEWTON = "vinewtonrsls"


def contact_solver_defaults(comm) -> dict:
    """A direct solve with the VI Newton; snes_atol 1e-12: one more Newton
    step (an iterative refinement) where the LU is less accurate than MUMPS
    (PETSc's own LU with reordering)."""
    from petthm.solvers.options import direct_solver_defaults
    return dict(direct_solver_defaults(comm), snes_type=VI_NEWTON, snes_atol="1e-12")


def contact_block_recipe() -> dict:
    """The contact scenes' change to the block path (``Scene.block_recipe``):
    Newton to a scaled residual of 1e-9, not ``contact_solver_defaults``'
    1e-12 (an iterative refinement of PETSc's own LU, which the block path,
    solving each Newton step to ``-ksp_rtol 1e-6``, does not have).
    Measured on Scenes 2 and 3 (manual, solver guide): a third of the Newton
    iterations go, the reported quantities move by <= 2e-9 of their values.
    A linear solve stops at a tenth of that (``ksp_atol`` 1e-10): below it
    Newton's next residual is its own nonlinear remainder (Scene 2 default,
    five long steps: the second Newton iteration's solve takes 3 Krylov
    iterations, not 7, with the same residuals to the printed digits;
    manual, solver guide)."""
    return {"snes_atol": "1e-9", "ksp_atol": "1e-10"}


def mechanics_model(p, mesh, degree, pressure, normal_stress: float, u_scale: float):
    """u (``degree``) and lam (on the fracture): elasticity, the face loads
    of a prescribed ``pressure(x, t)`` and lam, and the contact rows."""
    b = ModelBuilder(p, mesh.dim)
    b.elasticity(degree)
    mech = b.contact(normal_stress=normal_stress, u_scale=u_scale, pressure=pressure)
    return b.build(), mech


# -- sneddon ---------------------------------------------------------------------------
@dataclass(frozen=True)
class SneddonParams:
    """Pressurised crack in an infinite solid (sneddon; manual, verification)"""
    sneddon_dim: int = param(3, "-", "3: penny crack (quarter model), 2: Griffith crack (half model)",
                             choices=(2, 3), kind=MESH)
    sneddon_radius: float = param(100.0, "m", "crack radius R (3D) or half-length c (2D)", lo=0.0,
                                  lo_open=True, kind=MESH)
    sneddon_box: float = param(20.0, "-", "domain half-size / R", lo=2.0, kind=MESH)
    sneddon_crack_size: float = param(0.05, "-", "mesh size on the crack / R", lo=1e-4, hi=1.0, kind=MESH)


class _SneddonMonitor(Monitor):
    def __init__(self, scene, mech):
        self.scene, self.mech = scene, mech
        self.last = {}

    def errors(self, problem, t, X=None) -> dict:
        """Opening at the centre and the relative L2 error of the opening over r < 0.95 R."""
        sc = self.scene
        comm = problem.dm.comm
        x, g, lam = fracture_vertices(problem, X, t)
        r = sc.radius(x)
        centre = probes.nearest(comm, np.column_stack([r]), (0.0,), [g])[0]
        w0 = sc.centre_opening()
        R = sc.p.sneddon_radius
        xl, _ = problem.local_arrays(X or problem.X, t)
        asm = problem.region(FRACTURE)

        def sq_err(ctx):
            inside = sc.radius(ctx.x) < 0.95 * R
            return inside * (ct.opening(self.mech, ctx) - sc.exact_opening(sc.radius(ctx.x))) ** 2

        def sq_exact(ctx):
            inside = sc.radius(ctx.x) < 0.95 * R
            return inside * sc.exact_opening(sc.radius(ctx.x)) ** 2
        l2 = np.sqrt(asm.integrate(xl, sq_err, t) / asm.integrate(xl, sq_exact, t))
        return {"opening_centre": centre, "centre_error": abs(centre - w0) / w0,
                "opening_l2_error": float(l2), "lam_max": probes.global_max(comm, lam, empty=0.0)}

    def __call__(self, problem, t, X=None):
        self.last = self.errors(problem, t, X) if t > 0 else {}
        return self.last

    def report(self, problem, t):
        e = self.last
        return {"error": {k: e.get(k) for k in ("centre_error", "opening_l2_error")},
                "opening_centre": e.get("opening_centre"),
                "opening_centre_exact": self.scene.centre_opening()}


class Sneddon(Scene):
    name = "sneddon"
    description = "pressurised penny (3D) or Griffith (2D) crack: opening against Sneddon's solution"
    parameters = (mt.group("Rock", mt.ELASTIC), mt.group("Contact", mt.CONTACT, **mt.FRICTIONLESS),
                  mt.group("Fluid pressure and in-situ stress", ("initial_pressure", "insitu_stress"),
                           initial_pressure=1e6, insitu_stress="0"),
                  SneddonParams)
    time = TimeDefaults(final_time=1.0, dt_initial=1.0, mesh_size=0.0)
    history_columns = ("opening_centre", "centre_error", "opening_l2_error", "lam_max")

    @property
    def L(self):
        return self.p.sneddon_box * self.p.sneddon_radius

    def boundaries(self):
        L, d = self.L, self.p.sneddon_dim
        out = {"sym_x": lambda x: np.isclose(x[:, 0], 0.0)}
        if d == 3:
            out["sym_y"] = lambda x: np.isclose(x[:, 1], 0.0)
            out["far"] = lambda x: np.isclose(x[:, 0],
                                              L) | np.isclose(x[:, 1], L) | np.isclose(np.abs(x[:, 2]), L)
        else:
            out["far"] = lambda x: np.isclose(x[:, 0], L) | np.isclose(np.abs(x[:, 1]), L)
        return out

    def generate_mesh(self, path, size):
        p = self.p
        R, L = p.sneddon_radius, self.L
        hf = p.sneddon_crack_size * R
        if p.sneddon_dim == 2:
            return crack_half_model(path, R, L, hf, size)
        size = size or L / 10
        fr = [meshing.Fracture("disc", center=(0.0, 0.0, 0.0), radius=R, size=hf)]
        return meshing.box_with_fractures(path, [L, L, 2 * L], size, fr, grading_distance=3 * size,
                                          origin=(0.0, 0.0, -L))

    def normal_stress(self) -> float:
        return self.p.normal_stress(fracture_normal(self.p.sneddon_dim))

    def net_pressure(self) -> float:
        """p - sigma_n: the crack's fluid pressure over the normal stress."""
        return self.p.initial_pressure - self.normal_stress()

    def exact_opening(self, r):
        """Sneddon's total opening w(r) (manual, verification)."""
        p = self.p
        E, nu, R, pn = p.rock_youngs_modulus, p.rock_poisson_ratio, p.sneddon_radius, self.net_pressure()
        s = np.sqrt(np.clip(1 - (r / R) ** 2, 0.0, None))
        if p.sneddon_dim == 3:
            return 8 * (1 - nu ** 2) * pn * R / (np.pi * E) * s
        return 4 * (1 - nu ** 2) * pn / E * R * s

    def centre_opening(self) -> float:
        return float(self.exact_opening(np.zeros(1))[0])

    def radius(self, x):
        return np.linalg.norm(x[..., :2], axis=-1) if self.p.sneddon_dim == 3 else np.abs(x[..., 0])

    def build(self, mesh, degree):
        p = self.p
        if mesh.dim != p.sneddon_dim:
            raise InputError(f"option -thm_sneddon_dim = {p.sneddon_dim} but the mesh is {mesh.dim}D")
        sn, pn = self.normal_stress(), self.net_pressure()
        if not pn > 0:
            raise InputError(f"option -thm_initial_pressure = {p.initial_pressure:g} must exceed the normal "
                             f"stress {sn:g} (-thm_insitu_stress): Sneddon's crack is open")
        w0 = self.centre_opening()
        model, mech = mechanics_model(p, mesh, degree, lambda x, t: sn + pn, sn, w0)
        d = mesh.dim
        bcs = [Dirichlet("u", "far", lambda x, t: np.zeros((len(x), d))),
               Dirichlet("u", "sym_x", zero, components=(0,))]
        bcs += tip_tractions(model, zero, {"sym_x": 0, "sym_y": 1} if d == 3 else {"sym_x": 0})
        if d == 3:
            bcs.append(Dirichlet("u", "sym_y", zero, components=(1,)))
        scales = {"u": FieldScale(w0), "lam": FieldScale(pn + sn)}
        return Setup(model, bcs, scales, {}, _SneddonMonitor(self, mech))

    def solver_defaults(self, comm):
        return contact_solver_defaults(comm)


# -- contact_patch -----------------------------------------------------------------------
@dataclass(frozen=True)
class ContactPatchParams:
    """Closed fracture across the domain under compression (contact_patch; manual, verification)"""
    contact_dim: int = param(3, "-", "space dimension", choices=(2, 3), kind=MESH)
    contact_size: float = param(10.0, "m", "domain width and height", lo=0.0, lo_open=True, kind=MESH)
    contact_insitu_fraction: float = param(0.5, "-", "fraction of sigma and p present at t = 0; the rest "
                                           "is ramped up over the run", lo=0.0, hi=1.0, lo_open=True,
                                           kind=PHYSICS)


class _ContactPatchMonitor(Monitor):
    carried = ("worst",)

    def __init__(self, scene, law):
        self.scene, self.law = scene, law
        self.worst, self.last = {}, {}

    def errors(self, problem, t, X=None) -> dict:
        comm = problem.dm.comm
        _, g, lam = fracture_vertices(problem, X, t)
        ex = self.scene.exact_lam(t)
        a = self.law.aperture(lam, g)
        a_ex = self.law.aperture(np.array([ex]), 0.0)[0]
        lam_error = probes.global_max(comm, np.abs(lam - ex), empty=0.0)
        opening = probes.global_max(comm, np.abs(g), empty=0.0)
        aperture = probes.global_max(comm, np.abs(a - a_ex), empty=0.0)
        n = probes.global_sum(comm, len(a))
        recovered = recovered_traction(problem, X, t)
        return {"lam_error": lam_error / ex, "opening_max": opening, "aperture_error": aperture / a_ex,
                "aperture_mean": probes.global_sum(comm, float(a.sum())) / max(n, 1),
                "lam_recovered_error": probes.global_max(comm, np.abs(recovered - ex), empty=0.0) / ex}

    def __call__(self, problem, t, X=None):
        self.last = self.errors(problem, t, X)
        for k in ("lam_error", "opening_max", "aperture_error", "lam_recovered_error"):
            self.worst[k] = max(self.worst.get(k, 0.0), self.last[k])
        return self.last

    def report(self, problem, t):
        return {"error": dict(self.worst), "aperture_mean": self.last["aperture_mean"],
                "lam_exact": self.scene.exact_lam(t)}


class ContactPatch(Scene):
    name = "contact_patch"
    description = "closed fracture under compression and fluid pressure: lam = sigma - p, zero opening"
    parameters = (mt.group("Rock", mt.ELASTIC),
                  mt.group("Fracture", mt.JOINT + mt.CONTACT, fracture_aperture=0.6e-3, **mt.FRICTIONLESS),
                  mt.group("Loads at the end of the ramp", ("insitu_stress", "initial_pressure"),
                           initial_pressure=20e6),
                  ContactPatchParams)
    time = TimeDefaults(final_time=1.0, dt_initial=0.25, mesh_size=2.5)
    history_columns = ("lam_error", "opening_max", "aperture_error", "aperture_mean", "lam_recovered_error")

    def boundaries(self):
        p = self.p
        W, d = p.contact_size, p.contact_dim
        out = {"bottom": lambda x: np.isclose(x[:, -1], 0.0), "top": lambda x: np.isclose(x[:, -1], W)}
        for k in range(d - 1):
            out[f"side{k}"] = lambda x, k=k: np.isclose(x[:, k], 0.0) | np.isclose(x[:, k], W)
        return out

    def generate_mesh(self, path, size):
        p = self.p
        W = p.contact_size
        if p.contact_dim == 2:
            fr = [meshing.Fracture("segment", p0=(-W, 0.5 * W), p1=(2 * W, 0.5 * W))]
        else:
            fr = [meshing.Fracture("rectangle", center=(0.5 * W, 0.5 * W, 0.5 * W), half=(1.5 * W, 1.5 * W))]
        return meshing.box_with_fractures(path, [W] * p.contact_dim, size, fr)

    def sigma(self) -> float:
        return self.p.normal_stress(fracture_normal(self.p.contact_dim))

    def ramp(self, t):
        """Fraction of the final sigma and p applied at time t."""
        f = self.p.contact_insitu_fraction
        return f + (1 - f) * min(t / self.final_time, 1.0)

    def exact_lam(self, t):
        return (self.sigma() - self.p.initial_pressure) * self.ramp(t)

    def build(self, mesh, degree):
        p = self.p
        if mesh.dim != p.contact_dim:
            raise InputError(f"option -thm_contact_dim = {p.contact_dim} but the mesh is {mesh.dim}D")
        sigma = self.sigma()
        if not (sigma > 0 and p.initial_pressure < sigma):
            raise InputError(f"option -thm_initial_pressure = {p.initial_pressure:g} must be below "
                             f"-thm_insitu_stress = {sigma:g} (> 0: a closed fracture)")
        f, d = p.contact_insitu_fraction, mesh.dim
        el = pe.Elastic(p.rock_youngs_modulus, p.rock_poisson_ratio, d)
        u_scale = sigma * p.contact_size / (el.lame + 2 * el.shear)
        model, mech = mechanics_model(p, mesh, degree, lambda x, t: p.initial_pressure * self.ramp(t),
                                      f * sigma, u_scale)
        top = np.zeros(d)
        top[-1] = -1.0
        model.facets.append(pe.traction("u", "top", lambda x, t: top * sigma * (self.ramp(t) - f)))
        bcs = [Dirichlet("u", "bottom", zero, components=(d - 1,))]
        bcs += [Dirichlet("u", f"side{k}", zero, components=(k,)) for k in range(d - 1)]
        # the rollers hold the jump along the sides' normals: no tip here, tau_k = 0 there (friction)
        bcs += tip_tractions(model, constant_in_time(self.exact_lam(0.0)),
                             {f"side{k}": k for k in range(d - 1)})[1:]
        scales = {"u": FieldScale(u_scale), "lam": FieldScale(sigma)}
        law = ModelBuilder(p, d).joint_law()
        return Setup(model, bcs, scales, {"lam": constant(self.exact_lam(0.0))},
                     _ContactPatchMonitor(self, law))

    def solver_defaults(self, comm):
        return contact_solver_defaults(comm)
