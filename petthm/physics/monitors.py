"""Monitors shared by the scenes: well histories, mass and energy balances,
the range of a temperature field against its physical bounds, and the
running worst of any quantity (theory manual, "Equations: fracture heat").

Everything here is collective (``probes``) and keeps its state in its own
attributes, so that a scene's ``Monitor`` composes them.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from petthm.discretisation import probes
from petthm.discretisation.model import Domain, PointTerm
from petthm.params import CELSIUS
from petthm.physics.balance import BalanceMonitor, Conserved
from petthm.physics.kernels import contact as ct
from petthm.physics.kernels import wells as wl
from petthm.physics.kernels.regional import at


class Worst:
    """The largest value seen per key (NaN: not evaluated, kept as NaN)."""

    def __init__(self):
        self.values: dict[str, float] = {}

    def update(self, key: str, value: float) -> None:
        v = abs(value)
        self.values[key] = v if v != v else max(self.values.get(key, 0.0), v)

    def as_dict(self) -> dict:
        return dict(self.values)


# -- wells on a fracture ------------------------------------------------------------------
@dataclass
class FractureWells:
    """An injector and/or a producer at fracture vertices (the theory manual
    9; kernels/wells.py).  ``share``: the part of each well in the model
    (1/2 on a symmetry plane); ``flow_dim``: 1 for a line fracture (2D), 2
    for a surface (the producer's well index)."""
    injector_at: tuple | None
    producer_at: tuple | None
    heat: bool
    share: float = 1.0
    flow_dim: int = 1
    terms: list[PointTerm] = field(default_factory=list)

    def make(self, p, mesh, transmissivity: float) -> list[PointTerm]:
        """The well terms; the producer's well index uses ``transmissivity``
        a^3/(12 mu) (of the reference aperture and mu(T0))."""
        surf = mesh.fracture
        h = probes.global_min(mesh.dm.comm, surf.h if surf.ncells else [])
        T = "Tf" if self.heat else None
        rho_c, T_inj = (p.fluid_rho_c, p.T_inj) if self.heat else (0.0, None)
        self.terms = []
        if self.injector_at is not None:
            self.terms.append(wl.injector(self.injector_at, self.share * p.injection_rate, rho_c, T_inj, T=T))
        if self.producer_at is not None:
            PI = self.share * wl.well_index(float(transmissivity), h, p.well_radius, self.flow_dim)
            self.terms.append(wl.producer(self.producer_at, p.production_pressure, PI, rho_c, T=T))
        return self.terms

    def __call__(self, problem, t, X=None) -> dict:
        """injection_pressure; production_temperature (degC), production_rate
        (of the whole well), production_pressure_node."""
        out = {}
        if self.injector_at is not None:
            out["injection_pressure"] = probes.point_value(problem, "pf", self.injector_at, X, t)
        if self.producer_at is not None:
            prod = next(w for w in self.terms if w.name == "producer")
            pp = probes.point_value(problem, "pf", self.producer_at, X, t)
            vals = {"pf": pp}
            if self.heat:
                vals["Tf"] = probes.point_value(problem, "Tf", self.producer_at, X, t)
                out["production_temperature"] = vals["Tf"] - CELSIUS
            out["production_rate"] = prod.residual(vals, t)["pf"] / self.share
            out["production_pressure_node"] = pp
        return out


# -- balances ----------------------------------------------------------------------------------
def fracture_balances(flows: dict, reference_aperture: float, p0: float, heat=None,
                      elastic=None, water_energy: bool = False) -> list[Conserved]:
    """Fluid volume and (with ``heat`` = (T0, rho_f C_f, (rho C)m)) energy
    balances of theory manual, "Equations: fracture heat".  With ``elastic`` (a
    ``poroelastic.Elastic`` coupled to pm) the matrix's fluid volume gains
    the Biot term alpha div u (section 5).  ``water_energy``: the stored
    energy counts the water's content change, rho_f C_f m T with m the
    fluid volume stored (``-thm_heat_transport upwind``: kernels/transport.StoredWater).

    The stored amounts are integrated relative to the initial pressure and
    temperature (constants drop out of the change, and the subtraction of
    two large integrals would lose digits); enthalpy fluxes are in kelvin."""
    frac_flow, matrix_flow = flows[Domain.FRACTURE], flows.get(Domain.MATRIX)
    T0, rho_c_f, rho_c_m = heat if heat else (0.0, 0.0, 0.0)
    a_ref = reference_aperture

    def aperture(ctx):
        ap = frac_flow.aperture
        return ap.law.aperture(ctx.value(ap.mech.lam)[..., 0], ct.opening(ap.mech, ctx))

    def vol(flow):
        def f(ctx):
            fl = at(flow, ctx)
            s = fl.storage * (ctx.value(fl.p)[..., 0] - p0)
            if fl.T is not None and fl.thermal_storage:
                s = s - fl.thermal_storage * (ctx.value(fl.T)[..., 0] - T0)
            if fl.aperture is not None:          # (a - a_ref) + a (c_f dp - beta_f dT)
                a = aperture(ctx)
                s = a - a_ref + a * s
            return s
        return f
    storage = {Domain.FRACTURE: vol(frac_flow)}
    if matrix_flow is not None:
        storage[Domain.MATRIX] = vol(matrix_flow)
        if elastic is not None and elastic.p == matrix_flow.p and elastic.biot:
            pore = storage[Domain.MATRIX]
            storage[Domain.MATRIX] = lambda ctx: pore(ctx) + at(elastic, ctx).biot * np.trace(
                ctx.grad(elastic.u), axis1=2, axis2=3)
    out = [Conserved("mass", ("pf", "pm"), storage)]
    if heat:
        def frac_energy(ctx):
            Tf = ctx.value("Tf")[..., 0]
            if frac_flow.aperture is None:
                e = a_ref * rho_c_f * (Tf - T0)
                return e + rho_c_f * storage[Domain.FRACTURE](ctx) * Tf if water_energy else e
            a = aperture(ctx)                    # a (T - T0) + T0 (a - a_ref): the change of a T
            e = rho_c_f * (a * (Tf - T0) + T0 * (a - a_ref))
            if water_energy:                     # a (1 + s) T: + a s T
                e = e + rho_c_f * (storage[Domain.FRACTURE](ctx) - (a - a_ref)) * Tf
            return e

        def matrix_energy(ctx):
            Tm = ctx.value("Tm")[..., 0]
            e = rho_c_m * (Tm - T0)
            if water_energy and Domain.MATRIX in storage:
                e = e + rho_c_f * storage[Domain.MATRIX](ctx) * Tm
            return e
        out.append(Conserved("energy", ("Tf", "Tm"), {Domain.FRACTURE: frac_energy,
                                                      Domain.MATRIX: matrix_energy}))
    return out


class Balances:
    """The balances of a problem, evaluated after every step, with their worst values."""

    def __init__(self, balances: list[Conserved], worst: Worst):
        self.balances, self.worst = balances, worst
        self.monitor: BalanceMonitor | None = None

    def __call__(self, problem, t, X) -> dict:
        if self.monitor is None:
            self.monitor = BalanceMonitor(problem, self.balances)
        out = self.monitor(t, X)
        for k in ("mass_balance", "energy_balance"):
            if k in out:
                self.worst.update(k, out[k])
        return out

    @property
    def last_residual(self):
        """The scaled local residual of the last step (for reactions), or None."""
        return None if self.monitor is None else self.monitor.last_residual


def hit(t: float, times) -> float | None:
    """The time of ``times`` that ``t`` lands on (to 1e-9 relative), or None."""
    for th in times:
        if abs(t - th) <= 1e-9 * th:
            return th
    return None





# -- fracture mechanics ------------------------------------------------------------------------
def fracture_vertices(problem, X=None, t: float = 0.0):
    """(coordinates, opening g, lam) at the vertices of the fracture's - faces
    on this rank (each vertex once)."""
    from petthm.discretisation.model import Side, Trace
    disc = problem.disc
    surf = disc.regions[Domain.FRACTURE]
    xl, _ = problem.local_arrays(X or problem.X, t)
    sc, d = problem.scales["u"], surf.dim
    nv, nc = surf.rdim + 1, surf.ncells
    um = xl[disc.region_dofs(Domain.FRACTURE, Trace("u", Side.MINUS))[:, :nv * d]].reshape(nc, nv, d)
    up = xl[disc.region_dofs(Domain.FRACTURE, Trace("u", Side.PLUS))[:, :nv * d]].reshape(nc, nv, d)
    g = np.einsum("cva,ca->cv", up - um, surf.normals) * sc.scale
    lam = xl[disc.region_dofs(Domain.FRACTURE, "lam")[:, :nv]] * problem.scales["lam"].scale
    verts, first = np.unique(surf.cell_vertices.ravel(), return_index=True)
    x = surf.mesh.vertex_coords[verts]
    return x, g.ravel()[first], lam.ravel()[first]


def _contact_nodes(problem, X=None, t: float = 0.0):
    """Per fracture cell and lam node (SI): the lam dofs (nc, nb), lam
    (nc, nb) and the jump u+ - u- (nc, nb, d), and the local array."""
    from petthm.discretisation.model import Side, Trace
    disc = problem.disc
    xl, _ = problem.local_arrays(X or problem.X, t)
    lam_dofs = disc.region_dofs(Domain.FRACTURE, "lam")
    nc, nb, d = lam_dofs.shape[0], lam_dofs.shape[1], disc.regions[Domain.FRACTURE].dim
    up, um = (xl[disc.region_dofs(Domain.FRACTURE, Trace("u", side))[:, :nb * d]].reshape(nc, nb, d)
              for side in (Side.PLUS, Side.MINUS))
    return lam_dofs, xl[lam_dofs] * problem.scales["lam"].scale, (up - um) * problem.scales["u"].scale, xl


def _nodal_average(problem, dofs: np.ndarray, values: np.ndarray, covered: np.ndarray) -> np.ndarray:
    """``values`` (n, m) at the local dofs ``dofs`` (n,) of one scalar field,
    known where ``covered`` (the node is in a local cell): the average over
    the ranks that know it, on every rank that holds the node (a rank can
    hold a node of another rank's cells only).  Constrained dofs keep their
    local value."""
    out = values.copy()
    cols = [covered.astype(float)] + [values[:, k] * covered for k in range(values.shape[1])]
    parts = []
    for col in cols:
        part = np.zeros(problem.disc.nlocal)
        part[dofs] = col
        parts.append(part)
    shared = [s[dofs] for s in problem.summed_over_ranks(parts)]
    free = problem.disc.global_index[dofs] >= 0
    count = shared[0]
    ok = free & (count > 0)
    for k in range(values.shape[1]):
        out[ok, k] = shared[k + 1][ok] / count[ok]
    return out


def contact_node_checks(problem, closed_traction: float, X=None, t: float = 0.0):
    """(largest |g| over closed lam nodes on this rank, and per fracture cell
    the largest |lam_mid - (lam_a + lam_b)/2| over its edges with both ends
    closed (nc,)), SI: the nodal contact of manual, verification: contact leaves no opening
    where closed and no node-to-node oscillation of lam (the second
    difference of a smooth lam is O(h^2); near a well or a prescribed front
    it is O(h) or larger).  A node is closed where lam > ``closed_traction``;
    the second differences are None for P1 lam (no edge nodes)."""
    from petthm.discretisation.fe import EDGES
    surf = problem.disc.regions[Domain.FRACTURE]
    _, lam, jump, _ = _contact_nodes(problem, X, t)
    nb, r = lam.shape[1], surf.rdim
    g = np.einsum("cka,ca->ck", jump, surf.normals)
    closed = lam > closed_traction
    opening = float(np.max(np.abs(g[closed]), initial=0.0))
    if nb == r + 1:
        return opening, None
    a, b = EDGES[r][:, 0], EDGES[r][:, 1]
    second = np.abs(lam[:, r + 1:] - 0.5 * (lam[:, a] + lam[:, b])) * (closed[:, a] & closed[:, b])
    return opening, second.max(axis=1)


def contact_outputs(problem, t: float) -> dict[str, np.ndarray]:
    """The contact's fields a run writes with lam (``contact_node_fields``
    without the per-rank area weights, and ``lam_recovered``):
    ``Model.outputs`` of the contact."""
    fields = contact_node_fields(problem, t=t)
    out = {k: v for k, v in fields.items() if k not in ("weight", "slipping_area")}
    recovered = recovered_traction(problem, t=t)
    if recovered is not None:
        out["lam_recovered"] = recovered
    return out


def recovered_traction(problem, X=None, t: float = 0.0, recovery=None) -> np.ndarray | None:
    """The contact traction recovered from the rock's stress
    (``kernels.contact.RecoveredTraction``, the model's or ``recovery``) at
    lam's local nodes (SI, in the order of ``field_values("lam")``), with the
    rock's displacement gradient averaged over the cells around each node on
    each side (``wall_gradients``) and the faces' values averaged around each
    node (``Problem.nodal_average``); None without elasticity (collective)."""
    rt = problem.model.recovered_traction if recovery is None else recovery
    if rt is None:
        return None
    gradients = wall_gradients(problem, rt.elastic.u, X, t)
    return problem.nodal_average("lam", dataclasses.replace(rt, wall_gradient=gradients), X, t)


def wall_gradients(problem, u: str, X=None, t: float = 0.0) -> dict:
    """The gradient of the displacement ``u`` at each node of the rock,
    averaged over the cells around it with each cell's share of the node's
    volume (``Problem.nodal_average``: the cells of one side of the fracture
    only, as the faces' nodes are split), at the nodes of u's trace on each
    fracture face on each side: {side: (nc, nb, d, d)} (collective).  On a regular family
    of meshes the average of a P1 gradient is a P1 field of O(h) error or
    better, free of the scatter of one cell's gradient."""
    from petthm.discretisation.model import Trace
    disc = problem.disc
    d = disc.regions[Domain.FRACTURE].dim
    def gradient(ctx):                 # (nc, 1, d, d) where it is constant in each cell
        return np.broadcast_to(ctx.grad(u), ctx.shape + (d, d)).reshape(ctx.shape + (d * d,))
    G = problem.nodal_average(u, gradient, X, t, width=d * d)
    slot = np.full(disc.nlocal, -1)
    slot[disc.field_local_dofs(u)[:, 0]] = np.arange(len(G))
    out = {}
    for side in ct.SIDES:
        first = disc.region_dofs(Domain.FRACTURE, Trace(u, side))[:, ::d]         # (nc, nb): u's trace nodes
        out[side] = G[slot[first]].reshape(first.shape + (d, d))
    return out


def contact_node_fields(problem, X=None, t: float = 0.0) -> dict[str, np.ndarray]:
    """Fracture outputs at the contact traction's nodes (every local node of
    this rank, in the order of ``field_values("lam")``; a node no local cell
    touches takes the value of the ranks whose cells do), SI: ``opening`` g, the
    ``aperture`` (a deformable fracture), and with friction the ``slip``
    (the tangential jump, a global vector), ``slip_magnitude``, the
    ``shear_traction`` (tau as a global vector) and the Coulomb function
    ``coulomb`` = |tau| - (c0 + mu_f lam) (0 where slipping, < 0 stuck);
    ``weight``: each node's share of the fracture area on this rank (the
    dual pairing's D_k); with friction, ``slipping_area`` (one entry: this
    rank's fracture area at nodes with coulomb >= -1e-6 of the bound and a
    slip, by the D_k of its own cells: a sum over ranks is the area)."""
    from petthm.discretisation.fe import nodal_rule
    from petthm.physics.kernels.friction import tangent_basis
    disc, model = problem.disc, problem.model
    surf = disc.regions[Domain.FRACTURE]
    lam_dofs, lam, jump, xl = _contact_nodes(problem, X, t)
    nc, nb, d = lam_dofs.shape[0], lam_dofs.shape[1], surf.dim
    per_cell = {"opening": np.einsum("cka,ca->ck", jump, surf.normals)[..., None], "lam": lam[..., None]}
    if model.has("tau"):
        T = tangent_basis(surf.normals)                                         # (nc, d - 1, d)
        tau = xl[disc.region_dofs(Domain.FRACTURE, "tau")].reshape(nc, nb, d - 1)
        tau = tau * problem.scales["tau"].scale
        per_cell["slip"] = np.einsum("cka,cia,cib->ckb", jump, T, T)
        per_cell["shear_traction"] = np.einsum("cki,cia->cka", tau, T)
    order = disc.field_local_dofs("lam")[:, 0]
    slot = np.full(xl.size, -1)
    slot[order] = np.arange(len(order))
    idx = slot[lam_dofs.ravel()]
    covered = np.zeros(len(order), dtype=bool)
    covered[idx] = True
    out = {}
    for name, v in per_cell.items():
        # a node no local cell touches is averaged from the ranks whose cells do (below), except a
        # constrained one (on the front, where u is not split): its prescribed lam (and tau = 0), no jump
        a = np.zeros((len(order), v.shape[-1]))
        if name == "lam":
            a[:, 0] = xl[order] * problem.scales["lam"].scale
        a[idx] = v.reshape(-1, v.shape[-1])
        a = _nodal_average(problem, order, a, covered)
        out[name] = a[:, 0] if a.shape[1] == 1 else a
    weights = np.abs(surf.detJ)[:, None] * nodal_rule(surf.rdim, disc.field("lam").degree).weights[None, :]
    out["weight"] = np.bincount(idx, weights=weights.ravel(), minlength=len(order))
    if model.aperture_law is not None:
        out["aperture"] = model.aperture_law.aperture(out["lam"], out["opening"])
    if model.friction_law is not None:
        fr = model.friction_law
        out["slip_magnitude"] = np.linalg.norm(out["slip"], axis=1)
        bound = fr.bound(out["lam"])
        out["coulomb"] = np.linalg.norm(out["shear_traction"], axis=1) - bound
        slipping = (out["coulomb"] >= -1e-6 * np.abs(bound)) & (out["slip_magnitude"] > 0) & (bound > 0)
        out["slipping_area"] = np.array([float(np.sum(weights.ravel() * slipping[idx]))])
    del out["lam"]
    return out
