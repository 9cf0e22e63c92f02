"""Run output: summary.json, history.csv and P1/P2 fields in XDMF/HDF5.

physics.md section 12.  Fields are gathered to rank 0 and written with h5py
into ``fields.h5``; ``fields.xdmf`` describes the time series
(``Triangle``/``Tetrahedron`` for P1, ``Triangle_6``/``Tetrahedron_10`` for
P2, VTK node order) so that ParaView or meshio can read it.  Values are in SI
units, temperatures in degrees Celsius.
"""
from __future__ import annotations

import csv
import json
import os
from typing import Sequence

import numpy as np

from .fields import Discretisation, Domain, FieldSpec

TOPOLOGY = {(1, 1): ("Polyline", 2), (1, 2): ("Edge_3", 3),
            (2, 1): ("Triangle", 3), (2, 2): ("Triangle_6", 6),
            (3, 1): ("Tetrahedron", 4), (3, 2): ("Tetrahedron_10", 10)}


class History:
    """history.csv: one row per accepted step, written by rank 0 as it goes."""

    def __init__(self, path: str, columns: Sequence[str], rank: int, append: bool = False):
        self.columns = list(columns)
        self._file = None
        if rank == 0:
            append = append and os.path.isfile(path)
            self._file = open(path, "a" if append else "w", newline="")
            self._writer = csv.writer(self._file)
            if not append:
                self._writer.writerow(self.columns)
            self._file.flush()

    def write(self, row: dict) -> None:
        if self._file is None:
            return
        self._writer.writerow([_fmt(row.get(c, "")) for c in self.columns])
        self._file.flush()

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None


def _fmt(v):
    return f"{v:.12g}" if isinstance(v, float) else v


def write_summary(path: str, summary: dict, rank: int) -> None:
    if rank == 0:
        with open(path + ".tmp", "w") as f:
            json.dump(summary, f, indent=2, sort_keys=False, default=float)
        os.replace(path + ".tmp", path)


