"""A deck's boundary conditions by name (``-thm_bc_NAME_*``;
../shared/docs/reservoir.md section 2; manual: user guide, decks,
"Boundary conditions"): Dirichlet values and facet terms of each named
boundary.  A pressure or temperature held on a boundary that a fracture
reaches holds the fracture's pf or Tf there too."""
from __future__ import annotations

import dataclasses

import numpy as np

from petthm import params as P
from petthm.discretisation.constraints import Dirichlet
from petthm.discretisation.model import FacetTerm
from petthm.errors import InputError
from petthm.expressions import Expression
from petthm.params import CELSIUS
from petthm.physics.kernels.heatboundary import water_flux_term
from petthm.scenes.deckinput import BC_FIELD, BC_SUFFIXES, corners, insitu_tensor, vector_expressions

#: the fracture field a held pressure or temperature holds too, where a fracture reaches the boundary
FRACTURE_FIELD = {"pm": "pf", "Tm": "Tf"}
FRACTURE_HELD = ("pressure", "temperature")


class DeckBoundaries:
    """The boundary conditions of ``Reservoir`` (its ``p``, ``bc``)."""

    def boundary_conditions(self, mesh, fields) -> tuple[list, list]:
        """The Dirichlet conditions and the facet terms of the -thm_bc_NAME_*
        options; a held pressure (temperature) holds pf (Tf) too where the
        deck has it."""
        bcs, facets = [], []
        for name, values in self.bc.items():
            for suffix in BC_SUFFIXES:
                text = getattr(values, suffix)
                if not text:
                    continue
                option = f"-{P.named_option('bc', name, suffix)}"
                field = BC_FIELD[suffix]
                fracture = FRACTURE_FIELD.get(field) if suffix in FRACTURE_HELD else None
                if field not in fields and fracture not in fields:
                    raise InputError(f"option {option}: a condition on {field}, which this deck does not "
                                     f"have (its fields: {', '.join(fields)})")
                if field not in fields:
                    self.check_meets_fracture(mesh, name, option, field)
                made = self.condition(mesh, name, suffix, text, option)
                self.check_water_carries_heat(name, values, suffix, option, fields)
                if field in fields:
                    (bcs if isinstance(made, Dirichlet) else facets).append(made)
                if fracture in fields:
                    bcs.append(dataclasses.replace(made, field=fracture))
                if suffix == "flux" and "Tm" in fields and not values.temperature:
                    facets.append(self.carried_heat(mesh, name, text, option))
        return bcs, facets

    def carried_heat(self, mesh, name: str, text: str, option: str):
        """The heat of the water that a boundary's prescribed flux carries
        across it (``heatboundary.water_flux_term``)."""
        e = Expression(text, option, mesh.dim)
        return water_flux_term("Tm", self.p.fluid_rho_c, name, lambda ctx: _at_facets(e, ctx))

    def check_water_carries_heat(self, name: str, values, suffix: str, option: str, fields) -> None:
        """Water that crosses a boundary held at a pressure carries heat: a
        deck with temperatures holds that boundary's temperature too (the
        energy of water leaving at an unknown rate through a held pressure
        has no condition of its own yet)."""
        if suffix == "pressure" and not values.temperature and ("Tm" in fields or "Tf" in fields):
            raise InputError(f"option {option}: water crosses boundary {name} where its pressure is held, "
                             "and carries its heat: hold its temperature too "
                             f"(-thm_bc_{name}_temperature; the far field's, for an outflow)")

    def check_meets_fracture(self, mesh, name: str, option: str, field: str) -> None:
        """A condition held on the fractures alone needs a fracture that
        reaches the boundary (collective)."""
        from petthm.mesh.fracture import MINUS_LABEL
        on = np.intersect1d(mesh.label_points(name), mesh.label_points(None, label=MINUS_LABEL))
        if not mesh.dm.comm.tompi4py().allreduce(len(on)):
            raise InputError(f"option {option}: the deck has no {field} and no fracture reaches boundary "
                             f"{name}, so the condition holds nothing")

    def condition(self, mesh, name, suffix, text, option):
        """One boundary value: a Dirichlet condition or a facet term on boundary ``name``."""
        dim, label = mesh.dim, name
        if suffix == "displacement":
            parts = vector_expressions(text, option, dim)
            return Dirichlet("u", label, lambda x, t: np.stack([e(x) for e in parts], axis=1), steady=True)
        if suffix == "traction" or suffix == "normal_stress":
            return self.load(label, suffix, text, option, dim)
        e = Expression(text, option, dim)
        if suffix == "pressure":
            return Dirichlet("pm", label, lambda x, t: e(x), steady=True)
        if suffix == "temperature":
            return Dirichlet("Tm", label, lambda x, t: e(x) + CELSIUS, steady=True)
        if suffix == "normal_displacement":
            axis, sign = self.face_axis(mesh, label, name, option)
            return Dirichlet("u", label, lambda x, t: sign * e(x), components=(axis,), steady=True)
        kind = "pm" if suffix == "flux" else "Tm"
        return FacetTerm(kind, label, lambda ctx: _at_facets(e, ctx)[..., None])

    def load(self, label, suffix, text, option, dim):
        """A total traction (or normal stress) on a boundary: the load on u,
        the part beyond the in-situ traction -S n that the boundary already carries."""
        S = insitu_tensor(self.p, dim)
        if suffix == "traction":
            parts = vector_expressions(text, option, dim)
        else:
            sigma_n = Expression(text, option, dim)

        def f0(ctx):
            x = ctx.x.reshape(-1, dim)
            n = np.broadcast_to(ctx.n, ctx.x.shape).reshape(-1, dim)
            if suffix == "traction":
                total = np.stack([e(x) for e in parts], axis=1)
            else:
                total = -sigma_n(x)[:, None] * n
            load = total + np.einsum("nij,nj->ni", S(x), n)
            return -load.reshape(ctx.x.shape)
        return FacetTerm("u", label, f0)

    def face_axis(self, mesh, label, name, option) -> tuple[int, float]:
        """(axis, sign of the outward normal) of a plane boundary normal to an
        axis; an input error for any other (collective)."""
        cells, local, _ = mesh.boundary_facets(label)
        n = mesh.outward_normals(cells, local) if len(cells) else np.zeros((0, mesh.dim))
        lo, hi = corners(mesh.dm.comm, n, mesh.dim)
        for axis in range(mesh.dim):
            for sign in (1.0, -1.0):
                if sign * lo[axis] > 1 - 1e-9 and sign * hi[axis] > 1 - 1e-9:
                    return axis, sign
        raise InputError(f"option {option}: boundary '{name}' is not a plane normal to the x, y or z axis; "
                         f"give its displacement instead (-thm_bc_{name}_displacement)")


def _at_facets(e: Expression, ctx) -> np.ndarray:
    x = ctx.x
    return e(x.reshape(-1, x.shape[-1])).reshape(x.shape[:-1])
