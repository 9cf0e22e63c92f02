"""A deck's wells (``../shared/docs/reservoir.md`` sections 2 and 3; manual:
user guide, decks, "Wells"): the controls read from ``-thm_wells`` and
``-thm_well_NAME_*`` and checked, the ``LineWell`` of each from its mesh
group (``mesh/wellpaths.py``) and the rock around it, and its columns of
``history.csv``."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from petthm import params as P
from petthm.errors import InputError
from petthm.params import CELSIUS
from petthm.physics import linewells as lw
from petthm.scenes.deckinput import WELL_SUFFIXES, WellValues


@dataclass(frozen=True)
class Control:
    """A well's parsed control: a rate or a pressure schedule, the injected
    temperature (degC, None: not given) and the radius (m)."""
    rate: lw.Schedule | None
    pressure: lw.Schedule | None
    temperature: float | None
    radius: float


def well_controls(p, groups) -> dict:
    """{name: WellValues} of the wells of -thm_wells, each checked
    (``control``); an error for a name that is no group of dimension d - 2 of
    the mesh, and for options of a group not in -thm_wells."""
    from petsc4py import PETSc
    names = [s.strip() for s in p.wells.split(",") if s.strip()]
    groups_by_name = {g.name.lower(): g for g in groups.points}
    listed = set()
    out = {}
    for name in names:
        g = groups_by_name.get(name.lower())
        if g is None:
            known = [g.name for g in groups.points]
            raise InputError(f"option -thm_wells = {p.wells}: the mesh has no group '{name}' of dimension "
                             f"{groups.dim - 2}{P.did_you_mean(name, known)} (its groups of dimension "
                             f"{groups.dim - 2}: {', '.join(known) or 'none'})")
        values = P.read_named(WellValues(), WELL_SUFFIXES, "well", g.name)
        control(g.name, values, p)
        out[g.name] = values
        listed.add(g.name.lower())
    for key in PETSc.Options().getAll():
        low = key.lower()
        for g in groups.points:
            if low.startswith(f"thm_well_{g.name.lower()}_") and g.name.lower() not in listed:
                raise InputError(f"option -{key}: well {g.name} is not in -thm_wells (give -thm_wells "
                                 f"{','.join(names + [g.name])})")
    return out


def _numbers(text: str, option: str) -> tuple:
    try:
        return tuple(float(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise InputError(f"option {option} = {text}: numbers, a comma list for a schedule") from None


def control(name: str, v: WellValues, p) -> Control:
    """The parsed, checked control of well ``name``."""
    prefix = f"-thm_well_{name}_"
    if bool(v.rate) == bool(v.pressure):
        raise InputError(f"well {name}: give either {prefix}rate or {prefix}pressure (one control per well)")
    kind = "rate" if v.rate else "pressure"
    values = _numbers(getattr(v, kind), prefix + kind)
    times = _numbers(v.times, prefix + "times") if v.times else (0.0,) if len(values) == 1 else ()
    if len(times) != len(values):
        raise InputError(f"option {prefix}times = {v.times or '(none)'}: one time per value of "
                         f"{prefix}{kind} ({len(values)})")
    if times[0] != 0.0 or any(b <= a for a, b in zip(times, times[1:], strict=False)):
        raise InputError(f"option {prefix}times = {v.times}: increasing times from 0")
    schedule = lw.Schedule(times, values)
    temperature = _numbers(v.temperature, prefix + "temperature")[0] if v.temperature else None
    radius = v.radius or p.well_radius
    return Control(schedule if kind == "rate" else None, schedule if kind == "pressure" else None,
                   temperature, radius)


def history_columns(wells: dict) -> tuple:
    """The columns of ``history.csv`` of each well (reservoir.md section 3)."""
    return tuple(f"well_{name}_{what}" for name in wells
                 for what in ("rate", "pressure", "temperature", "power"))


def fracture_columns(w: lw.LineWell) -> dict:
    """{fracture: its column of history.csv} of the fractures a well crosses:
    the rate into each (m3/s), ``well_NAME_fracture_F_rate``."""
    return {f: f"well_{w.name}_fracture_{f}_rate" for f in dict.fromkeys(w.fractures) if f}


def schedule_times(wells: dict) -> list[float]:
    times = set()
    for v in wells.values():
        if v.times:
            times |= {t for t in _numbers(v.times, "") if t > 0}
    return sorted(times)


def power_reference(p, wells: dict) -> float:
    """T_ref of a producer's thermal power (K)."""
    if p.power_reference_temperature:
        return _numbers(p.power_reference_temperature, "-thm_power_reference_temperature")[0] + CELSIUS
    given = [_numbers(v.temperature, "")[0] for v in wells.values() if v.temperature]
    return (min(given) if given else 0.0) + CELSIUS


