"""Scenes: one module per family, each scene a ``base.Scene`` subclass
with its ``name``.

A run imports only its scene's module (``scene_class``: the others'
imports cost ~0.1 s of a small run's start); the listing and the option
contract import them all (``all_scenes``).  ``MODULES`` names each scene's
module; a test keeps it equal to the scenes the modules define.

May import: every layer below (io, solvers, physics, verification,
discretisation, mesh, base)."""
from importlib import import_module

#: scene name -> the module (in this package) that defines it
MODULES = {
    "contact_patch": "contact", "fracture_inflation": "crack", "partial_opening": "crack",
    "sneddon": "contact", "coupled_mms": "coupled_mms", "fracture_flow_patch": "flow",
    "leakoff_1d": "flow", "radial_flow": "flow", "friction_patch": "friction",
    "inclined_crack": "friction", "gravity_column": "mechanics", "thermal_stress": "mechanics",
    "heat_advection": "heat", "heat_erfc": "heat", "heat_mms": "heat", "inclined_penny": "scene3",
    "lauwerier": "lauwerier", "leakoff_heat": "scene1", "rigid_fracture": "scene1", "mandel": "poro",
    "terzaghi": "poro", "penny_impermeable": "thm", "reservoir": "reservoir",
}


def scenes_of(module) -> dict[str, type]:
    """{name: class} of the scenes a module defines."""
    from petthm.scenes.base import Scene
    return {c.name: c for c in vars(module).values()
            if isinstance(c, type) and issubclass(c, Scene) and c.name and c.__module__ == module.__name__}


def scene_class(name: str) -> type | None:
    """The scene called ``name`` (its module imported), or None if there is none."""
    if name not in MODULES:
        return None
    return scenes_of(import_module(f".{MODULES[name]}", __name__)).get(name)


def all_scenes() -> dict[str, type]:
    """{name: class} of every scene."""
    out = {}
    for module in sorted(set(MODULES.values())):
        out.update(scenes_of(import_module(f".{module}", __name__)))
    return out
