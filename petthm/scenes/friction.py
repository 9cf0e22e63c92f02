"""Frictional contact scenes (theory manual, "Contact and friction"; kernels/friction.py).

* ``friction_patch``: a fracture cutting the whole domain (normal to the
  last axis, at mid-height) under its in-situ normal stress sigma, sheared
  by a displacement delta(t) of the top face in x (ramped linearly) with
  the bottom clamped.  The exact state is uniform: the shear stress
  tau_s = min(G delta / H, mu_f sigma) (simple shear of both blocks), lam =
  sigma, and the slip s = max(delta - b H / G, 0) with the bound
  b = c0 + mu_f sigma: stick while G delta / H < b, slip after.  The faces x = 0 and x = W carry the
  exact state's traction (0, +-tau_s) so that the state is uniform up to
  them; the faces normal to y (3D) are free.  -thm_friction_shear_ratio is
  the final G delta / (H b): below 1 the whole run sticks, above 1 the
  whole fracture passes from stick to slip in one step.
* ``inclined_crack``: a plane-strain crack of half-length a through the
  centre of a square of side 2 L, inclined at psi to the x axis, in a
  uniaxial compression sigma along y (the in-situ state, u = 0 on the outer
  boundary) that is unlocked at t = 0: on the crack sigma_n = sigma cos^2 psi,
  |tau_0| = sigma sin psi cos psi, and where |tau_0| > c0 + mu_f sigma_n the
  crack slips under the driving stress dtau = |tau_0| - c0 - mu_f sigma_n
  with the elliptical profile of a shear (mode II) Griffith crack,
  |s(x)| = 4 (1 - nu^2) dtau / E sqrt(a^2 - x^2) (x along the crack from its
  centre; e.g. the "single fracture under shear compression" validation of
  GEOS), lam = sigma_n and |tau| = c0 + mu_f sigma_n.  -thm_inclined_dim 3:
  a penny crack of radius a dipping by psi about x in a compression along z
  (half model x >= 0): |s(r)| = 16 (1 - nu^2) dtau / (pi (2 - nu) E)
  sqrt(a^2 - r^2), along the in-situ shear.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from petthm.discretisation import probes
from petthm.discretisation.assembly import FieldScale
from petthm.discretisation.constraints import Dirichlet
from petthm.errors import InputError
from petthm.mesh import generate as meshing
from petthm.params import MESH, PHYSICS, param
from petthm.physics import materials as mt
from petthm.physics.kernels import poroelastic as pe
from petthm.physics.kernels.friction import tangent_basis
from petthm.physics.monitors import contact_node_fields
from petthm.scenes.base import Monitor, Scene, Setup, TimeDefaults, constant, tip_tractions
from petthm.scenes.contact import contact_solver_defaults, fracture_normal, mechanics_model


@dataclass(frozen=True)
class FrictionPatchParams:
    """Sheared fracture across the domain (friction_patch)"""
    friction_dim: int = param(2, "-", "space dimension", choices=(2, 3), kind=MESH)
    friction_size: float = param(10.0, "m", "domain width and height H", lo=0.0, lo_open=True, kind=MESH)
    friction_shear_ratio: float = param(2.0, "-", "final G delta / (H b), b = c0 + mu_f sigma: < 1 stick, "
                                        "> 1 slip", lo=0.0, kind=PHYSICS)


def slip_columns(problem, X=None, t: float = 0.0, fields: dict | None = None) -> dict:
    """History columns of a frictional fracture: the largest slip magnitude
    and the slipping area (from ``fields``, monitors.contact_node_fields at
    (X, t) when not given)."""
    comm = problem.dm.comm
    f = fields if fields is not None else contact_node_fields(problem, X, t)
    return {"slip_max": probes.global_max(comm, f["slip_magnitude"], empty=0.0),
            "slipping_area": probes.global_sum(comm, float(f["slipping_area"][0]))}


class _CoulombScene(Scene):
    """A scene whose fracture slips under Coulomb's law; ``normal_stress()``
    is the in-situ compressive stress on it."""

    def local_bound(self, lam):
        """c0 + mu_f lam at the nodes."""
        return self.p.fracture_cohesion + self.p.fracture_friction * lam

    def bound(self) -> float:
        """b = c0 + mu_f sigma_n: the shear stress at which the fracture slips."""
        return self.local_bound(self.normal_stress())


class _FrictionPatchMonitor(Monitor):
    carried = ("worst",)

    def __init__(self, scene):
        self.scene = scene
        self.worst, self.last = {}, {}

    def __call__(self, problem, t, X=None):
        sc, comm = self.scene, problem.dm.comm
        f = contact_node_fields(problem, X, t)
        lam, tau, s = problem.field_values("lam", X, t)[:, 0], f["shear_traction"], f["slip"]
        tau_s, slip = sc.exact(t)
        bound = sc.bound()
        ex = np.zeros(tau.shape[1])
        ex[0] = 1.0                                         # the shear is along x
        mag = np.linalg.norm(tau, axis=1)
        out = {"slip_exact": slip,
               "slip_error": probes.global_max(comm, np.linalg.norm(s - slip * ex, axis=1), empty=0.0),
               "tau_error": probes.global_max(comm, np.linalg.norm(tau + tau_s * ex, axis=1),   # opposes slip
                                              empty=0.0) / bound,
               "lam_error": probes.global_max(comm, np.abs(lam - sc.normal_stress()),
                                              empty=0.0) / sc.normal_stress(),
               "coulomb_max": probes.global_max(comm, f["coulomb"], empty=0.0) / bound,
               **slip_columns(problem, fields=f)}
        slipping = slip > 0
        out["law_error"] = probes.global_max(comm, np.abs(mag / sc.local_bound(lam) - 1.0),
                                             empty=0.0) if slipping else 0.0
        for k in ("slip_error", "tau_error", "lam_error", "law_error"):
            self.worst[k] = max(self.worst.get(k, 0.0), out[k])
        self.worst["stick_slip_max"] = max(self.worst.get("stick_slip_max", 0.0),
                                           0.0 if slipping else out["slip_max"])
        self.last = out
        return out

    def report(self, problem, t):
        return {"error": dict(self.worst), "slip_final": self.last.get("slip_max"),
                "slip_exact_final": self.scene.exact(t)[1]}


class FrictionPatch(_CoulombScene):
    name = "friction_patch"
    description = "sheared fracture across the domain: stick below mu_f sigma, then uniform slip"
    parameters = (mt.group("Rock", mt.ELASTIC), mt.group("Contact", mt.CONTACT),
                  mt.group("In-situ stress", ("insitu_stress",)), FrictionPatchParams)
    time = TimeDefaults(final_time=1.0, dt_initial=0.2, mesh_size=2.5)
    history_columns = ("slip_max", "slip_exact", "slip_error", "tau_error", "lam_error", "coulomb_max",
                       "law_error", "slipping_area")

    @property
    def H(self) -> float:
        return self.p.friction_size

    def shear_modulus(self) -> float:
        p = self.p
        return p.rock_youngs_modulus / (2 * (1 + p.rock_poisson_ratio))

    def normal_stress(self) -> float:
        return self.p.normal_stress(fracture_normal(self.p.friction_dim))

    def delta(self, t: float) -> float:
        """Top displacement in x at time t (linear ramp to the final ratio)."""
        final = self.p.friction_shear_ratio * self.H * self.bound() / self.shear_modulus()
        return final * min(t / self.final_time, 1.0)

    def exact(self, t: float) -> tuple[float, float]:
        """(shear stress tau_s, slip s) of the uniform state at time t."""
        G, H, b = self.shear_modulus(), self.H, self.bound()
        d = self.delta(t)
        return min(G * d / H, b), max(d - b * H / G, 0.0)

    def boundaries(self):
        W, d = self.H, self.p.friction_dim
        out = {"bottom": lambda x: np.isclose(x[:, -1], 0.0), "top": lambda x: np.isclose(x[:, -1], W),
               "left": lambda x: np.isclose(x[:, 0], 0.0), "right": lambda x: np.isclose(x[:, 0], W)}
        if d == 3:
            out["front"] = lambda x: np.isclose(x[:, 1], 0.0) | np.isclose(x[:, 1], W)
        return out

    def generate_mesh(self, path, size):
        W, d = self.H, self.p.friction_dim
        if d == 2:
            fr = [meshing.Fracture("segment", p0=(-W, 0.5 * W), p1=(2 * W, 0.5 * W))]
        else:
            fr = [meshing.Fracture("rectangle", center=(0.5 * W, 0.5 * W, 0.5 * W), half=(1.5 * W, 1.5 * W))]
        return meshing.box_with_fractures(path, [W] * d, size, fr)

    def build(self, mesh, degree):
        p = self.p
        d = mesh.dim
        if d != p.friction_dim:
            raise InputError(f"option -thm_friction_dim = {p.friction_dim} but the mesh is {d}D")
        sigma = self.normal_stress()
        if not sigma > 0:
            raise InputError(f"option -thm_insitu_stress = {sigma:g}: friction_patch needs a compressive "
                             "normal stress on the fracture")
        if not self.bound() > 0:
            raise InputError("friction_patch needs friction: -thm_fracture_friction > 0 or "
                             "-thm_fracture_cohesion > 0")
        u_scale = self.bound() * self.H / self.shear_modulus()
        model, _ = mechanics_model(p, mesh, degree, lambda x, t: 0.0, sigma, u_scale)
        ex = np.zeros(d)
        ex[-1] = 1.0

        def side_traction(sign):
            return lambda x, t: sign * ex * self.exact(t)[0]
        model.facets.append(pe.traction("u", "right", side_traction(1.0)))
        model.facets.append(pe.traction("u", "left", side_traction(-1.0)))
        rate = self.delta(self.final_time) / self.final_time
        bcs = [Dirichlet("u", "bottom", lambda x, t: np.zeros((len(x), d)), components=tuple(range(d))),
               Dirichlet("u", "top", lambda x, t: np.full(len(x), self.delta(t)),
                         rate=lambda x, t: np.full(len(x), rate if t < self.final_time else 0.0),
                         components=(0,))]
        if d == 3:
            bcs.append(Dirichlet("u", "top", lambda x, t: np.zeros(len(x)), components=(1,)))
        scales = {"u": FieldScale(u_scale), "lam": FieldScale(sigma), "tau": FieldScale(sigma)}
        return Setup(model, bcs, scales, {"lam": constant(sigma)}, _FrictionPatchMonitor(self))

    def solver_defaults(self, comm):
        return contact_solver_defaults(comm)


# -- inclined_crack ------------------------------------------------------------------------
@dataclass(frozen=True)
class InclinedCrackParams:
    """Frictional crack inclined in a uniaxial compression (inclined_crack)"""
    inclined_dim: int = param(2, "-", "2: plane-strain crack; 3: penny crack (half model x >= 0)",
                              choices=(2, 3), kind=MESH)
    inclined_half_length: float = param(1.0, "m", "crack half-length (2D) or radius (3D) a", lo=0.0,
                                        lo_open=True, kind=MESH)
    inclined_angle: float = param(45.0, "deg", "angle psi of the crack to the plane normal to the load",
                                  lo=0.0, hi=90.0, lo_open=True, kind=MESH)
    inclined_compression: float = param(10e6, "Pa", "uniaxial compression sigma along the last axis",
                                        lo=0.0, lo_open=True, kind=PHYSICS)
    inclined_box: float = param(20.0, "-", "domain half-size L / a", lo=2.0, kind=MESH)
    inclined_crack_size: float = param(0.05, "-", "mesh size on the crack / a", lo=1e-4, hi=1.0, kind=MESH)


class _InclinedCrackMonitor(Monitor):
    """Slip along the in-situ shear's direction against the exact profile,
    at the traction's nodes (monitors.contact_node_fields)."""

    def __init__(self, scene):
        self.scene = scene
        self.last, self.profile = {}, {}

    def __call__(self, problem, t, X=None):
        sc, comm = self.scene, problem.dm.comm
        f = contact_node_fields(problem, X, t)
        x = problem.disc.field_node_coordinates("lam")
        lam = problem.field_values("lam", X, t)[:, 0]
        n = sc.normal()
        r = np.linalg.norm(x - np.outer(x @ n, n), axis=1)          # distance from the centre, in the plane
        shear = sc.shear()
        slip = f["slip"] @ (shear / np.linalg.norm(shear))            # along the in-situ shear
        exact = sc.exact_slip(r)
        g = problem.disc.global_index[problem.disc.field_local_dofs("lam")[:, 0]]
        lo, hi = problem.X.getOwnershipRange()
        inner = (r < 0.95 * sc.a) & (g >= lo) & (g < hi)          # each node once over the ranks
        num = probes.global_sum(comm, float(np.sum((slip - exact)[inner] ** 2)))
        den = probes.global_sum(comm, float(np.sum(exact[inner] ** 2)))
        tau = np.linalg.norm(f["shear_traction"], axis=1)
        centre, centre_exact = probes.nearest(comm, x, np.zeros(x.shape[1]), (slip, exact))
        self.last = {"slip_centre": centre, "slip_centre_exact": centre_exact,    # nearest the centre
                     "slip_l2_error": float(np.sqrt(num / den)) if den > 0 else 0.0,
                     "lam_error": probes.global_max(comm, np.abs(lam - sc.normal_stress())[inner],
                                                    empty=0.0) / sc.normal_stress(),
                     "law_error": probes.global_max(comm, np.abs(tau / sc.local_bound(lam) - 1.0)[inner],
                                                    empty=0.0),
                     **slip_columns(problem, fields=f)}
        rows = probes.gather_root(comm, np.column_stack([r, slip, exact]))
        if rows is not None:
            order = np.argsort(rows[:, 0])
            self.profile = {"r": rows[order, 0].tolist(), "slip": rows[order, 1].tolist(),
                            "exact": rows[order, 2].tolist()}
        return self.last

    def report(self, problem, t):
        return dict(self.last, profile=self.profile,
                    error={k: self.last.get(k) for k in ("slip_l2_error", "lam_error", "law_error")})


