"""Wells in the rock matrix (theory manual, "Equations: wells", Scene 3): a well's
perforated interval is a line source (injector) or sink (producer) in the
pm equation, and the enthalpy it carries is a source or sink in the Tm
equation.

Distribution along the interval: uniform (the rate per metre is Q / l_p).
The line source Q/l_p delta_line is lumped onto the mesh vertices that lie
on the interval (the mesh must contain the segment:
``meshing.box_with_fractures`` embeds it), vertex k carrying the weight w_k = (its share of the interval's
length) / l_p (half of each adjacent node spacing; sum w_k = 1).  Each node
is a point term of ``kernels/wells.py``:

* injector: the rate w_k Q into pm; its vertices hold Tm = T_inj (a
  Dirichlet condition on the interval, ``Perforation.contains``: "injected
  temperature on the injector's interval", theory manual, "Equations: wells"), whose
  reaction is the enthalpy the well brings (rho_f C_f Q T_inj carried out by
  the fluid plus what the cold well bore conducts).  The alternative, the
  enthalpy w_k rho_f C_f Q T_inj as a nodal source (the fracture wells' form,
  ``enthalpy_source``), leaves the Galerkin outflow of the well's cells with
  the mean temperature of their nodes: the well node falls far below T_inj
  (-170 degC on a 5 m mesh; manual, Scene 3);
* producer at a rate: w_k Q_p out of pm, carrying rho_f C_f w_k Q_p T_m,k
  out of Tm (the local matrix enthalpy, advective outflow);
* producer at a pressure p_w: Q_k = PI_k (pm_k - p_w) with the line well's
  index PI_k = 2 pi k_h l_k / (mu(T0) ln(r_e / r_w)) (Peaceman 1983 for a
  well along the cells, r_e = 0.2 h the equivalent radius at element size
  h, floored at 2 r_w; l_k = w_k l_p, k_h the permeability across the well).

The injected volume is therefore Q t exactly (the weights sum to one, and
the balance monitors sum every point term), and the produced enthalpy is
what the Tm equation loses: the discrete mass and energy balances close to
the solver tolerance.  Uniform distribution is the choice: a well index
distribution would weight the nodes by the local mobility and needs a
well-bore pressure unknown per well (a later option, manual, Scene 3).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from petthm.discretisation import probes
from petthm.discretisation.model import PointTerm
from petthm.errors import InputError
from petthm.params import CELSIUS
from petthm.physics.kernels import wells as wl
from petthm.physics.linewells import well_index


@dataclass(frozen=True)
class Perforation:
    """The perforated interval of a vertical (or any straight) well: from
    ``bottom`` to ``top`` (x, y, z)."""
    name: str
    bottom: tuple
    top: tuple

    @property
    def length(self) -> float:
        return float(np.linalg.norm(np.subtract(self.top, self.bottom)))

    @property
    def direction(self) -> np.ndarray:
        return np.subtract(self.top, self.bottom) / self.length

    def contains(self, x: np.ndarray, tol: float = 1e-6) -> np.ndarray:
        """Mask of the points x (n, d) on the interval (within ``tol`` of its length)."""
        b, e, L = np.asarray(self.bottom, dtype=float), self.direction, self.length
        s = (x - b) @ e
        off = np.linalg.norm(x - b - s[:, None] * e, axis=1)
        t = tol * L
        return (off < t) & (s > -t) & (s < L + t)

    def segment(self) -> tuple:
        """((bottom), (top)) for ``meshing.box_with_fractures(well_lines=...)``."""
        return tuple(map(float, self.bottom)), tuple(map(float, self.top))


def nodes_on_interval(mesh, points: np.ndarray, perf: Perforation) -> tuple[np.ndarray, np.ndarray]:
    """(coordinates (n, d), position s along the interval) of this rank's
    mesh ``points`` (vertices or edges of a field's nodes) that lie on the
    perforated interval, within a round-off tolerance."""
    X = mesh.point_coordinates(points)
    tol = 1e-9 * max(float(mesh.h.max()) if mesh.ncells else 1.0, perf.length)
    on = perf.contains(X, tol / perf.length)
    return X[on], (X[on] - np.asarray(perf.bottom, dtype=float)) @ perf.direction


def lumped_weights(s: np.ndarray, length: float) -> np.ndarray:
    """The uniform line density's weights at the sorted positions ``s``
    (0 ... length): half of each adjacent spacing, over the length."""
    gaps = np.diff(s)
    w = np.zeros(len(s))
    w[:-1] += gaps / 2
    w[1:] += gaps / 2
    return w / length


@dataclass
class Node:
    point: tuple
    weight: float


def interval_nodes(mesh, perf: Perforation) -> list[Node]:
    """The mesh vertices on the interval (the same list on every rank,
    sorted bottom to top) with their lumped weights; an ``InputError`` if
    the mesh does not contain the interval's ends or has fewer than two
    vertices on it."""
    comm = mesh.dm.comm
    X, s = nodes_on_interval(mesh, np.arange(mesh.vstart, mesh.vend), perf)
    rows = probes.gather_all(comm, np.column_stack([s, X]) if len(s) else np.zeros((0, 1 + mesh.dim)))
    tol = 1e-9 * max(perf.length, 1.0)
    rows = rows[np.argsort(rows[:, 0], kind="stable")]
    keep = np.ones(len(rows), dtype=bool)
    keep[1:] = np.diff(rows[:, 0]) > tol                  # a node shared by ranks, once
    rows = rows[keep]
    L = perf.length
    if len(rows) < 2 or rows[0, 0] > tol or rows[-1, 0] < L - tol:
        raise InputError(f"the mesh has no vertices along the perforated interval of the "
                         f"{perf.name} from {tuple(perf.bottom)} to {tuple(perf.top)} (found "
                         f"{len(rows)}): a matrix well's interval must be a line of the mesh "
                         "(embed it in the gmsh geometry)")
    w = lumped_weights(rows[:, 0], L)
    return [Node(tuple(r[1:]), float(wk)) for r, wk in zip(rows, w, strict=False)]


def line_well_index(permeability: float, length: float, h: float, well_radius: float, mu: float) -> float:
    """PI (m3/(s Pa)) of a node carrying ``length`` of a well in a rock of
    permeability k across the well: 2 pi k l / (mu ln(r_e/r_w)), r_e = 0.2 h
    (floored at 2 r_w): ``linewells.well_index``."""
    return float(well_index(permeability, length, h, well_radius, mu))


@dataclass
class MatrixWells:
    """An injector at rate Q and a producer at rate Q_p (or at pressure p_w
    when ``production_rate`` is None) in the matrix fields pm and Tm.
    ``make`` returns the point terms; calling the object after a step gives
    the history columns of the wells."""
    injector: Perforation
    producer: Perforation
    injection_rate: float
    injection_temperature: float        # K
    production_rate: float | None
    production_pressure: float
    fluid_rho_c: float
    heat: bool = True
    enthalpy_source: bool = False       # the injector's enthalpy as a nodal source, not Tm = T_inj
    weights: dict = field(default_factory=dict)       # term name -> (well, weight)

    def make(self, mesh, permeability: float, viscosity: float, well_radius: float) -> list[PointTerm]:
        """The point terms on the vertices of both intervals."""
        T = "Tm" if self.heat else None
        rho_c = self.fluid_rho_c if self.heat else 0.0
        h = probes.global_min(mesh.dm.comm, mesh.h if mesh.ncells else [])
        terms = []
        for k, n in enumerate(interval_nodes(mesh, self.injector)):
            name = f"injector[{k}]"
            source = self.heat and self.enthalpy_source
            terms.append(wl.injector(n.point, n.weight * self.injection_rate, rho_c,
                                     self.injection_temperature if source else None, p="pm",
                                     T=T if source else None, name=name))
            self.weights[name] = ("injector", n.weight)
        for k, n in enumerate(interval_nodes(mesh, self.producer)):
            name = f"producer[{k}]"
            if self.production_rate is not None:
                terms.append(wl.rate_producer(n.point, n.weight * self.production_rate, rho_c, p="pm", T=T,
                                              name=name))
            else:
                PI = line_well_index(permeability, n.weight * self.producer.length, h, well_radius, viscosity)
                terms.append(wl.producer(n.point, self.production_pressure, PI, rho_c, p="pm", T=T,
                                         name=name))
            self.weights[name] = ("producer", n.weight)
        return terms

    def __call__(self, problem, t, X=None) -> dict:
        """injection_pressure and production_pressure (the weighted means of
        pm over the intervals), production_rate, production_temperature (the
        produced fluid's mixed temperature, degC), injected_volume_rate."""
        xl, _ = problem.local_arrays(X or problem.X, t)
        sums = np.zeros(6)            # w pm (inj), w pm (prod), rate (prod), rate T (prod), rate (inj)
        for pd in problem.points:
            if not pd.dofs or pd.term.name not in self.weights:
                continue
            well, w = self.weights[pd.term.name]
            v = pd.values(xl, problem.scales)
            r = pd.term.residual(v, t)
            if well == "injector":
                sums[0] += w * v["pm"]
                sums[4] += -r["pm"]
            else:
                sums[1] += w * v["pm"]
                sums[2] += r["pm"]
                sums[3] += r["pm"] * v.get("Tm", 0.0)
                sums[5] += w * v.get("Tm", 0.0)
        sums = probes.mpi(problem.dm.comm).allreduce(sums)
        out = {"injection_pressure": float(sums[0]), "production_pressure": float(sums[1]),
               "production_rate": float(sums[2]), "injection_rate": float(sums[4])}
        if self.heat:
            Tp = sums[3] / sums[2] if sums[2] > 0 else sums[5]
            out["production_temperature"] = float(Tp) - CELSIUS
        return out


__all__ = ["Perforation", "MatrixWells", "interval_nodes", "lumped_weights", "line_well_index"]
