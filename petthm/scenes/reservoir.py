"""The ``reservoir`` scene: a user's reservoir as a deck, a gmsh mesh whose
physical groups carry names and an options file that refers to them
(``../shared/docs/reservoir.md``; manual: user guide, "Decks").

What a deck holds here:

* the mesh (``-thm_mesh_file``, required): its physical groups of the mesh's
  dimension d are the rock's regions (every cell in one), those of dimension
  d - 1 its boundaries, each named by its group's name;
* the rock and fluid (the global ``-thm_rock_*`` and ``-thm_fluid_*``
  options; the permeability may be a full tensor);
* the fields (``-thm_fields``, default every field the deck has: u, pm where
  the permeability is not zero, Tm);
* gravity (``-thm_gravity``, default 0 in a deck), along -z (-y in 2D): in
  Darcy's law q = -k/mu (grad p - rho_f g), and in the in-situ stress's
  balance;
* the initial state, numbers or expressions of x, y, z
  (``-thm_initial_temperature``, ``-thm_initial_pressure``,
  ``-thm_insitu_stress``): u is measured from it, so the in-situ stress must
  balance gravity (``check_equilibrium``);
* boundary conditions by name (``-thm_bc_NAME_*``, ``BoundaryValues``);
  a boundary without one has no flow, no heat flux and keeps its in-situ
  traction.

* the rock of each region (``-thm_region_NAME_rock_*``, ``REGION_FIELDS``):
  the global value where a region gives none; every kernel takes each
  cell's region's values (kernels/regional.py).

* wells (``-thm_wells``, ``-thm_well_NAME_*``, ``WellValues``): named
  polylines (3D) or points (2D) of the mesh, each with one bottom-hole
  pressure, at a rate or a pressure by a piecewise-constant schedule
  (physics/linewells.py; ``deckwells.py`` makes them from the options).

* fractures (``-thm_fractures``, ``-thm_fracture_NAME_aperture``):
  named groups of dimension d - 1 split into cohesive cells, with
  fracture flow pf and heat Tf at a fixed aperture each, leakoff (pm = pf
  on the walls) and the walls' heat exchange (``deckfractures.py``); a
  held pressure or temperature holds pf or Tf where a fracture reaches the
  boundary (``deckbc.py``); a well may cross fractures, connected to each
  at the crossing (``deckwells.py``).  A fractured deck's rock mechanics is
  refused with an error that says so.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from petthm import params as P
from petthm.discretisation import probes
from petthm.discretisation.assembly import FieldScale
from petthm.discretisation.model import Range
from petthm.errors import InputError
from petthm.expressions import Expression, values_at
from petthm.mesh import groups as mg
from petthm.mesh.groups import CELL_SETS
from petthm.params import CELSIUS
from petthm.physics import materials as mt
from petthm.physics.builders import ModelBuilder
from petthm.physics.kernels.regional import Regional, per_region
from petthm.physics.linewells import well_term
from petthm.scenes import deckfractures as df
from petthm.scenes import deckwells as dw
from petthm.scenes.base import Scene, Setup, TimeDefaults
from petthm.scenes.deckbc import DeckBoundaries
from petthm.scenes.deckinput import (
    BC_SUFFIXES,
    DECK_FIELDS,
    REGION_FIELDS,
    WELL_SUFFIXES,
    BoundaryValues,
    DeckParams,
    WellValues,
    bulk_density,
    classify,
    deck_groups,
    domain_extent,
    first_not_liquid,
    insitu_tensor,
    named_field,
    rock_values,
    unknown_named_options,
)
from petthm.scenes.deckmonitor import DeckMonitor
from petthm.solvers.options import direct_solver_defaults


class Reservoir(DeckBoundaries, Scene):
    """A deck: the module docstring."""
    name = "reservoir"
    description = "your own reservoir: a gmsh mesh with named groups and an options file (manual: decks)"
    takes_expressions = True
    parameters = (
        mt.group("Rock", mt.ELASTIC + ("rock_biot_coefficient", "rock_porosity", "rock_permeability",
                                       "rock_thermal_expansion") + mt.ROCK_HEAT),
        mt.group("Fluid", mt.FLUID_HEAT + mt.FLUID_FLOW),
        mt.group("Initial state", ("initial_temperature", "initial_pressure", "insitu_stress"),
                 insitu_stress="0"),
        mt.group("Gravity", ("gravity",), gravity=0.0),
        mt.group("Fracture", ("fracture_aperture", "fracture_heat_exchange",
                              "fracture_supg_wall_conduction")),
        mt.group("Wells", ("well_radius",)),
        mt.group("Coupling", ("thermomechanical_heating",)),
        mt.group("Heat transport", mt.HEAT_DISCRETISATION),
        DeckParams)
    time = TimeDefaults(final_time=3.15576e7, dt_initial=8.64e4, dt_growth=1.2, dt_max=3.15576e7 / 12)
    history_columns = ("u_max", "pm_change_max", "pf_change_max", "Tm_change_max", "Tf_change_max")

    def __init__(self, run, p):
        super().__init__(run, p)
        from petsc4py import PETSc
        self.groups = deck_groups(run.mesh_file, PETSc.COMM_WORLD.tompi4py())
        #: the fractures' groups (-thm_fractures) and each one's parameters (-thm_fracture_NAME_*)
        self.fracture_groups = df.fracture_groups(p.fractures, self.groups)
        self.fractures = df.fracture_values(p, self.fracture_groups)
        self.bc = {g.name: P.read_named(BoundaryValues(), BC_SUFFIXES, "bc", g.name)
                   for g in self.groups.boundaries if g not in self.fracture_groups}
        #: the parameters of each region, in the order of the mesh's regions (-thm_region_NAME_rock_*)
        self.rocks = {g.name: P.read_named(p, REGION_FIELDS, "region", g.name) for g in self.groups.regions}
        #: the wells' controls (-thm_wells, -thm_well_NAME_*)
        self.wells = dw.well_controls(p, self.groups)
        self.history_columns = type(self).history_columns + dw.history_columns(self.wells) + \
            df.history_columns(self.fractures)

    def parameter_sets(self):
        """The run's and the deck's parameters, the boundaries' values
        (-thm_bc_NAME_*) and the regions' rock (-thm_region_NAME_rock_*): a
        restart keeps them, as every physics option."""
        by_name = {f.name: f for f in dataclasses.fields(self.p)}
        fields = [named_field("bc", name, f, getattr(values, f.name))
                  for name, values in self.bc.items() for f in dataclasses.fields(BoundaryValues)]
        fields += [named_field("region", name, by_name[f], getattr(rock, f))
                   for name, rock in self.rocks.items() for f in REGION_FIELDS]
        fields += [named_field("well", name, f, getattr(values, f.name))
                   for name, values in self.wells.items() for f in dataclasses.fields(WellValues)]
        fields += [named_field("fracture", name, by_name[f], getattr(q, f))
                   for name, q in self.fractures.items() for f in df.FRACTURE_FIELDS]
        return (self.run, self.p, dataclasses.make_dataclass("Named", fields, frozen=True)())

    @classmethod
    def named_options(cls, run):
        from petsc4py import PETSc
        groups = deck_groups(run.mesh_file, PETSc.COMM_WORLD.tompi4py())
        known = P.known_options(cls.parameters)
        unknown_named_options(groups, known=known)
        text = PETSc.Options().getString("thm_fractures", "")
        fractures = df.fracture_groups(text, groups)
        df.check_fracture_options(text, groups, fractures, known)
        return (P.named_options(BoundaryValues, BC_SUFFIXES, "bc", [g.name for g in groups.boundaries]) |
                df.named_fracture_options(fractures) |
                {P.named_option("region", g.name, f) for f in REGION_FIELDS for g in groups.regions} |
                P.named_options(WellValues, WELL_SUFFIXES, "well", [g.name for g in groups.points]))

    @classmethod
    def named_help(cls, mesh_file):
        """The -thm_bc_NAME_* options of the mesh's boundaries, the
        -thm_region_NAME_rock_* of its regions and the -thm_well_NAME_* of its
        wells' groups (rank 0 alone: -help)."""
        bc = P.help_text((BoundaryValues,)).split("\n")[1:]
        well = P.help_text((WellValues,)).split("\n")[1:]
        rock = [line for line in P.help_text((cls.parameters[0],)).split("\n")[1:]
                if line.split()[0][len("-thm_"):] in REGION_FIELDS]
        fracture = ["  Fractures (named in -thm_fractures; default: the global value)"] + \
            [line.replace("-thm_fracture_", "-thm_fracture_<NAME>_", 1)
             for line in P.help_text(cls.parameters).split("\n")[1:]
             if line.split()[0][len("-thm_"):] in df.FRACTURE_FIELDS]
        if not mesh_file:
            return "\n".join(["  Boundaries (give -thm_mesh_file F.msh to list them for its boundaries)"] +
                             [line.replace("-thm_", "-thm_bc_<NAME>_", 1) for line in bc] +
                             ["  Regions (default: the global value)"] +
                             [line.replace("-thm_", "-thm_region_<NAME>_", 1) for line in rock] +
                             ["  Wells (named in -thm_wells)"] +
                             [line.replace("-thm_", "-thm_well_<NAME>_", 1) for line in well] + fracture)
        groups = classify(mg.read_physical_names(mesh_file), mesh_file)
        lines = []
        for kind, what, named, options in (("bc", "Boundary", groups.boundaries, bc),
                                           ("region", "Region", groups.regions, rock),
                                           ("well", "Well", groups.points, well)):
            for g in named:
                lines.append(f"  {what} {g.name} of {mesh_file}")
                lines += [line.replace("-thm_", f"-thm_{kind}_{g.name.lower()}_", 1) for line in options]
        return "\n".join(lines + fracture)

    # a sparse direct solve; the size rule puts the block preconditioner in its place on large decks
    solver_defaults = staticmethod(direct_solver_defaults)

    def mesh_dimension(self):
        return self.groups.dim, ""

    def fracture_tags(self) -> tuple[int, ...]:
        """The tags of the groups of -thm_fractures, in its order: only they
        are split (a deck's boundaries and regions keep their faces whatever
        their tags)."""
        return tuple(g.tag for g in self.fracture_groups)

    def water_temperatures(self):
        """None before the mesh: a deck's temperatures are checked at the nodes (``check_water``)."""
        return []

    # -- the mesh ----------------------------------------------------------------------------
    def label_mesh(self, dm) -> None:
        """Boundary labels by name; every cell in a named region (before distribution)."""
        self.check_regions(dm)
        mg.label_named_boundaries(dm, self.groups.boundaries)

    def check_regions(self, dm) -> None:
        """Every cell carries the tag of a named region in the "Cell Sets" label (collective)."""
        from mpi4py import MPI
        start, end = dm.getHeightStratum(0)
        inside = sum(dm.getStratumSize(CELL_SETS, g.tag) for g in self.groups.regions) \
            if dm.hasLabel(CELL_SETS) else 0
        outside = dm.comm.tompi4py().allreduce(end - start - inside, op=MPI.SUM)
        if outside:
            raise InputError(f"mesh '{self.run.mesh_file}': {outside} cell(s) belong to no named region "
                             f"(the regions: {', '.join(g.name for g in self.groups.regions)}); put every "
                             f"cell in a physical group of dimension {self.groups.dim} with a name")

    # -- the fields ------------------------------------------------------------------------------
    def fields(self, dim: int) -> tuple[str, ...]:
        """The deck's fields in canonical order: -thm_fields, else every field
        it has (u, Tm; pm where a permeability is not zero; pf and Tf with
        fractures), checked (``check_fields``)."""
        p = self.p
        has = ["u", "Tm"]
        permeabilities = [self.permeability(name, dim) for name in self.rocks]     # each checked
        if any(np.any(k != 0) for k in permeabilities):
            has.append("pm")
        if self.fractures:
            has += ["pf", "Tf"]
        wanted = [s.strip() for s in p.fields.split(",") if s.strip()] or has
        for f in wanted:
            if f not in DECK_FIELDS:
                raise InputError(f"option -thm_fields = {p.fields}: '{f}' is not a field of a deck "
                                 f"({', '.join(DECK_FIELDS)}){P.did_you_mean(f, DECK_FIELDS)}")
            if f not in has:
                raise InputError(f"option -thm_fields = {p.fields}: {f} needs "
                                 + ("fractures (-thm_fractures)" if f in ("pf", "Tf") else
                                    "a permeability that is not zero (-thm_rock_permeability or a region's "
                                    "-thm_region_NAME_rock_permeability)"))
        fields = tuple(f for f in DECK_FIELDS if f in wanted)
        self.check_fields(fields)
        return fields

    def check_fields(self, fields) -> None:
        """The fields of a fractured deck go together: its rock's pm and Tm
        meet the fractures' pf and Tf on the walls, Tf needs pf; a
        fractured deck's mechanics is not part of a deck yet."""
        if not self.fractures:
            return
        option = f"option -thm_fields = {self.p.fields}" if self.p.fields else "the deck's fields"
        if "pf" not in fields:
            raise InputError(f"{option}: a fractured deck (-thm_fractures = {self.p.fractures}) needs pf, "
                             "the fractures' water")
        rules = (("u", None, "the rock mechanics of a fractured deck (contact on its fractures) is not part "
                             "of a deck yet: leave u out (-thm_fields pm,pf,Tm,Tf)"),
                 ("pm", "pf", "pm needs pf in a fractured deck (the walls' pressure is the fracture's)"),
                 ("Tm", "Tf", "Tm needs Tf where the fractures carry water (pf): the walls' temperature "
                              "is the fracture's water's"),
                 ("Tf", "pf", "Tf needs pf (the fracture's water)"),
                 ("Tf", "Tm", "Tf needs Tm (the rock the fracture's water exchanges heat with)"))
        for have, needs, why in rules:
            if have in fields and (needs is None or needs not in fields) and \
                    not (have == "Tm" and "pf" not in fields):
                raise InputError(f"{option}: {why}")

    def check_flow_regions(self, dim: int) -> None:
        """pm needs, in every region, a permeability or a storage that is
        not zero (else its pressure is undetermined there)."""
        for name, q in self.rocks.items():
            if q.storage == 0 and not np.any(self.permeability(name, dim)):
                raise InputError(f"region {name}: neither permeability nor storage (porosity 0 and Biot "
                                 "coefficient 1), so its pressure is undetermined; give it a permeability "
                                 f"(-thm_region_{name}_rock_permeability) or a porosity, or leave pm out "
                                 "(-thm_fields)")

    def degrees(self, fields, degree: int) -> int:
        """The degree of pm and Tm: -thm_fe_degree_flow, else P1 with P2 u
        (Taylor-Hood), else -thm_fe_degree."""
        if self.p.fe_degree_flow:
            return self.p.fe_degree_flow
        return 1 if "u" in fields and degree == 2 else degree

    # -- the model ------------------------------------------------------------------------------
    def build(self, mesh, degree):
        p, dim = self.p, mesh.dim
        fields = self.fields(dim)
        fd = self.degrees(fields, degree)
        T0, p0 = self.initial_temperature(), self.initial_pressure()
        bcs, facets = self.boundary_conditions(mesh, fields)
        self.check_water(mesh, fields)
        b = ModelBuilder(*self.rock_parameters(dim))
        g = np.zeros(dim)
        g[-1] = -p.gravity
        if "u" in fields:
            self.check_held(bcs, dim)
            self.check_equilibrium(mesh)
            b.elasticity(degree, biot="pm" in fields, thermal="Tm" in fields, p_ref=p0, T_ref=T0)
        if "pm" in fields:
            self.check_flow_regions(dim)
            b.matrix_flow(fd, permeability=per_region(self.permeability(name, dim) for name in self.rocks),
                          storage=b.rock(lambda q: q.storage),
                          thermal_storage=b.rock(lambda q: q.rock_porosity * q.fluid_thermal_expansion),
                          heat="Tm" in fields,
                          gravity=tuple(p.fluid_density * g), reference_pressure=0.0,
                          reference_temperature=CELSIUS)
        if "pf" in fields:
            a = df.apertures(self.fractures)
            b.fracture_flow(fd, reference_aperture=a, heat="Tf" in fields, gravity=tuple(p.fluid_density * g))
            if "pm" in fields:
                b.leakoff()
        temperatures = self.temperature_range(mesh)
        if "Tm" in fields:
            b.matrix_heat(fd)
            b.model.ranges["Tm"] = temperatures
        if "Tf" in fields:
            b.fracture_heat(fd, reference_aperture=a)
            b.model.ranges["Tf"] = temperatures
        b.model.facets.extend(facets)
        if self.wells:
            self.line_wells = dw.line_wells(self, mesh, fields)
            b.model.node_sets.extend(well_term(w) for w in self.line_wells)
            self.history_columns += tuple(c for w in self.line_wells for c in dw.fracture_columns(w).values())
        model = b.build()
        if len(set(map(rock_values, self.rocks.values()))) > 1:
            model.cell_regions = self.cell_regions(mesh)
        if "pf" in fields and isinstance(a, Regional):
            model.fracture_regions = df.fracture_regions(mesh, len(self.fractures))
        init = {"u": lambda x: np.zeros((len(x), dim)), "pm": p0, "pf": p0, "Tm": T0, "Tf": T0}
        return Setup(model, bcs, self.scales(mesh, fields, temperatures), {f: init[f] for f in fields},
                     DeckMonitor(fields, init, getattr(self, "line_wells", []), self.power_reference(),
                                 df.aperture_columns(self.fractures)))

    def hit_times(self) -> list[float]:
        """The times of the wells' schedules: the steps land on them."""
        return dw.schedule_times(self.wells)

    def power_reference(self) -> float:
        """T_ref of the producers' thermal power (K): -thm_power_reference_temperature,
        else the lowest injection temperature (else 0 degC)."""
        return dw.power_reference(self.p, self.wells)

    def rock_parameters(self, dim: int) -> tuple:
        """(global parameters, dim, each region's parameters) of the model
        builder; the in-situ state's expressions are the scene's own (the
        builder's initial values are 0)."""
        zero = {"initial_temperature": 0.0, "initial_pressure": 0.0}
        regions = tuple(dataclasses.replace(q, **zero) for q in self.rocks.values())
        return dataclasses.replace(self.p, **zero), dim, regions

    def permeability(self, name: str, dim: int) -> np.ndarray:
        """The permeability tensor of region ``name`` (its option named in an error)."""
        option = "-" + P.named_option("region", name, "rock_permeability") \
            if self.rocks[name].rock_permeability != self.p.rock_permeability else "-thm_rock_permeability"
        return self.rocks[name].permeability(dim, option)

    def cell_regions(self, mesh) -> np.ndarray:
        """The index of each local cell's region (in the order of ``rocks``), from its tag."""
        top = max(g.tag for g in self.groups.regions)
        lookup = np.full(top + 1, -1)
        for i, g in enumerate(self.groups.regions):
            lookup[g.tag] = i
        tags = mg.cell_tags(mesh)
        known = (tags >= 0) & (tags <= top)
        return np.where(known, lookup[np.clip(tags, 0, top)], -1)

    def initial_temperature(self):
        """T0(x) in kelvin at points (n, d)."""
        value = self.p.initial_temperature
        return lambda x: values_at(value, x) + CELSIUS

    def initial_pressure(self):
        """p0(x) in Pa (gauge) at points (n, d)."""
        value = self.p.initial_pressure
        return lambda x: values_at(value, x)

    # -- checks of the deck -------------------------------------------------------------------
    def check_held(self, bcs, dim) -> None:
        """Mechanics needs conditions that hold the rock in place: each
        displacement component held somewhere (rotations are not checked)."""
        held = set()
        for d in bcs:
            if d.field == "u":
                held |= set(range(dim)) if d.components is None else set(d.components)
        free = [("x", "y", "z")[a] for a in range(dim) if a not in held]
        if free:
            raise InputError(f"the deck has u but nothing holds u_{','.join(free)}: the rock can move as a "
                             "rigid body; give a boundary -thm_bc_NAME_displacement or _normal_displacement "
                             f"(along {', '.join(free)})")

    def check_equilibrium(self, mesh) -> None:
        """The in-situ stress balances gravity: |div S + rho_b g e_z| (S
        compression positive, e_z up) at every cell's centroid by central
        differences, against -thm_equilibrium_tolerance (collective)."""
        p, dim = self.p, mesh.dim
        comm = mesh.dm.comm.tompi4py()
        S = insitu_tensor(p, dim)
        x = mesh.vertex_coords[mesh.cell_vertices].mean(axis=1) if mesh.ncells else np.zeros((0, dim))
        extent = domain_extent(mesh)
        delta = 1e-4 * extent
        div = np.zeros((len(x), dim))
        for j in range(dim):
            step = np.zeros(dim)
            step[j] = delta
            div += (S(x + step)[:, :, j] - S(x - step)[:, :, j]) / (2 * delta)
        densities = np.array([bulk_density(q) for q in self.rocks.values()])
        rho_b = densities[self.cell_regions(mesh)]
        div[:, -1] += rho_b * p.gravity
        largest = probes.global_max(comm, np.abs(S(x)), empty=0.0)
        scale = densities.max() * p.gravity if p.gravity > 0 else largest / extent
        if scale == 0:
            return
        err = np.linalg.norm(div, axis=1) / scale
        worst = float(err.max()) if len(err) else 0.0
        top = probes.global_max(comm, worst)
        if top <= p.equilibrium_tolerance:
            return
        mine = worst == top and len(err) > 0
        where = None
        if mine:
            k = int(np.argmax(err))
            cell = mesh.cstart + k
            tag = mesh.dm.getLabelValue(CELL_SETS, cell) if mesh.dm.hasLabel(CELL_SETS) else -1
            where = (self.groups.region_of_tag(tag), tuple(float(c) for c in x[k]))
        where = next(w for w in comm.allgather(where) if w is not None)
        point = ", ".join(f"{c:.6g}" for c in where[1])
        raise InputError(f"option -thm_insitu_stress = {p.insitu_stress}: the in-situ stress does not "
                         f"balance gravity (-thm_gravity = {p.gravity:g}): abs(div sigma0 + rho_b g) is "
                         f"{top:.3g} times {'rho_b g' if p.gravity > 0 else 'its scale'} in region "
                         f"{where[0]} at ({point}), above -thm_equilibrium_tolerance = "
                         f"{p.equilibrium_tolerance:g}")

    def check_water(self, mesh, fields) -> None:
        """Every initial and boundary temperature is liquid water at the
        initial pressure there, node by node (collective)."""
        x = mesh.vertex_coords
        given = [("thm_initial_temperature", values_at(self.p.initial_temperature, x), x)]
        for name, bv in self.bc.items():
            if bv.temperature:
                option = P.named_option("bc", name, "temperature")
                pts = mesh.point_coordinates(mesh.label_points(name, 0))
                given.append((option, Expression(bv.temperature, "-" + option, mesh.dim)(pts), pts))
        message = None
        for option, T, pts in given:
            message = message or first_not_liquid(option, T, values_at(self.p.initial_pressure, pts), pts)
        found = [m for m in mesh.dm.comm.tompi4py().allgather(message) if m]
        if found:
            raise InputError(found[0])

    def temperature_range(self, mesh) -> Range:
        """[lowest, highest] of the initial and boundary temperatures over the mesh's nodes (K)."""
        x = mesh.vertex_coords
        values = [values_at(self.p.initial_temperature, x)]
        for name, bv in self.bc.items():
            if bv.temperature:
                pts = mesh.point_coordinates(mesh.label_points(name, 0))
                values.append(Expression(bv.temperature, f"-thm_bc_{name}_temperature", mesh.dim)(pts))
        values += [np.array([float(w.temperature)]) for w in self.wells.values() if w.temperature]
        v = np.concatenate(values)
        comm = mesh.dm.comm
        return Range(probes.global_min(comm, v) + CELSIUS, probes.global_max(comm, v) + CELSIUS)

    def scales(self, mesh, fields, temperatures: Range) -> dict:
        """Unknown scales from the deck's own ranges: the spread of the
        temperatures and pressures, the displacement they cause over the domain."""
        p, comm = self.p, mesh.dm.comm
        extent = domain_extent(mesh)
        Tr = temperatures
        dT = max(Tr.upper - Tr.lower, 1.0)
        p0 = values_at(p.initial_pressure, mesh.vertex_coords)
        plo, phi = probes.global_min(comm, p0), probes.global_max(comm, p0)
        dp = max(phi - plo, p.fluid_density * p.gravity * extent, 1e5)
        out = {"Tm": FieldScale(dT, 0.5 * (Tr.upper + Tr.lower)), "pm": FieldScale(dp, 0.5 * (plo + phi))}
        out["Tf"], out["pf"] = FieldScale(dT, 0.5 * (Tr.upper + Tr.lower)), FieldScale(dp, 0.5 * (plo + phi))
        strains = [max(q.rock_thermal_expansion * dT / 3, q.rock_biot_coefficient * dp / q.bulk_modulus)
                   for q in self.rocks.values()]
        strain = max(strains + [1e-6])
        out["u"] = FieldScale(strain * extent)
        return {f: out[f] for f in fields}
