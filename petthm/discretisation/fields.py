"""Fields -> PetscSection, element->dof index arrays and Dirichlet dofs.

Each field is continuous Lagrange P1 (dofs on vertices) or P2 (vertices and
edges) with ``ncomp`` components.  The section is made by DMPlexCreateSection
with the Dirichlet points constrained, so the global vector holds only the
unknowns; constrained values live in the local vector and are written there
before every residual or Jacobian evaluation.  The element->dof arrays index
the local vector and are built once, in the node order of ``fe.tabulate``.
"""
from __future__ import annotations

import enum
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from petsc4py import PETSc

from petthm import compat
from petthm.mesh.fracture import Side
from petthm.mesh.plex import Mesh
from petthm.mesh.topology import simplex_stratum


def same_points(ref: np.ndarray, query: np.ndarray, tol: float) -> np.ndarray:
    """The row of ``ref`` at each row of ``query``'s coordinates (-1 where
    none lies within ``tol``).  The copies of a split node have the same
    coordinates bit for bit, so an exact match (a sort) finds them; only rows
    left over go to a k-d tree (scipy's import costs a small run 0.09 s)."""
    def key(X):
        X = np.ascontiguousarray(X, dtype=float) + 0.0          # -0.0 -> 0.0
        return X.view(np.dtype((np.void, X.itemsize * X.shape[1]))).ravel()
    kr, kq = key(ref), key(query)
    order = np.argsort(kr, kind="stable")
    ks = kr[order]
    pos = np.minimum(np.searchsorted(ks, kq), max(len(kr) - 1, 0))
    idx = np.where(ks[pos] == kq, order[pos], -1) if len(kr) else np.full(len(kq), -1)
    left = idx < 0
    if left.any() and len(kr):
        from scipy.spatial import cKDTree
        dist, near = cKDTree(ref).query(query[left])
        idx[left] = np.where(dist <= tol, near, -1)
    return idx


class Domain(enum.Enum):
    """Where a field lives and a term is integrated."""
    MATRIX = "matrix"            # the cells of the (split) mesh
    FRACTURE = "fracture"        # the - faces of the cohesive cells

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class Trace:
    """A matrix field seen on one face of the fracture (its nodes in the - face's order)."""
    field: str
    side: Side

    def __str__(self) -> str:
        return self.field + self.side.value


def traces(name: str) -> tuple[Trace, Trace]:
    """The traces of a matrix field on the - and the + face."""
    return Trace(name, Side.MINUS), Trace(name, Side.PLUS)


@dataclass(frozen=True)
class Adjacent:
    """A matrix field in the rock cell next to each fracture face on one
    side, seen at the fracture's quadrature points (its gradient there: the
    wall conduction of the fracture heat's SUPG residual, kernels/wallflux.py)."""
    field: str
    side: Side

    def __str__(self) -> str:
        return self.field + self.side.value + "(cell)"


#: a field name, the trace of a matrix field on a fracture face, or a matrix
#: field in the rock cell next to a fracture face
FieldRef = str | Trace | Adjacent


def base_field(ref: FieldRef) -> str:
    """The field of a field reference."""
    return ref.field if isinstance(ref, (Trace, Adjacent)) else ref


@dataclass(frozen=True)
class FieldSpec:
    """A primary field: name (also the fieldsplit prefix and output name),
    number of components and Lagrange degree; its SI ``unit`` and the unit
    its outputs are written in: output = SI value + ``output_offset``
    (temperatures: kelvin inside, degrees Celsius out)."""
    name: str
    ncomp: int = 1
    degree: int = 2
    region: Domain = Domain.MATRIX
    unit: str = ""
    output_unit: str = ""
    output_offset: float = 0.0

    def output(self, values):
        """SI values in the field's output unit."""
        return values + self.output_offset if self.output_offset else values


@dataclass
class DirichletDofs:
    """Local dof indices of one field on one boundary part and their node coordinates."""
    field: str
    boundary: str
    dofs: np.ndarray        # (n, ncomp) local dof indices
    coords: np.ndarray      # (n, dim)
    source: str = ""        # tied dofs: the fracture field whose Dirichlet data they take
    components: tuple | None = None   # constrained components (None: all)


def boundary_entry(entry) -> tuple[str, tuple | None]:
    """A Dirichlet entry of ``Discretisation``: a boundary name, or (name, components)."""
    if isinstance(entry, str):
        return entry, None
    name, comps = entry
    return name, (None if comps is None else tuple(int(c) for c in comps))


@dataclass
class Tie:
    """Matrix-field dofs on the fracture faces that are the fracture field's
    unknowns (pressure or temperature continuity imposed strongly, see
    manual, verification: fracture flow and heat): local dofs of ``field`` and the global index of
    ``target``'s dof at the same node."""
    field: str
    target: str
    dofs: np.ndarray         # (n,) local dof indices of field (constrained in the section)
    target_global: np.ndarray  # (n,) global indices of target's unknowns


