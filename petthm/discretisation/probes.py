"""MPI-safe probes and reductions: every value a scene reports is the same on
all ranks.

Every function here is collective on the communicator it is given (or on
the problem's) and must be called by all ranks; a rank without the
relevant nodes contributes nothing (an empty array) and still takes part.
Scenes use these and no MPI calls of their own.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np


def _op(name: str):
    from mpi4py import MPI
    return getattr(MPI, name)


def mpi(comm):
    """The mpi4py communicator of a PETSc communicator (or an mpi4py one)."""
    return comm.tompi4py() if hasattr(comm, "tompi4py") else comm


def global_max(comm, values, empty: float = -np.inf) -> float:
    """Largest entry over all ranks (``empty`` where no rank has one)."""
    v = np.asarray(values, dtype=float)
    return mpi(comm).allreduce(float(v.max()) if v.size else empty, op=_op("MAX"))


def global_min(comm, values, empty: float = np.inf) -> float:
    v = np.asarray(values, dtype=float)
    return mpi(comm).allreduce(float(v.min()) if v.size else empty, op=_op("MIN"))


def global_sum(comm, value):
    """Sum over ranks of a number or an array."""
    if np.ndim(value):
        return mpi(comm).allreduce(np.asarray(value, dtype=float))
    return mpi(comm).allreduce(value)


def global_count(comm, mask) -> int:
    return int(mpi(comm).allreduce(int(np.count_nonzero(mask))))


def gather_all(comm, a: np.ndarray) -> np.ndarray:
    """The concatenation of every rank's rows (on all ranks)."""
    parts = mpi(comm).allgather(np.asarray(a))
    return np.concatenate(parts) if parts else np.asarray(a)


def gather_root(comm, a: np.ndarray):
    """The concatenation of every rank's rows on rank 0 (None elsewhere)."""
    parts = mpi(comm).gather(np.asarray(a), root=0)
    return np.concatenate(parts) if parts is not None else None


def nearest(comm, x: np.ndarray, point, values: Sequence[np.ndarray], ord: int = 2) -> list[float]:
    """The values at the node of ``x`` (rows of this rank) nearest to ``point``
    over all ranks (``ord``: the norm of the distance); ties go to the lowest rank."""
    owner, k = nearest_node(comm, x, point, ord)
    c = mpi(comm)
    mine = [float(np.asarray(v)[k]) for v in values] if c.rank == owner else None
    return c.bcast(mine, root=owner)


def nearest_node(comm, x: np.ndarray, point, ord: int = 2) -> tuple[int, int]:
    """(rank, row of that rank's ``x``) of the node nearest to ``point`` over
    all ranks; ties go to the lowest rank (the row is -1 on the other ranks)."""
    x = np.asarray(x)
    d = np.linalg.norm(x - np.asarray(point)[None, :x.shape[1]], ord=ord, axis=1) if len(x) else np.zeros(0)
    k = int(np.argmin(d)) if len(d) else 0
    c = mpi(comm)
    best = (float(d[k]), c.rank) if len(d) else (np.inf, c.rank)
    _, owner = c.allreduce(best, op=_op("MINLOC"))
    return owner, (k if c.rank == owner else -1)


# -- probes of a problem's fields ------------------------------------------------------
def point_value(problem, name: str, point, X=None, t: float = 0.0, component: int = 0) -> float:
    """SI value of a field's component at the node nearest to ``point`` (the
    node found once per field and point and kept on the problem: the mesh
    does not move; monitors ask at every step)."""
    key = (name, tuple(float(v) for v in np.ravel(point)))
    if key not in problem.probe_nodes:
        problem.probe_nodes[key] = nearest_node(problem.dm.comm, problem.disc.field_node_coordinates(name),
                                                point)
    owner, k = problem.probe_nodes[key]
    c = mpi(problem.dm.comm)
    v = problem.field_values(name, X, t, nodes=[k] if c.rank == owner else [])     # collective
    value = float(v[0, component]) if c.rank == owner else None
    return c.bcast(value, root=owner)


def max_nodal_error(problem, name: str, exact: Callable, X=None, t: float = 0.0, component: int = 0) -> float:
    """max over all nodes of |value - exact(node coordinates)| of a field's component (SI)."""
    v = problem.field_values(name, X, t)[:, component]
    x = problem.disc.field_node_coordinates(name)
    return global_max(problem.dm.comm, np.abs(v - exact(x)) if len(v) else v, empty=0.0)


def field_range(problem, name: str, X=None, t: float = 0.0, offset: float = 0.0) -> tuple[float, float]:
    """(min, max) over all nodes of a scalar field, minus ``offset`` (e.g. kelvin -> degC)."""
    v = problem.field_values(name, X, t)[:, 0] - offset
    comm = problem.dm.comm
    return global_min(comm, v), global_max(comm, v)