def line_wells(scene, mesh, fields) -> list[lw.LineWell]:
    """The ``LineWell`` of each of the scene's wells (collective).  A node on
    a fracture connects to it too; a deck without pm takes wells whose
    every node is on a fracture (in pf and Tf)."""
    from petthm.mesh.wellpaths import read_well_paths
    p, groups = scene.p, scene.groups
    wanted = [g for g in groups.points if g.name in scene.wells]
    paths = read_well_paths(scene.run.mesh_file, mesh.dim, wanted, groups.regions, mesh.dm.comm.tompi4py())
    crossings = fracture_of_nodes(scene, mesh, paths)
    rock = "pm" in fields
    K = [scene.permeability(name, mesh.dim) for name in scene.rocks] if rock else None
    heat = "Tm" in fields
    out = []
    for path, on in zip(paths, crossings, strict=True):
        if not rock and np.any(on < 0):
            raise InputError(f"option -thm_wells = {p.wells}: a well in the rock needs pm (its fields: "
                             f"{', '.join(fields)}; well {path.name} has nodes off the fractures)")
        check_crossings(scene, path, on, mesh.dim)
        c = control(path.name, scene.wells[path.name], p)
        if heat and c.rate is not None and max(c.rate.values) > 0 and c.temperature is None:
            raise InputError(f"well {path.name} injects (-thm_well_{path.name}_rate > 0): give "
                             f"-thm_well_{path.name}_temperature")
        out.append(_line_well(scene, path, c, K, heat, on, mesh.dim))
    return out


def fracture_of_nodes(scene, mesh, paths) -> list[np.ndarray]:
    """For each well path, the index of the fracture (in the order of
    -thm_fractures) that each node lies on, -1 in the rock (collective)."""
    from mpi4py import MPI
    from scipy.spatial import cKDTree

    from petthm.scenes import deckfractures as df
    out = [np.full(len(path.points), -1) for path in paths]
    if mesh.fracture is None:
        return out
    fr = mesh.fracture
    regions = df.fracture_regions(mesh, len(scene.fractures))
    face_fracture = regions if regions is not None else np.zeros(fr.ncells, dtype=int)
    x = mesh.vertex_coords[fr.cell_vertices.ravel()]
    which = np.repeat(face_fracture, fr.cell_vertices.shape[1])
    comm = mesh.dm.comm.tompi4py()
    tolerance = 1e-9 * max(float(mesh.h.max()) if mesh.ncells else 1.0, 1e-300)
    tree = cKDTree(x) if len(x) else None
    for k, path in enumerate(paths):
        if tree is not None:
            d, j = tree.query(path.points, distance_upper_bound=tolerance)
            hit = np.isfinite(d)
            out[k][hit] = which[j[hit]]
        mine = out[k].astype(np.int64)
        comm.Allreduce(mine.copy(), mine, op=MPI.MAX)
        out[k] = mine
    return out


def check_crossings(scene, path, on: np.ndarray, dim: int) -> None:
    """A 3D well meets each fracture at one node at most (it crosses it): a
    well that runs inside a fracture is not part of a deck yet."""
    if dim != 3:
        return
    names = list(scene.fractures)
    for k in np.unique(on[on >= 0]):
        nodes = np.flatnonzero(on == k)
        if len(nodes) > 1:
            a, b = (", ".join(f"{c:.6g}" for c in path.points[i]) for i in nodes[:2])
            raise InputError(f"well {path.name} runs inside fracture {names[k]} (its nodes at ({a}) and "
                             f"({b})): a well along a fracture is not part of a deck yet; a well may cross "
                             "fractures")