class Discretisation:
    """The PetscSection of a set of fields on a mesh and its index arrays."""

    def __init__(self, mesh: Mesh, fields: Sequence[FieldSpec],
                 dirichlet: dict[str, Sequence[str]] | None = None, dm: PETSc.DM | None = None,
                 regions: dict | None = None, ties: dict[str, str] | None = None):
        """``ties``: {matrix field: fracture field}, e.g. {"pm": "pf"}: the
        matrix field's nodes on both fracture faces are the fracture field's
        nodes (strong continuity across the wall)."""
        self.mesh = mesh
        self.ties_spec = dict(ties or {})
        self.dm = dm or mesh.dm
        self.fields = list(fields)
        self.index = {f.name: i for i, f in enumerate(self.fields)}
        self.regions = dict(regions or {})
        self.regions[Domain.MATRIX] = mesh
        dirichlet = dirichlet or {}
        dm = self.dm
        self.depths = {f.name: (0, 1) if f.degree == 2 else (0,) for f in self.fields}
        self.support = {f.name: self._support_points(f) for f in self.fields}
        dirichlet = {k: [boundary_entry(e) for e in v] for k, v in dirichlet.items()}
        pstart, pend = dm.getChart()
        bc_mask = {f.name: self._bc_mask(dirichlet.get(f.name, ()), f, pstart, pend) for f in self.fields}
        self.tied_points = {f: self._tied_points(f) for f in self.ties_spec}
        for f, pts in self.tied_points.items():
            bc_mask[f][pts - pstart] = True
        self.section = self._create_section(bc_mask, pstart)
        compat.set_local_section(dm, self.section)
        self.nlocal = self.section.getStorageSize()
        self.offsets = self._point_offsets()
        self.elem_dofs = {f.name: self._element_dofs(f) for f in self.fields}
        self.dirichlet = [self._dirichlet(f, b, c) for f in self.fields for b, c in dirichlet.get(f.name, ())]
        self.global_index = compat.lgmap_indices(dm)
        if self.global_index.size != self.nlocal:
            raise RuntimeError("local-to-global map does not match the local section")
        self._trace_cache = {}
        self._node_coordinates: dict[str, np.ndarray] = {}     # field_node_coordinates, per field
        self.ties = []
        for f, g in self.ties_spec.items():
            self._tie(f, g, [b for b, _ in dirichlet.get(g, ())])

    # -- ties (strong continuity of a matrix field with a fracture field) --------
    def _tied_points(self, f: str) -> np.ndarray:
        from petthm.mesh.fracture import MINUS_LABEL, PLUS_LABEL
        g = self.ties_spec[f]
        if self.field(f).region is not Domain.MATRIX or self.field(g).region is not Domain.FRACTURE or \
                self.field(f).degree != self.field(g).degree or self.field(f).ncomp != 1:
            raise ValueError(f"cannot tie {f} to {g}: need a scalar matrix field and a "
                             "fracture field of the same degree")
        on = np.union1d(self.mesh.label_points(None, label=MINUS_LABEL),
                        self.mesh.label_points(None, label=PLUS_LABEL))
        return np.intersect1d(self.support[f], on).astype(compat.INT)

    def _tie(self, f: str, g: str, g_boundaries) -> None:
        """Find, for every tied node of ``f``, the global unknown of ``g`` at the
        same coordinates (the - copy of the node; on any rank), or the Dirichlet
        boundary of ``g`` that constrains it."""
        pts = self.tied_points[f]
        coords = self.mesh.point_coordinates(pts)
        dofs = self.offsets[f][pts - self.pstart]
        constrained = np.zeros(len(pts), dtype=bool)
        for b in g_boundaries:
            on_b = np.isin(pts, self.mesh.label_points(b))
            if on_b.any():
                self.dirichlet.append(DirichletDofs(f, b, dofs[on_b][:, None], coords[on_b], source=g))
            constrained |= on_b
        gp = self.support[g]
        gg = self.global_index[self.offsets[g][gp - self.pstart]]
        lo, hi = self.ownership_range()
        own = (gg >= lo) & (gg < hi)
        comm = self.mesh.dm.comm.tompi4py()
        allc = np.concatenate(
            comm.allgather(self.mesh.point_coordinates(gp[own])) or [np.zeros((0, self.mesh.dim))])
        allg = np.concatenate(comm.allgather(gg[own]))
        free = ~constrained
        target = np.full(len(pts), -1, dtype=compat.INT)
        if free.any():
            if not len(allc):
                raise RuntimeError(f"no {g} unknowns to tie {f} to")
            h = float(self.mesh.h.max()) if self.mesh.ncells else 1.0
            idx = same_points(allc, coords[free], 1e-8 * h)
            if np.any(idx < 0):
                raise RuntimeError(f"a tied {f} node has no {g} node at its position")
            target[free] = allg[idx]
        self.ties.append(Tie(f, g, dofs[free], target[free]))
        self.global_index[dofs[free]] = target[free]

    # -- section --------------------------------------------------------------
    def _support_points(self, f: FieldSpec) -> np.ndarray:
        """Sorted points that carry the field's nodes: vertices and (P2) simplex
        edges of the mesh, or, for a fracture field, of the closure of the - faces
        (label ``fracture.MINUS_LABEL``, made before distribution so that
        ranks agree on shared points)."""
        pts = np.concatenate([np.arange(*simplex_stratum(self.dm, d)) for d in self.depths[f.name]])
        if f.region is Domain.FRACTURE:
            from petthm.mesh.fracture import MINUS_LABEL
            on = self.mesh.label_points(None, label=MINUS_LABEL)
            pts = np.intersect1d(pts, on)
        return pts.astype(compat.INT)

    def _bc_mask(self, entries, f: FieldSpec, pstart: int, pend: int) -> np.ndarray:
        """(points, ncomp) mask of the constrained components of ``f``."""
        mask = np.zeros((pend - pstart, f.ncomp), dtype=bool)
        for b, comps in entries:
            pts = np.concatenate([self.mesh.label_points(b, d) for d in self.depths[f.name]])
            pts = np.intersect1d(pts, self.support[f.name]).astype(compat.INT)
            mask[np.ix_(pts - pstart, np.arange(f.ncomp) if comps is None else np.asarray(comps))] = True
        return mask

    def _create_section(self, bc_mask, pstart) -> PETSc.Section:
        dim = self.mesh.dim
        num_comp = [f.ncomp for f in self.fields]
        num_dof = np.zeros((len(self.fields), dim + 1), dtype=compat.INT)
        for i, f in enumerate(self.fields):
            for d in self.depths[f.name]:
                num_dof[i, d] = f.ncomp
        bc_field, bc_comps, bc_is = [], [], []
        for i, f in enumerate(self.fields):        # one entry per distinct set of constrained components
            mask = bc_mask[f.name]
            on = np.flatnonzero(mask.any(axis=1))
            if not on.size:
                continue
            patterns, which = np.unique(mask[on], axis=0, return_inverse=True)
            for k, pat in enumerate(patterns):
                bc_field.append(i)
                bc_comps.append(PETSc.IS().createGeneral(np.flatnonzero(pat).astype(compat.INT),
                                                         comm=PETSc.COMM_SELF))
                bc_is.append(PETSc.IS().createGeneral((on[which.ravel() == k] + pstart).astype(compat.INT),
                                                      comm=PETSc.COMM_SELF))
        self.dm.setNumFields(len(self.fields))
        labels = self._support_labels()
        sec = compat.create_section(self.dm, labels, num_comp, num_dof.ravel(),
                                    bc_field, bc_comps, bc_is)
        for lab in labels:
            if lab is not None:
                lab.destroy()
        for i, f in enumerate(self.fields):
            sec.setFieldName(i, f.name)
        return sec

    def _support_labels(self) -> list:
        """Per field None (all vertices/edges of a purely simplicial mesh) or a
        label (value 1) on its support points, so that no dofs go onto the
        prism-tensor edges of cohesive cells or off a fracture."""
        hybrid = simplex_stratum(self.dm, 1)[1] != self.dm.getDepthStratum(1)[1]
        if not hybrid and all(f.region is Domain.MATRIX for f in self.fields):
            return [None] * len(self.fields)
        labels = []
        for f in self.fields:
            label = PETSc.DMLabel().create(f"thm_support_{f.name}")
            if self.support[f.name].size:
                label.setStratumIS(1, PETSc.IS().createGeneral(self.support[f.name], comm=PETSc.COMM_SELF))
            labels.append(label)
        return labels

    def _point_offsets(self) -> dict[str, np.ndarray]:
        """Local offset of each field's first dof at each vertex/edge point.

        Computed in numpy from the dof layout (points in chart order, fields
        interleaved per point, as PetscSectionSetUp lays them out) and checked
        against the section at a sample of points.
        """
        pstart, pend = self.dm.getChart()
        ndof = np.zeros(pend - pstart, dtype=np.int64)
        fstart = {}
        for f in self.fields:
            fdof = np.zeros(pend - pstart, dtype=np.int64)
            fdof[self.support[f.name] - pstart] = f.ncomp
            fstart[f.name] = ndof.copy()
            ndof += fdof
        start = np.concatenate([[0], np.cumsum(ndof)[:-1]])
        offsets = {f.name: (start + fstart[f.name]).astype(compat.INT) for f in self.fields}
        sample = np.unique(np.linspace(pstart, pend - 1, min(64, pend - pstart)).astype(int))
        for i, f in enumerate(self.fields):
            for p in sample:
                if self.section.getFieldDof(int(p), i) and \
                        self.section.getFieldOffset(int(p), i) != offsets[f.name][p - pstart]:
                    raise RuntimeError("unexpected PetscSection layout (a permutation is set?)")
        self.pstart = pstart
        return offsets

    def _element_dofs(self, f: FieldSpec) -> np.ndarray:
        m = self.regions.get(f.region)
        if m is None:
            return np.zeros((0, 0), dtype=compat.INT)
        points = m.cell_vertices + m.vstart
        if f.degree == 2:
            points = np.hstack([points, m.cell_edges])
        base = self.offsets[f.name][points - self.pstart]                # (nc, nb)
        return (base[:, :,
                     None] + np.arange(f.ncomp)).reshape(len(base),
                                                         base.shape[1] * f.ncomp).astype(compat.INT)

    def _dirichlet(self, f: FieldSpec, boundary: str, comps=None) -> DirichletDofs:
        pts = np.concatenate([self.mesh.label_points(boundary, d) for d in self.depths[f.name]])
        pts = np.intersect1d(pts, self.support[f.name])
        base = self.offsets[f.name][pts - self.pstart]
        cols = np.arange(f.ncomp) if comps is None else np.asarray(comps)
        return DirichletDofs(f.name, boundary, base[:, None] + cols, self.mesh.point_coordinates(pts),
                             components=comps)

    # -- element dofs per region (traces of matrix fields on the fracture) ------
    def region_dofs(self, region: Domain, name: FieldRef) -> np.ndarray:
        """Element dofs of a field on a domain's elements: the field's own
        elements, or on the fracture a ``Trace`` of a matrix field on the -
        face or on the paired + face, nodes in the - face's order, or an
        ``Adjacent`` matrix field: the dofs of the rock cell next to each face."""
        if isinstance(name, Adjacent):
            return self.elem_dofs[name.field][self.regions[region].adjacent_cells(name.side)]
        if not isinstance(name, Trace):
            if region is not self.field(name).region:
                raise ValueError(f"field {name} does not live on the {region} (use a Trace)")
            return self.elem_dofs[name]
        key = (region, name)
        if key not in self._trace_cache:
            base = name.field
            surf = self.regions[region]
            f = self.field(base)
            verts, edges = (surf.cell_vertices, surf.cell_edges) if name.side is Side.MINUS else \
                (surf.plus_vertices, surf.plus_edges)
            points = verts + surf.vstart
            if f.degree == 2:
                points = np.hstack([points, edges])
            base_off = self.offsets[base][points - self.pstart]
            self._trace_cache[key] = (base_off[:, :, None] + np.arange(f.ncomp)).reshape(
                len(base_off), base_off.shape[1] * f.ncomp).astype(compat.INT)
        return self._trace_cache[key]

    # -- helpers ----------------------------------------------------------------
    def field(self, name: FieldRef) -> FieldSpec:
        """The FieldSpec of a field, or of the matrix field of a ``Trace``."""
        return self.fields[self.index[base_field(name)]]

    def node_points(self, name: str) -> np.ndarray:
        """The mesh points carrying the field's nodes: vertices (+ simplex edges for P2)."""
        return self.support[name]

    def field_local_dofs(self, name: str) -> np.ndarray:
        """All local dof indices of a field (vertex and edge points), (n, ncomp)."""
        f = self.field(name)
        return self.offsets[name][self.node_points(name) - self.pstart][:, None] + np.arange(f.ncomp)

    def field_node_coordinates(self, name: str) -> np.ndarray:
        """Coordinates of the field's nodes (n, dim), computed once per field
        (read-only: monitors ask for them at every step)."""
        if name not in self._node_coordinates:
            x = self.mesh.point_coordinates(self.node_points(name))
            x.flags.writeable = False
            self._node_coordinates[name] = x
        return self._node_coordinates[name]

    def global_sizes(self) -> dict[str, int]:
        """Number of unknowns per field (global, constrained dofs excluded)."""
        out = {}
        tied = np.concatenate([t.dofs for t in self.ties]) if self.ties else np.zeros(0, dtype=int)
        for _i, f in enumerate(self.fields):
            dofs = np.setdiff1d(self.field_local_dofs(f.name).ravel(), tied)
            g = self.global_index[dofs]
            out[f.name] = self.mesh.dm.comm.tompi4py().allreduce(int(self._owned(g).sum()))
        return out

    def _owned(self, g: np.ndarray) -> np.ndarray:
        lo, hi = self.ownership_range()
        return (g >= lo) & (g < hi)

    def ownership_range(self) -> tuple[int, int]:
        v = self.dm.getGlobalVec()
        r = v.getOwnershipRange()
        self.dm.restoreGlobalVec(v)
        return r
