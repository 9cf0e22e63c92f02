"""The time-step schedule's data: the scene's schedule (first step, growth,
largest step, hit times), its collapse floor and step count, the recovery
factor after rejected tries, and the options of ``-thm_dt_control error``
(theory manual, "Time stepping and solvers").  ``solver.TimeStepper`` applies them."""
from __future__ import annotations

import math
from dataclasses import dataclass

#: a step cut by rejected tries grows back by this factor per accepted step (or
#: the schedule's growth, if larger) until it reaches the schedule's step again
RECOVERY = 2.0


def error_control_defaults(control: StepControl) -> dict[str, str]:
    """The TS options of ``-thm_dt_control error`` (proposed: a user's
    ``-ts_adapt_*``, ``-ts_atol``, ``-ts_rtol`` win).  PETSc's basic
    adaptivity on backward Euler's local error estimate (TSTheta: the step's
    distance to the quadratic through the last three states), measured on
    the scaled unknowns (``Problem.scales``: each field's range is ~1), so
    ``-ts_atol`` is a fraction of each field's range (1e-3: 0.08 K on an 80 K
    cooling); the largest entry counts (a front is local); the scene's
    largest step and the collapse floor bound the steps."""
    out = {"ts_adapt_type": "basic", "ts_atol": "1e-3", "ts_rtol": "0",
           "ts_adapt_wnormtype": "infinity", "ts_adapt_dt_min": repr(control.dt_floor())}
    if math.isfinite(control.dt_max):
        out["ts_adapt_dt_max"] = repr(control.dt_max)
    return out


@dataclass
class StepControl:
    final_time: float
    dt_initial: float
    growth: float = 1.0
    dt_max: float = math.inf
    hit_times: tuple = ()        # times to land on exactly
    pc_reuse: str = "off"        # on, off, auto: on for a direct solve (PreconditionerReuse)
    pc_reuse_max_krylov: int = 30
    courant: float = 0.0         # largest front Courant number per step (0: no limit)
    predictor: str = "none"      # Newton's first iterate of a step: linear, none (predictor.py)

    def dt_floor(self) -> float:
        """The smallest step a run may take before its end: 1e-10 of the end
        time and 1e-6 of the first step (a step cut that far by rejections
        does not recover, and a run on such steps never ends)."""
        return min(1e-10 * self.final_time, 1e-6 * self.dt_initial)

    def collapsed(self, dt: float, t: float) -> bool:
        """Whether the step just taken (ending at t) is below ``dt_floor``;
        the last step, clipped to land on the end time, may be shorter."""
        return dt < self.dt_floor() and t < self.final_time * (1 - 1e-12)

    def check_reachable(self, end: float, option: str = "") -> None:
        """Steps that shrink (growth < 1) add up to at most dt_initial / (1 -
        growth): short of ``end``, the run could never reach it (an
        ``InputError`` naming ``option``, the growth's, or the scene's
        default)."""
        if self.growth >= 1.0:
            return
        reach = self.dt_initial / (1.0 - self.growth) if self.growth > 0 else self.dt_initial
        if reach < end:
            from petthm.errors import InputError
            name = f"option -{option}" if option else "the scene's time-step growth"
            raise InputError(f"{name} = {self.growth:g}: steps shrinking by this factor from the first "
                             f"step {self.dt_initial:g} s add up to at most {reach:.4g} s, short of the end "
                             f"time {end:.6g} s (a growth factor >= 1 keeps or grows the steps)")

    def steps_left(self, t: float, dt: float) -> int:
        """Steps from t to the final time when the last step was dt: each
        next step min(dt growth, dt_max), the last one clipped (for the
        progress line's estimate)."""
        remaining, n = self.final_time - t, 0
        tiny = 1e-12 * max(abs(self.final_time), 1e-300)
        while remaining > tiny and n < 10 ** 6:
            dt = min(dt * self.growth, self.dt_max) if dt > 0 else self.dt_initial
            if self.growth <= 1.0 or dt >= self.dt_max:
                return n + math.ceil(remaining / dt - 1e-9)
            remaining -= dt
            n += 1
        return n


__all__ = ["RECOVERY", "StepControl", "error_control_defaults"]
