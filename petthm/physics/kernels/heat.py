"""Heat transport on one region (matrix cells or fracture faces): the theory manual
sections 6 and 7, and the wall exchange between fracture and rock.

In conservative form with the fluid's enthalpy flux b T, b = rho_f C_f q
(q the Darcy flux of ``kernels/flow.Flow``, or a prescribed velocity), for
the unknown T::

    C dT/dt + div(b T - L grad T) = 0

Matrix: C = (rho C)_m, L = lambda_m.  Fracture: C = a rho_f C_f,
L = a lambda_f (a deformable fracture: the stored energy's rate gains
C T da/dt), and grad is the tangential gradient.  Weak form::

    int w C Tdot - grad w . (b T - L grad T) + sum_e int tau (b . grad w) R

The conservative heat form makes the discrete energy balance exact: with
w = 1 every flux term cancels, so the stored-energy change equals the
enthalpy brought in by wells and boundaries (theory manual, "Equations: fracture heat").  It
differs from the advective form of section 7 by T (S pdot - B Tdot), the
fluid's storage rate times T, which vanishes for an incompressible fluid.
Where the fluid leaves through a boundary without a temperature condition
it carries its enthalpy out (``heatboundary.outflow_term``).
SUPG (Brooks & Hughes 1982) uses the residual of the conservative form,

    R = C Tdot + b . grad T + T div b - L lap T (- s),

tau = ((2|b|/h_p)^2 + 9 (4 L/h_p^2)^2)^(-1/2), h_p = h/p (h the longest
edge; in the advective term, on rock cells, the cell's length along the
streamline: ``advective_tau_term``), with div b taken
from the mass balance of the flow that advects the heat (no second
derivatives of p): div b = -rho_f C_f m, m = S pdot - B Tdot (+ alpha
d(div u)/dt in a Biot rock) - s_p, the fluid stored less the flow's source.
On a deformable fracture the stored energy's C T da/dt and the leakoff's
enthalpy rho_f C_f q_L T (the tied wall rows) cancel against the da/dt and
q_L parts of div b, so m leaves out da/dt there.  Without this term (the
advective form's residual, used before) the scheme is consistent only to
O(tau T div b) with T in kelvin: the full coupled MMS (manual, verification: coupled MMS)
measured L2 slope 2 instead of 3 at P2 and a temperature error dominated by
that term at P1.  What R leaves out on the fracture is lambda_f grad a .
grad T and, unless -thm_fracture_supg_wall_conduction is on, the rock's wall
conduction (``Heat.wall``, kernels/wallflux.py; terms of the size of the
temperature change, not of T).  The fracture's
wall exchange hw (T - Tm) is left out of R: it is a coupling to the rock,
and where it dominates (hw = Nu lambda_f / (2a) is about 1e4 W/m2/K, the
Damkoehler number hw h / |b| is 1e2-1e3) its SUPG term
tau (b . grad w) hw (T - Tm) has off-diagonal entries of the size of the
exchange itself and no sign, and Tf left [Tinj, T0] by 12-19 % in Scene 2.
Without it the scheme is streamline upwinding of the advection-conduction
operator with the (lumped) exchange as a source: Tf stays in the bounds,
at the price of consistency O(tau hw (T - Tm)) in the exchange layer,
which no mesh resolves there (its thickness rho_f C_f q / hw is a few mm).
With w = 1 the SUPG term vanishes, so it does not disturb the balance.
``Heat.upwind`` replaces SUPG by the algebraic upwinding of
``kernels/transport.py`` (bound-preserving, first order), with the
capacity lumped (``Heat.lumped``; on a deformable fracture the stored
energy's C d(aT)/dt too).
Every Jacobian block is exact (tests check them against finite
differences with a negative control).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np

from petthm.discretisation.model import Adjacent, CellJacobian, CellResidual, Domain, Region
from petthm.physics.kernels.flow import (
    Flow,
    _storages,
    aperture_state,
    compressed_content,
    content_rate_beyond_storage,
    g0_block,
    increment_product,
    mobility,
    permeability_grad_p,
    storage_rate,
    unit_darcy,
)
from petthm.physics.kernels.limiter import SETTLE, FluxLimiter
from petthm.physics.kernels.regional import Regional, at, regional
from petthm.physics.kernels.transport import StoredWater, Upwinding, stored_water_terms, upwinding_terms
from petthm.physics.kernels.wallflux import SIDES, WallConduction, supg_g3, wall_flux

#: f(x (nc, nq, d), t) -> array broadcastable to the quadrature points
PointFunction = Callable[[np.ndarray, float], np.ndarray]


@dataclass(frozen=True)
class Heat:
    """Heat-transport coefficients of one region.  With an ``aperture`` the
    capacity and conductivity are per unit aperture (C = a capacity,
    L = a conductivity) and the stored energy's rate gains capacity T da/dt.
    Heat is advected by the Darcy flux of ``flow`` or by a prescribed Darcy
    ``velocity`` v(x, t) (then b = rho_f C_f v, which must be divergence-free
    for the energy balance); ``source`` s(x, t) (W/m3) is added to the right
    side (-int w s, and -s in the SUPG residual R).  With a prescribed
    velocity the enthalpy flux is written b (T - T_ref): the same discrete
    equations (int grad w . b T_ref cancels against the outflow term's
    T_ref part for a divergence-free b with the temperature prescribed
    where the fluid enters), without the round-off of b T in kelvin that
    floors the residual of a field varying by far less than T."""
    region: Domain
    T: str
    capacity: float | Regional      # C
    conductivity: object            # L: a number, a (d, d) tensor (no advection then) or a Regional
    fluid_rho_c: float = 0.0        # rho_f C_f (0: no advection)
    flow: Flow | None = None     # the flow that advects heat, or
    velocity: PointFunction | None = None   # a prescribed Darcy velocity (m/s)
    source: PointFunction | None = None     # W/m3
    reference_temperature: float = 0.0         # T_ref of the enthalpy flux b (T - T_ref), see below
    degree: int = 2
    supg: bool = True
    aperture: object | None = None
    lumped: bool = False            # capacity term by row-sum lumping (P1, no aperture)
    biot: tuple = ()                # (u field, alpha): alpha d(div u)/dt in the flow's mass balance (SUPG)
    wall: WallConduction | None = None      # the rock's wall conduction in R (kernels/wallflux.py)
    upwind: bool = False            # algebraic upwinding (kernels/transport.py) instead of SUPG
    limited: bool = False           # the upwinding's diffusion flux-corrected (kernels/limiter.py)
    settle: float = SETTLE          # the limiter's settling tolerance (kernels/limiter.py)

    @property
    def advects(self) -> bool:
        return (self.flow is not None or self.velocity is not None) and self.fluid_rho_c != 0.0


# -- heat -------------------------------------------------------------------------
class _HeatPoint:
    """Everything the heat residual and its derivatives need at the quadrature
    points (computed once per batch of cells: ``heat_point``)."""

    def __init__(self, h: Heat, ctx):
        self.h = h
        T = h.T
        self.gT = ctx.grad(T)[:, :, 0, :]                           # (nc, nq, d)
        self.Tv = ctx.value(T)[..., 0]
        self.ap = aperture_state(h, ctx)
        a = 1.0 if self.ap is None else self.ap.a
        self.C, self.L = h.capacity * a, h.conductivity * a         # numbers or (nc, nq)
        self.advect = h.advects
        self.mass = None                 # the flow's mass rate (SUPG's T div b), where R carries it
        d = ctx.dim
        if self.advect:
            if h.flow is not None:
                M, dM = mobility(h.flow, ctx)
                self.M, self.dM = M, dM
                self.b = -h.fluid_rho_c * M[..., None] * permeability_grad_p(h.flow, ctx)     # (nc, nq, d)
                # m = (db/dT)/b componentwise factor: b depends on T through M(T)
                self.m = dM / M if h.flow.T == T else np.zeros_like(M)
            else:
                self.b = h.fluid_rho_c * np.broadcast_to(h.velocity(ctx.x, ctx.t), ctx.shape + (d,))
                self.m = np.zeros(ctx.shape)
            hp = ctx.h / h.degree
            self.B1 = 144.0 / hp ** 4                                      # B0 = B1 L^2
            self.adv, self.D = advective_tau_term(self.b, ctx, h.degree)
            self.tau = (1.0 / np.sqrt(self.adv + self.B1 * self.L ** 2) if h.supg
                        else np.zeros(self.b.shape[:2]))
            R = self.C * ctx.dot(T)[..., 0] + np.einsum("cqa,cqa->cq", self.b, self.gT)
            if h.degree > 1:
                self.lapT = ctx.lap(T)[..., 0]
                R = R - self.L * self.lapT
            if h.source is not None:
                R = R - np.broadcast_to(h.source(ctx.x, ctx.t), R.shape)
            if h.wall is not None:
                R = R - wall_flux(h.wall, ctx)
            if h.flow is not None and h.supg:      # T div b = -rho_f C_f T m (the module docstring)
                self.mass = storage_rate(h.flow, ctx)
                if self.ap is not None:
                    self.mass = self.mass + content_rate_beyond_storage(h.flow, ctx)
                if h.biot:
                    self.mass = self.mass + h.biot[1] * np.trace(ctx.grad_dot(h.biot[0]), axis1=2, axis2=3)
                R = R - h.fluid_rho_c * self.Tv * self.mass
            self.R = R
        self.d = d

    @property
    def conservative(self) -> bool:
        """R carries T div b from the flow's mass balance."""
        return self.mass is not None

    @cached_property
    def dZ_db(self):
        """dZ_a/db_c of Z = tau R b: (nc, nq, a, c) (once per batch of cells:
        the T-T and T-p blocks both take it)."""
        tau, R, b = self.tau, self.R, self.b
        eye = np.eye(self.d)[None, None]
        return (-(tau ** 3 * R)[..., None, None] * b[..., :, None] * self.D[..., None, :]
                + tau[..., None, None] * b[..., :, None] * self.gT[..., None, :]
                + (tau * R)[..., None, None] * eye)


