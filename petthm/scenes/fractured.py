"""What the fracture flow and heat scenes share: the rigid-fracture physics
(theory manual, "Equations: fracture flow"), the strip geometry, a monitor of wells,
balances and the fracture temperature's bounds, and the closed initial
state of a deformable fracture under the in-situ stress (Scenes 2 and 3).

Fracture fields ``pf``, ``Tf`` live on the - faces of the cohesive cells;
the matrix fields ``pm``, ``Tm`` on the split mesh.  The interface
conditions pm = pf and (``equilibrium`` exchange) Tm = Tf on both faces are
imposed by tying the matrix nodes on the walls to the fracture unknowns
(manual, verification: fracture flow and heat).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from petthm.errors import InputError
from petthm.mesh import generate as meshing
from petthm.params import CELSIUS, MESH, param
from petthm.physics import materials as mt
from petthm.physics.builders import ModelBuilder
from petthm.physics.monitors import Balances, FractureWells, Worst, fracture_balances
from petthm.scenes.base import Monitor

#: ``auto`` first rock layer of a layered mesh: this fraction of the rock's
#: diffusion length sqrt(kappa t) at the scene's first output time
AUTO_LAYER_FRACTION = 0.5


@dataclass(frozen=True)
class FirstLayer:
    """A ``-thm_*_layer`` value: the first rock layer's thickness in m on
    each side of the fracture (0: no layered mesh), or ``auto`` (None)."""
    thickness: float | None

    def __str__(self) -> str:
        return "auto" if self.thickness is None else f"{self.thickness:g}"

    @property
    def layered(self) -> bool:
        return self.thickness is None or self.thickness > 0

    def resolve(self, diffusivity: float, t_first: float) -> float:
        """The thickness in m: as given, or ``AUTO_LAYER_FRACTION``
        sqrt(kappa t_first), kappa the rock's thermal diffusivity
        lambda/(rho c) (theory manual, "Equations: fracture heat"): the conduction layer's depth
        at the first time the scene reports."""
        if self.thickness is not None:
            return self.thickness
        return AUTO_LAYER_FRACTION * math.sqrt(diffusivity * t_first)


def first_layer_option(option: str):
    """The parser of a ``-thm_*_layer`` option: ``auto`` or a thickness >= 0 (m)."""
    def parse(text) -> FirstLayer:
        word = str(text).strip().lower()
        if word == "auto":
            return FirstLayer(None)
        try:
            value = float(word)
        except ValueError:
            value = -1.0
        if not (value >= 0 and math.isfinite(value)):
            raise InputError(f"option -{option} = {text} is not auto or a thickness >= 0 (m)")
        return FirstLayer(value)
    return parse


def first_layer_param(option: str, default: float, mesh: str, when: str):
    """The declaration of a ``-thm_*_layer`` option: ``mesh`` says how the
    layered mesh is made, ``when`` what ``auto``'s time is."""
    return param(default, "m", f"first rock layer on each side of the fracture (0: {mesh}); a layered mesh "
                 f"grows from it by -{option}_growth; ~0.5 sqrt(kappa t) resolves the rock's thermal layer "
                 f"from time t on; auto: {AUTO_LAYER_FRACTION:g} sqrt(kappa t) at {when}",
                 parse=first_layer_option(option), kind=MESH)


def first_layer(scene, value: FirstLayer) -> float:
    """A scene's first layer in m (``value``; auto: from its rock's diffusivity
    and ``scene.first_output_time()``), said once when it is computed."""
    p, t_first = scene.p, scene.first_output_time()
    thickness = value.resolve(p.conductivity / p.rho_c, t_first)
    if value.thickness is None:
        print(f"layered mesh: first rock layer {thickness:.3g} m ({AUTO_LAYER_FRACTION:g} sqrt(kappa t) at "
              f"t = {t_first:g} s)", flush=True)
    return thickness


#: the wells and initial state of the Scene 1 family (injector, producer, rock at 100 degC; water at
#: 1 MPa gauge, liquid at 100 degC, produced at the initial pressure)
SCENE1_WELLS = mt.group("Wells and initial state", mt.WELLS + ("initial_temperature", "initial_pressure"),
                        initial_temperature=100.0, initial_pressure=1e6, production_pressure=1e6)


def rigid_fracture_physics(b: ModelBuilder, degree: int, *, heat: bool, permeability=None,
                           matrix_storage: float = 0.0, matrix_thermal_storage: float = 0.0,
                           rock_conductivity=None) -> None:
    """pf (+ pm with a ``permeability`` tensor, + Tf and Tm with ``heat``) on a
    fracture of fixed aperture ``-thm_fracture_aperture``."""
    a = b.p.fracture_aperture
    b.fracture_flow(degree, reference_aperture=a, heat=heat)
    if permeability is not None:
        b.matrix_flow(degree, permeability=permeability, storage=matrix_storage,
                      thermal_storage=matrix_thermal_storage, heat=heat)
        b.leakoff()
    if heat:
        b.fracture_heat(degree, reference_aperture=a)
        b.matrix_heat(degree, conductivity=rock_conductivity)


