"""Rock properties that differ from region to region (theory manual,
"Heterogeneous rock"; a deck's ``-thm_region_NAME_*`` options).

A coefficient of a kernel object (``poroelastic.Elastic``, ``flow.Flow``,
``heat.Heat``, ...) is a number or a ``Regional``: one value per rock
region, in the order of the model's ``cell_regions`` (the region index of
each cell).  The assembler gives every batch of cells the cells of one
region only (``Assembler.chunks``), so that within a batch every
coefficient is one number: ``at(obj, ctx)`` is the kernel object with its
``Regional`` values replaced by those of the batch's region
(``ctx.region``), and the kernels compute with numbers as on a uniform rock.
Term registrations bind their kernels with ``regional`` in place of
``functools.partial``: the kernel receives the object of the batch's region.

Properties jump across a region boundary; the finite-element fields are
continuous there and the weak form integrates each cell with its own
coefficients, so the normal flux (Darcy's, the conduction's, the
traction) is continuous in the weak sense with no interface term.  A
kernel on the fracture (whose faces have no region of their own) refuses a
rock object whose values differ (``at`` raises).
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from functools import partial

import numpy as np


@dataclass(frozen=True, eq=False)
class Regional:
    """One value of a coefficient per rock region (numbers, or arrays of one shape)."""
    values: tuple

    def __bool__(self) -> bool:
        """Whether any region has a value that is not zero (a term is registered where one does)."""
        return any(bool(np.any(v)) for v in self.values)

    def __getitem__(self, region: int):
        return self.values[region]

    @property
    def largest(self) -> float:
        """The largest value over the regions (numbers)."""
        return max(float(np.max(v)) for v in self.values)


def per_region(values) -> object:
    """A coefficient from one value per region: the value itself where all are
    equal (a uniform rock computes as before), else a ``Regional``."""
    values = tuple(values)
    first = values[0]
    if all(np.array_equal(np.asarray(v), np.asarray(first)) for v in values[1:]):
        return first
    return Regional(values)


def _frozen_dataclass(obj) -> bool:
    return dataclasses.is_dataclass(obj) and not isinstance(obj, type) and obj.__dataclass_params__.frozen


#: id(object) -> (object, whether it holds a Regional); the object is kept so that its id stays its own
_HOLDS: dict[int, tuple] = {}
#: (id(object), region) -> (object, the object of that region)
_RESOLVED: dict[tuple, tuple] = {}


def holds_regional(obj) -> bool:
    """Whether ``obj`` is a ``Regional`` or a frozen dataclass or tuple holding one (at any depth)."""
    if isinstance(obj, Regional):
        return True
    if isinstance(obj, tuple):
        return any(holds_regional(v) for v in obj)
    if not _frozen_dataclass(obj):
        return False
    key = id(obj)
    if key not in _HOLDS:
        _HOLDS[key] = (obj, any(holds_regional(getattr(obj, f.name)) for f in dataclasses.fields(obj)))
    return _HOLDS[key][1]


def _resolve(obj, region: int):
    if isinstance(obj, Regional):
        return obj.values[region]
    if isinstance(obj, tuple):
        return tuple(_resolve(v, region) for v in obj)
    if not holds_regional(obj):
        return obj
    key = (id(obj), region)
    if key not in _RESOLVED:
        changes = {f.name: _resolve(getattr(obj, f.name), region) for f in dataclasses.fields(obj)
                   if f.init and holds_regional(getattr(obj, f.name))}
        _RESOLVED[key] = (obj, dataclasses.replace(obj, **changes))
    return _RESOLVED[key][1]


def at(obj, ctx):
    """``obj`` (a kernel object, a tuple or a coefficient) with the values of
    the region of the batch of cells ``ctx`` (the same object again for the
    same region: caches keyed by it work).  An error on a batch without a
    region (the fracture's faces, boundary facets) where the values differ."""
    if not holds_regional(obj):
        return obj
    region = getattr(ctx, "region", None)
    if region is None:
        raise NotImplementedError("rock properties that differ between regions on fracture faces or "
                                  "boundary facets (a term there needs the rock cell next to each face)")
    return _resolve(obj, region)


class _Bound:
    """``kernel(at(obj, ctx), *args, ctx)``: the kernel of ``regional``."""

    def __init__(self, kernel, obj, args):
        self.kernel, self.obj, self.args = kernel, obj, args

    def __call__(self, ctx):
        return self.kernel(at(self.obj, ctx), *self.args, ctx)


def regional(kernel, obj, *args):
    """``partial(kernel, obj, *args)`` that receives ``obj`` with the values
    of the batch's region (``at``); a plain partial where ``obj`` holds none."""
    if not holds_regional(obj):
        return partial(kernel, obj, *args)
    return _Bound(kernel, obj, args)
