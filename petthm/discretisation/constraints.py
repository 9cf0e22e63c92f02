"""Dirichlet conditions and ties: the local dofs that are not unknowns.

* A ``Dirichlet`` condition prescribes a field (or some components of a
  vector field) on a boundary part; the section constrains those dofs, so
  the global vector holds only the unknowns and the prescribed values are
  written into the local vector before every residual or Jacobian
  evaluation.
* A tie makes a matrix field's nodes on the fracture walls the fracture
  field's unknowns (pm = pf, and Tm = Tf with the ``equilibrium`` wall
  exchange; manual, verification: fracture flow and heat): the tied dofs take the target's values and
  add their residual rows into the target's rows.

The sum of the (SI) residual rows of constrained dofs is the consistent
reaction: the net inflow through those boundaries (``reaction``).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from petsc4py import PETSc

from petthm import compat
from petthm.discretisation.fields import Discretisation

#: Dirichlet data: f(x (n, d), t) -> values (n,) or (n, ncomp); optional time derivative
BoundaryFunction = Callable[[np.ndarray, float], np.ndarray]


@dataclass
class Dirichlet:
    field: str
    boundary: str
    value: BoundaryFunction
    rate: BoundaryFunction | None = None   # d value / dt (default 0)
    components: tuple | None = None        # constrained components of a vector field (None: all)
    steady: bool = False                   # the value does not change in time: evaluated once

    def entry(self):
        """The boundary entry of ``fields.Discretisation``."""
        return self.boundary if self.components is None else (self.boundary, self.components)


def boundary_entries(dirichlet: list[Dirichlet]) -> dict[str, list]:
    """{field: [boundary entries]} for ``fields.Discretisation``."""
    out: dict[str, list] = {}
    for d in dirichlet:
        out.setdefault(d.field, []).append(d.entry())
    return out


class Constraints:
    """The Dirichlet data and ties of a discretisation (see the module docstring)."""

    def __init__(self, disc: Discretisation, dirichlet: list[Dirichlet], template: PETSc.Vec):
        self.disc = disc
        self.dirichlet = list(dirichlet)
        byname = {(d.field, d.boundary, d.components): d for d in dirichlet}
        self.bc = []                           # (Dirichlet, fields.DirichletDofs)
        self._steady_values: dict[int, np.ndarray] = {}     # the values of steady conditions, per dofs
        for dd in disc.dirichlet:
            d = byname.get((dd.source or dd.field, dd.boundary, dd.components))
            if d is not None:
                self.bc.append((d, dd))
        ties = disc.ties
        self.tie_dofs = np.concatenate([t.dofs for t in ties]).astype(compat.INT) if ties else \
            np.zeros(0, dtype=compat.INT)
        target = np.concatenate([t.target_global for t in ties]).astype(compat.INT) if ties else \
            np.zeros(0, dtype=compat.INT)
        self._tie_vec = PETSc.Vec().createSeq(len(target), comm=PETSc.COMM_SELF)
        src = PETSc.IS().createGeneral(target, comm=PETSc.COMM_SELF)
        self._tie_scatter = PETSc.Scatter().create(template, src, self._tie_vec, None)

    # -- ties ----------------------------------------------------------------------
    def tie_values(self, X: PETSc.Vec, xl: np.ndarray) -> None:
        """Write the targets' values of global ``X`` into the tied local dofs."""
        if not self.disc.ties:
            return
        self._tie_scatter.scatter(X, self._tie_vec, PETSc.InsertMode.INSERT_VALUES, PETSc.ScatterMode.FORWARD)
        xl[self.tie_dofs] = self._tie_vec.getArray()

    def tie_add(self, rl: np.ndarray, F: PETSc.Vec) -> None:
        """Add the residual rows of tied dofs into their targets' rows of F."""
        if not self.disc.ties:
            return
        self._tie_vec.getArray()[:] = rl[self.tie_dofs]
        self._tie_scatter.scatter(self._tie_vec, F, PETSc.InsertMode.ADD_VALUES, PETSc.ScatterMode.REVERSE)

    # -- Dirichlet values ------------------------------------------------------------
    def insert(self, xl: np.ndarray, xdl: np.ndarray, t: float, scales) -> None:
        """Scaled prescribed values and rates into the local solution and rate arrays."""
        for d, dofs in self.bc:
            if dofs.dofs.size == 0:
                continue
            sc = scales[dofs.field]
            shape = dofs.dofs.shape
            vals = self._steady_values.get(id(dofs)) if d.steady else None
            if vals is None:
                vals = np.asarray(d.value(dofs.coords, t), dtype=float).reshape(shape)
                if d.steady:
                    self._steady_values[id(dofs)] = vals
            xl[dofs.dofs] = (vals - sc.offset) / sc.scale
            rate = 0.0 if d.rate is None else \
                np.asarray(d.rate(dofs.coords, t), dtype=float).reshape(shape) / sc.scale
            xdl[dofs.dofs] = rate

    def constrained_local(self) -> np.ndarray:
        """Local dofs held by Dirichlet constraints or ties (not unknowns)."""
        parts = [dd.dofs.ravel() for dd in self.disc.dirichlet] + [t.dofs for t in self.disc.ties]
        return np.concatenate(parts) if parts else np.zeros(0, dtype=compat.INT)

    def boundaries(self, fields) -> list[str]:
        """Names of the boundaries with Dirichlet conditions on ``fields`` (all ranks)."""
        return sorted({d.boundary for d in self.dirichlet if d.field in fields})

    def reaction_dofs(self, fields, boundaries=None) -> np.ndarray:
        """Local constrained dofs of ``fields`` on ``boundaries`` (default all)."""
        idx = [dd.dofs.ravel() for d, dd in self.bc if dd.field in fields and dd.dofs.size
               and (boundaries is None or dd.boundary in boundaries)]
        return np.unique(np.concatenate(idx)) if idx else np.zeros(0, dtype=compat.INT)
