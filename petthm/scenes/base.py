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

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from petthm import params as P
from petthm.discretisation.assembly import FieldScale
from petthm.discretisation.constraints import Dirichlet
from petthm.discretisation.model import Model
from petthm.discretisation.problem import OnSides
from petthm.errors import InputError
from petthm.mesh.fracture import TIP_BC
from petthm.physics.materials import Parameters


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
    created in their ``__init__``; those that gather over the steps are
    named in ``carried`` (dotted names reach into a part, ``"base.worst"``)
    and go into the checkpoint, so that a restarted run reports the whole
    run.  Their values are plain data and the same on every rank."""

    #: the attributes that hold what the monitor gathered over the steps (see the class docstring)
    carried: tuple[str, ...] = ()
    #: the files (in the output folder) ``report`` writes
    files: tuple[str, ...] = ()

    def __call__(self, problem, t: float, X=None) -> dict:
        return {}

    def report(self, problem, t: float) -> dict:
        return {}

    def stop_reason(self) -> str | None:
        """Why the run cannot go on after the step just monitored (the same
        on every rank: a value of global reductions), or None.  The run then
        ends as failed with this message, the step's state written."""
        return None

    def carried_state(self) -> dict:
        """{name: value} of the ``carried`` attributes (for the checkpoint)."""
        return {name: _attribute(self, name) for name in self.carried}

    def restore(self, state: dict) -> None:
        """Put back ``carried_state``'s values, in place: a part that the
        monitor shares with another (a ``Worst`` of the balances and of the
        temperature range) stays shared."""
        for name, value in state.items():
            if name not in self.carried:
                continue
            owner, _, last = name.rpartition(".")
            holder = _attribute(self, owner) if owner else self
            now = getattr(holder, last)
            if isinstance(now, dict) and isinstance(value, dict):
                now.clear()
                now.update(value)
            elif isinstance(now, list) and isinstance(value, list):
                now[:] = value
            elif hasattr(now, "__dict__") and type(now) is type(value):
                vars(now).update(vars(value))
            else:
                setattr(holder, last, value)


def _attribute(obj, dotted: str):
    for part in dotted.split("."):
        obj = getattr(obj, part)
    return obj


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