def advective_tau_term(b, ctx, degree: int):
    """The advective part (2|b|/h_p)^2 of tau^-2 and its half-derivative
    D = (1/2) d/db of it, (nc, nq) and (nc, nq, d).

    Rock cells: h is the cell's length along the streamline (its longest
    chord parallel to b), h_b = 2|b| / sum_a |b . grad lambda_a| with the
    barycentric coordinates lambda_a (Tezduyar & Park 1986), so the term
    is (p sum_a |b . grad lambda_a|)^2.  It keeps tau |b| / h_b <= 1/2: the
    SUPG capacity term tau C Tdot b . grad w stays below the Galerkin one
    (a larger tau makes the capacity matrix indefinite, and a shorter step
    does not help).  On the thin cells of a layered mesh the longest edge
    overstates the length across the layers 20-40 times: Newton diverged
    at every step length tried where the rock's water crosses the layers
    (Scene 1 with leakoff, manual, Scene 1), and twice h_b still did.
    Fracture faces keep h = their longest edge (their cells are isotropic;
    on a line it is the same length)."""
    G = ctx.Jinv                                                   # rows: grad lambda_1..d
    if G.shape[1] != G.shape[2]:
        A = 4.0 / (ctx.h / degree) ** 2
        return A * np.einsum("cqa,cqa->cq", b, b), A[..., None] * b
    grads = np.concatenate([-G.sum(axis=1, keepdims=True), G], axis=1)           # (nc, d+1, d)
    proj = b @ np.swapaxes(grads, 1, 2)                                            # (nc, nq, d+1)
    S = np.abs(proj).sum(axis=2)
    D = degree ** 2 * S[..., None] * (np.sign(proj) @ grads)
    return (degree * S) ** 2, D


