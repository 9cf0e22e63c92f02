"""Fluid properties (theory manual, "Equations: fluid properties")."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from petthm.errors import InputError

#: one standard atmosphere (Pa): absolute pressure = gauge pressure + ATMOSPHERE
ATMOSPHERE = 101_325.0
#: IAPWS-IF97 region 1 (compressed liquid): 273.15 K <= T <= 623.15 K, p_sat(T) <= p <= 100 MPa
REGION1_T_MAX_C = 350.0
REGION1_P_MAX = 100e6


def liquid_range(p_abs: float) -> tuple[float, float] | None:
    """(lowest, highest) temperature in degC of liquid water at the absolute
    pressure ``p_abs`` (IAPWS-IF97 region 1: above 0 degC, below the
    saturation temperature T_sat(p) of the ``iapws`` package and at most
    350 degC, region 1's edge); None where region 1 has no liquid at this
    pressure (below the triple point's 611.2 Pa, above 100 MPa)."""
    from iapws.iapws97 import Pc, _TSat_P
    p_mpa = p_abs * 1e-6
    if not 611.2128 * 1e-6 <= p_mpa <= REGION1_P_MAX * 1e-6:
        return None
    t_sat = _TSat_P(p_mpa) - 273.15 if p_mpa <= Pc else float("inf")
    return 0.0, min(t_sat, REGION1_T_MAX_C)


def check_liquid(option: str, T: float, p_abs: float, where: str) -> None:
    """An ``InputError`` unless ``T`` (degC, option ``-option``) is liquid
    water at ``p_abs`` (Pa; ``where`` says where it comes from)."""
    bounds = liquid_range(p_abs)
    if bounds is None:
        raise InputError(f"option -{option} = {T:g} degC: there is no liquid water at {p_abs / 1e6:.6g} MPa "
                         f"absolute ({where}); IAPWS-IF97 region 1 needs 611.2 Pa to 100 MPa")
    lo, hi = bounds
    edge = hi == REGION1_T_MAX_C                     # region 1 holds T = 350 degC; boiling water does not
    if not (lo < T and (hi >= T if edge else hi > T)):
        bound = f"T <= {hi:g} degC, the edge of region 1" if edge else f"T < {hi:.4g} degC, boiling"
        raise InputError(f"option -{option} = {T:g} degC is not liquid water at {p_abs / 1e6:.6g} MPa "
                         f"absolute ({where}): IAPWS-IF97 region 1 needs {lo:g} degC < T and {bound}")


def water_viscosity(T, lib=np):
    """mu(T) of water in Pa s, T in kelvin (theory manual, "Equations: fluid properties"); ``lib``:
    numpy, or sympy for the symbolic form."""
    return lib.exp(-52.843 + 3703.6 / T + 5.866 * lib.log(T) - 5.88e-29 * T ** 10)


@dataclass(frozen=True)
class Viscosity:
    """mu(T) in Pa s: a constant, or water (theory manual, "Equations: fluid properties", T in kelvin):
    mu = exp(-52.843 + 3703.6/T + 5.866 ln T - 5.88e-29 T^10).

    ``mobility(T)`` returns 1/mu and its derivative d(1/mu)/dT."""
    value: float = 1e-3
    water: bool = False

    def mu(self, T):
        if not self.water:
            return np.full(np.shape(T), self.value)
        return water_viscosity(np.asarray(T, dtype=float))

    def symbolic(self, T):
        """mu(T) as a sympy expression of the symbol ``T`` (manufactured solutions)."""
        import sympy
        return water_viscosity(T, sympy) if self.water else sympy.Float(self.value)

    def mobility(self, T):
        """(1/mu, d(1/mu)/dT)."""
        if not self.water:
            return np.full(np.shape(T), 1.0 / self.value), np.zeros(np.shape(T))
        T = np.asarray(T, dtype=float)
        m = 1.0 / self.mu(T)
        dlnmu = -3703.6 / T ** 2 + 5.866 / T - 5.88e-28 * T ** 9
        return m, -m * dlnmu

    @staticmethod
    def parse(text: str) -> Viscosity:
        """'-thm_fluid_viscosity': a positive number (Pa s) or 'water'."""
        if str(text).strip().lower() == "water":
            return Viscosity(water=True)
        v = float(text)
        if not v > 0:
            raise ValueError("must be > 0 or 'water'")
        return Viscosity(value=v)