def on_sides(f: Callable) -> OnSides:
    """An initial state f(x, inside) of a field that jumps across a fracture:
    ``inside`` is a point of a cell next to each node (``Problem.set_initial``)."""
    return OnSides(f)


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

    #: pressures are gauge (absolute = p + 101 325 Pa); False: absolute (theory manual, "Equations:
    #: fluid properties")
    gauge_pressure: bool = True
    #: the pressure (Pa; gauge or absolute as above) of the water of a scene without a pressure option
    water_pressure: float | None = None

    def __init__(self, run: P.RunParams, p: Parameters):
        self.run = run
        self.p = p

    @classmethod
    def read(cls, run: P.RunParams) -> Scene:
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

    # checks of the input ---------------------------------------------------------
    #: whether the scene takes option values that are expressions of position (a deck's initial state)
    takes_expressions: bool = False

    def check_inputs(self) -> None:
        """Values inside their option's range that are impossible for the
        scene, before anything is built (an ``InputError`` naming the option
        and the bound): an expression of position where the scene takes a
        number, and every temperature given where there is water must be
        liquid water at the pressure there (``fluid.check_liquid``)."""
        from petthm.physics.fluid import check_liquid
        if not self.takes_expressions:
            self.check_numbers()
        for option, T, p_abs, where in self.water_temperatures():
            check_liquid(option, T, p_abs, where)

    def check_numbers(self) -> None:
        """An ``InputError`` for an option value that is an expression of
        position (``expressions.Expression``): only decks take those."""
        import dataclasses

        from petthm.expressions import Expression
        for f in dataclasses.fields(self.p):
            value = getattr(self.p, f.name)
            parts = getattr(value, "components", (value,))
            if any(isinstance(v, Expression) for v in parts):
                raise InputError(f"option -{P.option_name(f)} = {value}: scene {self.name} takes a number "
                                 "here; expressions of x, y, z are for the reservoir scene's decks")

    def has_water(self) -> bool:
        """Whether the scene's rock or fracture holds water (it declares fluid properties)."""
        import dataclasses
        return any(f.name.startswith("fluid_") for f in dataclasses.fields(self.p))

    def water_temperatures(self) -> list[tuple[str, float, float, str]]:
        """(option, temperature in degC, absolute pressure in Pa, where the
        pressure comes from) of every temperature option of a scene with
        water: initial, injection and boundary temperatures, at the initial
        pressure (-thm_initial_pressure, else ``water_pressure``)."""
        import dataclasses

        from petthm.physics.fluid import ATMOSPHERE
        if not self.has_water():
            return []
        temps = [f for f in dataclasses.fields(self.p) if f.metadata["unit"] == "degC"]
        if not temps:
            return []
        if hasattr(self.p, "initial_pressure"):
            p, where = self.p.initial_pressure, f"-thm_initial_pressure = {self.p.initial_pressure:g} Pa"
        elif self.water_pressure is not None:
            p, where = self.water_pressure, f"scene {self.name}'s water at {self.water_pressure:g} Pa"
        else:
            raise TypeError(f"scene {self.name} has water temperatures but declares no water pressure")
        p_abs = p + ATMOSPHERE if self.gauge_pressure else p
        where += ", gauge" if self.gauge_pressure else ", absolute"
        return [(P.option_name(f), getattr(self.p, f.name), p_abs, where) for f in temps]

    def check_against_domain(self, lower, upper) -> None:
        """Lengths that cannot fit the domain (the mesh's bounding box
        ``lower``-``upper``): a mesh size of the scene's mesh generator
        (-thm_mesh_size, a scene's -thm_*_size in m) larger than the domain's
        largest extent, and a well radius of half its smallest extent or more."""
        import dataclasses
        extent = np.asarray(upper, dtype=float) - np.asarray(lower, dtype=float)
        largest, smallest = float(extent.max()), float(extent.min())
        generated = not self.run.mesh_file
        sizes = [(P.option_name(f), getattr(obj, f.name)) for obj in (self.run, self.p)
                 for f in dataclasses.fields(obj)
                 if generated and "mesh size" in f.metadata["help"] and f.metadata["unit"] == "m"]
        for option, h in sizes:
            if h > largest:
                raise InputError(f"option -{option} = {h:g} m is larger than the domain (its largest extent "
                                 f"is {largest:.4g} m): at most {largest:.4g} m")
        r_w = getattr(self.p, "well_radius", None)
        if r_w is not None and r_w >= 0.5 * smallest:
            raise InputError(f"option -thm_well_radius = {r_w:g} m does not fit in the domain (its smallest "
                             f"extent is {smallest:.4g} m): less than {0.5 * smallest:.4g} m")

    # hooks ------------------------------------------------------------------
    @classmethod
    def named_options(cls, run: P.RunParams) -> set[str]:
        """The options (without the dash) of the named groups of the run's
        mesh that the scene reads besides its parameters (a deck's; none here)."""
        return set()

    def parameter_sets(self) -> tuple:
        """The parameter objects whose options a run records (summary.json's
        provenance, the checkpoint's record a restart is checked against)."""
        return (self.run, self.p)

    @classmethod
    def named_help(cls, mesh_file: str) -> str:
        """The -help lines of the options the named groups of ``mesh_file``
        expand to ("" for a scene without them)."""
        return ""

    def boundaries(self) -> dict[str, Callable[[np.ndarray], np.ndarray]]:
        return {}

    def label_mesh(self, dm) -> None:
        """Label the boundary parts of the mesh before it is distributed:
        from ``boundaries()``' coordinate tests here."""
        from petthm.mesh.plex import label_boundaries
        label_boundaries(dm, self.boundaries())

    def fracture_tags(self) -> tuple[int, ...] | None:
        """The "Face Sets" values of the mesh's fractures, split into cohesive
        cells (manual: theory, "Unknowns"); None: every value from
        ``FRACTURE_TAG0`` (10) up, the numbering of the scenes' own meshes."""
        return None

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


