"""Coulomb friction on the fracture faces (theory manual, "Contact and friction").

Unknowns: the tangential traction ``tau`` (a fracture field with d - 1
components in the tangent basis t_i of each face, ``tangent_basis``), next
to the normal contact traction ``lam`` and the displacement u (traces u-,
u+).  Sign convention as for lam (kernels/contact.py): tau is the traction
the contact exerts on the + face (the - face gets -tau), so the momentum
residual gains

    - int_Gamma tau_h . [[v]]_t,     [[v]]_t = sum_i t_i (t_i . [[v]]),

with tau_h in the dual basis (the pairing of lam, ``FRACTURE_DUAL``).

Coulomb's law, |tau| <= b = mu_f lam + c0 (cohesion c0), stick (no slip
increment) or slip (tau = -b ds/|ds|: tau opposes the increment ds of the
tangential jump s = [[u]]_t over the time step), is the projection

    C(tau, lam, ds) = tau - P_b(tau - c ds) = 0,     P_b(z) = z min(1, b/|z|),

(the semismooth complementarity function of Hueber, Stadler & Wohlmuth,
in the form of Berge et al. / PorePy), one equation per node: it is
integrated with the nodal rule of the dual pairing (``FRACTURE_NODAL``), so
row k is D_k C at node k.  Stick: C = c ds (ds = 0); slip: |tau| = b with
tau parallel to -ds; b = 0 (open, or mu_f = c0 = 0): tau = 0.  The
constant c (Pa/m) only weights ds against tau and does not change the
solution: c = E / h with the rock's Young's modulus and the face size, a
stiffness of the mesh, not a tuned penalty.  ds = s_dot / shift is the
increment of the backward-Euler step (shift = 1/dt).  Exact generalised
Jacobian: stick: dC/d(ds) = c I; slip: dC/dtau = I - b/|z| (I - zz/|z|^2),
dC/d(ds) = c b/|z| (I - zz/|z|^2), dC/dlam = -mu_f z/|z|.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np

from petthm.discretisation.model import FRACTURE_DUAL, FRACTURE_NODAL, CellJacobian, CellResidual, Side
from petthm.physics.kernels.contact import SIDES, FractureMechanics


@dataclass(frozen=True)
class Friction:
    """Coulomb friction on the faces of ``mech`` (see the module docstring)."""
    mech: FractureMechanics
    coefficient: float                 # mu_f
    cohesion: float = 0.0              # c0, Pa
    youngs_modulus: float = 1.0        # E of the rock (Pa): c = E / h
    tau: str = "tau"

    def bound(self, lam):
        """c0 + mu_f lam: the Coulomb bound of |tau| (before the cut at 0)."""
        return self.cohesion + self.coefficient * lam


def tangent_basis(normals: np.ndarray) -> np.ndarray:
    """Unit tangents t_i (..., d - 1, d) of unit normals n (..., d): in 2D
    t = (n_y, -n_x); in 3D t1 = (a x n)/|a x n| with a = e_y (e_x where n is
    nearly e_y), t2 = n x t1.  A horizontal fracture (n = e_y in 2D, e_z in
    3D) has t = e_x (2D), t1 = e_x, t2 = e_y (3D)."""
    n = np.asarray(normals, dtype=float)
    if n.shape[-1] == 2:
        return np.stack([n[..., 1], -n[..., 0]], axis=-1)[..., None, :]
    a = np.zeros_like(n)
    near_y = np.abs(n[..., 1]) > 0.9
    a[..., 1] = ~near_y
    a[..., 0] = near_y
    t1 = np.cross(a, n)
    t1 /= np.linalg.norm(t1, axis=-1, keepdims=True)
    return np.stack([t1, np.cross(n, t1)], axis=-2)


def _tangents(ctx) -> np.ndarray:
    """(nc, 1, d - 1, d) of the batch's faces."""
    return ctx.cached("tangents", lambda: tangent_basis(ctx.normals))


def _load_f0(fr: Friction, sign: float, ctx):
    """-sign sum_i tau_i t_i: the friction load on the + (sign 1) or - face."""
    return -sign * np.einsum("cqi,cqid->cqd", ctx.value(fr.tau), np.broadcast_to(
        _tangents(ctx), ctx.shape + _tangents(ctx).shape[2:]))


def _load_g0(sign: float, ctx):
    """d(load)/d(tau) = -sign T^T (nc, 1, d, d - 1)."""
    return -sign * np.swapaxes(_tangents(ctx), -1, -2)


