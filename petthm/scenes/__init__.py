"""Scenes: one module per family; importing a module registers its scenes."""


def load_all() -> None:
    from . import contact, fracture, heat, poro, thm  # noqa: F401
