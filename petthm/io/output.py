"""Run output: summary.json, history.csv and P1/P2 fields in XDMF/HDF5.

manual, user guide.  Each rank writes its own part of the fields into
``fields.h5`` (h5py, ranks in turn: ``in_turns``); ``fields.xdmf`` describes the time series
(``Triangle``/``Tetrahedron`` for P1, ``Triangle_6``/``Tetrahedron_10`` for
P2, VTK node order) so that ParaView or meshio can read it.  Values are in SI
units, temperatures in degrees Celsius.
"""
from __future__ import annotations

import contextlib
import csv
import json
import os
from collections.abc import Callable, Sequence

import numpy as np

from petthm.discretisation.fields import Discretisation, Domain, FieldSpec
from petthm.errors import InputError, WriteFailure, os_error_text
from petthm.mesh.groups import CELL_SETS, cell_tags

TOPOLOGY = {(1, 1): ("Polyline", 2), (1, 2): ("Edge_3", 3),
            (2, 1): ("Triangle", 3), (2, 2): ("Triangle_6", 6),
            (3, 1): ("Tetrahedron", 4), (3, 2): ("Tetrahedron_10", 10)}


class History:
    """history.csv: one row per accepted step, written by rank 0 as it goes
    (collective: every rank calls; a failed write is a ``WriteFailure`` on
    every rank)."""

    def __init__(self, path: str, columns: Sequence[str], comm, append: bool = False):
        self.path = path
        self.columns = list(columns)
        self.comm = comm
        self._file = None

        def start():
            keep = append and os.path.isfile(path)
            self._file = open(path, "a" if keep else "w", newline="")     # noqa: SIM115 - open for the run
            self._writer = csv.writer(self._file)
            if not keep:
                self._writer.writerow(self.columns)
            self._file.flush()
        on_root(comm, start, path)

    def write(self, row: dict) -> None:
        def append():
            self._writer.writerow([_fmt(row.get(c, "")) for c in self.columns])
            self._file.flush()
        on_root(self.comm, append, self.path)

    def close(self) -> None:
        if self._file is not None:
            with contextlib.suppress(OSError):  # the last flush on a full disk: the rows written stay
                self._file.close()
            self._file = None


def history_number(v: float) -> str:
    """A float as history.csv writes it (12 significant digits)."""
    return f"{v:.12g}"


def _fmt(v):
    return history_number(v) if isinstance(v, float) else v


def write_summary(path: str, summary: dict, comm) -> None:
    """summary.json, replaced atomically by rank 0 (collective)."""
    def write():
        with open(path + ".tmp", "w") as f:
            json.dump(summary, f, indent=2, sort_keys=False, default=float)
        os.replace(path + ".tmp", path)
    on_root(comm, write, path)


def _failure(path: str, error: BaseException) -> str:
    return f"cannot write {path}: {os_error_text(error)}"


#: what a failed write raises in h5py and the file system
WRITE_ERRORS = (OSError, RuntimeError)


def agree_on_failure(comm, message: str | None) -> None:
    """Raise ``WriteFailure`` on every rank if any rank has a ``message``
    (collective)."""
    messages = [m for m in comm.allgather(message) if m]
    if messages:
        raise WriteFailure(messages[0])


def on_root(comm, action: Callable[[], None], path: str) -> None:
    """``action()`` on rank 0, which writes ``path``; a failed write is a
    ``WriteFailure`` on every rank (collective)."""
    comm = _mpi(comm)
    message = None
    if comm.rank == 0:
        try:
            action()
        except WRITE_ERRORS as e:
            message = _failure(path, e)
    agree_on_failure(comm, message)