def heat_point(h: Heat, ctx) -> _HeatPoint:
    h = at(h, ctx)
    return ctx.cached(("heat", id(h)), lambda: _HeatPoint(h, ctx))


def _conduction(hp: _HeatPoint, gT):
    L = hp.L
    if hp.ap is not None:                                            # per point (deformable fracture)
        return L[..., None] * gT
    return L * gT if np.isscalar(L) else np.einsum("ab,cqb->cqa", L, gT)


def heat_f0_capacity(h: Heat, ctx):
    """The stored energy's rate alone (the lumped capacity term; ``heat_f0``)."""
    return stored_energy_rate(h, ctx)[..., None]


def stored_energy_rate(h: Heat, ctx):
    """C dT/dt, or C d(aT)/dt on a deformable fracture (``heat_f0``), (nc, nq)."""
    h = at(h, ctx)
    ap = aperture_state(h, ctx)
    if ap is None:
        return h.capacity * ctx.dot(h.T)[..., 0]
    Tdot = ctx.dot(h.T)[..., 0]
    T = ctx.value(h.T)[..., 0]
    return h.capacity * (ap.a * Tdot + T * ap.adot - increment_product(ctx, ap.adot, Tdot))


def heat_f0(h: Heat, ctx):
    """C dT/dt (- s); on a deformable fracture the stored energy's rate
    C d(aT)/dt as backward Euler's exact quotient C (a T - a_old T_old)/dt
    = C (a Tdot + T adot - adot Tdot dt): the energy balance telescopes from
    step to step (without the last term it is off by C da dT per step)."""
    r = np.zeros(ctx.shape) if h.lumped else stored_energy_rate(h, ctx)
    if h.source is not None:
        r = r - np.broadcast_to(h.source(ctx.x, ctx.t), ctx.shape)
    return r[..., None]


