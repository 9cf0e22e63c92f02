"""Wells along mesh lines, each with one bottom-hole pressure (theory manual,
"Equations: wells"; a deck's ``-thm_well_NAME_*``).

A well's perforated nodes k (its polyline's mesh vertices; in 2D one or
more points, per metre out of plane) exchange water with the rock by
Peaceman's well index PI_k:

    q_k = PI_k (p_w + h_k - p_k),     h_k = rho_f g (z_ref - z_k),

the volume rate into the rock at node k, with p_w the bottom-hole pressure
at the well's shallowest node z_ref and h_k the well bore's hydrostatic
head below it.  ``pressure`` control prescribes p_w(t); ``rate`` control
prescribes Q(t) = sum_k q_k, so that

    p_w = (Q + sum_k PI_k (p_k - h_k)) / sum_k PI_k

and the rate splits among the nodes by their indices and the rock's
pressure there.  p_w is eliminated: each node's row depends on every
node's pressure (a rank-one coupling: the Jacobian block
PI_k (delta_kj - PI_j / sum PI)), and the sums run over all ranks
(``model.NodeSetTerm``).  The heat that node k brings is
rho_f C_f q_k T_inj where water enters the rock (T_inj the well's
temperature; the rock's own T_k where none is given) and rho_f C_f q_k T_k
where it leaves.

PI_k = 2 pi k_perp l_k / (mu ln(r_e / r_w)) (Peaceman 1983): l_k the
node's share of the well's length (half of each segment beside it; 1 m in
2D), k_perp = sqrt(k_1 k_2) of the permeability across the well (the two
principal values in the plane normal to it; in 2D sqrt(det k)), averaged
over the cells at the node, r_e = 0.2 h (h the mean length of the mesh
edges at the node, r_e floored at 2 r_w) and mu at the node's initial
temperature.  A node where the well crosses a fracture (whose pressure
is the rock's there: the walls are tied to it) adds the fracture's index,
2 pi T / ln(r_e / r_w) with T = a^3 / (12 mu) (``fracture_well_index``),
so that the well's rate splits among the fractures it crosses by their
transmissivities; a well of fractures alone (no rock pressure) has that
index alone, in the fracture's pressure and temperature.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from petthm.discretisation.model import NodeSetTerm


@dataclass(frozen=True)
class Schedule:
    """A piecewise-constant value: ``values[i]`` on (times[i], times[i+1]]
    (the first from t = 0, the last to the end)."""
    times: tuple
    values: tuple

    def at(self, t: float) -> float:
        k = int(np.searchsorted(self.times, t, side="left")) - 1
        return float(self.values[min(max(k, 0), len(self.values) - 1)])


@dataclass(frozen=True)
class LineWell:
    """One well: its nodes, their indices and heads, and its control."""
    name: str
    points: np.ndarray              # (n, d) mesh vertices
    index: np.ndarray               # PI_k (m3/(s Pa)), (n,)
    head: np.ndarray                # h_k (Pa), (n,)
    rate: Schedule | None = None     # Q(t), m3/s into the rock (2D: per metre)
    pressure: Schedule | None = None  # p_w(t), Pa
    temperature: float | None = None  # T_inj (K)
    rho_c: float = 0.0              # rho_f C_f; 0: no heat
    p: str = "pm"
    T: str | None = "Tm"
    fractures: tuple = ()           # the fracture each node is on ("": the rock), for the rates per fracture


def well_index(k_perp, length, h, well_radius: float, mu) -> np.ndarray:
    """PI = 2 pi k_perp l / (mu ln(r_e / r_w)), r_e = 0.2 h floored at 2 r_w (arrays)."""
    re = np.maximum(0.2 * np.asarray(h, dtype=float), 2.0 * well_radius)
    kl = np.asarray(k_perp) * np.asarray(length)
    return 2.0 * math.pi * kl / (np.asarray(mu) * np.log(re / well_radius))


def fracture_well_index(transmissivity, h, well_radius: float, flow_dim: int) -> np.ndarray:
    """The index of a well node on a fracture of ``transmissivity`` a^3 /
    (12 mu) (m3/(Pa s), arrays): where a well crosses a fracture (flow_dim
    2, 3D) the fracture's radial inflow 2 pi T / ln(r_e / r_w), r_e as
    ``well_index``; where a well normal to a 2D section lies in a fracture
    (flow_dim 1), 2 T / r_w, the node reached from both sides over r_w (as
    the paper's scenes' wells, ``kernels.wells.well_index``)."""
    T = np.asarray(transmissivity, dtype=float)
    if flow_dim == 1:
        return 2.0 * T / well_radius
    re = np.maximum(0.2 * np.asarray(h, dtype=float), 2.0 * well_radius)
    return 2.0 * math.pi * T / np.log(re / well_radius)


def permeability_across(K: np.ndarray, direction: np.ndarray | None) -> float:
    """sqrt(k_1 k_2) of the permeability K across a well along ``direction``
    (3D); sqrt(det K) of a 2D K (a well normal to the plane, ``direction`` None)."""
    if direction is None:
        return float(math.sqrt(max(np.linalg.det(K), 0.0)))
    e = np.asarray(direction, dtype=float) / np.linalg.norm(direction)
    basis = np.linalg.svd(np.eye(3) - np.outer(e, e))[0][:, :2]         # two unit vectors normal to e
    return float(math.sqrt(max(np.linalg.det(basis.T @ K @ basis), 0.0)))


@dataclass
class WellState:
    """A well at a state: the bottom-hole pressure and the owned nodes' rates."""
    pressure: float
    q: np.ndarray                  # owned nodes' rates into the rock (m3/s)
    S: float                       # sum of PI


