"""Mechanics of the fracture faces: fluid pressure and contact traction on the
rock, the frictionless contact constraint and the hydraulic aperture
(theory manual, "Equations: rock deformation").

Unknowns: ``u`` (matrix, discontinuous across the fracture: its traces are
"u-" and "u+") and the contact traction ``lam`` (a fracture field, >= 0,
compressive positive).  Normal opening g = (u+ - u-) . n with n from the -
to the + face.

* Face load (section 2: sigma . n+- = -(pf + lam) n+-, written relative to the
  in-situ state because u is the displacement from it): with
  P = pf + lam + sigma0_nn, sigma0_nn = n . sigma0 . n (tension positive; in
  the in-situ state P = 0), the momentum residual gains

      - int_Gamma P [[v]] . n,   [[v]] = v+ - v-.

  This is the work of the net face pressure on the opening; an in-situ stress
  with shear on the fracture plane cannot be carried by a frictionless
  fracture and is refused by the scenes.

* Contact (section 3): lam >= 0, g >= 0, lam g = 0.  lam has the nodes of
  the trace of u (P1 or P2) and is paired with u in the dual basis psi
  (``fe.tabulate_dual``, the ``FRACTURE_DUAL`` region): the load of lam is
  - int lam_h [[v]] . n with lam_h = sum_k lam_k psi_k, and the residual of
  the ``lam`` row k is the weak opening int psi_k g = D_k g~_k, a nodal
  quantity (g~ = g at every vertex; manual, verification: contact).  SNES's
  variational-inequality Newton (``-snes_type vinewtonrsls``) with the bound
  lam >= 0 solves the complementarity: a node either has lam > 0 and
  int mu g = 0 (closed), or lam = 0 and int mu g >= 0 (open).  There is no
  penalty or augmentation constant: the only constants are the unknown and
  residual scales, set from the scene's stress scale and the Jacobian
  (``Problem.auto_residual_scales``).

* Hydraulic aperture: a = ac(lam) + g, ac(lam) = max(a0 - lam/Kn, ares)
  (g taken as max(g, 0), see ``JointLaw.aperture``).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import numpy as np

from petthm.discretisation.model import (
    FRACTURE,
    FRACTURE_DUAL,
    CellJacobian,
    CellResidual,
    Region,
    Side,
    Trace,
)
from petthm.physics.kernels.poroelastic import Elastic, wall_stress


@dataclass(frozen=True)
class FractureMechanics:
    """Loads and contact on the fracture faces (see the module docstring)."""
    dim: int
    u: str = "u"
    lam: str | None = "lam"                 # contact traction field (None: no contact)
    pf: str | None = None                   # fracture pressure field, or
    pressure: Callable | None = None        # a prescribed pf(x, t) (SI), x (nc, nq, d)
    insitu_normal_stress: float = 0.0          # sigma0_nn, tension positive
    insitu_stress: tuple = ()                  # sigma0 (d x d, row by row, tension positive): its shear
                                               # on each face, carried by tau in the in-situ state
    gap_tolerance: float = 0.0                 # m, see ``_gap_f0``
    region: Region = FRACTURE
    pairing: Region = FRACTURE_DUAL            # where lam meets u (FRACTURE: the consistent pairing)

    def trace(self, side: Side) -> Trace:
        """The displacement on one face."""
        return Trace(self.u, side)


@dataclass(frozen=True)
class JointLaw:
    """Linear joint law ac(lam) = max(a0 - lam/Kn, ares) (theory manual, "Contact and friction")."""
    a0: float
    stiffness: float
    residual: float

    def closure_aperture(self, lam):
        """(ac, d ac/d lam) for contact tractions ``lam`` (array)."""
        a = self.a0 - lam / self.stiffness
        above = a > self.residual
        return np.where(above, a, self.residual), np.where(above, -1.0 / self.stiffness, 0.0)

    def aperture(self, lam, g):
        """Hydraulic aperture a = ac(lam) + max(g, 0) (g < 0 only by the VI's
        tolerance, see ``_gap_f0``: a closed node's aperture is ac(lam) exactly)."""
        return self.closure_aperture(lam)[0] + np.maximum(g, 0.0)


def opening(fm: FractureMechanics, ctx):
    """Normal opening g = (u+ - u-) . n at the quadrature points (nc, nq)."""
    jump = ctx.value(fm.trace(Side.PLUS)) - ctx.value(fm.trace(Side.MINUS))
    return np.einsum("cqa,cqa->cq", jump, np.broadcast_to(ctx.normals, jump.shape))


def fluid_load(fm: FractureMechanics, ctx):
    """pf + sigma0_nn (nc, nq): the net face pressure without the contact traction."""
    P = np.full(ctx.shape, fm.insitu_normal_stress)
    if fm.pf is not None:
        P = P + ctx.value(fm.pf)[..., 0]
    elif fm.pressure is not None:
        P = P + np.broadcast_to(fm.pressure(ctx.x, ctx.t), ctx.shape)
    return P


def _face_load(fm: FractureMechanics, sign: float, ctx):
    """-sign ((pf + sigma0_nn) n + sigma0_t): the fluid's and the in-situ
    stress's load on the + (sign = 1) or - (sign = -1) face's rock (the
    consistent pairing); sigma0_t = (I - n n) sigma0 n, the in-situ shear on
    the plane, which the friction traction tau = -sigma0_t carries in the
    in-situ state (kernels/friction.py)."""
    load = fluid_load(fm, ctx)[..., None] * ctx.normals
    if len(fm.insitu_stress):
        n = ctx.normals
        t = np.einsum("ab,cqb->cqa", np.reshape(fm.insitu_stress, (fm.dim, fm.dim)), n)
        load = load + (t - np.einsum("cqa,cqa->cq", t, n)[..., None] * n)
    return -sign * load


def _contact_load(fm: FractureMechanics, sign: float, ctx):
    """-sign lam_h n: the contact traction's load on one face (lam_h in the
    basis of ``fm.pairing``: the dual basis by default)."""
    return -sign * ctx.value(fm.lam)[..., 0][..., None] * ctx.normals


def _load_g0(sign: float, ctx):
    """d(face load)/d(pf or lam): -sign n (nc, 1, d, 1)."""
    return (-sign * ctx.normals)[..., None]


def _gap_f0(fm: FractureMechanics, ctx):
    """g + g_tol: the VI's complementarity function.  A node with lam = 0 and
    g = 0 to round-off ("biactive") is then open; without the shift the
    reduced-space method can keep such a node closed for ever (its Newton
    step wants lam < 0, which the projection undoes while g stays 0).  The
    scenes set g_tol = 1e-12 of the displacement scale: it allows that much
    penetration, far below any tolerance."""
    return (opening(fm, ctx) + fm.gap_tolerance)[..., None]


def _gap_g0(sign: float, ctx):
    """d g / d u+- = +-n (nc, 1, 1, d)."""
    return (sign * ctx.normals)[:, :, None, :]


#: the faces in the order their terms are registered
SIDES = (Side.PLUS, Side.MINUS)


def fracture_mechanics_terms(fm: FractureMechanics) -> tuple[list, list]:
    """Face loads on u+ and u- (the fluid's on ``fm.region``, the contact
    traction's on ``fm.pairing``), and the contact rows of ``lam``."""
    res, jac = [], []
    for side in SIDES:
        u = fm.trace(side)
        res.append(CellResidual(u, partial(_face_load, fm, side.sign), None, region=fm.region))
        if fm.pf is not None:
            jac.append(CellJacobian(u, fm.pf, g0=partial(_load_g0, side.sign), region=fm.region))
        if fm.lam is not None:
            res.append(CellResidual(u, partial(_contact_load, fm, side.sign), None, region=fm.pairing))
            jac.append(CellJacobian(u, fm.lam, g0=partial(_load_g0, side.sign), region=fm.pairing))
    if fm.lam is not None:
        res.append(CellResidual(fm.lam, partial(_gap_f0, fm), None, region=fm.pairing))
        for side in SIDES:
            jac.append(CellJacobian(fm.lam, fm.trace(side), g0=partial(_gap_g0, side.sign),
                                    region=fm.pairing))
    return res, jac


# -- the traction recovered from the rock's stress (theory manual, "Contact and friction") ----------
@dataclass(frozen=True)
class RecoveredTraction:
    """The contact traction recovered from the rock's stress on the two faces
    (theory manual, "The recovered traction").

    Equilibrium of a face of the rock on side s (outward normal nu_s = -s n)
    reads n . sigma_s n = -(pf + lam + sigma0_nn) + nu_s . h_s, where h_s is any
    further load on that face (the manufactured solutions' face loads), so

        lam*_s = -n . sigma_s n - (pf + sigma0_nn) + nu_s . h_s,

    and lam* is the mean of the two faces' values.  sigma_s
    (``poroelastic.wall_stress``) takes pm and Tm on the face and the
    displacement gradient ``wall_gradient[side]`` (per fracture face and
    node of u's trace, (nc, nb, d, d): the rock's gradient averaged over the
    cells around the node on that side, ``monitors.wall_gradients``; for
    the nodal rule, whose points are those nodes: u has the highest
    degree of the fields; the model holds None, and
    ``monitors.recovered_traction`` sets it).  ``face_load(side, ctx)``
    (nc, nq, d): h_s, or None."""
    mech: FractureMechanics
    elastic: Elastic                         # the rock's
    face_load: Callable | None = None
    wall_gradient: dict | None = None

    def on_side(self, side: Side, ctx):
        """lam*_s (nc, nq) at the fracture's points."""
        G = ctx.cell_values(self.wall_gradient[side])
        if G.shape[1] != ctx.shape[1]:
            raise ValueError(f"wall_gradient has {G.shape[1]} nodes per face and the rule {ctx.shape[1]} "
                             "points: it is evaluated at the nodes of u's trace (the nodal rule)")
        sigma = wall_stress(self.elastic, side, ctx, G)
        n = np.broadcast_to(ctx.normals, sigma.shape[:-1])
        lam = -np.einsum("cqa,cqab,cqb->cq", n, sigma, n) - fluid_load(self.mech, ctx)
        if self.face_load is not None:
            lam = lam - side.sign * np.einsum("cqa,cqa->cq", self.face_load(side, ctx), n)
        return lam

    def __call__(self, ctx):
        """lam* (nc, nq): the mean of the two faces'."""
        return 0.5 * (self.on_side(Side.MINUS, ctx) + self.on_side(Side.PLUS, ctx))


# -- the aperture of a deformable fracture (theory manual, "Contact and friction") -------------------
@dataclass(frozen=True)
class ApertureState:
    """The hydraulic aperture and its derivatives at the quadrature points (nc, nq)."""
    a: np.ndarray          # a = ac(lam) + H(g) g
    dlam: np.ndarray       # d a / d lam = ac'(lam)
    H: np.ndarray          # d a / d g = H(g)
    adot: np.ndarray       # d a / dt = ac' dlam/dt + H dg/dt


@dataclass(frozen=True)
class Aperture:
    """a(lam, g) = ac(lam) + max(g, 0) of a fracture with contact: the
    aperture that ``flow.Flow`` and ``heat.Heat`` multiply their
    per-unit-aperture coefficients by (storage a c_f, a beta_f, permeability
    a^3/12, capacity a rho_f C_f, conductivity a lambda_f).  da/dt is the chain
    rule ac'(lam) dlam/dt + H(g) dg/dt, exact for any time integrator away from
    the kinks of a."""
    mech: FractureMechanics
    law: JointLaw

    def state(self, ctx) -> ApertureState:
        return ctx.cached(("aperture", id(self)), lambda: self._state(ctx))

    def _state(self, ctx) -> ApertureState:
        m = self.mech
        lam = ctx.value(m.lam)[..., 0]
        g = opening(m, ctx)
        ac, dac = self.law.closure_aperture(lam)
        H = (g > 0).astype(float)
        up, um = m.trace(Side.PLUS), m.trace(Side.MINUS)
        n = np.broadcast_to(ctx.normals, ctx.value(up).shape)
        gdot = np.einsum("cqa,cqa->cq", ctx.dot(up) - ctx.dot(um), n)
        return ApertureState(ac + H * g, dac, H, dac * ctx.dot(m.lam)[..., 0] + H * gdot)

    def jacobians(self, test, s0: Callable, s1: Callable | None, region: Region | None = None) -> list:
        """Blocks d(residual of ``test``)/d(lam, u+, u-) through the aperture.

        ``s0(ctx)`` (nc, nq) and ``s1(ctx)`` (nc, nq, d) are the derivatives of
        the residual's f0 and f1 with respect to a (None: that one does not
        depend on a), where a and da/dt change together (d(da/dt)/d(unknown)
        = shift da/d(unknown), since ac' and H are piecewise constant).
        ``region``: where the term is integrated (default: the fracture)."""
        m = self.mech

        def g0_lam(ctx):
            return (self.state(ctx).dlam * s0(ctx))[..., None, None]

        def g2_lam(ctx):
            return (self.state(ctx).dlam[..., None] * s1(ctx))[:, :, None, :, None]

        def g0_u(sign, ctx):
            return (sign * self.state(ctx).H * s0(ctx))[..., None, None] * ctx.normals[:, :, None, :]

        def g2_u(sign, ctx):
            return sign * (self.state(ctx).H[..., None] * s1(ctx))[:, :, None, :, None] * \
                ctx.normals[:, :, None, None, :]
        has0, has1 = s0 is not None, s1 is not None
        region = region or m.region
        out = [CellJacobian(test, m.lam, g0=g0_lam if has0 else None, g2=g2_lam if has1 else None,
                            region=region)]
        for side in SIDES:
            out.append(CellJacobian(test, m.trace(side), g0=partial(g0_u, side.sign) if has0 else None,
                                    g2=partial(g2_u, side.sign) if has1 else None, region=region))
        return out

    def element_jacobians(self, test, E: Callable, region: Region) -> list:
        """Blocks d(residual of ``test``)/d(lam, u+, u-) of an element term
        through the aperture: ``E(ctx)`` (nc, nb, nq) is d r_i / d a_q, the
        derivative of the element residual with respect to the aperture at
        each quadrature point of ``region`` (the term depends on a, not on da/dt)."""
        m = self.mech

        def lam_block(ctx):
            st = self.state(ctx)
            dlam = np.broadcast_to(st.dlam, ctx.shape)
            return (E(ctx) @ (dlam[..., None] * ctx.basis(m.lam)[None]))[:, None, None]

        def u_block(sign, ctx):
            st = self.state(ctx)
            H = np.broadcast_to(st.H, ctx.shape)
            K = E(ctx) @ (sign * H[..., None] * ctx.basis(m.trace(Side.PLUS))[None])    # (nc, nbF, nbG)
            n = ctx.normals[:, 0, :]                                                      # (nc, d)
            return K[:, None, None, :, :] * n[:, None, :, None, None]
        out = [CellJacobian(test, m.lam, region=region, element=lam_block)]
        out += [CellJacobian(test, m.trace(side), region=region, element=partial(u_block, side.sign))
                for side in SIDES]
        return out

