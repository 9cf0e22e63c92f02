"""What a deck gives as input (../shared/docs/reservoir.md; manual: user
guide, decks): the option declarations of a deck and of its boundaries,
the named groups of its mesh, the checks of its options and names, and
its values of position (expressions, the in-situ stress, liquid water).
``reservoir.Reservoir`` builds the scene from them."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from petthm import params as P
from petthm.discretisation import probes
from petthm.errors import InputError
from petthm.expressions import Expression, split_list, values_at
from petthm.mesh import groups as mg
from petthm.params import DISCRETISATION, PHYSICS, did_you_mean, param
from petthm.physics import materials as mt

#: the fields a deck may have
DECK_FIELDS = ("u", "pm", "pf", "Tm", "Tf")
#: the rock properties a region may give (-thm_region_NAME_rock_*, ../shared/docs/reservoir.md section 2)
REGION_FIELDS = mt.ELASTIC + ("rock_biot_coefficient", "rock_density", "rock_heat_capacity",
                              "rock_conductivity", "rock_thermal_expansion", "rock_porosity",
                              "rock_permeability")


@dataclass(frozen=True)
class DeckParams:
    """Deck (reservoir)"""
    fields: str = param("", "-", "the fields to solve for, a comma list of u, pm, pf, Tm, Tf (default: every "
                        "field the deck has: u, Tm, pm where the permeability is not zero, pf and Tf with "
                        "fractures)",
                        kind=DISCRETISATION)
    fe_degree_flow: int = param(0, "-", "degree of pm and Tm (0: P1 with P2 u, else -thm_fe_degree)",
                                choices=(0, 1, 2), kind=DISCRETISATION)
    fractures: str = param("", "-", "the fractures, a comma list of the names of the mesh's groups of "
                           "dimension 2 (3D) or 1 (2D): -thm_fracture_NAME_* (manual: decks, fractures)",
                           kind=PHYSICS)
    wells: str = param("", "-", "the wells, a comma list of the names of the mesh's groups of dimension 1 "
                       "(3D) or 0 (2D): -thm_well_NAME_* (manual: decks, wells)", kind=PHYSICS)
    power_reference_temperature: str = param("", "degC", "T_ref of a producer's thermal power rho_f C_f Q "
                                             "(T - T_ref) (default: the lowest injection temperature)",
                                             kind=PHYSICS)
    equilibrium_tolerance: float = param(1e-6, "-", "the largest imbalance div sigma0 + rho_b g of the "
                                         "in-situ stress accepted, relative to rho_b g (without gravity: "
                                         "to the stress's largest value over the domain's extent)",
                                         lo=0.0, lo_open=True, kind=PHYSICS)


@dataclass(frozen=True)
class BoundaryValues:
    """The conditions on one named boundary: ``-thm_bc_NAME_SUFFIX``, read by
    ``params.read_named`` (kind ``bc``); numbers or expressions of x, y, z."""
    pressure: str = param("", "Pa", "pressure held on the boundary", kind=PHYSICS)
    temperature: str = param("", "degC", "temperature held on the boundary", kind=PHYSICS)
    flux: str = param("", "m/s", "water flux out through the boundary (Darcy velocity . n)", kind=PHYSICS)
    heat_flux: str = param("", "W/m2", "conductive heat flux out through the boundary", kind=PHYSICS)
    normal_displacement: str = param("", "m", "displacement along the outward normal (a plane face normal "
                                     "to an axis)", kind=PHYSICS)
    displacement: str = param("", "m", "displacement ux,uy[,uz]", kind=PHYSICS)
    normal_stress: str = param("", "Pa", "total normal stress on the boundary, compression positive",
                               kind=PHYSICS)
    traction: str = param("", "Pa", "total traction tx,ty[,tz] on the boundary", kind=PHYSICS)


@dataclass(frozen=True)
class WellValues:
    """The control of one named well: ``-thm_well_NAME_SUFFIX``, read by
    ``params.read_named`` (kind ``well``)."""
    rate: str = param("", "m3/s", "volume rate into the rock (> 0 injects, < 0 produces; 2D: per metre); a "
                      "comma list with _times is a schedule", kind=PHYSICS)
    pressure: str = param("", "Pa", "bottom-hole pressure at the well's shallowest node instead of a rate "
                          "(a list with _times likewise)", kind=PHYSICS)
    times: str = param("", "s", "the times the schedule's values start, 0 first, increasing", kind=PHYSICS)
    temperature: str = param("", "degC", "temperature of the injected water", kind=PHYSICS)
    radius: float = param(0.0, "m", "well radius r_w of the well index (0: -thm_well_radius)", lo=0.0,
                          kind=PHYSICS)


WELL_SUFFIXES = tuple(f.name for f in dataclasses.fields(WellValues))


#: the field each boundary value acts on
BC_FIELD = {"pressure": "pm", "temperature": "Tm", "flux": "pm", "heat_flux": "Tm",
            "normal_displacement": "u", "displacement": "u", "normal_stress": "u", "traction": "u"}
BC_SUFFIXES = tuple(f.name for f in dataclasses.fields(BoundaryValues))


# -- the mesh's names -----------------------------------------------------------------------
@dataclass(frozen=True)
class DeckGroups:
    """The named groups of a deck's mesh: its dimension, regions and boundaries."""
    dim: int
    regions: tuple
    boundaries: tuple
    points: tuple = ()           # groups of dimension d - 2: the wells a deck may name in -thm_wells

    def region_of_tag(self, tag: int) -> str:
        return next((g.name for g in self.regions if g.tag == tag), f"tag {tag}")


