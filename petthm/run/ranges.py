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
every scene; the extremes are carried through a restart.
"""
from __future__ import annotations

import math
import sys

from petthm.discretisation import probes
from petthm.discretisation.model import Model, Range
from petthm.scenes.base import Monitor

#: the carried state's key (the scene monitor's keys are its own attribute names)
CARRIED = "field_ranges.extremes"


def excursion(r: Range, lo: float, hi: float) -> float:
    """How far [lo, hi] reaches out of the range's interval (0 inside; NaN unbounded)."""
    if not r.bounded:
        return math.nan
    return max(0.0, r.lower - lo, hi - r.upper)


def difference_unit(unit: str) -> str:
    """The unit of a difference of values in ``unit`` (a difference of degrees Celsius is a kelvin)."""
    return "K" if unit == "degC" else unit


class FieldRanges:
    """The range of each field of ``model.ranges`` every step, and its
    extremes over the run (see the module docstring)."""

    def __init__(self, model: Model):
        self.specs = {f.name: f for f in model.fields if f.name in model.ranges}
        self.ranges = {name: model.ranges[name] for name in self.specs}
        self.extremes = {name: [math.inf, -math.inf] for name in self.specs}    # SI, carried
        self.warned: set[str] = set()

    def columns(self) -> list[str]:
        return [f"{name}_{end}" for name in self.specs for end in ("min", "max")]

    def __call__(self, problem, t: float, X=None) -> dict:
        out = {}
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
        return {**self.scene.carried_state(), CARRIED: {k: list(v) for k, v in self.ranges.extremes.items()}}

    def restore(self, state: dict) -> None:
        self.scene.restore(state)
        for name, ext in state.get(CARRIED, {}).items():
            if name in self.ranges.extremes:
                self.ranges.extremes[name] = list(ext)
