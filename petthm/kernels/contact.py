"""Mechanics of the fracture faces: fluid pressure and contact traction on the
rock, the frictionless contact constraint and the hydraulic aperture
(physics.md sections 2 and 3).

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

* Contact (section 3): lam >= 0, g >= 0, lam g = 0.  The residual of the
  ``lam`` row is the weak opening int mu g (mu the lam test function); SNES's
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

from dataclasses import dataclass
from functools import partial
from typing import Callable, Optional

import numpy as np

from ..model import CellJacobian, CellResidual


@dataclass(frozen=True)
class FractureMechanics:
    """Loads and contact on the fracture faces (see the module docstring)."""
    dim: int
    u: str = "u"
    lam: Optional[str] = "lam"                 # contact traction field (None: no contact)
    pf: Optional[str] = None                   # fracture pressure field, or
    pressure: Optional[Callable] = None        # a prescribed pf(x, t) (SI), x (nc, nq, d)
    insitu_normal_stress: float = 0.0          # sigma0_nn, tension positive
    gap_tolerance: float = 0.0                 # m, see ``_gap_f0``
    region: str = "fracture"


@dataclass(frozen=True)
class JointLaw:
    """Linear joint law ac(lam) = max(a0 - lam/Kn, ares) (physics.md section 3)."""
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


def normals(ctx):
    """Unit normal of each fracture face (nc, 1, d), from the - to the + face."""
    return ctx._asm.mesh.normals[ctx._cells][:, None, :]


def opening(fm: FractureMechanics, ctx):
    """Normal opening g = (u+ - u-) . n at the quadrature points (nc, nq)."""
    jump = ctx.value(fm.u + "+") - ctx.value(fm.u + "-")
    return np.einsum("cqa,cqa->cq", jump, np.broadcast_to(normals(ctx), jump.shape))


def net_pressure(fm: FractureMechanics, ctx):
    """P = pf + lam + sigma0_nn (nc, nq)."""
    P = np.full(ctx.shape, fm.insitu_normal_stress)
    if fm.pf is not None:
        P = P + ctx.value(fm.pf)[..., 0]
    elif fm.pressure is not None:
        P = P + np.broadcast_to(fm.pressure(ctx.x, ctx.t), ctx.shape)
    if fm.lam is not None:
        P = P + ctx.value(fm.lam)[..., 0]
    return P


def _face_load(fm: FractureMechanics, sign: float, ctx):
    """-sign P n: the load on the + (sign = 1) or - (sign = -1) face's rock."""
    return -sign * net_pressure(fm, ctx)[..., None] * normals(ctx)


def _load_g0(sign: float, ctx):
    """d(face load)/d(pf or lam): -sign n (nc, 1, d, 1)."""
    return (-sign * normals(ctx))[..., None]


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
    return (sign * normals(ctx))[:, :, None, :]


def fracture_mechanics_terms(fm: FractureMechanics) -> tuple[list, list]:
    """Face loads on u+ and u-, and the contact rows of ``lam``."""
    res, jac = [], []
    for side, sign in (("+", 1.0), ("-", -1.0)):
        res.append(CellResidual(fm.u + side, partial(_face_load, fm, sign), None, region=fm.region))
        for q in (fm.pf, fm.lam):
            if q is not None:
                jac.append(CellJacobian(fm.u + side, q, g0=partial(_load_g0, sign), region=fm.region))
    if fm.lam is not None:
        res.append(CellResidual(fm.lam, partial(_gap_f0, fm), None, region=fm.region))
        for side, sign in (("+", 1.0), ("-", -1.0)):
            jac.append(CellJacobian(fm.lam, fm.u + side, g0=partial(_gap_g0, sign), region=fm.region))
    return res, jac


# -- flow in a deformable fracture (physics.md section 4) ----------------------------------
@dataclass(frozen=True)
class DeformableFlow:
    """Cubic-law flow with the aperture of the joint law and the opening:

        da/dt + a c_f dpf/dt - div( a^3/(12 mu) grad pf ) = 0   (+ wells)

    a = ac(lam) + max(g, 0), so da/dt = ac'(lam) dlam/dt + H(g) dg/dt (the
    chain rule; exact for any time integrator).  Isothermal, constant
    viscosity.  Weak form: int w (da/dt + a c_f pdot) + grad w . (a^3/(12 mu)) grad p."""
    mech: FractureMechanics
    law: JointLaw
    compressibility: float
    viscosity: float
    p: str = "pf"