def deck_groups(path: str, comm) -> DeckGroups:
    """Read and classify the named groups of the deck's mesh (collective)."""
    if not path:
        raise InputError("scene reservoir needs -thm_mesh_file F.msh: a gmsh mesh whose physical groups name "
                         "the rock's regions and boundaries (manual: user guide, decks)")
    if not path.endswith(".msh"):
        raise InputError(f"option -thm_mesh_file = {path}: a deck's mesh is a gmsh .msh file (2.2 or 4.1)")
    return classify(mg.named_groups(path, comm), path)


def classify(groups, path: str) -> DeckGroups:
    """The regions (the groups of the largest dimension) and boundaries (one
    dimension less) among a mesh's named groups, their names checked."""
    if not groups:
        raise InputError(f"option -thm_mesh_file = {path}: the mesh has no named physical groups; a deck "
                         "refers to its regions and boundaries by name")
    dim = max(g.dim for g in groups)
    if dim not in (2, 3):
        raise InputError(f"option -thm_mesh_file = {path}: its largest named group has dimension {dim}; a "
                         "deck's regions are groups of dimension 2 (plane strain) or 3")
    regions = tuple(g for g in groups if g.dim == dim)
    boundaries = tuple(g for g in groups if g.dim == dim - 1)
    points = tuple(g for g in groups if g.dim == dim - 2)
    kinds = {g.name: "region" for g in regions} | {g.name: "bc" for g in boundaries} | \
        {g.name: "well" for g in points}
    mg.check_names(regions + boundaries + points, kinds=kinds)
    return DeckGroups(dim, regions, boundaries, points)


def unknown_named_options(groups: DeckGroups, known=(), options=None) -> None:
    """An input error for a -thm_bc_NAME_* (-thm_region_NAME_*,
    -thm_well_NAME_*) option whose NAME is not a boundary (region, well
    group) of the mesh, or whose suffix is not one a boundary (region,
    well) takes; ``known``: global options under those prefixes
    (``-thm_well_radius``)."""
    from petsc4py import PETSc
    opts = options or PETSc.Options()
    known = {k.lower() for k in known}
    kinds = (("bc", "boundary", "boundaries", groups.boundaries, BC_SUFFIXES),
             ("region", "region", "regions", groups.regions, REGION_FIELDS),
             ("well", "well", "wells", groups.points, WELL_SUFFIXES))
    for key in sorted(opts.getAll()):
        low = key.lower()
        if low in known:
            continue
        for kind, what, plural, named, suffixes in kinds:
            if low.startswith(f"thm_{kind}_"):
                _check_named_option(key, low[len(kind) + 5:], what, plural, [g.name for g in named], suffixes)


def _check_named_option(key, rest, what, plural, names, suffixes) -> None:
    """``rest``: the option's NAME_SUFFIX (lower case)."""
    name = next((n.lower() for n in sorted(names, key=len, reverse=True) if rest.startswith(n.lower() + "_")),
                rest.split("_")[0])
    if name not in {n.lower() for n in names}:
        raise InputError(f"option -{key}: the mesh has no {what} '{name}'{did_you_mean(name, names)}; "
                         f"its {plural}: {', '.join(names) or 'none'}")
    check_suffix(key, rest[len(name) + 1:], what, suffixes)


