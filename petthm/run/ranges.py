"""The ranges of the fields a model names in ``Model.ranges`` (the user
guide, "Outputs"; theory manual, "Discrete bounds"): every step the
history's ``<field>_min`` and ``<field>_max`` (in the field's output unit),
and in summary.json ``bounds.<field>``: the interval, the extremes over the
whole run and how far they left the interval (``below`` the lower end,
``above`` the upper, the larger of the two as ``violation``), in the
field's unit of difference (K for temperatures), and the violation as a
fraction of the interval.

``WithRanges`` puts these beside the scene's own monitor, so that a scene
declares where its fields belong and the run reports it, the same way for
every scene; the extremes are carried through a restart.  A model with a
heat source of its own rates (``Model.heating``: -thm_thermomechanical_heating)
has the temperatures' allowance for it in the history's ``heating_allowance``
and in ``bounds.<field>.heating_allowance`` (K): what that source alone can
add to an excursion by then.
"""
from __future__ import annotations

import math
import sys

import numpy as np

from petthm.discretisation import probes
from petthm.discretisation.model import Heating, Model, Range
from petthm.physics.kernels.regional import at
from petthm.scenes.base import Monitor

#: the carried state's key (the scene monitor's keys are its own attribute names)
CARRIED = "field_ranges.extremes"
CARRIED_HEATING = "field_ranges.heating_allowance"


def excursion(r: Range, lo: float, hi: float) -> float:
    """How far [lo, hi] reaches out of the range's interval (0 inside; NaN unbounded)."""
    if not r.bounded:
        return math.nan
    return max(0.0, r.lower - lo, hi - r.upper)


def difference_unit(unit: str) -> str:
    """The unit of a difference of values in ``unit`` (a difference of degrees Celsius is a kelvin)."""
    return "K" if unit == "degC" else unit


class HeatingAllowance:
    """How far the model's heat source of its own rates (``Model.heating``,
    the thermo-mechanical heating) can take the temperatures out of their
    range: each step dt max |power| / capacity over the region's points (K),
    summed over the steps (``total``, carried through a restart, whose
    start state the monitor sees as a step's end).  Bounded by it: the
    maximum principle of the heat equation
    with a source, which the bound-preserving schemes keep (lumped capacity:
    a node's source over its capacity is a mean of power / capacity)."""

    def __init__(self, heating: Heating):
        self.heating = heating
        self.total = 0.0
        self._last = None                      # (t, scaled local state) of the last step

    def __call__(self, problem, t: float, X=None) -> float:
        """This step's allowance (K), added to ``total`` (collective)."""
        from mpi4py import MPI

        from petthm.discretisation.context import CellContext
        xl = problem.local_arrays(X or problem.X, t)[0].copy()
        last, self._last = self._last, (t, xl)
        if last is None or not t > last[0]:
            return 0.0
        dt = t - last[0]
        xdl = (xl - last[1]) / dt
        asm = problem.region(self.heating.region)
        peak = 0.0                                  # the largest heating rate, K/s
        for cells in asm.chunks():
            ctx = CellContext(asm, cells, xl, xdl, t, 1.0 / dt)
            rate = np.abs(self.heating.power(ctx)) / at(self.heating.capacity, ctx)
            peak = max(peak, float(rate.max(initial=0.0)))
        peak = problem.dm.comm.tompi4py().allreduce(peak, op=MPI.MAX)
        step = dt * peak
        self.total += step
        return step