class InclinedCrack(_CoulombScene):
    name = "inclined_crack"
    description = "frictional crack inclined in uniaxial compression: slip against the mode II profile"
    parameters = (mt.group("Rock", mt.ELASTIC), mt.group("Contact", mt.CONTACT), InclinedCrackParams)
    time = TimeDefaults(final_time=1.0, dt_initial=1.0, mesh_size=0.0)
    history_columns = ("slip_centre", "slip_centre_exact", "slip_l2_error", "lam_error", "law_error",
                       "slip_max", "slipping_area")

    @property
    def a(self) -> float:
        return self.p.inclined_half_length

    @property
    def dim(self) -> int:
        return self.p.inclined_dim

    def normal(self) -> np.ndarray:
        """The crack's unit normal: e_y (2D) or e_z (3D) turned by psi about the z (2D) or x (3D) axis."""
        psi = np.radians(self.p.inclined_angle)
        if self.dim == 2:
            return np.array([-np.sin(psi), np.cos(psi)])
        return np.array([0.0, -np.sin(psi), np.cos(psi)])

    def stress(self) -> np.ndarray:
        """The in-situ uniaxial compression along the last axis (tension positive)."""
        S = np.zeros((self.dim, self.dim))
        S[-1, -1] = -self.p.inclined_compression
        return S

    def normal_stress(self) -> float:
        n = self.normal()
        return -float(n @ self.stress() @ n)

    def shear(self) -> np.ndarray:
        """The in-situ shear traction on the plane, (I - n n) sigma0 n."""
        n = self.normal()
        t = self.stress() @ n
        return t - (t @ n) * n

    def driving_stress(self) -> float:
        return max(float(np.linalg.norm(self.shear())) - self.bound(), 0.0)

    def exact_slip(self, r):
        """The slip along the in-situ shear: the + face slides along it.  2D
        (mode II Griffith): 4 (1 - nu^2) dtau / E sqrt(a^2 - r^2); 3D (penny
        crack in uniform shear): 16 (1 - nu^2) dtau / (pi (2 - nu) E) sqrt(a^2 - r^2)."""
        p = self.p
        E, nu = p.rock_youngs_modulus, p.rock_poisson_ratio
        c = 4 * (1 - nu ** 2) / E if self.dim == 2 else 16 * (1 - nu ** 2) / (np.pi * (2 - nu) * E)
        return c * self.driving_stress() * np.sqrt(np.maximum(self.a ** 2 - r ** 2, 0.0))

    def boundaries(self):
        L = self.p.inclined_box * self.a
        if self.dim == 2:
            return {"far": lambda x: np.isclose(np.abs(x[:, 0]), L) | np.isclose(np.abs(x[:, 1]), L)}
        return {"sym_x": lambda x: np.isclose(x[:, 0], 0.0),
                "far": lambda x: np.isclose(x[:, 0], L) | np.isclose(np.abs(x[:, 1]), L)
                | np.isclose(np.abs(x[:, 2]), L)}

    def generate_mesh(self, path, size):
        p, a = self.p, self.a
        L = p.inclined_box * a
        h = p.inclined_crack_size * a
        size = size or L / 10
        if self.dim == 2:
            psi = np.radians(p.inclined_angle)
            e = a * np.array([np.cos(psi), np.sin(psi)])
            fr = [meshing.Fracture("segment", p0=tuple(-e), p1=tuple(e), size=h)]
            return meshing.box_with_fractures(path, [2 * L, 2 * L], size, fr, grading_distance=3 * size,
                                              origin=(-L, -L))
        fr = [meshing.Fracture("disc", center=(0.0, 0.0, 0.0), radius=a, size=h, dip=p.inclined_angle,
                               strike=0)]
        return meshing.box_with_fractures(path, [L, 2 * L, 2 * L], size, fr, grading_distance=3 * size,
                                          origin=(0.0, -L, -L))

    def build(self, mesh, degree):
        from petthm.physics.builders import ModelBuilder
        p, d = self.p, self.dim
        if mesh.dim != d:
            raise InputError(f"option -thm_inclined_dim = {d} but the mesh is {mesh.dim}D")
        if not self.bound() > 0:
            raise InputError("inclined_crack needs friction: -thm_fracture_friction > 0 or "
                             "-thm_fracture_cohesion > 0 (a frictionless crack cannot carry the in-situ "
                             "shear)")
        normals = mesh.fracture.normals if mesh.fracture is not None and len(mesh.fracture.normals) else None
        if normals is not None and not np.allclose(np.abs(normals @ self.normal()), 1.0, atol=1e-6):
            raise InputError("inclined_crack: the mesh's fracture is not the plane of -thm_inclined_angle")
        sn = self.normal_stress()
        w_ref = max(float(self.exact_slip(np.zeros(1))[0]), 1e-6 * self.a * sn / p.rock_youngs_modulus)
        b = ModelBuilder(p, d)
        b.elasticity(degree)
        b.contact(normal_stress=sn, u_scale=w_ref, pressure=lambda x, t: 0.0, insitu_stress=self.stress())
        model = b.build()
        bcs = [Dirichlet("u", "far", lambda x, t: np.zeros((len(x), d)))]
        symmetry = None
        if d == 3:       # symmetry: no x-displacement, no shear along the tangent that is e_x
            bcs.append(Dirichlet("u", "sym_x", lambda x, t: np.zeros(len(x)), components=(0,)))
            symmetry = {"sym_x": int(np.argmax(np.abs(tangent_basis(self.normal()[None, :])[0][:, 0])))}
        bcs += tip_tractions(model, lambda x, t: np.full(len(x), sn), symmetry)
        scales = {"u": FieldScale(w_ref), "lam": FieldScale(sn)}
        return Setup(model, bcs, scales, {"lam": constant(sn)}, _InclinedCrackMonitor(self))

    def solver_defaults(self, comm):
        return contact_solver_defaults(comm)
