"""The physical parameters: every option of manual, user guide (and the
few more the builders read) declared once, with its unit, help, range and
one type.

A scene lists the parameters it uses as titled groups (``group``), each a
frozen dataclass of some of the declarations below, with the scene's own
defaults; ``params.read_all`` reads them into one frozen ``Parameters``
object, whose derived quantities (``rho_c``, ``viscosity``, ...) are
computed from the declared values.  Scene-specific quantities (geometry,
mesh sizes, a scene's case switches) stay with the scene as
``-thm_<scene>_*`` options.

Values that are not plain numbers are parsed once, when read:
``fluid_viscosity`` into a ``fluid.Viscosity``, ``insitu_stress`` into an
``InSituStress``, ``fracture_heat_exchange`` into an ``Exchange``; the
initial state (``initial_temperature``, ``initial_pressure`` and the
components of ``insitu_stress``) into a number or, for a deck, an
``expressions.Expression`` of position.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from petthm.errors import InputError
from petthm.expressions import Expression, number_or_expression, split_list
from petthm.params import CELSIUS, DISCRETISATION, PHYSICS, param
from petthm.physics.fluid import Viscosity

#: Nusselt number of laminar flow between parallel plates (theory manual, "Equations: fracture heat")
NUSSELT = 7.54


# -- parsed values -------------------------------------------------------------------------
def parse_viscosity(text: str) -> Viscosity:
    try:
        return Viscosity.parse(text)
    except ValueError:
        raise InputError(f"option -thm_fluid_viscosity = {text} is not a number > 0 or 'water'") from None


@dataclass(frozen=True)
class Exchange:
    """The wall heat exchange (theory manual, "Equations: fracture heat"): ``equilibrium``
    (Tm = Tf on the walls), ``nusselt`` (hw = Nu lambda_f / (2 a)) or a given hw."""
    mode: str                       # "equilibrium", "nusselt" or "given"
    hw: float = 0.0                 # W/(m2 K), mode "given"

    def __str__(self) -> str:
        return f"{self.hw:g}" if self.mode == "given" else self.mode

    def coefficient(self, aperture: float, fluid_conductivity: float) -> float | None:
        """None for equilibrium, else hw at the aperture ``aperture``."""
        if self.mode == "equilibrium":
            return None
        if self.mode == "nusselt":
            return NUSSELT * fluid_conductivity / (2 * aperture)
        return self.hw


def parse_exchange(text: str) -> Exchange:
    mode = str(text).strip().lower()
    if mode in ("equilibrium", "nusselt"):
        return Exchange(mode)
    try:
        hw = float(mode)
    except ValueError:
        hw = -1.0
    if not (hw > 0 and math.isfinite(hw)):
        raise InputError(f"option -thm_fracture_heat_exchange = {text} is not equilibrium, nusselt or "
                         "a number > 0 (W/(m2 K))")
    return Exchange("given", hw)


#: Voigt order of the six components of -thm_insitu_stress
VOIGT = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))


@dataclass(frozen=True)
class InSituStress:
    """The in-situ total stress (compression positive, theory manual, "Equations: rock deformation"):
    one number (the normal stress on every fracture, no shear on it) or the
    tensor sxx,syy,szz,syz,sxz,sxy (2D scenes: the x-y plane)."""
    components: tuple

    def __str__(self) -> str:
        return ",".join(str(c) if isinstance(c, Expression) else f"{c:g}" for c in self.components)

    @property
    def varies(self) -> bool:
        """Whether a component is an expression of position."""
        return any(isinstance(c, Expression) for c in self.components)

    @property
    def tensor(self) -> np.ndarray | None:
        if len(self.components) == 1:
            return None
        S = np.zeros((3, 3))
        for (i, j), v in zip(VOIGT, self.components, strict=False):
            S[i, j] = S[j, i] = v
        return S

    def normal(self, n) -> float:
        """The compressive normal stress on a plane of unit normal ``n``."""
        S = self.tensor
        if S is None:
            return float(self.components[0])
        n3 = np.zeros(3)
        n3[:len(n)] = n
        return float(n3 @ S @ n3)

    def check_frictionless(self, n) -> None:
        """A frictionless fracture carries no in-situ shear (theory manual, "Equations: rock deformation")."""
        S = self.tensor
        if S is None:
            return
        n3 = np.zeros(3)
        n3[:len(n)] = n
        t = S @ n3
        shear = np.linalg.norm(t - (n3 @ t) * n3)
        if shear > 1e-9 * max(np.abs(S).max(), 1e-300):
            raise InputError(f"option -thm_insitu_stress = {self}: the stress has a shear traction of "
                             f"{shear:.4g} Pa on the fracture plane (normal {tuple(np.round(n3, 6))}), "
                             "which a frictionless fracture cannot carry")


def parse_insitu_stress(text) -> InSituStress:
    """One number, or six numbers or expressions of position (a deck's; the
    scenes' own meshes take numbers, ``Scene.check_inputs``)."""
    vals = text if isinstance(text, tuple) else tuple(split_list(str(text)))
    parse = number_or_expression("thm_insitu_stress")
    comps = tuple(parse(v) for v in vals)
    if len(comps) == 1 and isinstance(comps[0], Expression):
        raise InputError(f"option -thm_insitu_stress = {text} is not one number or six "
                         "(sxx,syy,szz,syz,sxz,sxy, Pa, compression positive)")
    if len(comps) not in (1, 6) or not all(isinstance(c, Expression) or math.isfinite(c) for c in comps):
        raise InputError(f"option -thm_insitu_stress = {text} takes one number or six finite ones "
                         "(sxx,syy,szz,syz,sxz,sxy, Pa, compression positive)")
    return InSituStress(comps)


# -- the declarations (one per option) ----------------------------------------------------
_POS = dict(lo=0.0, lo_open=True)

DECLARED = {
    # rock (theory manual, "Equations: rock deformation")
    "rock_youngs_modulus": param(37.5e9, "Pa", "drained Young's modulus E", **_POS, kind=PHYSICS),
    "rock_poisson_ratio": param(0.25, "-", "drained Poisson ratio nu", lo=0.0, hi=0.4999, kind=PHYSICS),
    "rock_biot_coefficient": param(0.8, "-", "Biot coefficient alpha", lo=0.0, hi=1.0, kind=PHYSICS),
    "rock_porosity": param(0.0, "-", "porosity phi", lo=0.0, hi=1.0, kind=PHYSICS),
    "rock_permeability": param((1e-14,), "m2", "matrix permeability k_m: one value, kxx,kyy[,kzz], or the "
                               "full tensor kxx,kyy,kzz,kyz,kxz,kxy (2D: kxx,kyy,kxy), positive "
                               "semi-definite",
                               kind=PHYSICS),
    "rock_density": param(2650.0, "kg/m3", "rock density rho_s", **_POS, kind=PHYSICS),
    "rock_heat_capacity": param(800.0, "J/(kg K)", "rock heat capacity C_s", **_POS, kind=PHYSICS),
    "rock_conductivity": param(2.9, "W/(m K)", "rock thermal conductivity lambda_s", **_POS, kind=PHYSICS),
    "rock_thermal_expansion": param(2.4e-5, "1/K", "rock volumetric thermal expansion beta_s", lo=0.0,
                                    kind=PHYSICS),
    # fluid (sections 4-8)
    "fluid_density": param(1000.0, "kg/m3", "fluid density rho_f", **_POS, kind=PHYSICS),
    "fluid_heat_capacity": param(4200.0, "J/(kg K)", "fluid heat capacity C_f", **_POS, kind=PHYSICS),
    "fluid_conductivity": param(0.6, "W/(m K)", "fluid thermal conductivity lambda_f", lo=0.0, kind=PHYSICS),
    "fluid_thermal_expansion": param(2.07e-4, "1/K", "fluid volumetric thermal expansion beta_f", lo=0.0,
                                     kind=PHYSICS),
    "fluid_compressibility": param(4.5e-10, "1/Pa", "fluid compressibility c_f", lo=0.0, kind=PHYSICS),
    "fluid_viscosity": param("1e-3", "Pa s", "viscosity: a number, or 'water' for mu(T)",
                             parse=parse_viscosity, kind=PHYSICS),
    # fractures (sections 3, 4, 7)
    "fracture_aperture": param(1e-3, "m", "hydraulic aperture a0 (rigid fracture), or a0 at zero "
                               "contact traction (deformable)", **_POS, kind=PHYSICS),
    "fracture_normal_stiffness": param(1e11, "Pa/m", "normal joint stiffness Kn", **_POS, kind=PHYSICS),
    "fracture_residual_fraction": param(1e-3, "-", "residual aperture ares / a0", lo=0.0, hi=1.0,
                                        kind=PHYSICS),
    "contact_pairing": param("dual", "-", "how the contact traction meets the opening: dual (lam on the "
                             "nodes of the u trace, dual basis: nodal contact for P1 and P2 u) or consistent "
                             "(P1 lam, L2 pairing)",
                             choices=("dual", "consistent"), kind=DISCRETISATION),
    "fracture_friction": param(0.6, "-", "Coulomb friction coefficient mu_f of the fracture faces "
                               "(0: frictionless; 0.6: Byerlee's rock friction)", lo=0.0, kind=PHYSICS),
    "fracture_cohesion": param(0.0, "Pa", "cohesion c0 of the Coulomb law |tau| <= c0 + mu_f lam", lo=0.0,
                               kind=PHYSICS),
    "fracture_heat_exchange": param("equilibrium", "-", "wall heat exchange: equilibrium, nusselt, or "
                                    "hw in W/(m2 K)", parse=parse_exchange, kind=PHYSICS),
    "fracture_supg_wall_conduction": param(False, "-", "with the equilibrium exchange, the rock's wall "
                                           "conduction in the fracture heat's SUPG residual (consistent "
                                           "SUPG: P2 reaches its accuracy; over- or undershoots by "
                                           "1-6 % where the wall layers are thin against the fracture "
                                           "cells; manual, verification: fracture flow and heat)",
                                           kind=DISCRETISATION),
    "heat_transport": param("auto", "-", "discretisation of the heat advection: auto (limited for P1 "
                            "temperatures, supg for P2), supg "
                            "(streamline upwind Petrov-Galerkin), upwind (algebraic upwinding with the "
                            "capacity lumped: bound-preserving, first order where advection dominates), "
                            "limited (the upwinding flux-corrected: bound-preserving, Galerkin where the "
                            "temperature is smooth) or galerkin (no stabilisation); theory manual, "
                            "discrete bounds",
                            choices=("auto", "supg", "upwind", "limited", "galerkin"), kind=DISCRETISATION),
    "heat_limiter_settle": param(1e-4, "-", "with -thm_heat_transport limited: how far the limited fluxes "
                                 "may push a local extreme of a step's solved state further (their sum over "
                                 "the node's upwinding diffusion), as a fraction of the temperature range, "
                                 "before the step's factors are lowered to the solved state's (larger: the "
                                 "factors of the step's start are kept more often; theory manual, limited "
                                 "flux correction)", lo=0.0, lo_open=True, kind=DISCRETISATION),
    # state and wells (sections 2, 9)
    "initial_temperature": param(80.0, "degC", "initial rock and fluid temperature T0 (a deck: or an "
                                 "expression of x, y, z)",
                                 parse=number_or_expression("thm_initial_temperature"), kind=PHYSICS),
    "initial_pressure": param(0.0, "Pa", "initial fluid pressure p0 (a deck: or an expression of x, y, z)",
                              parse=number_or_expression("thm_initial_pressure"), kind=PHYSICS),
    "insitu_stress": param("60e6", "Pa", "in-situ stress: compressive normal stress on the fracture, or "
                           "sxx,syy,szz,syz,sxz,sxy (compression positive)", parse=parse_insitu_stress,
                           kind=PHYSICS),
    "surface_temperature": param(20.0, "degC", "temperature of the cooled surface for t > 0", kind=PHYSICS),
    "injection_rate": param(1e-4, "m3/s", "injection rate Q (per metre in 2D)", lo=0.0, kind=PHYSICS),
    "injection_temperature": param(20.0, "degC", "injected water temperature", kind=PHYSICS),
    "production_pressure": param(0.0, "Pa", "producer well pressure", kind=PHYSICS),
    "production_rate": param(0.0, "m3/s", "producer rate Q_p (0: the producer runs at "
                             "-thm_production_pressure)", lo=0.0, kind=PHYSICS),
    "well_radius": param(0.1, "m", "well radius r_w (producer well index)", **_POS, kind=PHYSICS),
    # body force (section 2)
    "gravity": param(9.81, "m/s2", "gravitational acceleration g (downwards)", lo=0.0, kind=PHYSICS),
    # optional coupling terms
    "thermomechanical_heating": param(False, "-", "the strain and pressure heating of the theory manual "
                                      "section 6 in the rock heat equation (off: section 6 allows it)",
                                      kind=PHYSICS),
}

# named selections of the declarations, for scenes to compose groups from
ELASTIC = ("rock_youngs_modulus", "rock_poisson_ratio")
ROCK_HEAT = ("rock_density", "rock_heat_capacity", "rock_conductivity")
FLUID_HEAT = ("fluid_density", "fluid_heat_capacity", "fluid_conductivity")
FLUID_FLOW = ("fluid_viscosity", "fluid_compressibility", "fluid_thermal_expansion")
JOINT = ("fracture_aperture", "fracture_normal_stiffness", "fracture_residual_fraction")
CONTACT = ("contact_pairing", "fracture_friction", "fracture_cohesion")
HEAT_DISCRETISATION = ("heat_transport", "heat_limiter_settle")
FRACTURE_HEAT = ("fracture_heat_exchange", "fracture_supg_wall_conduction", *HEAT_DISCRETISATION)
#: the defaults of a scene whose reference solution is frictionless
FRICTIONLESS = {"fracture_friction": 0.0}
WELLS = ("injection_rate", "injection_temperature", "production_pressure", "well_radius")


def group(title: str, names, **defaults) -> type:
    """A frozen dataclass of the declarations ``names`` (title: its
    docstring, the heading in -help) with the scene's ``defaults``."""
    unknown = [n for n in list(names) + list(defaults) if n not in DECLARED]
    if unknown:
        raise KeyError(f"not declared in petthm.physics.materials: {', '.join(unknown)}")
    missing = [n for n in defaults if n not in names]
    if missing:
        raise KeyError(f"defaults for parameters outside the group: {', '.join(missing)}")
    fields = []
    for n in names:
        f = DECLARED[n]
        default = defaults.get(n, f.default)
        fields.append((n, object, dataclasses.field(default=default, metadata=f.metadata)))
    cls = dataclasses.make_dataclass(title.replace(" ", "_"), fields, frozen=True)
    cls.__doc__ = title
    return cls


class Parameters:
    """Base of the merged parameter object of a scene: derived quantities."""

    @property
    def rho_c(self) -> float:
        """(rho C)m = (1 - phi) rho_s C_s + phi rho_f C_f (theory manual, "Equations: rock heat")."""
        phi = self.rock_porosity
        return (1 - phi) * self.rock_density * self.rock_heat_capacity + phi * self.fluid_rho_c

    @property
    def conductivity(self) -> float:
        """lambda_m = (1 - phi) lambda_s + phi lambda_f."""
        phi = self.rock_porosity
        return (1 - phi) * self.rock_conductivity + phi * self.fluid_conductivity

    @property
    def fluid_rho_c(self) -> float:
        return self.fluid_density * self.fluid_heat_capacity

    @property
    def T0(self) -> float:
        """Initial temperature in kelvin."""
        return self.initial_temperature + CELSIUS

    @property
    def T_inj(self) -> float:
        return self.injection_temperature + CELSIUS

    @property
    def bulk_modulus(self) -> float:
        return self.rock_youngs_modulus / (3 * (1 - 2 * self.rock_poisson_ratio))

    @property
    def shear_modulus(self) -> float:
        return self.rock_youngs_modulus / (2 * (1 + self.rock_poisson_ratio))

    @property
    def storage(self) -> float:
        """1/M = phi c_f + (alpha - phi)/K_s, K_s = K/(1 - alpha) (alpha = 1: K_s infinite)."""
        a, phi = self.rock_biot_coefficient, self.rock_porosity
        return phi * self.fluid_compressibility + (a - phi) * (1 - a) / self.bulk_modulus

    def normal_stress(self, normal) -> float:
        """The in-situ compressive stress on a fracture of unit normal ``normal``
        (-thm_insitu_stress; refused if it has shear on the fracture plane)."""
        self.insitu_stress.check_frictionless(normal)
        return self.insitu_stress.normal(normal)

    def permeability(self, dim: int, option: str = "-thm_rock_permeability") -> np.ndarray:
        """The permeability tensor (dim, dim) from one value, the dim
        diagonal values, or the full symmetric tensor (3D: kxx,kyy,kzz,kyz,kxz,kxy;
        2D: kxx,kyy,kxy), which must be positive semi-definite."""
        K = self._permeability_tensor(dim, option)
        k = self.rock_permeability
        low = float(np.linalg.eigvalsh(K).min())
        if low < -1e-12 * float(np.abs(K).max()):
            raise InputError(f"option {option} = {','.join(f'{v:g}' for v in k)} is not positive "
                             f"semi-definite (an eigenvalue is {low:.4g} m2)")
        return K

    def _permeability_tensor(self, dim: int, option: str) -> np.ndarray:
        k = self.rock_permeability
        full = 6 if dim == 3 else 3
        if len(k) == 1:
            return k[0] * np.eye(dim)
        if len(k) == dim:
            return np.diag(k)
        if len(k) != full:
            raise InputError(f"option {option} takes 1, {dim} or {full} values "
                             f"({'kxx,kyy,kzz,kyz,kxz,kxy' if dim == 3 else 'kxx,kyy,kxy'}), got {len(k)}")
        pairs = VOIGT if dim == 3 else ((0, 0), (1, 1), (0, 1))
        K = np.zeros((dim, dim))
        for (i, j), v in zip(pairs, k, strict=True):
            K[i, j] = K[j, i] = v
        return K

    def isotropic_permeability(self) -> float:
        """The one value of an isotropic permeability (scenes with a 1D reference solution)."""
        k = self.rock_permeability
        if min(k) < 0:
            raise InputError(f"option -thm_rock_permeability = {','.join(map(str, k))} is negative: a "
                             "permeability is >= 0 m2")
        if len(set(k)) != 1:
            raise InputError(f"option -thm_rock_permeability = {','.join(map(str, k))}: this scene "
                             "takes one (isotropic) value")
        return float(k[0])
