"""The named physical groups of a gmsh mesh (``../shared/docs/reservoir.md``
section 1): a deck refers to the mesh's rock units, fractures, boundaries and
wells by the names of its physical groups.

The names come from the file's ``$PhysicalNames`` section, which both of
gmsh's formats (2.2 and 4.1, ASCII or binary) write as text before the
nodes: rank 0 reads that section alone and broadcasts it, so no rank reads
the mesh for its names.  ``check_names`` applies the contract's rules: a
name matches ``[A-Za-z][A-Za-z0-9]*``; two names that differ only in case,
a name of DMPlex's own labels, and a name that is the first word of a
global option under the same prefix (a fracture called ``normal`` would
make ``-thm_fracture_normal_stiffness`` ambiguous) are input errors.
``label_named_boundaries`` labels the boundary groups by name from the
"Face Sets" label PETSc's gmsh reader makes.
"""
from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np

from petthm.errors import InputError
from petthm.mesh.fracture import FACE_SETS
from petthm.mesh.topology import label_name

#: what a group's name may be (PETSc cuts option values at spaces; an underscore would make the
#: option suffixes ambiguous)
NAME = re.compile(r"[A-Za-z][A-Za-z0-9]*\Z")
#: the labels DMPlex makes itself (lower case: names match without regard to case)
#: the cell label PETSc's gmsh reader makes from the physical groups of the cells
CELL_SETS = "Cell Sets"
DMPLEX_LABELS = ("depth", "celltype", "cell sets", "face sets", "vertex sets")
#: the option prefix of each kind of group
PREFIXES = {"region": "-thm_region_", "fracture": "-thm_fracture_", "bc": "-thm_bc_", "well": "-thm_well_"}


@dataclass(frozen=True)
class Group:
    """One physical group: its dimension, gmsh tag and name."""
    dim: int
    tag: int
    name: str


def read_physical_names(path: str) -> list[Group]:
    """The physical groups that have names in a gmsh file (its
    ``$PhysicalNames`` section; an empty list without one)."""
    groups: list[Group] = []
    try:
        with open(path, "rb") as f:
            for raw in f:
                line = raw.strip()
                if line == b"$PhysicalNames":
                    return _names_section(f, path)
                if line in (b"$Nodes", b"$Entities", b"$Elements"):
                    break
    except OSError as e:
        raise InputError(f"option -thm_mesh_file: cannot read {path}: {e.strerror}") from None
    return groups


def _names_section(f, path: str) -> list[Group]:
    try:
        count = int(f.readline())
        groups = []
        for _ in range(count):
            dim, tag, name = f.readline().decode().strip().split(maxsplit=2)
            groups.append(Group(int(dim), int(tag), name.strip().strip('"')))
    except (ValueError, UnicodeDecodeError):
        raise InputError(f"option -thm_mesh_file: {path}: its $PhysicalNames section is not "
                         "gmsh's (a count, then 'dim tag \"name\"' per line)") from None
    return groups


def named_groups(path: str, comm) -> list[Group]:
    """``read_physical_names`` on rank 0, broadcast to every rank of
    ``comm`` (an mpi4py communicator); an input error on one is raised on all."""
    result = None
    if comm.rank == 0:
        try:
            result = read_physical_names(path)
        except InputError as e:
            result = e
    result = comm.bcast(result, root=0)
    if isinstance(result, InputError):
        raise result
    return result


def reserved_words(options: Iterable[str], kind: str) -> set[str]:
    """The first words after the prefix of ``kind`` (``PREFIXES``) of the
    global options ``options`` (with or without the leading dash; lower
    case): the names a group of that kind cannot take."""
    prefix = PREFIXES[kind][1:]
    names = (o.lstrip("-") for o in options)
    return {o[len(prefix):].split("_")[0].lower() for o in names if o.startswith(prefix)}


def check_names(groups: Iterable[Group], reserved: Mapping[str, set[str]] | None = None,
                kinds: Mapping[str, str] | None = None) -> None:
    """Input errors for the names of ``groups`` that break the contract:
    the pattern ``NAME``, names equal but for case, DMPlex's labels, and a
    name in ``reserved[kind]`` for its group's kind (``kinds``: name ->
    region, fracture, bc or well)."""
    seen: dict[str, Group] = {}
    for g in groups:
        where = f"physical group '{g.name}' (dimension {g.dim}, tag {g.tag})"
        if not NAME.match(g.name):
            raise InputError(f"{where}: a name is a letter followed by letters and digits "
                             "([A-Za-z][A-Za-z0-9]*), without spaces or underscores")
        key = g.name.lower()
        if key in DMPLEX_LABELS:
            raise InputError(f"{where}: the name of a label DMPlex makes itself "
                             f"({', '.join(DMPLEX_LABELS)}); rename the group")
        other = seen.get(key)
        if other is not None:
            raise InputError(f"{where} and '{other.name}' (dimension {other.dim}, tag {other.tag}) "
                             + ("share the name" if other.name == g.name else "differ only in case")
                             + "; a name (matched without regard to case) names one group")
        seen[key] = g
        kind = (kinds or {}).get(g.name)
        if kind and key in (reserved or {}).get(kind, set()):
            raise InputError(f"{where}: '{g.name}' is the first word of a global {PREFIXES[kind]}* option "
                             f"({PREFIXES[kind]}{key}_...); rename the group")


def label_named_boundaries(dm, groups: Iterable[Group]) -> None:
    """One label per named boundary group (``topology.label_name``, as
    ``plex.label_boundaries`` makes from coordinates): the facets of the
    group's tag in the "Face Sets" label and their closure.  Before
    distribution (the labels travel with the points).  A group that no facet
    of the mesh carries is an input error naming it."""
    from mpi4py import MPI
    comm = dm.comm.tompi4py()
    has = dm.hasLabel(FACE_SETS)
    for g in groups:
        size = dm.getStratumSize(FACE_SETS, g.tag) if has else 0
        if comm.allreduce(size, op=MPI.SUM) == 0:
            raise InputError(f"physical group '{g.name}' (dimension {g.dim}, tag {g.tag}) has no facets "
                             "of the mesh: a boundary group is a set of faces of the mesh's cells")
        name = label_name(g.name)
        dm.createLabel(name)
        label = dm.getLabel(name)
        if size:
            for p in dm.getStratumIS(FACE_SETS, g.tag).getIndices():
                label.setValue(int(p), 1)
        dm.labelComplete(label)


def cell_tags(mesh) -> np.ndarray:
    """The "Cell Sets" label value (gmsh physical tag) of each local cell of
    ``mesh`` (a ``plex.Mesh``), -1 where a cell has none."""
    tags = np.full(mesh.ncells, -1, dtype=np.int32)
    values = mesh.dm.getLabelIdIS(CELL_SETS).getIndices() if mesh.dm.getLabelSize(CELL_SETS) else []
    for tag in values:
        if mesh.dm.getStratumSize(CELL_SETS, tag):
            cells = mesh.dm.getStratumIS(CELL_SETS, tag).getIndices() - mesh.cstart
            tags[cells[(cells >= 0) & (cells < mesh.ncells)]] = tag
    return tags
