"""What a deck reports every step (manual: user guide, decks, "What a run
writes"): how far it has moved from its initial state and each well's
rate, pressure, temperature and power."""
from __future__ import annotations

import sys

import numpy as np

from petthm.discretisation import probes
from petthm.scenes import deckwells as dw
from petthm.scenes.base import Monitor


class DeckMonitor(Monitor):
    """How far the deck has moved from its initial state: the largest
    displacement (m) and the largest change of pm, pf (Pa) and Tm, Tf (K) over the
    nodes, per step (beside the field ranges of ``run.ranges``); and each
    well's rate, pressure, temperature and power (``deckwells.well_columns``)."""

    def __init__(self, fields, initial, wells=(), power_reference: float = 0.0, fixed=None):
        self.fields, self.initial = fields, initial
        #: columns whose values do not change (a rigid fracture's aperture)
        self.fixed = dict(fixed or {})
        self.wells, self.power_reference = list(wells), power_reference
        self.warned: set[str] = set()
        self._initial_values = {}
        self.last = {}

    def __call__(self, problem, t, X=None):
        out = dict(self.fixed)
        if "u" in self.fields:
            v = problem.field_values("u", X, t)
            size = np.linalg.norm(v, axis=1) if len(v) else v[:, 0]
            out["u_max"] = probes.global_max(problem.dm.comm, size, empty=0.0)
        for name in ("pm", "pf", "Tm", "Tf"):
            if name in self.fields:
                out[f"{name}_change_max"] = probes.max_nodal_error(problem, name, self.initial_at(name), X, t)
        for w in self.wells:
            columns = dw.well_columns(problem, w, t, X, self.power_reference)
            out.update(columns)
            self.check_water(problem, w, t, columns)
        self.last = out
        return out

    def initial_at(self, name: str):
        """The initial value of field ``name`` at its nodes, evaluated once
        (the nodes do not move; a deck's initial state is an expression)."""
        if name not in self._initial_values:
            initial = self.initial[name]
            cache = {}

            def at(x):
                if "x" not in cache or cache["x"] is not x:
                    cache["x"], cache["v"] = x, initial(x)
                return cache["v"]
            self._initial_values[name] = at
        return self._initial_values[name]

    def check_water(self, problem, w, t: float, columns: dict) -> None:
        """Once per well, a warning where its bottom-hole pressure leaves
        liquid water (the model has one phase; ``deckwells.not_liquid``)."""
        if w.name in self.warned:
            return
        message = dw.not_liquid(w.name, columns, t)
        if message:
            self.warned.add(w.name)
            if problem.dm.comm.getRank() == 0:
                print(f"warning: {message}", file=sys.stderr, flush=True)

    def report(self, problem, t):
        return {"change": dict(self.last)}