def in_turns(comm, write: Callable[[int], None], path: str = "") -> None:
    """Call ``write(rank)`` on one rank after the other, rank 0 first
    (collective).  h5py without MPI-IO cannot open a file on several ranks at
    once; taking turns lets each rank write its own part of one file, so
    nothing of field size is gathered on a rank (memory per rank stays that
    of its part; the writes are serial in time).  A failed write (of
    ``path``) is a ``WriteFailure`` on every rank; no rank writes after it."""
    comm = _mpi(comm)
    message = None
    for r in range(comm.size):
        if comm.rank == r and message is None:
            try:
                write(r)
            except WRITE_ERRORS as e:
                message = _failure(path, e)
        message = comm.bcast(message, root=r)     # the next turn starts after this one's write
    if message:
        raise WriteFailure(message)


def check_space(comm, path: str, nbytes: int) -> None:
    """A ``WriteFailure`` on every rank if the file system of ``path`` has
    less free space than the ``nbytes`` the ranks are about to write there
    (their sum, with a margin for HDF5's metadata): a write is refused
    before it can leave a half-written file (collective)."""
    comm = _mpi(comm)
    total = comm.allreduce(int(nbytes))
    message = None
    if comm.rank == 0:
        try:
            st = os.statvfs(os.path.dirname(os.path.abspath(path)))
            free = st.f_bavail * st.f_frsize
        except OSError:
            free = None
        need = int(1.1 * total) + SPACE_MARGIN
        if free is not None and free < need:
            message = (f"cannot write {path}: No space left on device ({free} bytes free, "
                       f"{need} needed)")
    agree_on_failure(comm, message)


#: the free space kept beyond an output's own size (bytes): HDF5's metadata, the XDMF (256 KiB)
SPACE_MARGIN = 1 << 18


def _mpi(comm):
    """An mpi4py communicator of ``comm`` (a petsc4py or mpi4py one)."""
    return comm.tompi4py() if hasattr(comm, "tompi4py") else comm


