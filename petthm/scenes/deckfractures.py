"""A deck's fractures (``../shared/docs/reservoir.md`` sections 1 and 2;
manual: user guide, decks, "Fractures"): the groups of dimension d - 1
named in ``-thm_fractures``, split into cohesive cells; fracture flow pf
and heat Tf along them with each fracture's own aperture
(``-thm_fracture_NAME_aperture``, the global ``-thm_fracture_aperture``
where none is given), leakoff into the rock (pm = pf on the walls) and the
walls' heat exchange (``-thm_fracture_heat_exchange``).

A deck's fractures are rigid: their aperture does not change.  The rock
mechanics of a fractured deck (u with contact on the fractures) is refused
with an error that says so.  Wells that cross fractures: ``deckwells.py``."""
from __future__ import annotations

import numpy as np

from petthm import params as P
from petthm.errors import InputError
from petthm.physics.kernels.regional import per_region
from petthm.scenes.deckinput import check_suffix

#: the values a fracture may give (-thm_fracture_NAME_SUFFIX, SUFFIX the name less "fracture_")
FRACTURE_FIELDS = ("fracture_aperture",)
FRACTURE_STRIP = "fracture_"
#: per-fracture options of deformable fractures, which a deck does not hold yet
DEFORMABLE_SUFFIXES = ("normal_stiffness", "residual_fraction", "friction", "cohesion")


def fracture_groups(text: str, groups) -> tuple:
    """The groups of ``-thm_fractures`` (``text``; dimension d - 1 of the
    mesh), each checked; an error for a name that is no such group."""
    names = [s.strip() for s in text.split(",") if s.strip()]
    by_name = {g.name.lower(): g for g in groups.boundaries}
    out = []
    for name in names:
        g = by_name.get(name.lower())
        if g is None:
            known = [g.name for g in groups.boundaries]
            dims = {k.name.lower(): groups.dim for k in groups.regions} | \
                {k.name.lower(): groups.dim - 2 for k in groups.points}
            why = (f"'{name}' is a group of dimension {dims[name.lower()]}" if name.lower() in dims else
                   f"the mesh has no group '{name}'{P.did_you_mean(name, known)}")
            raise InputError(f"option -thm_fractures = {text}: {why}; a fracture is a group of "
                             f"dimension {groups.dim - 1} (the mesh's: {', '.join(known) or 'none'})")
        if g in out:
            raise InputError(f"option -thm_fractures = {text}: '{name}' is listed twice")
        out.append(g)
    return tuple(out)


def fracture_values(p, fractures) -> dict:
    """{name: parameters} of each fracture: ``p`` with its own values
    (-thm_fracture_NAME_aperture) where given."""
    return {g.name: P.read_named(p, FRACTURE_FIELDS, "fracture", g.name, strip=FRACTURE_STRIP)
            for g in fractures}


def named_fracture_options(fractures) -> set[str]:
    """The -thm_fracture_NAME_* options of the fractures (lower case, no dash)."""
    return {P.named_option("fracture", g.name, f[len(FRACTURE_STRIP):]) for f in FRACTURE_FIELDS
            for g in fractures}


def check_fracture_options(fractures_text: str, groups, fractures, known, options=None) -> None:
    """An input error for a -thm_fracture_NAME_* option of a group that is
    not a fracture, of a deformable fracture's value, or of a value a
    fracture does not take (``known``: the global options, lower case); and
    for a boundary condition -thm_bc_NAME_* on a fracture."""
    from petsc4py import PETSc
    opts = options or PETSc.Options()
    listed = {g.name.lower() for g in fractures}
    candidates = sorted({g.name for g in groups.boundaries}, key=len, reverse=True)
    suffixes = [f[len(FRACTURE_STRIP):] for f in FRACTURE_FIELDS]
    for key in sorted(opts.getAll()):
        low = key.lower()
        on = next((g.name for g in fractures if low.startswith(f"thm_bc_{g.name.lower()}_")), None)
        if on:
            raise InputError(f"option -{key}: {on} is a fracture (-thm_fractures), not a boundary; a "
                             "pressure or temperature held on a boundary holds a fracture that reaches it")
        if not low.startswith("thm_fracture_") or low in known:
            continue
        if low.endswith(DEFORMABLE_SUFFIXES):
            raise InputError(f"option -{key}: deformable fractures (normal stiffness, friction, cohesion) "
                             "are not part of a deck yet; a deck's fractures are rigid "
                             "(-thm_fracture_NAME_aperture)")
        rest = low[len("thm_fracture_"):]
        name = next((n for n in candidates if rest.startswith(n.lower() + "_")), None)
        if name is None or name.lower() not in listed:
            shown = name or rest.split("_")[0]
            hint = (f"; give -thm_fractures {','.join([g.name for g in fractures] + [name])}" if name else
                    P.did_you_mean(shown, [g.name for g in fractures]))
            raise InputError(f"option -{key}: '{shown}' is not a fracture of this deck (-thm_fractures = "
                             f"{fractures_text or 'none'}){hint}")
        check_suffix(key, rest[len(name) + 1:], "fracture", suffixes)


def apertures(values: dict):
    """The fractures' apertures: one number where all are equal, else a
    ``Regional`` in the order of ``values`` (the model's fracture_regions)."""
    return per_region(q.fracture_aperture for q in values.values())


def fracture_regions(mesh, count: int) -> np.ndarray | None:
    """The index of each local fracture face's fracture (the split's labels
    ``thm_fracture_k``, in the order of -thm_fractures); None for one fracture."""
    if count < 2 or mesh.fracture is None:
        return None
    dm, faces = mesh.dm, mesh.fracture.faces
    out = np.full(len(faces), -1)
    for k in range(count):
        name = f"thm_fracture_{k}"
        if dm.hasLabel(name) and dm.getStratumSize(name, 1):
            out[np.isin(faces, dm.getStratumIS(name, 1).getIndices())] = k
    if (out < 0).any():
        raise RuntimeError(f"{int((out < 0).sum())} fracture faces belong to no fracture")
    return out


def history_columns(values: dict) -> tuple:
    """Each fracture's columns of history.csv (../shared/docs/reservoir.md section 3)."""
    return tuple(f"fracture_{name}_{what}" for name in values for what in ("aperture_max", "aperture_mean"))


def aperture_columns(values: dict) -> dict:
    """The columns of each fracture's aperture: the largest and the
    area-weighted mean, both its fixed aperture (a deck's fractures are rigid)."""
    return {f"fracture_{name}_{what}": q.fracture_aperture for name, q in values.items()
            for what in ("aperture_max", "aperture_mean")}
