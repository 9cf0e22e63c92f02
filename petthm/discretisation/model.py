"""Registration tables: which kernels act on which field (pair) on which region.

A physics model is a ``Model``: the active fields, the residual terms
(``f0``: coefficient of the test function, ``f1``: coefficient of its
gradient), the Jacobian blocks (``g0``..``g3`` in PETSc's naming, plus
``g2_lap``: test gradient times the trial function's Laplacian, which the
consistent SUPG term of P2 elements needs) and the facet terms of the
Neumann/Robin conditions.  Kernels are functions ``kernel(ctx)`` of a
quadrature context (see ``assembly.CellContext``) returning arrays over
(cells, quadrature points, ...); parameters are bound with closures.

Where a term lives is typed: a ``Region`` is a ``Domain`` (the matrix cells,
or the - faces of the cohesive cells of the fracture) with its quadrature
rule (Gauss, or the vertex rule of row-sum lumping); on the fracture a
matrix field is seen through a ``Trace`` on one face (``Side``).  Models are
composed by the builders of ``petthm.physics.builders``.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from petthm.discretisation.fields import (  # noqa: F401
    Adjacent,
    Domain,
    FieldRef,
    FieldSpec,
    Side,
    Trace,
    base_field,
    traces,
)

Kernel = Callable[..., "object"]


@dataclass(frozen=True)
class Region:
    """A domain with a quadrature rule: ``lumped`` integrates with the vertex
    rule (row-sum lumping of P1 mass-type terms); ``dual``: Gauss, with the
    domain's own fields (the contact traction) in their dual basis
    (``fe.tabulate_dual``; the multiplier pairing of manual, verification: contact);
    ``nodal``: the Lagrange nodes with the weights of the dual pairing
    (``fe.nodal_rule``; the friction law, a function of nodal values)."""
    domain: Domain = Domain.MATRIX
    lumped: bool = False
    dual: bool = False
    nodal: bool = False

    def _key(self) -> tuple:
        return (self.domain.value, self.lumped, self.dual, self.nodal)

    def __lt__(self, other: Region) -> bool:     # matrix after fracture, lumped after Gauss
        return self._key() < other._key()

    def __str__(self) -> str:
        return self.domain.value + "".join(f"@{k}" for k in ("lumped", "dual", "nodal") if getattr(self, k))


MATRIX = Region(Domain.MATRIX)
FRACTURE = Region(Domain.FRACTURE)
FRACTURE_LUMPED = Region(Domain.FRACTURE, lumped=True)
FRACTURE_DUAL = Region(Domain.FRACTURE, dual=True)
FRACTURE_NODAL = Region(Domain.FRACTURE, nodal=True)
MATRIX_LUMPED = Region(Domain.MATRIX, lumped=True)


@dataclass(frozen=True)
class CellResidual:
    """Residual of ``field`` on the cells: int f0 . v + f1 : grad v, plus an
    ``element`` term: a kernel that returns each element's residual vector
    (nc, nb, ncomp) directly (a term that couples the element's nodal values,
    such as the algebraic upwinding of ``kernels/transport.py``)."""
    field: FieldRef
    f0: Kernel | None = None
    f1: Kernel | None = None
    region: Region = MATRIX
    element: Kernel | None = None
    #: called once per assembly, before the cells (``prepare(asm, xl, xdl, t,
    #: shift)``), by a term whose element kernel needs data gathered over the
    #: whole region first (the nodal limiter of ``kernels/limiter.py``)
    prepare: Callable | None = None


@dataclass(frozen=True)
class CellJacobian:
    """d(residual of ``test``)/d(``trial``) (+ shift * d/d(trial_dot))."""
    test: FieldRef
    trial: FieldRef
    g0: Kernel | None = None
    g1: Kernel | None = None
    g2: Kernel | None = None
    g3: Kernel | None = None
    g2_lap: Kernel | None = None
    region: Region = MATRIX
    #: each element's matrix (nc, ncomp_test, ncomp_trial, nb_test, nb_trial), added as it is
    element: Kernel | None = None
    prepare: Callable | None = None           # as CellResidual.prepare
    #: the block depends on neither the state, the time nor the shift (a
    #: linear term with constant coefficients, e.g. elasticity): ``Problem``
    #: assembles it once and keeps its values until the residual scaling changes
    constant: bool = False


@dataclass(frozen=True)
class FacetTerm:
    """Residual f0 (and its Jacobian g0 w.r.t. the same field) on a boundary part."""
    field: str
    boundary: str
    f0: Kernel
    g0: Kernel | None = None


@dataclass(frozen=True)
class PointTerm:
    """Residual terms at one node (a well, theory manual, "Equations: wells").

    ``residual(values, t)`` receives the SI values of ``fields`` at the node
    and returns {field: contribution}; ``jacobian(values, t)`` returns
    {(test, trial): derivative} (SI).  ``point`` is the node's position (a
    mesh vertex)."""
    name: str
    point: tuple
    fields: tuple
    residual: Kernel
    jacobian: Kernel


@dataclass(frozen=True)
class NodeSetTerm:
    """Residual terms at a set of nodes coupled through sums over the whole
    set (a well whose bottom-hole pressure ties its perforated nodes:
    theory manual, "Equations: wells").

    ``points`` (n, d) are the nodes' positions (mesh vertices), the same list
    on every rank; ``fields`` the fields the term reads and adds to at them.
    ``residual(ctx)`` returns {field: (m,)} for the m nodes this rank owns
    (``NodeSetContext``); ``jacobian(ctx)`` returns {(test, trial): values}
    for each block of ``blocks``: (test, trial, "diagonal") holds the
    derivative of a node's row by its own value, (m,); (test, trial,
    "dense") by every node's value, (m, n).  Both are collective (they may
    call ``ctx.total``) and are called on every rank, with m = 0 too."""
    name: str
    points: np.ndarray
    fields: tuple
    blocks: tuple
    residual: Kernel
    jacobian: Kernel


class NodeSetContext(Protocol):
    """What a ``NodeSetTerm`` sees: ``values`` {field: (m,) SI values at the
    owned nodes}, ``owned`` (m,) their positions in the term's list, ``t``,
    and ``total(a)``: the sum of ``a`` over the ranks (collective)."""
    values: dict
    owned: np.ndarray
    t: float

    def total(self, a) -> np.ndarray: ...


#: the residual and Jacobian registrations of one physical term
Terms = tuple[list, list]


class ApertureLaw(Protocol):
    """The hydraulic aperture of a deformable fracture, a(lam, opening)
    (``physics.kernels.contact.JointLaw``)."""

    def aperture(self, lam: np.ndarray, opening: np.ndarray) -> np.ndarray: ...


class FrictionLaw(Protocol):
    """The Coulomb bound of the shear traction, c0 + mu_f lam
    (``physics.kernels.friction.Friction``)."""

    def bound(self, lam: np.ndarray) -> np.ndarray: ...


@dataclass(frozen=True)
class NodeOutputs:
    """Values a model writes with a region's fields besides its unknowns:
    ``fields(problem, t)`` returns {name: values at the nodes of the field
    ``like``} (SI), written with that field (the contact's opening,
    aperture, slip, ...)."""
    region: Domain
    like: str
    fields: Callable


@dataclass(frozen=True)
class Range:
    """The interval a field's nodal values belong in (SI; None: no bound
    there), reported every step: the field's minimum and maximum in the
    history, the largest excursion in the summary; with ``warn_above``
    (a fraction of ``upper - lower``) a one-time warning with ``hint``."""
    lower: float | None = None
    upper: float | None = None
    warn_above: float | None = None
    hint: str = ""

    @property
    def bounded(self) -> bool:
        return self.lower is not None and self.upper is not None


@dataclass(frozen=True)
class Heating:
    """A heat source of the state's own rates that the temperature ranges
    allow for (the thermo-mechanical heating, ``run/ranges.py``):
    ``power(ctx)`` (W/m3, positive where it heats) at the points of
    ``region``'s cells, in a field of volumetric heat capacity ``capacity``
    (a number, or one per rock region: kernels/regional.py)
    (J/(m3 K))."""
    region: Region
    power: Callable
    capacity: object


@dataclass
class Model:
    """The active fields and every term, each on its region.  ``bounds``
    make the problem a variational inequality (contact: the traction
    ``lam`` >= 0), solved by SNES's VI Newton methods; ``ties`` make a matrix
    field's nodes on the fracture walls the fracture field's unknowns."""
    fields: list[FieldSpec] = field(default_factory=list)
    residuals: list[CellResidual] = field(default_factory=list)
    jacobians: list[CellJacobian] = field(default_factory=list)
    facets: list[FacetTerm] = field(default_factory=list)
    points: list[PointTerm] = field(default_factory=list)
    node_sets: list[NodeSetTerm] = field(default_factory=list)
    ties: dict = field(default_factory=dict)      # {matrix field: fracture field}
    bounds: dict = field(default_factory=dict)    # {field: (lower, upper)} SI, None: unbounded
    preconditioner: list[CellJacobian] = field(default_factory=list)
    aperture_law: ApertureLaw | None = None   # a deformable fracture's a(lam, g) (outputs, monitors)
    friction_law: FrictionLaw | None = None   # the Coulomb bound with friction (outputs, monitors)
    outputs: list[NodeOutputs] = field(default_factory=list)
    #: the contact traction recovered from the rock's stress, f(ctx) (nc, nq) on the fracture
    #: (kernels/contact.RecoveredTraction), projected onto lam's nodes for the outputs and monitors
    recovered_traction: Callable | None = None
    #: fields whose range every step reports, with the interval they belong in
    ranges: dict[str, Range] = field(default_factory=dict)
    #: checks of the mesh a term is accurate on: ``check(mesh)`` returns a warning, or None
    mesh_checks: list[Callable] = field(default_factory=list)
    #: a heat source the temperature ranges allow for (``Heating``)
    heating: Heating | None = None
    #: the rock region of each local cell (an index into the values of the
    #: kernels' ``Regional`` coefficients, kernels/regional.py); None: one rock
    cell_regions: np.ndarray | None = None
    #: the fracture of each local fracture face (an index into the values of
    #: the fracture kernels' ``Regional`` coefficients); None: one fracture's values
    fracture_regions: np.ndarray | None = None

    def regions(self) -> list[Region]:
        return sorted({t.region for t in self.residuals} | {t.region for t in self.jacobians})

    def has(self, name: str) -> bool:
        return any(f.name == name for f in self.fields)

    def spec(self, name: str) -> FieldSpec:
        """The FieldSpec of an active field."""
        return next(f for f in self.fields if f.name == name)

    def add_field(self, spec: FieldSpec) -> None:
        if self.has(spec.name):
            raise ValueError(f"field {spec.name} is already in the model")
        self.fields.append(spec)

    def add(self, terms: Terms) -> None:
        """Register the residuals and Jacobian blocks of a term."""
        res, jac = terms
        self.residuals += res
        self.jacobians += jac