class FieldWriter:
    """Time series of nodal fields on the matrix mesh, or (``Domain.FRACTURE``)
    on the fracture surface (the - faces), one degree for all."""

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
        dmo = mesh.dm.clone()
        regions = {} if region is Domain.MATRIX else {region: disc.regions[region]}
        nodes = Discretisation(mesh, [FieldSpec("node", 1, degree, region)], dm=dmo, regions=regions)
        gid = nodes.global_index
        self.local_gid = gid[nodes.field_local_dofs("node")[:, 0]]
        conn = gid[nodes.elem_dofs["node"]]
        coords = nodes.field_node_coordinates("node")
        self.nnodes = self.comm.allreduce(int(nodes._owned(gid).sum()))
        self._nodes_disc = nodes
        self._steps: list[tuple[float, list[tuple[str, int]]]] = []
        conn_all = self.comm.gather(conn, root=0)
        xyz = self._gather_nodal(coords)
        if self.rank == 0:
            import h5py
            os.makedirs(directory, exist_ok=True)
            self.ncells = sum(len(c) for c in conn_all)
            if resume_at is not None and os.path.isfile(self.h5path):
                self._resume(resume_at)
            else:
                with h5py.File(self.h5path, "w") as h5:
                    h5["mesh/topology"] = np.concatenate(conn_all).astype(np.int64)
                    h5["mesh/geometry"] = xyz
        dmo.destroy()

    def _resume(self, t: float) -> None:
        """Go on with the series of an earlier run (restart): keep its steps
        up to time t, drop the later ones (rank 0)."""
        import h5py
        with h5py.File(self.h5path, "a") as h5:
            times = list(h5.attrs.get("times", []))
            keep = sum(1 for s in times if s <= t * (1 + 1e-12) + 1e-300)
            for name in list(h5.get("fields", {})):
                for k in list(h5["fields"][name]):
                    if int(k) >= keep:
                        del h5["fields"][name][k]
            h5.attrs["times"] = times[:keep]
            for k, s in enumerate(times[:keep]):
                data = [(name, h5["fields"][name][str(k)]) for name in h5.get("fields", {})
                        if str(k) in h5["fields"][name]]
                entries = [(name, 1 if d.ndim == 1 else d.shape[1]) for name, d in data]
                self._steps.append((s, entries))

    def _gather_nodal(self, values: np.ndarray) -> np.ndarray | None:
        parts = self.comm.gather((self.local_gid, np.asarray(values)), root=0)
        if self.rank != 0:
            return None
        filled = [(g, v) for g, v in parts if len(g)]         # ranks without nodes send nothing
        ncomp = filled[0][1].reshape(len(filled[0][0]), -1).shape[1] if filled else 1
        out = np.zeros((self.nnodes, ncomp))
        for g, v in filled:
            out[g] = v.reshape(len(g), ncomp)
        return out[:, 0] if ncomp == 1 else out

    def write(self, t: float, fields: dict[str, np.ndarray]) -> None:
        """Write nodal arrays (local nodes of this writer's degree, SI) at time t."""
        k = len(self._steps)
        entries = []
        gathered = {name: self._gather_nodal(v) for name, v in fields.items()}
        if self.rank == 0:
            import h5py
            with h5py.File(self.h5path, "a") as h5:
                for name, arr in gathered.items():
                    if arr.ndim == 2 and arr.shape[1] == 2:
                        arr = np.column_stack([arr, np.zeros(len(arr))])
                    h5[f"fields/{name}/{k}"] = arr
                    entries.append((name, arr.shape[1] if arr.ndim == 2 else 1))
                h5.attrs["times"] = [s for s, _ in self._steps] + [t]
            self._steps.append((t, entries))
            self._write_xdmf()
        else:
            self._steps.append((t, entries))

    def _write_xdmf(self) -> None:
        topo, npc = TOPOLOGY[(self.rdim, self.degree)]
        per = f' NodesPerElement="{npc}"' if topo == "Polyline" else ""
        geo = "XY" if self.dim == 2 else "XYZ"
        out = ['<?xml version="1.0" ?>', '<Xdmf Version="3.0">', "<Domain>",
               '<Grid Name="TimeSeries" GridType="Collection" CollectionType="Temporal">']
        for k, (t, entries) in enumerate(self._steps):
            out += [f'<Grid Name="step{k}" GridType="Uniform">', f'<Time Value="{t!r}"/>',
                    f'<Topology TopologyType="{topo}" NumberOfElements="{self.ncells}"{per}>',
                    f'<DataItem Dimensions="{self.ncells} {npc}" NumberType="Int" Precision="8" '
                    f'Format="HDF">{self.h5name}:/mesh/topology</DataItem>', "</Topology>",
                    f'<Geometry GeometryType="{geo}">',
                    f'<DataItem Dimensions="{self.nnodes} {self.dim}" Format="HDF">'
                    f'{self.h5name}:/mesh/geometry</DataItem>', "</Geometry>"]
            for name, ncomp in entries:
                kind = "Scalar" if ncomp == 1 else "Vector"
                dims = f"{self.nnodes}" if ncomp == 1 else f"{self.nnodes} {ncomp}"
                out += [f'<Attribute Name="{name}" AttributeType="{kind}" Center="Node">',
                        f'<DataItem Dimensions="{dims}" Format="HDF">{self.h5name}:/fields/{name}/{k}'
                        "</DataItem>", "</Attribute>"]
            out.append("</Grid>")
        out += ["</Grid>", "</Domain>", "</Xdmf>"]
        with open(self.xdmfpath + ".tmp", "w") as f:
            f.write("\n".join(out) + "\n")
        os.replace(self.xdmfpath + ".tmp", self.xdmfpath)



__all__ = ["History", "FieldWriter", "write_summary"]