class FieldRanges:
    """The range of each field of ``model.ranges`` every step, and its
    extremes over the run (see the module docstring); with the model's
    ``heating``, the allowance it makes (``HeatingAllowance``)."""

    def __init__(self, model: Model):
        self.specs = {f.name: f for f in model.fields if f.name in model.ranges}
        self.ranges = {name: model.ranges[name] for name in self.specs}
        self.extremes = {name: [math.inf, -math.inf] for name in self.specs}    # SI, carried
        self.warned: set[str] = set()
        self.heating = HeatingAllowance(model.heating) if model.heating is not None and self.specs else None

    def columns(self) -> list[str]:
        heating = ["heating_allowance"] if self.heating is not None else []
        return [f"{name}_{end}" for name in self.specs for end in ("min", "max")] + heating

    def __call__(self, problem, t: float, X=None) -> dict:
        out = {}
        if self.heating is not None:
            self.heating(problem, t, X)
            out["heating_allowance"] = self.heating.total
        for name, spec in self.specs.items():
            lo, hi = probes.field_range(problem, name, X, t)
            ext = self.extremes[name]
            ext[0], ext[1] = min(ext[0], lo), max(ext[1], hi)
            self._warn(problem, name, t, lo, hi)
            out[f"{name}_min"], out[f"{name}_max"] = float(spec.output(lo)), float(spec.output(hi))
        return out

    def _warn(self, problem, name: str, t: float, lo: float, hi: float) -> None:
        r = self.ranges[name]
        if r.warn_above is None or name in self.warned or not r.bounded:
            return
        fraction = excursion(r, lo, hi) / (r.upper - r.lower)
        if fraction <= r.warn_above:
            return
        self.warned.add(name)
        if problem.dm.comm.rank == 0:
            spec = self.specs[name]
            unit = spec.output_unit or spec.unit
            print(f"warning: at t = {t:.4g} s {name} = [{spec.output(lo):.2f}, {spec.output(hi):.2f}] {unit} "
                  f"leaves [{spec.output(r.lower):g}, {spec.output(r.upper):g}] by {100 * fraction:.0f} % of "
                  f"the range (the run's largest: summary.json, bounds.{name}){r.hint}",
                  file=sys.stderr, flush=True)

    def report(self) -> dict:
        out = {}
        for name, spec in self.specs.items():
            r, (lo, hi) = self.ranges[name], self.extremes[name]
            unit = spec.output_unit or spec.unit
            entry = {"unit": unit, "min": float(spec.output(lo)), "max": float(spec.output(hi))}
            if r.bounded:
                v = excursion(r, lo, hi)
                entry.update({"lower": float(spec.output(r.lower)), "upper": float(spec.output(r.upper)),
                              "below": max(0.0, r.lower - lo), "above": max(0.0, hi - r.upper),
                              "violation": v, "violation_unit": difference_unit(unit),
                              "violation_fraction": v / max(r.upper - r.lower, 1e-300)})
                if self.heating is not None:
                    entry["heating_allowance"] = self.heating.total
            out[name] = entry
        return {"bounds": out} if out else {}


class WithRanges(Monitor):
    """A scene's monitor with the model's field ranges beside it."""

    def __init__(self, scene: Monitor, ranges: FieldRanges):
        self.scene, self.ranges = scene, ranges
        self.files = scene.files

    def __call__(self, problem, t: float, X=None) -> dict:
        out = self.scene(problem, t, X)
        out.update(self.ranges(problem, t, X))
        return out

    def report(self, problem, t: float) -> dict:
        out = self.scene.report(problem, t)
        out.update(self.ranges.report())
        return out

    def stop_reason(self) -> str | None:
        return self.scene.stop_reason()

    def carried_state(self) -> dict:
        out = {**self.scene.carried_state(), CARRIED: {k: list(v) for k, v in self.ranges.extremes.items()}}
        if self.ranges.heating is not None:
            out[CARRIED_HEATING] = self.ranges.heating.total
        return out

    def restore(self, state: dict) -> None:
        self.scene.restore(state)
        for name, ext in state.get(CARRIED, {}).items():
            if name in self.ranges.extremes:
                self.ranges.extremes[name] = list(ext)
        if self.ranges.heating is not None:
            self.ranges.heating.total = float(state.get(CARRIED_HEATING, 0.0))