class ClosedUnderStress:
    """A deformable fracture that starts closed under the in-situ stress
    (theory manual, "Contact and friction"): the scene's ``normal()`` gives the
    fracture's unit normal; lam0 = sigma_n - p0 and a = ac(lam0)."""

    def normal(self) -> np.ndarray:
        raise NotImplementedError

    @property
    def normal_stress(self) -> float:
        """The in-situ compressive normal stress on the fracture (-thm_insitu_stress)."""
        return self.p.normal_stress(self.normal())

    @property
    def lam0(self) -> float:
        """The initial contact traction sigma_n - p0."""
        return self.normal_stress - self.p.initial_pressure

    def initial_aperture(self) -> float:
        """ac(lam0) of the joint law (the scales, well indices, relative outputs)."""
        return float(ModelBuilder(self.p, 3).joint_law().closure_aperture(np.array([self.lam0]))[0][0])

    def check_closed_start(self) -> None:
        """A fluid pressure at or above the normal stress would start the fracture open: refused."""
        p = self.p
        if not self.lam0 > 0:
            raise InputError(f"option -thm_initial_pressure = {p.initial_pressure:g} must be below the "
                             f"in-situ normal stress {self.normal_stress:g} (-thm_insitu_stress): the "
                             "fracture starts closed")


def transmissivity(p, aperture: float, T: float) -> float:
    """a^3 / (12 mu(T)) of the fracture."""
    return float(aperture ** 3 / (12 * p.fluid_viscosity.mu(T)))


#: the pressure scale of a shut-in whose own pressures are all 0 (gauge) (Pa)
SHUT_IN_PRESSURE_SCALE = 1e6


def rate_pressure_scale(dp: float, *pressures: float) -> float:
    """The scale of a pressure unknown driven by an injection rate: ``dp``,
    the pressure change the scene computes from the rate (Pa), when it is
    positive (returned as it is: the results of a nonzero rate do not move).

    A zero rate (a shut-in; ``-thm_injection_rate``'s range allows it) gives
    dp = 0, and a zero scale would make x_hat = (x - offset) / scale NaN.
    With no flow the pressures stay at their initial state, and any
    positive scale works: the scale only sets the unknown's units (and its
    residual rows' reference).  The fallback is a size from the scene's own
    ``pressures`` (its initial, production or boundary pressures): the
    largest magnitude among them, or ``SHUT_IN_PRESSURE_SCALE`` (1 MPa) where
    they are all 0 (gauge)."""
    if dp > 0:
        return dp
    return max((abs(float(x)) for x in pressures), default=0.0) or SHUT_IN_PRESSURE_SCALE


def balances_of(b: ModelBuilder, reference_aperture: float, p0: float, heat: bool, worst: Worst) -> Balances:
    """The fluid volume (and energy) balances of a fracture model (stored
    amounts relative to p0 and T0)."""
    p = b.p
    energy = (p.T0, p.fluid_rho_c, p.rho_c) if heat else None
    water = any(h.upwind for h in b.heats.values())
    return Balances(fracture_balances(b.flows, reference_aperture, p0, energy, b.elastic, water), worst)


def far_sides(width: float, axis: int = 1):
    """Boundary predicate of the two far sides x[axis] = 0 and 2 W of a strip."""
    return lambda x: np.isclose(x[:, axis], 0.0) | np.isclose(x[:, axis], 2 * width)


def strip_with_fracture(path, length, width, size, fracture_size):
    """[0, L] x [0, 2W] with a fracture along y = W cutting both ends, graded toward it."""
    fr = [meshing.Fracture("segment", p0=(0.0, width), p1=(length, width), size=fracture_size)]
    return meshing.box_with_fractures(path, [length, 2 * width], size, fr, grading_distance=0.5 * width)


class WellsMonitor(Monitor):
    """Well histories and balances (the temperatures' ranges: run/ranges.py)."""

    carried = ("worst",)

    def __init__(self, wells: FractureWells | None, balances: Balances, worst: Worst):
        self.wells, self.balances, self.worst = wells, balances, worst

    def __call__(self, problem, t, X=None) -> dict:
        out = self.wells(problem, t, X) if self.wells is not None else {}
        out.update(self.balances(problem, t, X))
        return out


def heat_wells_monitor(b: ModelBuilder, wells, reference_aperture: float | None = None) -> WellsMonitor:
    """Wells, mass and energy balances of a fracture TH model (the
    fracture's aperture, or the deformable fracture's initial one)."""
    p, worst = b.p, Worst()
    a = p.fracture_aperture if reference_aperture is None else reference_aperture
    return WellsMonitor(wells, balances_of(b, a, p.initial_pressure, True, worst), worst)


__all__ = ["rigid_fracture_physics", "transmissivity", "rate_pressure_scale", "balances_of", "far_sides",
           "strip_with_fracture", "WellsMonitor", "CELSIUS"]
