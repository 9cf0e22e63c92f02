"""Fluid properties (physics.md section 8)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def water_viscosity(T, lib=np):
    """mu(T) of water in Pa s, T in kelvin (physics.md section 8); ``lib``:
    numpy, or sympy for the symbolic form."""
    return lib.exp(-52.843 + 3703.6 / T + 5.866 * lib.log(T) - 5.88e-29 * T ** 10)


@dataclass(frozen=True)
class Viscosity:
    """mu(T) in Pa s: a constant, or water (physics.md section 8, T in kelvin):
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
    def parse(text: str) -> "Viscosity":
        """'-thm_fluid_viscosity': a positive number (Pa s) or 'water'."""
        if str(text).strip().lower() == "water":
            return Viscosity(water=True)
        v = float(text)
        if not v > 0:
            raise ValueError("must be > 0 or 'water'")
        return Viscosity(value=v)