class FieldWriter:
    """Time series of nodal fields on the matrix mesh, or (``Domain.FRACTURE``)
    on the fracture surface (the - faces), one degree for all.

    ``STEM.h5`` holds the mesh (``mesh/topology``: the node numbers of every
    cell, ``mesh/geometry``, ``mesh/partition``: the rank that wrote each
    cell, and on the matrix of a mesh with cell groups ``mesh/region``: the
    gmsh physical tag of each cell's region, -1 for none) and
    ``fields/NAME/K`` for output K, numbered as the distributed mesh numbers
    its nodes: each rank writes the rows of the nodes it owns (a contiguous
    range) and of its cells, ranks in turn (``in_turns``).
    A restart whose partition differs writes its mesh anew (``mesh_1``, ...);
    the attribute ``meshes`` names each output's mesh group, and
    ``read_output`` reads an output with its mesh."""

    def __init__(self, disc: Discretisation, directory: str, degree: int, stem: str = "fields",
                 region: Domain = Domain.MATRIX, resume_at: float | None = None):
        mesh = disc.mesh
        self.comm = mesh.dm.comm.tompi4py()
        self.rank = self.comm.rank
        self.dim = mesh.dim
        self.rdim = mesh.dim if region is Domain.MATRIX else mesh.dim - 1
        self.degree = degree
        self.h5path = os.path.join(directory, stem + ".h5")
        self.xdmfpath = os.path.join(directory, stem + ".xdmf")
        self.h5name = stem + ".h5"
        #: per output: (time, [(field, ncomp)], mesh group, cells, nodes)
        self._steps: list[tuple[float, list[tuple[str, int]], str, int, int]] = []
        #: the mesh groups that hold the cells' regions
        self._region_groups: set[str] = set()
        dmo = mesh.dm.clone()
        regions = {} if region is Domain.MATRIX else {region: disc.regions[region]}
        nodes = Discretisation(mesh, [FieldSpec("node", 1, degree, region)], dm=dmo, regions=regions)
        mesh_parts = self._number_nodes(nodes)
        if region is Domain.MATRIX and mesh.dm.hasLabel(CELL_SETS):
            mesh_parts["region"] = (cell_tags(mesh), (self.ncells,), self.cell_range, np.int32)
        dmo.destroy()
        resume = resume_at is not None and os.path.isfile(self.h5path)
        self.group, new_mesh = self._resume(resume_at, mesh_parts) if resume else ("mesh", True)
        if new_mesh:
            self._write_parts({f"{self.group}/{k}": v for k, v in mesh_parts.items()},
                              mode="a" if resume else "w")
            if "region" in mesh_parts:
                self._region_groups.add(self.group)

    def _number_nodes(self, nodes: Discretisation) -> dict:
        """This rank's rows of the mesh datasets; sets the node and cell ranges."""
        gid = nodes.global_index
        local_gid = gid[nodes.field_local_dofs("node")[:, 0]]
        owned = nodes._owned(local_gid)
        self._rows = np.flatnonzero(owned)[np.argsort(local_gid[owned])]   # local nodes by row
        self.node_range = nodes.ownership_range()
        if len(self._rows) != self.node_range[1] - self.node_range[0]:
            raise RuntimeError("output nodes owned by a rank are not its ownership range")
        conn = gid[nodes.elem_dofs["node"]].astype(np.int64)
        first = self.comm.exscan(len(conn)) or 0
        self.cell_range = (first, first + len(conn))
        self.ncells = self.comm.allreduce(len(conn))
        self.nnodes = self.comm.allreduce(len(self._rows))
        npc = self.comm.allreduce(conn.shape[1] if len(conn) else 0, op=_max())
        coords = nodes.field_node_coordinates("node")[self._rows]
        return {"topology": (conn, (self.ncells, npc), self.cell_range, np.int64),
                "geometry": (coords, (self.nnodes, self.dim), self.node_range, float),
                "partition": (np.full(len(conn), self.rank, dtype=np.int32), (self.ncells,),
                              self.cell_range, np.int32)}

    def _write_parts(self, parts: dict, mode: str = "a", attrs: dict | None = None) -> None:
        """Datasets NAME: (this rank's rows, global shape, (first, end) row, dtype):
        rank 0 creates them (``mode`` "w": a new file), then every rank
        writes its rows (collective)."""
        import h5py

        def write(rank):
            with h5py.File(self.h5path, mode if rank == 0 else "a") as h5:
                for name, (rows, shape, (lo, hi), dtype) in parts.items():
                    if rank == 0:
                        h5.create_dataset(name, shape=shape, dtype=dtype)
                    if hi > lo:
                        h5[name][lo:hi] = rows
                if rank == 0 and attrs:
                    for k, v in attrs.items():
                        h5.attrs[k] = v
        check_space(self.comm, self.h5path, sum(np.asarray(p[0]).nbytes for p in parts.values()))
        in_turns(self.comm, write, self.h5path)

    def _resume(self, t: float, mesh_parts: dict) -> tuple[str, bool]:
        """Go on with the series of an earlier run (restart): keep its outputs
        up to time t, drop the later ones.  Returns the mesh group to go on
        with, and whether it is new: the last one if it holds this run's mesh
        (same partition), else a new name (collective)."""
        message = None
        if self.rank == 0:
            try:
                last, taken = self._keep_outputs_to(t)
            except (OSError, KeyError, ValueError, RuntimeError, TypeError) as e:
                message = unreadable(self.h5path, e)
        message = self.comm.bcast(message, root=0)
        if message:
            raise InputError(message)
        self._steps, last, taken, self._region_groups = self.comm.bcast(
            (self._steps, last, taken, self._region_groups) if self.rank == 0 else None, root=0)
        if self._same_mesh(last, mesh_parts):
            return last, False
        return next(f"mesh_{i}" for i in range(1, len(taken) + 2) if f"mesh_{i}" not in taken), True

    def _keep_outputs_to(self, t: float) -> tuple[str, list[str]]:
        """Drop the outputs after time t from the file (rank 0); returns the
        last mesh group kept and the mesh groups in the file."""
        import h5py
        with h5py.File(self.h5path, "r+") as h5:
            if "times" not in h5.attrs:
                raise KeyError("it holds no output series")
            times = list(h5.attrs["times"])
            keep = sum(1 for s in times if s <= t * (1 + 1e-12) + 1e-300)
            groups = [str(g) for g in h5.attrs.get("meshes", ["mesh"] * len(times))][:keep]
            for name in list(h5.get("fields", {})):
                for k in list(h5["fields"][name]):
                    if int(k) >= keep:
                        del h5["fields"][name][k]
            h5.attrs["times"], h5.attrs["meshes"] = times[:keep], groups
            for k, s in enumerate(times[:keep]):
                data = [(name, h5["fields"][name][str(k)]) for name in h5.get("fields", {})
                        if str(k) in h5["fields"][name]]
                cells, nodes = (h5[f"{groups[k]}/{d}"].shape[0] for d in ("topology", "geometry"))
                self._steps.append((s, [(name, 1 if d.ndim == 1 else d.shape[1]) for name, d in data],
                                    groups[k], cells, nodes))
            last = groups[-1] if groups else "mesh"
            taken = sorted(g for g in h5 if g.startswith("mesh"))
            self._region_groups = {g for g in taken if "region" in h5[g]}
        return last, taken

    def _same_mesh(self, group: str, mesh_parts: dict) -> bool:
        """Whether group holds this run's mesh: each rank compares its own rows
        (collective)."""
        import h5py
        same, message = True, None
        try:
            with h5py.File(self.h5path, "r") as h5:
                for name in ("topology", "geometry"):
                    rows, shape, (lo, hi), _ = mesh_parts[name]
                    d = h5.get(f"{group}/{name}")
                    same &= d is not None and d.shape == shape and np.array_equal(d[lo:hi], rows)
        except (OSError, KeyError, ValueError, RuntimeError) as e:
            message = unreadable(self.h5path, e)
        messages = [m for m in self.comm.allgather(message) if m]
        if messages:
            raise InputError(messages[0])
        return bool(self.comm.allreduce(int(same), op=_min()))

    def write(self, t: float, fields: dict[str, np.ndarray]) -> None:
        """Write nodal arrays (local nodes of this writer's degree, SI) at time t
        (collective: every rank passes the same names)."""
        k = len(self._steps)
        parts, entries = {}, []
        for name, values in fields.items():
            arr = np.asarray(values, dtype=float)
            ncomp = self.comm.allreduce(arr.size // len(arr) if len(arr) else 0, op=_max())
            arr = arr.reshape(len(arr), ncomp)[self._rows]
            if ncomp == 2:                                   # XDMF vectors have 3 components
                arr, ncomp = np.column_stack([arr, np.zeros(len(arr))]), 3
            shape = (self.nnodes,) if ncomp == 1 else (self.nnodes, ncomp)
            rows = arr.reshape((len(arr),) + shape[1:])
            parts[f"fields/{name}/{k}"] = (rows, shape, self.node_range, float)
            entries.append((name, ncomp))
        self._steps.append((t, entries, self.group, self.ncells, self.nnodes))
        self._write_parts(parts, attrs={"times": [s[0] for s in self._steps],
                                        "meshes": [s[2] for s in self._steps]})
        on_root(self.comm, self._write_xdmf, self.xdmfpath)

    def _write_xdmf(self) -> None:
        topo, npc = TOPOLOGY[(self.rdim, self.degree)]
        per = f' NodesPerElement="{npc}"' if topo == "Polyline" else ""
        geo = "XY" if self.dim == 2 else "XYZ"
        out = ['<?xml version="1.0" ?>', '<Xdmf Version="3.0">', "<Domain>",
               '<Grid Name="TimeSeries" GridType="Collection" CollectionType="Temporal">']
        for k, (t, entries, group, ncells, nnodes) in enumerate(self._steps):
            out += [f'<Grid Name="step{k}" GridType="Uniform">', f'<Time Value="{t!r}"/>',
                    f'<Topology TopologyType="{topo}" NumberOfElements="{ncells}"{per}>',
                    f'<DataItem Dimensions="{ncells} {npc}" NumberType="Int" Precision="8" '
                    f'Format="HDF">{self.h5name}:/{group}/topology</DataItem>', "</Topology>",
                    f'<Geometry GeometryType="{geo}">',
                    f'<DataItem Dimensions="{nnodes} {self.dim}" Format="HDF">'
                    f'{self.h5name}:/{group}/geometry</DataItem>', "</Geometry>"]
            if group in self._region_groups:
                out += ['<Attribute Name="region" AttributeType="Scalar" Center="Cell">',
                        f'<DataItem Dimensions="{ncells}" NumberType="Int" Format="HDF">'
                        f'{self.h5name}:/{group}/region</DataItem>', "</Attribute>"]
            for name, ncomp in entries:
                kind = "Scalar" if ncomp == 1 else "Vector"
                dims = f"{nnodes}" if ncomp == 1 else f"{nnodes} {ncomp}"
                out += [f'<Attribute Name="{name}" AttributeType="{kind}" Center="Node">',
                        f'<DataItem Dimensions="{dims}" Format="HDF">{self.h5name}:/fields/{name}/{k}'
                        "</DataItem>", "</Attribute>"]
            out.append("</Grid>")
        out += ["</Grid>", "</Domain>", "</Xdmf>"]
        with open(self.xdmfpath + ".tmp", "w") as f:
            f.write("\n".join(out) + "\n")
        os.replace(self.xdmfpath + ".tmp", self.xdmfpath)


def read_cell_regions(path: str, step: int = -1) -> np.ndarray:
    """The region tag of each cell of output ``step``'s mesh (``FieldWriter``:
    ``mesh/region``), in the order of its topology."""
    import h5py
    h5path = path if path.endswith(".h5") else os.path.join(path, "fields.h5")
    with h5py.File(h5path, "r") as h5:
        groups = [str(g) for g in h5.attrs.get("meshes", ["mesh"] * len(h5.attrs["times"]))]
        return h5[f"{groups[step]}/region"][()]


def read_output(path: str, step: int = -1) -> tuple[np.ndarray, np.ndarray, float, dict]:
    """(geometry, topology, time, {field: values}) of output ``step`` of a
    run's ``fields`` / ``fracture`` series (its own mesh group, after a
    restart too); ``path``: the series' ``.h5`` or its ``.xdmf``.  A file
    that is not such a series is a ``ValueError`` naming it."""
    import h5py
    h5path = os.path.splitext(path)[0] + ".h5" if path.endswith(".xdmf") else path
    try:
        with h5py.File(h5path, "r") as h5:
            times = list(h5.attrs["times"])
            if not -len(times) <= step < len(times):
                raise IndexError(f"{h5path} has outputs 0 to {len(times) - 1}, not {step}")
            k = range(len(times))[step]
            group = str(list(h5.attrs.get("meshes", ["mesh"] * len(times)))[k])
            fields = {name: h5["fields"][name][str(k)][()] for name in h5.get("fields", {})
                      if str(k) in h5["fields"][name]}
            return h5[f"{group}/geometry"][()], h5[f"{group}/topology"][()], float(times[k]), fields
    except (OSError, KeyError) as e:
        raise ValueError(f"{h5path} is not a readable petthm field series ({os_error_text(e)})") from None


def unreadable(path: str, error: BaseException) -> str:
    """The one-line error for an output file of an earlier run that cannot be read."""
    return (f"{path} cannot be read ({os_error_text(error)}): the file is truncated or damaged; "
            "restore it, or start a new run (another -thm_output_dir, or -thm_overwrite)")


def _max():
    from mpi4py import MPI
    return MPI.MAX


def _min():
    from mpi4py import MPI
    return MPI.MIN


__all__ = ["History", "FieldWriter", "in_turns", "read_output", "write_summary"]
