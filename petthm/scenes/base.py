"""What a scene is: geometry and mesh, active fields and model, boundary and
initial conditions, time window, monitors and reference solution."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Callable

import numpy as np

from .. import params as P
from ..params import param


@dataclass(frozen=True)
class TimeDefaults:
    final_time: float
    dt_initial: float
    dt_growth: float = 1.0
    dt_max: float = float("inf")
    output_interval: int = 1
    mesh_size: float = 0.1


@dataclass(frozen=True)
class HeatMaterial:
    """Rock and fluid thermal properties (physics.md section 6)"""
    rock_density: float = param(2650.0, "kg/m3", "rock density rho_s", lo=0.0, lo_open=True)
    rock_heat_capacity: float = param(800.0, "J/(kg K)", "rock heat capacity C_s", lo=0.0, lo_open=True)
    rock_conductivity: float = param(2.9, "W/(m K)", "rock thermal conductivity lambda_s", lo=0.0, lo_open=True)
    rock_porosity: float = param(0.0, "-", "porosity phi", lo=0.0, hi=1.0)
    fluid_density: float = param(1000.0, "kg/m3", "fluid density rho_f", lo=0.0, lo_open=True)
    fluid_heat_capacity: float = param(4200.0, "J/(kg K)", "fluid heat capacity C_f", lo=0.0, lo_open=True)
    fluid_conductivity: float = param(0.6, "W/(m K)", "fluid thermal conductivity lambda_f", lo=0.0)

    @property
    def rho_c(self) -> float:
        """(rho C)m = (1 - phi) rho_s C_s + phi rho_f C_f."""
        phi = self.rock_porosity
        return (1 - phi) * self.rock_density * self.rock_heat_capacity + \
            phi * self.fluid_density * self.fluid_heat_capacity

    @property
    def conductivity(self) -> float:
        """lambda_m = (1 - phi) lambda_s + phi lambda_f."""
        phi = self.rock_porosity
        return (1 - phi) * self.rock_conductivity + phi * self.fluid_conductivity

    @property
    def fluid_rho_c(self) -> float:
        return self.fluid_density * self.fluid_heat_capacity


def with_defaults(cls, **defaults):
    """A copy of a parameter dataclass with other default values (same options)."""
    fields = []
    for f in dataclasses.fields(cls):
        default = defaults.get(f.name, f.default)
        fields.append((f.name, f.type, dataclasses.field(default=default, metadata=f.metadata)))
    return dataclasses.make_dataclass(cls.__name__, fields, bases=(cls,), frozen=True,
                                      namespace={"__doc__": cls.__doc__})


class Scene:
    """Base class; subclasses set the class attributes and implement the hooks."""
    name: str = ""
    description: str = ""
    parameter_sets: tuple = ()
    time: TimeDefaults = TimeDefaults(1.0, 0.1)
    history_columns: tuple = ()
    fractured: bool = False          # split the mesh along its fractures (physics.md section 1)
    direct_solve: bool = False       # propose a sparse direct solve (solver.direct_solver_defaults)

    def __init__(self, run: P.RunParams, values: dict):
        self.run = run
        self.p = values                         # {class: frozen instance}

    def __getitem__(self, cls):
        """The parameter object of a set (or of its ``with_defaults`` variant)."""
        if cls in self.p:
            return self.p[cls]
        for k, v in self.p.items():
            if issubclass(k, cls):
                return v
        raise KeyError(cls.__name__)

    # hooks ------------------------------------------------------------------
    def boundaries(self) -> dict[str, Callable[[np.ndarray], np.ndarray]]:
        return {}

    def generate_mesh(self, path: str, size: float) -> str:
        raise NotImplementedError

    def build(self, mesh, degree: int):
        """Return (model, dirichlet list, scales, initial-value functions)."""
        raise NotImplementedError

    def monitors(self, problem, t: float, X=None) -> dict:
        return {}

    def solver_defaults(self, comm) -> dict[str, str]:
        """Solver options this scene proposes over ``solver.SOLVER_DEFAULTS``
        (the user's options still win)."""
        if self.direct_solve:
            from ..solver import direct_solver_defaults
            return direct_solver_defaults(comm)
        return {}

    def hit_times(self) -> list[float]:
        """Times the time stepper must land on exactly (reference comparisons)."""
        return []

    def report(self, problem, t: float) -> dict:
        return {}


REGISTRY: dict[str, type] = {}


def register(cls):
    REGISTRY[cls.name] = cls
    return cls