def check_suffix(key: str, suffix: str, what: str, suffixes) -> None:
    """An input error for option ``key`` of a named group whose ``suffix`` is
    none that a ``what`` (boundary, region, well, fracture) takes."""
    if suffix not in suffixes:
        raise InputError(f"option -{key}: a {what} takes {', '.join(suffixes)}"
                         f"{did_you_mean(suffix, suffixes)}")


# -- values of position ---------------------------------------------------------------------
def vector_expressions(text: str, option: str, dim: int) -> list[Expression]:
    items = split_list(text)
    if len(items) != dim:
        raise InputError(f"option {option} = {text}: {dim} components ({'ux,uy,uz' if dim == 3 else 'ux,uy'} "
                         "or tx,ty[,tz]), numbers or expressions of position")
    return [Expression(s, option, dim) for s in items]


def insitu_tensor(p, dim: int):
    """S(x) (n, dim, dim): the in-situ total stress, compression positive,
    from -thm_insitu_stress (one number: isotropic; six: sxx,syy,szz,syz,sxz,sxy;
    in 2D the x-y block)."""
    comps = p.insitu_stress.components
    if len(comps) == 1:
        comps = (comps[0],) * 3 + (0.0,) * 3

    def S(points):
        out = np.zeros((len(points), dim, dim))
        for (i, j), c in zip(mt.VOIGT, comps, strict=True):
            if i < dim and j < dim:
                out[:, i, j] = out[:, j, i] = values_at(c, points)
        return out
    return S


def corners(comm, points, dim: int) -> tuple[np.ndarray, np.ndarray]:
    """(lowest, highest) coordinate along each axis of ``points`` (n, dim) over all ranks."""
    lo = np.array([probes.global_min(comm, points[:, a]) for a in range(dim)])
    hi = np.array([probes.global_max(comm, points[:, a]) for a in range(dim)])
    return lo, hi


def domain_extent(mesh) -> float:
    """The mesh's largest extent along an axis (m, collective)."""
    lo, hi = corners(mesh.dm.comm, mesh.vertex_coords, mesh.dim)
    return float(np.max(hi - lo))


def first_not_liquid(option: str, temps, p_gauge, points) -> str | None:
    """The message of the first point where ``temps`` (degC) is not liquid water
    at the gauge pressure ``p_gauge`` (Pa), or None.  The saturation
    temperature grows with the pressure, so it is taken exactly only at the
    points that a grid of pressures below theirs does not clear."""
    from petthm.physics.fluid import ATMOSPHERE, check_liquid, liquid_range
    if not len(temps):
        return None
    pa = np.asarray(p_gauge, dtype=float) + ATMOSPHERE
    grid = np.geomspace(max(pa.min(), 611.3), max(pa.max(), 611.4), 64)
    below = grid[np.clip(np.searchsorted(grid, pa, side="right") - 1, 0, len(grid) - 1)]
    cleared = np.zeros(len(pa), dtype=bool)
    for q in np.unique(below):
        bounds = liquid_range(q)
        if bounds is not None:
            at = (below == q) & (pa >= q)
            lowest, highest = bounds
            cleared |= at & (temps > lowest) & (temps < highest)
    for k in np.flatnonzero(~cleared):
        try:
            check_liquid(option, float(temps[k]), float(pa[k]),
                         f"-thm_initial_pressure at ({', '.join(f'{c:.6g}' for c in points[k])}), gauge")
        except InputError as e:
            return str(e)
    return None


def bulk_density(q) -> float:
    """rho_b = (1 - phi) rho_s + phi rho_f of a region's parameters."""
    return (1 - q.rock_porosity) * q.rock_density + q.rock_porosity * q.fluid_density


def rock_values(q) -> tuple:
    """A region's rock properties, comparable (``REGION_FIELDS``)."""
    return tuple(getattr(q, f) for f in REGION_FIELDS)


def named_field(kind: str, name: str, f: dataclasses.Field, value) -> tuple:
    """A field of the dataclass of a named group's values (``parameter_sets``)."""
    option = P.named_option(kind, name, f.name)
    return (option, type(value), dataclasses.field(default=value, metadata={**f.metadata, "option": option}))
