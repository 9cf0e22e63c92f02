"""What a scene is: a short declaration of geometry and mesh, parameters,
the builders of its physics, boundary and initial conditions, time window,
monitors and reference solution.

A scene class declares its name, description, parameter groups
(``parameters``: ``materials.group`` selections and its own dataclasses of
``-thm_<scene>_*`` options), time defaults and history columns.  An
instance holds the run options and the merged parameter object ``p``; its
``build(mesh, degree)`` returns a ``Setup``: the model (made with
``builders.ModelBuilder``), the Dirichlet conditions, the unknown scales,
the initial state and the ``Monitor`` that observes the run.  The run's
state (errors so far, last values) lives in that monitor, not in the scene.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from .. import params as P
from ..assembly import FieldScale
from ..constraints import Dirichlet
from ..fracture import TIP_BC
from ..materials import Parameters
from ..model import Model


@dataclass(frozen=True)
class TimeDefaults:
    final_time: float
    dt_initial: float
    dt_growth: float = 1.0
    dt_max: float = float("inf")
    output_interval: int = 1
    mesh_size: float = 0.1


class Monitor:
    """Observes a run: ``__call__(problem, t, X)`` after every accepted step
    (and for the initial state) returns the history row's scene columns;
    ``report(problem, t)`` the scene's part of summary.json.  Subclasses keep
    the run's state (worst errors, samples at given times) as attributes
    created in their ``__init__``."""

    def __call__(self, problem, t: float, X=None) -> dict:
        return {}

    def report(self, problem, t: float) -> dict:
        return {}

    def stop_reason(self) -> str | None:
        """Why the run cannot go on after the step just monitored (the same
        on every rank: a value of global reductions), or None.  The run then
        ends as failed with this message, the step's state written."""
        return None


@dataclass
class Setup:
    """What a scene builds on a mesh (see the module docstring)."""
    model: Model
    dirichlet: list[Dirichlet]
    scales: dict[str, FieldScale]
    initial: dict[str, Callable[[np.ndarray], np.ndarray]] = field(default_factory=dict)
    monitor: Monitor = field(default_factory=Monitor)

    def __post_init__(self):
        """The tangential traction (friction) takes the normal traction's scale."""
        if self.model.has("tau") and "tau" not in self.scales:
            self.scales["tau"] = FieldScale(self.scales["lam"].scale)


def tip_tractions(model: Model, lam: Callable, symmetry: dict | None = None) -> list[Dirichlet]:
    """The contact tractions on the fracture front, where u is not split:
    lam = ``lam(x, t)`` and, with friction, tau = 0 (the front's rows would
    otherwise not determine them); ``symmetry``: {boundary: tangential
    component} of the symmetry planes that cut the fracture: there the
    jump of u along that tangent is held at 0, and the shear traction along
    it vanishes by symmetry (tau_i = 0)."""
    out = [Dirichlet("lam", TIP_BC, lam)]
    if model.has("tau"):
        m = model.spec("tau").ncomp
        out.append(Dirichlet("tau", TIP_BC, lambda x, t: np.zeros((len(x), m))))
        out += [Dirichlet("tau", b, lambda x, t: np.zeros(len(x)), components=(i,))
                for b, i in (symmetry or {}).items()]
    return out


def constant(value: float) -> Callable:
    """f(x) = value at every node (initial states)."""
    return lambda x: np.full(len(x), value)


def constant_in_time(value: float) -> Callable:
    """f(x, t) = value (Dirichlet data)."""
    return lambda x, t: np.full(len(x), value)


def on_sides(f: Callable) -> Callable:
    """An initial state f(x, inside) of a field that jumps across a fracture:
    ``inside`` is a point of a cell next to each node (``Problem.set_initial``)."""
    f.sided = True
    return f


def zero(x, t):
    return np.zeros(len(x))


def face(axis: int, value: float, atol: float = 1e-9) -> Callable:
    """Boundary predicate x[axis] = value."""
    return lambda x: np.isclose(x[:, axis], value, atol=atol)


class Scene:
    """Base class of the scenes (see the module docstring)."""
    name: str = ""
    description: str = ""
    parameters: tuple = ()
    time: TimeDefaults = TimeDefaults(1.0, 0.1)
    history_columns: tuple = ()
    dimension: int | None = None       # the space dimension of a scene without a -thm_*_dim option

    def __init__(self, run: P.RunParams, p: Parameters):
        self.run = run
        self.p = p

    @classmethod
    def read(cls, run: P.RunParams) -> "Scene":
        """The scene with its parameters read from the options database."""
        return cls(run, P.read_all(cls.parameters, base=Parameters))

    @property
    def final_time(self) -> float:
        return self.run.final_time or self.time.final_time

    @property
    def output_dir(self) -> str:
        """The run's folder: the folder of the run a restart continues
        (``-thm_restart``: a restart goes on there), else ``-thm_output_dir``,
        else output/<scene>."""
        import os
        return self.run.restart or self.run.output_dir or os.path.join("output", self.name)

    def mesh_dimension(self) -> tuple[int | None, str]:
        """(the space dimension the scene needs, the option that sets it or
        ""): a parameter named ``*_dim`` of the scene, else ``dimension``
        (None: not declared)."""
        import dataclasses
        for f in dataclasses.fields(self.p):
            if f.name.endswith("_dim"):
                return int(getattr(self.p, f.name)), P.option_name(f)
        return self.dimension, ""

    # hooks ------------------------------------------------------------------
    def boundaries(self) -> dict[str, Callable[[np.ndarray], np.ndarray]]:
        return {}

    def generate_mesh(self, path: str, size: float) -> str:
        raise NotImplementedError

    def build(self, mesh, degree: int) -> Setup:
        raise NotImplementedError

    def solver_defaults(self, comm) -> dict[str, str]:
        """Solver options this scene proposes over ``solver.SOLVER_DEFAULTS``
        (the user's options still win)."""
        return {}

    def block_recipe(self, snes_type: str) -> dict[str, str]:
        """This scene's changes to the block preconditioner that the size rule
        proposes (``recipes.BLOCK_RECIPE``; the user's options still win) for
        the run's nonlinear method ``snes_type`` (the user's ``-snes_type``,
        else the scene's default: ``app.Run.setup``)."""
        return {}

    def hit_times(self) -> list[float]:
        """Times the time stepper must land on exactly (reference comparisons)."""
        return []

    def first_output_time(self) -> float:
        """The first time the scene reports on (its first hit time, else the
        final time): what ``-thm_*_layer auto`` resolves."""
        return min(self.hit_times(), default=self.final_time)


REGISTRY: dict[str, type] = {}


def register(cls):
    REGISTRY[cls.name] = cls
    return cls
