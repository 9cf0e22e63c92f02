"""Scenes: one module per family; importing a module registers its scenes."""


def load_all() -> None:
    from . import contact, coupled_mms, flow, friction, heat, lauwerier, mechanics, poro, scene1, scene3, thm  # noqa: F401