def state(w: LineWell, ctx) -> WellState:
    """p_w and the owned nodes' q_k (collective)."""
    PI, h = w.index[ctx.owned], w.head[ctx.owned]
    p = ctx.values[w.p]
    S = float(np.sum(w.index))
    if w.rate is not None:
        total = float(ctx.total([np.sum(PI * (p - h))])[0])
        pw = (w.rate.at(ctx.t) + total) / S
    else:
        pw = w.pressure.at(ctx.t)
    return WellState(pw, PI * (pw + h - p), S)


def _carried(w: LineWell, ctx, q):
    """The temperature of the water each owned node exchanges (K): T_inj (or the
    rock's) where it enters the rock, the rock's where it leaves."""
    T = ctx.values[w.T]
    inj = T if w.temperature is None else np.full_like(T, w.temperature)
    return np.where(q > 0, inj, T)


def residual(w: LineWell, ctx) -> dict:
    s = state(w, ctx)
    out = {w.p: -s.q}
    if w.T is not None and w.rho_c:
        out[w.T] = -w.rho_c * s.q * _carried(w, ctx, s.q)
    return out


def _dq_dp(w: LineWell, ctx, s: WellState) -> np.ndarray:
    """dq_o/dp_j: (m, n) under rate control, the diagonal (m,) under pressure control."""
    PI = w.index[ctx.owned]
    if w.rate is None:
        return -PI
    D = PI[:, None] * w.index[None, :] / s.S
    D[np.arange(len(PI)), ctx.owned] -= PI
    return D


def jacobian(w: LineWell, ctx) -> dict:
    s = state(w, ctx)
    dq = _dq_dp(w, ctx, s)
    out = {(w.p, w.p): -dq}
    if w.T is not None and w.rho_c:
        c = _carried(w, ctx, s.q)
        out[(w.T, w.p)] = -w.rho_c * (c[:, None] * dq if dq.ndim == 2 else c * dq)
        leaving = (s.q <= 0) | (w.temperature is None)
        out[(w.T, w.T)] = -w.rho_c * np.where(leaving, s.q, 0.0)
    return out


def well_term(w: LineWell) -> NodeSetTerm:
    kind = "dense" if w.rate is not None else "diagonal"
    blocks = [(w.p, w.p, kind)]
    fields = (w.p,)
    if w.T is not None and w.rho_c:
        blocks += [(w.T, w.p, kind), (w.T, w.T, "diagonal")]
        fields = (w.p, w.T)
    return NodeSetTerm(w.name, np.asarray(w.points, dtype=float), fields, tuple(blocks),
                       lambda ctx: residual(w, ctx), lambda ctx: jacobian(w, ctx))
