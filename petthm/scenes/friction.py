"""Frictional contact scenes (physics.md section 3; kernels/friction.py).

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
  GEOS), lam = sigma_n and |tau| = c0 + mu_f sigma_n.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import materials as mt
from .. import meshing, probes
from ..assembly import FieldScale
from ..constraints import Dirichlet
from ..errors import InputError
from ..fields import Domain, Side, Trace
from ..kernels import poroelastic as pe
from ..kernels.friction import tangent_basis
from ..monitors import contact_node_fields
from ..params import param
from .base import Monitor, Scene, Setup, TimeDefaults, constant, register, tip_tractions
from .contact import contact_solver_defaults, fracture_normal, mechanics_model


@dataclass(frozen=True)
class FrictionPatchParams:
    """Sheared fracture across the domain (friction_patch)"""
    friction_dim: int = param(2, "-", "space dimension", choices=(2, 3))
    friction_size: float = param(10.0, "m", "domain width and height H", lo=0.0, lo_open=True)
    friction_shear_ratio: float = param(2.0, "-", "final G delta / (H b), b = c0 + mu_f sigma: < 1 stick, "
                                        "> 1 slip", lo=0.0)


def fracture_state(problem, X=None, t: float = 0.0, with_coordinates: bool = False):
    """At the fracture's lam nodes on this rank (each node once): lam (n,),
    tau (n, d - 1) and the tangential jump s (n, d - 1), in the tangent basis
    of each face (kernels/friction.tangent_basis); and the nodes'
    coordinates (n, d) ``with_coordinates``."""
    disc = problem.disc
    surf = disc.regions[Domain.FRACTURE]
    xl, _ = problem.local_arrays(X or problem.X, t)
    lam_dofs = disc.region_dofs(Domain.FRACTURE, "lam")
    nc, nb, d = lam_dofs.shape[0], lam_dofs.shape[1], surf.dim
    lam = xl[lam_dofs] * problem.scales["lam"].scale
    tau = xl[disc.region_dofs(Domain.FRACTURE, "tau")].reshape(nc, nb, d - 1) * problem.scales["tau"].scale
    up, um = (xl[disc.region_dofs(Domain.FRACTURE, Trace("u", side))[:, :nb * d]].reshape(nc, nb, d)
              for side in (Side.PLUS, Side.MINUS))
    T = tangent_basis(surf.normals)                                             # (nc, d - 1, d)
    s = np.einsum("cka,cia->cki", up - um, T) * problem.scales["u"].scale
    local, first = np.unique(lam_dofs.ravel(), return_index=True)
    out = (lam.ravel()[first], tau.reshape(-1, d - 1)[first], s.reshape(-1, d - 1)[first])
    if with_coordinates:
        coords = disc.field_node_coordinates("lam")
        order = np.argsort(disc.field_local_dofs("lam").ravel())
        pos = np.searchsorted(disc.field_local_dofs("lam").ravel()[order], local)
        out = out + (coords[order][pos],)
    return out


def slip_columns(problem, X=None, t: float = 0.0) -> dict:
    """History columns of a frictional fracture: the largest slip magnitude
    and the slipping area (monitors.contact_node_fields)."""
    comm = problem.dm.comm
    f = contact_node_fields(problem, X, t)
    return {"slip_max": probes.global_max(comm, f["slip_magnitude"], empty=0.0),
            "slipping_area": probes.global_sum(comm, float(f["slipping_area"][0]))}


class _FrictionPatchMonitor(Monitor):
    def __init__(self, scene):
        self.scene = scene
        self.worst, self.last = {}, {}

    def __call__(self, problem, t, X=None):
        sc, comm = self.scene, problem.dm.comm
        lam, tau, s = fracture_state(problem, X, t)
        self.last = slip_columns(problem, X, t)
        tau_s, slip = sc.exact(t)
        bound = sc.bound()
        tau_ex = np.zeros(tau.shape[1])
        tau_ex[0] = -tau_s                                  # tau opposes the + face's slip in +x
        s_ex = np.zeros(tau.shape[1])
        s_ex[0] = slip
        mag = np.linalg.norm(tau, axis=1)
        out = {"slip_max": probes.global_max(comm, np.linalg.norm(s, axis=1), empty=0.0),
               "slip_exact": slip,
               "slip_error": probes.global_max(comm, np.linalg.norm(s - s_ex, axis=1), empty=0.0),
               "tau_error": probes.global_max(comm, np.linalg.norm(tau - tau_ex, axis=1), empty=0.0) / bound,
               "lam_error": probes.global_max(comm, np.abs(lam - sc.sigma()), empty=0.0) / sc.sigma(),
               "coulomb_max": probes.global_max(comm, mag - sc.local_bound(lam), empty=0.0) / bound,
               **self.last}
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


@register
class FrictionPatch(Scene):
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

    def sigma(self) -> float:
        return self.p.normal_stress(fracture_normal(self.p.friction_dim))

    def bound(self) -> float:
        """b = c0 + mu_f sigma: the shear stress at which the fracture slips."""
        return self.p.fracture_cohesion + self.p.fracture_friction * self.sigma()

    def local_bound(self, lam):
        """c0 + mu_f lam at the nodes."""
        return self.p.fracture_cohesion + self.p.fracture_friction * lam

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
        sigma = self.sigma()
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
    inclined_half_length: float = param(1.0, "m", "crack half-length a", lo=0.0, lo_open=True)
    inclined_angle: float = param(45.0, "deg", "crack angle psi to the x axis (the load is along y)",
                                  lo=0.0, hi=90.0, lo_open=True)
    inclined_compression: float = param(10e6, "Pa", "uniaxial compression sigma along y", lo=0.0,
                                        lo_open=True)
    inclined_box: float = param(20.0, "-", "domain half-size L / a", lo=2.0)
    inclined_crack_size: float = param(0.05, "-", "mesh size on the crack / a", lo=1e-4, hi=1.0)


class _InclinedCrackMonitor(Monitor):
    def __init__(self, scene):
        self.scene = scene
        self.last, self.profile = {}, {}

    def __call__(self, problem, t, X=None):
        sc, comm = self.scene, problem.dm.comm
        lam, tau, s, x = fracture_state(problem, X, t, with_coordinates=True)
        shear = slip_columns(problem, X, t)
        xi = x @ sc.direction()                       # position along the crack from its centre
        slip = s[:, 0] * sc.slip_sign()
        exact = sc.exact_slip(xi)
        inner = np.abs(xi) < 0.95 * sc.a
        num = probes.global_sum(comm, float(np.sum((slip - exact)[inner] ** 2)))
        den = probes.global_sum(comm, float(np.sum(exact[inner] ** 2)))
        centre = probes.global_max(comm, slip[np.abs(xi) < 1e-9 * sc.a], empty=-np.inf)
        self.last = {"slip_centre": centre, "slip_centre_exact": sc.exact_slip(np.zeros(1))[0],
                     "slip_l2_error": float(np.sqrt(num / den)) if den > 0 else 0.0,
                     "lam_error": probes.global_max(comm, np.abs(lam - sc.normal_stress())[inner],
                                                    empty=0.0) / sc.normal_stress(),
                     "law_error": probes.global_max(
                         comm, np.abs(np.linalg.norm(tau, axis=1) / sc.local_bound(lam) - 1.0)[inner],
                         empty=0.0), **shear}
        rows = probes.gather_root(comm, np.column_stack([xi, slip, exact]))
        if rows is not None:
            order = np.argsort(rows[:, 0])
            self.profile = {"x": rows[order, 0].tolist(), "slip": rows[order, 1].tolist(),
                            "exact": rows[order, 2].tolist()}
        return self.last

    def report(self, problem, t):
        return dict(self.last, profile=self.profile)


@register
class InclinedCrack(Scene):
    name = "inclined_crack"
    description = "frictional crack inclined in uniaxial compression: slip against the mode II profile"
    parameters = (mt.group("Rock", mt.ELASTIC), mt.group("Contact", mt.CONTACT), InclinedCrackParams)
    time = TimeDefaults(final_time=1.0, dt_initial=1.0, mesh_size=0.0)
    history_columns = ("slip_centre", "slip_centre_exact", "slip_l2_error", "lam_error", "law_error",
                       "slip_max", "slipping_area")

    @property
    def a(self) -> float:
        return self.p.inclined_half_length

    def direction(self) -> np.ndarray:
        psi = np.radians(self.p.inclined_angle)
        return np.array([np.cos(psi), np.sin(psi)])

    def normal(self) -> np.ndarray:
        psi = np.radians(self.p.inclined_angle)
        return np.array([-np.sin(psi), np.cos(psi)])

    def traction(self) -> np.ndarray:
        """sigma0 . n of the in-situ uniaxial compression (tension positive)."""
        return np.array([0.0, -self.p.inclined_compression * self.normal()[1]])

    def normal_stress(self) -> float:
        return -float(self.traction() @ self.normal())

    def bound(self) -> float:
        return self.local_bound(self.normal_stress())

    def local_bound(self, lam):
        """c0 + mu_f lam."""
        return self.p.fracture_cohesion + self.p.fracture_friction * lam

    def driving_stress(self) -> float:
        shear = self.traction() - (self.traction() @ self.normal()) * self.normal()
        return max(float(np.linalg.norm(shear)) - self.bound(), 0.0)

    def slip_sign(self) -> float:
        """The + face slides along sigma0_t (the in-situ shear that tau can no
        longer carry pushes it): +1 where that is along the tangent t of the face."""
        from ..kernels.friction import tangent_basis
        shear = self.traction() - (self.traction() @ self.normal()) * self.normal()
        t = tangent_basis(self.normal()[None, :])[0, 0]
        return float(np.sign(shear @ t)) or 1.0

    def exact_slip(self, xi):
        p = self.p
        E, nu = p.rock_youngs_modulus, p.rock_poisson_ratio
        return 4 * (1 - nu ** 2) / E * self.driving_stress() * np.sqrt(np.maximum(self.a ** 2 - xi ** 2, 0.0))

    def boundaries(self):
        L = self.p.inclined_box * self.a
        return {"far": lambda x: np.isclose(np.abs(x[:, 0]), L) | np.isclose(np.abs(x[:, 1]), L)}

    def generate_mesh(self, path, size):
        p, a = self.p, self.a
        L = p.inclined_box * a
        h = p.inclined_crack_size * a
        e = a * self.direction()
        fr = [meshing.Fracture("segment", p0=tuple(-e), p1=tuple(e), size=h)]
        return meshing.box_with_fractures(path, [2 * L, 2 * L], size or L / 10, fr,
                                          grading_distance=3 * (size or L / 10), origin=(-L, -L))

    def build(self, mesh, degree):
        from ..builders import ModelBuilder
        p = self.p
        if mesh.dim != 2:
            raise InputError("inclined_crack is a 2D scene: the mesh is 3D")
        if not self.bound() > 0:
            raise InputError("inclined_crack needs friction: -thm_fracture_friction > 0 or "
                             "-thm_fracture_cohesion > 0 (a frictionless crack cannot carry the in-situ "
                             "shear)")
        sn = self.normal_stress()
        w_ref = max(float(self.exact_slip(np.zeros(1))[0]), 1e-6 * self.a * sn / p.rock_youngs_modulus)
        b = ModelBuilder(p, 2)
        b.elasticity(degree)
        b.contact(normal_stress=sn, u_scale=w_ref, pressure=lambda x, t: 0.0,
                  insitu_shear=tuple(self.traction()))
        model = b.build()
        bcs = [Dirichlet("u", "far", lambda x, t: np.zeros((len(x), 2)))] + \
            tip_tractions(model, lambda x, t: np.full(len(x), sn))
        scales = {"u": FieldScale(w_ref), "lam": FieldScale(sn)}
        return Setup(model, bcs, scales, {"lam": constant(sn)}, _InclinedCrackMonitor(self))

    def solver_defaults(self, comm):
        return contact_solver_defaults(comm)