@dataclass(frozen=True)
class _LawState:
    """The friction law at the nodes: C and its derivatives (see the module docstring)."""
    C: np.ndarray          # (nc, nq, m)
    dtau: np.ndarray       # (nc, nq, m, m)
    dds: np.ndarray        # (nc, nq, m, m)  dC / d(ds)
    dlam: np.ndarray       # (nc, nq, m)


def slip_increment(fr: Friction, ctx) -> np.ndarray:
    """ds = T (u+_dot - u-_dot) / shift (nc, nq, d - 1): the increment of
    the tangential jump over the step (zero where no step is known)."""
    m = fr.mech
    jump = ctx.dot(m.trace(Side.PLUS)) - ctx.dot(m.trace(Side.MINUS))
    T = _tangents(ctx)
    rate = np.einsum("cqd,cqid->cqi", jump, np.broadcast_to(T, jump.shape[:2] + T.shape[2:]))
    return rate / ctx.shift if ctx.shift > 0 else np.zeros_like(rate)


def law_state(fr: Friction, ctx) -> _LawState:
    return ctx.cached(("friction", id(fr)), lambda: _law_state(fr, ctx))


def _law_state(fr: Friction, ctx) -> _LawState:
    tau = ctx.value(fr.tau)
    lam = ctx.value(fr.mech.lam)[..., 0]
    c = fr.youngs_modulus / ctx.h[:, :, None]                                   # (nc, 1, 1)
    z = tau - c * slip_increment(fr, ctx)
    bound = fr.bound(lam)
    b = np.maximum(bound, 0.0)
    norm = np.linalg.norm(z, axis=-1)
    slip = (norm > b) | (b <= 0.0)          # b = 0: P_0 = 0, tau = 0 whatever z (an open node slides)
    safe = np.where(norm > 0.0, norm, 1.0)
    zhat = z / safe[..., None]
    ratio = np.where(slip, b / safe, 0.0)[..., None, None]
    k = tau.shape[-1]
    eye = np.eye(k)
    dP = ratio * (eye - zhat[..., :, None] * zhat[..., None, :])             # dP_b/dz where slipping
    s = slip[..., None, None]
    C = np.where(slip[..., None], tau - b[..., None] * zhat, tau - z)
    dtau = np.where(s, eye - dP, 0.0)
    dds = np.where(s, c[..., None] * dP, c[..., None] * eye)
    dlam = np.where((slip & (bound > 0))[..., None], -fr.coefficient * zhat, 0.0)
    return _LawState(C, dtau, dds, dlam)


def _law_f0(fr: Friction, ctx):
    return law_state(fr, ctx).C


def _law_g0_tau(fr: Friction, ctx):
    return law_state(fr, ctx).dtau


def _law_g0_lam(fr: Friction, ctx):
    return law_state(fr, ctx).dlam[..., None]


def _law_g0_u(fr: Friction, sign: float, ctx):
    """dC/du+- = dC/d(ds) (+-T): ds = T (u+_dot - u-_dot)/shift and the
    Jacobian is d/du + shift d/du_dot."""
    T = np.broadcast_to(_tangents(ctx), ctx.shape + _tangents(ctx).shape[2:])
    return sign * np.einsum("cqij,cqjd->cqid", law_state(fr, ctx).dds, T)


def friction_terms(fr: Friction) -> tuple[list, list]:
    """The friction load on u+- and the law's rows of ``tau`` (with their Jacobians)."""
    m = fr.mech
    res, jac = [], []
    for side in SIDES:
        u = m.trace(side)
        res.append(CellResidual(u, partial(_load_f0, fr, side.sign), None, region=FRACTURE_DUAL))
        jac.append(CellJacobian(u, fr.tau, g0=partial(_load_g0, side.sign), region=FRACTURE_DUAL))
    res.append(CellResidual(fr.tau, partial(_law_f0, fr), None, region=FRACTURE_NODAL))
    jac.append(CellJacobian(fr.tau, fr.tau, g0=partial(_law_g0_tau, fr), region=FRACTURE_NODAL))
    jac.append(CellJacobian(fr.tau, m.lam, g0=partial(_law_g0_lam, fr), region=FRACTURE_NODAL))
    for side in SIDES:
        jac.append(CellJacobian(fr.tau, m.trace(side), g0=partial(_law_g0_u, fr, side.sign),
                                region=FRACTURE_NODAL))
    return res, jac