def _line_well(scene, path, c: Control, K, heat: bool, on: np.ndarray, dim: int) -> lw.LineWell:
    """The well of ``path``: each node's index the rock's (Peaceman; none
    without pm) plus, on a fracture, the fracture's
    (``linewells.fracture_well_index``)."""
    p = scene.p
    mu = np.broadcast_to(p.fluid_viscosity.mu(scene.initial_temperature()(path.points)), (len(path.points),))
    index = np.zeros(len(path.points))
    if K is not None:
        across = np.array([[lw.permeability_across(k, None if path.direction is None else path.direction[i])
                            for k in K] for i in range(len(path.points))])
        k_perp = np.sum(path.regions * across, axis=1)
        index = lw.well_index(k_perp, path.length, path.edge, c.radius, mu)
    crossing = on >= 0
    if crossing.any():
        apertures = np.array([q.fracture_aperture for q in scene.fractures.values()])
        transmissivity = apertures[on[crossing]] ** 3 / (12 * mu[crossing])
        index = index + np.bincount(np.flatnonzero(crossing), lw.fracture_well_index(
            transmissivity, path.edge[crossing], c.radius, dim - 1), minlength=len(index))
    z = path.points[:, -1]
    head = p.fluid_density * p.gravity * (z.max() - z)
    fields = ("pm", "Tm") if K is not None else ("pf", "Tf")
    names = tuple(scene.fractures)
    return lw.LineWell(path.name, path.points, index, head, rate=c.rate, pressure=c.pressure,
                       temperature=None if c.temperature is None else c.temperature + CELSIUS,
                       rho_c=p.fluid_rho_c if heat else 0.0, p=fields[0], T=fields[1] if heat else None,
                       fractures=tuple(names[k] if k >= 0 else "" for k in on))


def not_liquid(name: str, columns: dict, t: float) -> str | None:
    """What is wrong where a well's bottom-hole pressure (absolute) holds no
    liquid water at its water's temperature (``well_columns``), or None."""
    from petthm.physics.fluid import ATMOSPHERE, liquid_range
    p_abs = columns[f"well_{name}_pressure"] + ATMOSPHERE
    T = columns[f"well_{name}_temperature"]
    bounds = liquid_range(p_abs)
    if bounds is None and p_abs > 611.2128:              # above region 1's 100 MPa: not a boiling well
        return None
    if bounds is not None and (not np.isfinite(T) or bounds[0] < T < bounds[1]):
        return None
    water = f"water at {T:.4g} degC" if np.isfinite(T) else "water"
    return (f"at t = {t:.4g} s well {name}'s bottom-hole pressure is {p_abs / 1e6:.4g} MPa absolute, where "
            f"{water} is not liquid: the model has no steam; its results there are not physical (lower "
            f"-thm_well_{name}_rate or raise its pressure)")


def well_columns(problem, w: lw.LineWell, t: float, X, power_reference: float) -> dict:
    """A well's rate (m3/s into the rock), bottom-hole pressure (Pa), the
    temperature of its water (degC: injected, or the produced mix) and
    produced thermal power (W) at the state X (collective)."""
    ns = next(n for n in problem.node_sets if n.term.name == w.name)
    xl, _ = problem.local_arrays(X or problem.X, t)
    ctx = ns.context(xl, t, problem.scales)
    s = lw.state(w, ctx)
    T = ctx.values[w.T] if w.T is not None else np.zeros_like(s.q)
    out_of_rock = s.q < 0
    sums = ctx.total([s.q.sum(), (s.q * T)[out_of_rock].sum(), s.q[out_of_rock].sum()])
    Q = float(sums[0])
    name = f"well_{w.name}"
    row = {f"{name}_rate": Q, f"{name}_pressure": s.pressure, f"{name}_temperature": float("nan"),
           f"{name}_power": 0.0}
    crossed = fracture_columns(w)
    if crossed:
        on = np.asarray(w.fractures)[ctx.owned]
        rates = ctx.total([s.q[on == f].sum() for f in crossed])
        row.update({column: float(q) for column, q in zip(crossed.values(), rates, strict=True)})
    if w.T is None:
        return row
    if Q > 0 and w.temperature is not None:
        row[f"{name}_temperature"] = w.temperature - CELSIUS
    elif sums[2] < 0:
        produced = float(sums[1] / sums[2])
        row[f"{name}_temperature"] = produced - CELSIUS
        if Q < 0:
            row[f"{name}_power"] = w.rho_c * abs(Q) * (produced - power_reference)
    return row
