"""Registration tables: which kernels act on which field (pair) on which region.

A physics model is a ``Model``: the active fields, the residual terms
(``f0``: coefficient of the test function, ``f1``: coefficient of its
gradient), the Jacobian blocks (``g0``..``g3`` in PETSc's naming, plus
``g2_lap``: test gradient times the trial function's Laplacian, which the
consistent SUPG term of P2 elements needs) and the facet terms of the
Neumann/Robin conditions.  Kernels are functions ``kernel(ctx)`` of a
quadrature context (see ``assembly.CellContext``) returning arrays over
(cells, quadrature points, ...); parameters are bound with closures.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Optional

from .fields import FieldSpec

Kernel = Callable[..., "object"]


@dataclass(frozen=True)
class CellResidual:
    """Residual of ``field`` on the cells: int f0 . v + f1 : grad v."""
    field: str
    f0: Optional[Kernel] = None
    f1: Optional[Kernel] = None
    region: str = "matrix"


@dataclass(frozen=True)
class CellJacobian:
    """d(residual of ``test``)/d(``trial``) (+ shift * d/d(trial_dot))."""
    test: str
    trial: str
    g0: Optional[Kernel] = None
    g1: Optional[Kernel] = None
    g2: Optional[Kernel] = None
    g3: Optional[Kernel] = None
    g2_lap: Optional[Kernel] = None
    region: str = "matrix"


@dataclass(frozen=True)
class FacetTerm:
    """Residual f0 (and its Jacobian g0 w.r.t. the same field) on a boundary part."""
    field: str
    boundary: str
    f0: Kernel
    g0: Optional[Kernel] = None


@dataclass(frozen=True)
class PointTerm:
    """Residual terms at one node (a well, physics.md section 9).

    ``residual(values, t)`` receives the SI values of ``fields`` at the node
    and returns {field: contribution}; ``jacobian(values, t)`` returns
    {(test, trial): derivative} (SI).  ``point`` is the node's position (a
    mesh vertex)."""
    name: str
    point: tuple
    fields: tuple
    residual: Kernel
    jacobian: Kernel


@dataclass
class Model:
    """The active fields and every term, each on its region ("matrix": the
    cells; "fracture": the - faces of the cohesive cells, where the names
    "Tm-"/"Tm+" denote the traces of a matrix field on the two faces).
    ``bounds`` make the problem a variational inequality (contact: the
    traction ``lam`` >= 0), solved by SNES's VI Newton methods."""
    fields: list[FieldSpec]
    residuals: list[CellResidual] = field(default_factory=list)
    jacobians: list[CellJacobian] = field(default_factory=list)
    facets: list[FacetTerm] = field(default_factory=list)
    points: list[PointTerm] = field(default_factory=list)
    ties: dict = field(default_factory=dict)      # {matrix field: fracture field}
    bounds: dict = field(default_factory=dict)    # {field: (lower, upper)} SI, None: unbounded

    def regions(self) -> list[str]:
        return sorted({t.region for t in self.residuals} | {t.region for t in self.jacobians})