def heat_f1(h: Heat, ctx):
    hp = heat_point(h, ctx)
    f1 = _conduction(hp, hp.gT)
    if hp.advect:
        f1 = f1 - hp.b * (hp.Tv - h.reference_temperature)[..., None]
        if h.supg:
            f1 = f1 + (hp.tau * hp.R)[..., None] * hp.b
    return f1[:, :, None, :]


def heat_g0_TT(h: Heat, ctx):
    ap = aperture_state(h, ctx)
    if ap is None:
        return g0_block(h.capacity * ctx.shift)
    return g0_block(h.capacity * ap.a * ctx.shift)      # d/dT of C (a Tdot + T adot - adot Tdot / shift)


def heat_g2_TT(h: Heat, ctx):
    hp = heat_point(h, ctx)
    b, m = hp.b, hp.m[..., None]
    g = -b * (1.0 + hp.Tv[..., None] * m)                   # d(-b T)/dT
    if h.supg:
        g = g + (hp.tau * hp.C * ctx.shift)[..., None] * b
        g = g + (hp.dZ_db @ (b * m)[..., None])[..., 0]
        if hp.conservative:
            g = g + (hp.tau * _dE_dT(h, hp, ctx))[..., None] * b
    return g[:, :, None, :, None]


def _dE_dT(h: Heat, hp: _HeatPoint, ctx):
    """d/dT of E = -rho_f C_f T m (the T div b of R), Tdot moving with T (shift)."""
    d = -h.fluid_rho_c * hp.mass
    fl = h.flow
    if fl.T == h.T and fl.thermal_storage:
        d = d + h.fluid_rho_c * hp.Tv * _storages(fl, ctx)[1] * ctx.shift
        if hp.ap is not None:                 # adot s of a deformable fracture's content
            d = d + h.fluid_rho_c * hp.Tv * hp.ap.adot * fl.thermal_storage
    return d


def heat_g2_Tp(h: Heat, ctx):
    """d(tau R b)/dp through E = -rho_f C_f T S pdot: tau b (-rho_f C_f T S shift)
    (and through adot s on a deformable fracture: + adot c_f)."""
    hp = heat_point(h, ctx)
    dm = _storages(h.flow, ctx)[0] * ctx.shift
    if hp.ap is not None:
        dm = dm + hp.ap.adot * h.flow.storage
    return ((hp.tau * -h.fluid_rho_c * hp.Tv * dm)[..., None] * hp.b)[:, :, None, :, None]