def _aperture_state(fl: DeformableFlow, ctx):
    """(a, d a/d lam, H(g), d a/dt) at the quadrature points (nc, nq)."""
    key = ("aperture", id(fl))
    if key not in ctx._cache:
        m = fl.mech
        lam = ctx.value(m.lam)[..., 0]
        g = opening(m, ctx)
        ac, dac = fl.law.closure_aperture(lam)
        H = (g > 0).astype(float)
        n = np.broadcast_to(normals(ctx), ctx.value(m.u + "+").shape)
        gdot = np.einsum("cqa,cqa->cq", ctx.dot(m.u + "+") - ctx.dot(m.u + "-"), n)
        adot = dac * ctx.dot(m.lam)[..., 0] + H * gdot
        ctx._cache[key] = (ac + H * g, dac, H, adot)
    return ctx._cache[key]


def _dflow_f0(fl: DeformableFlow, ctx):
    a, _, _, adot = _aperture_state(fl, ctx)
    return (adot + a * fl.compressibility * ctx.dot(fl.p)[..., 0])[..., None]


def _dflow_f1(fl: DeformableFlow, ctx):
    a, _, _, _ = _aperture_state(fl, ctx)
    return (a ** 3 / (12 * fl.viscosity))[..., None, None] * ctx.grad(fl.p)


def _dflow_g0_pp(fl: DeformableFlow, ctx):
    a, _, _, _ = _aperture_state(fl, ctx)
    return (a * fl.compressibility * ctx.shift)[..., None, None]


def _dflow_g3_pp(fl: DeformableFlow, ctx):
    a, _, _, _ = _aperture_state(fl, ctx)
    d = ctx.dim
    return (a ** 3 / (12 * fl.viscosity))[..., None, None, None, None] * np.eye(d)[None, None, None, :, None, :]


def _da_sensitivity(fl: DeformableFlow, ctx):
    """d(f0)/d(a) per unit change of a (shift from a-dot, c_f pdot from storage) and d(f1)/d(a)."""
    a, _, _, _ = _aperture_state(fl, ctx)
    s0 = ctx.shift + fl.compressibility * ctx.dot(fl.p)[..., 0]
    s1 = (3 * a ** 2 / (12 * fl.viscosity))[..., None] * ctx.grad(fl.p)[:, :, 0, :]      # (nc, nq, d)
    return s0, s1


def _dflow_g0_plam(fl: DeformableFlow, ctx):
    _, dac, _, _ = _aperture_state(fl, ctx)
    s0, _ = _da_sensitivity(fl, ctx)
    return (dac * s0)[..., None, None]


def _dflow_g2_plam(fl: DeformableFlow, ctx):
    _, dac, _, _ = _aperture_state(fl, ctx)
    _, s1 = _da_sensitivity(fl, ctx)
    return (dac[..., None] * s1)[:, :, None, :, None]


def _dflow_g0_pu(fl: DeformableFlow, sign: float, ctx):
    _, _, H, _ = _aperture_state(fl, ctx)
    s0, _ = _da_sensitivity(fl, ctx)
    return (sign * H * s0)[..., None, None] * normals(ctx)[:, :, None, :]


def _dflow_g2_pu(fl: DeformableFlow, sign: float, ctx):
    _, _, H, _ = _aperture_state(fl, ctx)
    _, s1 = _da_sensitivity(fl, ctx)
    return sign * (H[..., None] * s1)[:, :, None, :, None] * normals(ctx)[:, :, None, None, :]


def deformable_flow_terms(fl: DeformableFlow) -> tuple[list, list]:
    """Residual and Jacobian of the fracture flow with a = a(lam, g)."""
    m, reg = fl.mech, fl.mech.region
    res = [CellResidual(fl.p, partial(_dflow_f0, fl), partial(_dflow_f1, fl), region=reg)]
    jac = [CellJacobian(fl.p, fl.p, g0=partial(_dflow_g0_pp, fl), g3=partial(_dflow_g3_pp, fl), region=reg),
           CellJacobian(fl.p, m.lam, g0=partial(_dflow_g0_plam, fl), g2=partial(_dflow_g2_plam, fl), region=reg)]
    for side, sign in (("+", 1.0), ("-", -1.0)):
        jac.append(CellJacobian(fl.p, m.u + side, g0=partial(_dflow_g0_pu, fl, sign),
                                g2=partial(_dflow_g2_pu, fl, sign), region=reg))
    return res, jac
