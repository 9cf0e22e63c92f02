"""Scenes: one module per family; importing a module registers its scenes.

A run imports only its scene's module (``load``: the others' imports cost
~0.1 s of a small run's start); the listing and the option contract import
them all (``load_all``).  ``MODULES`` names each scene's module; a test
keeps it equal to what the modules register."""
from importlib import import_module

#: scene name -> the module (in this package) that registers it
MODULES = {
    "contact_patch": "contact", "fracture_inflation": "crack", "partial_opening": "crack",
    "sneddon": "contact", "coupled_mms": "coupled_mms", "fracture_flow_patch": "flow",
    "leakoff_1d": "flow", "radial_flow": "flow", "friction_patch": "friction",
    "inclined_crack": "friction", "gravity_column": "mechanics", "thermal_stress": "mechanics",
    "heat_advection": "heat", "heat_erfc": "heat", "heat_mms": "heat", "inclined_penny": "scene3",
    "lauwerier": "lauwerier", "leakoff_heat": "scene1", "rigid_fracture": "scene1", "mandel": "poro",
    "terzaghi": "poro", "penny_impermeable": "thm",
}


def load(name: str) -> None:
    """Register the scene ``name`` (every scene if the name is not known:
    the caller's unknown-scene error then lists them all)."""
    if name in MODULES:
        import_module(f".{MODULES[name]}", __name__)
    else:
        load_all()


def load_all() -> None:
    for module in sorted(set(MODULES.values())):
        import_module(f".{module}", __name__)