def heat_g3_Tu(h: Heat, ctx):
    """d(tau R b)/d grad u through E = -rho_f C_f T alpha d(div u)/dt:
    tau b_a (-rho_f C_f T alpha shift) d_ij."""
    hp = heat_point(h, ctx)
    c = hp.tau * -h.fluid_rho_c * hp.Tv * h.biot[1] * ctx.shift
    d = ctx.dim
    return (c[..., None] * hp.b)[:, :, None, :, None, None] * np.eye(d)[None, None, None, None]


def heat_g3_TT(h: Heat, ctx):
    d = ctx.dim
    hp = heat_point(h, ctx) if (h.supg or h.aperture is not None) else None
    L = h.conductivity if hp is None else hp.L
    if h.aperture is not None:                                       # per point (deformable fracture)
        g = L[..., None, None] * np.eye(d)
    else:
        g = (L * np.eye(d) if np.isscalar(L) else np.asarray(L))[None, None]
    if h.supg:
        g = g + hp.tau[..., None, None] * hp.b[..., :, None] * hp.b[..., None, :]
    return g[:, :, None, :, None, :]


def heat_g2lap_TT(h: Heat, ctx):
    hp = heat_point(h, ctx)
    return ((-hp.L * hp.tau)[..., None] * hp.b)[:, :, None, :, None]


def heat_g3_Tp(h: Heat, ctx):
    """d f1/d grad p = (-T I + dZ/db) db/dgrad p, db/dgrad p = -rho_f C_f M K."""
    hp = heat_point(h, ctx)
    coef = hp.M if hp.ap is None else hp.M * hp.ap.a ** 3
    dbdg = -h.fluid_rho_c * coef[..., None, None] * h.flow.permeability[None, None]
    D = -hp.Tv[..., None, None] * np.eye(hp.d)[None, None]
    if h.supg:
        D = D + hp.dZ_db
    return (D @ dbdg)[:, :, None, :, None, :]


def heat_s0_aperture(h: Heat, ctx):
    """d f0/d a (with da/dt = shift da): capacity T shift (the Tdot of a Tdot cancels
    against that of -adot Tdot / shift)."""
    return h.capacity * ctx.value(h.T)[..., 0] * ctx.shift


def heat_s1_aperture(h: Heat, ctx):
    """d f1/d a: conductivity grad T - (db/da) T + d(tau R b)/da, db/da = 3 b / a
    (computed as -rho_f C_f M 3 a^2 K_unit grad p), with
    dR/da = capacity Tdot + db/da . grad T - conductivity lap T and
    dtau/da = -tau^3 (A b . db/da + B1 L conductivity)."""
    hp = heat_point(h, ctx)
    s = h.conductivity * hp.gT
    if hp.advect:
        db = -h.fluid_rho_c * (3 * hp.ap.a ** 2 * hp.M)[..., None] * unit_darcy(h.flow, ctx)
        s = s - db * hp.Tv[..., None]
        if h.supg:
            dR = h.capacity * ctx.dot(h.T)[..., 0] + np.einsum("cqa,cqa->cq", db, hp.gT)
            if h.degree > 1:
                dR = dR - h.conductivity * hp.lapT
            if hp.conservative:       # E = -rho_f C_f T a (storage pdot - thermal_storage Tdot)
                fl = h.flow
                s_, sdot = compressed_content(fl, ctx)
                m1 = sdot + ctx.shift * s_                  # d(a sdot + adot s)/da
                dR = dR - h.fluid_rho_c * hp.Tv * m1
            dtau = -hp.tau ** 3 * (np.einsum("cqa,cqa->cq", hp.D, db) + hp.B1 * hp.L * h.conductivity)
            s = s + (dtau * hp.R + hp.tau * dR)[..., None] * hp.b + (hp.tau * hp.R)[..., None] * db
    return s


def _scalar(value) -> bool:
    """A number, or one number per region."""
    return all(np.isscalar(v) for v in value.values) if isinstance(value, Regional) else np.isscalar(value)


def _check_heat(h: Heat) -> None:
    if h.flow is not None and h.velocity is not None:
        raise ValueError("heat is advected by a flow or by a prescribed velocity, not both")
    if h.reference_temperature and h.velocity is None:
        raise ValueError("a reference temperature only with a prescribed (divergence-free) velocity")
    if h.advects and not _scalar(h.conductivity):
        raise ValueError("a conductivity tensor is only supported without advection")
    if h.aperture is not None and (not np.isscalar(h.conductivity) or h.velocity is not None):
        raise ValueError("a deformable fracture takes a scalar conductivity and the flow's velocity")
    if h.lumped and h.degree != 1:
        raise ValueError("a lumped capacity needs P1")
    if h.limited and not h.upwind:
        raise ValueError("the flux limiter corrects the algebraic upwinding")
    if h.upwind and (h.supg or not h.lumped or not h.advects):
        raise ValueError("algebraic upwinding replaces SUPG, with the capacity lumped, on advected heat")


def heat_terms(h: Heat) -> tuple[list, list]:
    _check_heat(h)
    advect = h.advects
    supg = advect and h.supg
    hh = h if advect else replace(h, fluid_rho_c=0.0, flow=None, velocity=None, supg=False)
    region, lumped = Region(h.region), Region(h.region, lumped=True)
    res = [CellResidual(h.T, regional(heat_f0, hh), regional(heat_f1, hh), region=region)]
    water = h.upwind and h.flow is not None
    capacity = h.lumped and not (water and h.aperture is not None)   # else the content a (1 + s)
    if capacity:
        res.append(CellResidual(h.T, regional(heat_f0_capacity, hh), None, region=lumped))
        jac = [CellJacobian(h.T, h.T, g0=regional(heat_g0_TT, hh), region=lumped)]
    else:
        jac = []
    jac += [CellJacobian(h.T, h.T, g0=regional(heat_g0_TT, hh) if h.capacity and not h.lumped else None,
                        g2=regional(heat_g2_TT, hh) if advect else None,
                        g3=regional(heat_g3_TT, hh),
                        g2_lap=regional(heat_g2lap_TT, hh) if supg and h.degree > 1 else None,
                        region=region)]
    if advect and h.flow is not None:
        g2 = regional(heat_g2_Tp, hh) if supg and h.flow.storage else None
        jac.append(CellJacobian(h.T, h.flow.p, g2=g2, g3=regional(heat_g3_Tp, hh), region=region))
        if supg and h.biot:
            jac.append(CellJacobian(h.T, h.biot[0], g3=regional(heat_g3_Tu, hh), region=region))
    if supg and h.wall is not None:
        jac += [CellJacobian(h.T, Adjacent(h.wall.field, s), g3=regional(heat_g3_wall, hh, s), region=region)
                for s in SIDES]
    if h.aperture is not None:
        s0 = None if h.lumped else regional(heat_s0_aperture, hh)
        jac += h.aperture.jacobians(h.T, s0, regional(heat_s1_aperture, hh))
        if capacity:
            jac += h.aperture.jacobians(h.T, regional(heat_s0_aperture, hh), None, lumped)
    if h.upwind:
        limiter = FluxLimiter(settle=h.settle) if h.limited else None
        u = Upwinding(hh, heat_point, limiter)
        if limiter is not None:
            limiter.bind(u)
        r, j = upwinding_terms(u)
        res, jac = res + r, jac + j
    if water:
        r, j = stored_water_terms(StoredWater(hh, h.flow, h.biot))
        res, jac = res + r, jac + j
    return res, jac



def heat_g3_wall(h: Heat, side, ctx):
    """d(tau R b)/d(grad Tm) in the rock cell next to the face on ``side``."""
    hp = heat_point(h, ctx)
    return supg_g3(h.wall, side, hp.tau, hp.b, ctx)
