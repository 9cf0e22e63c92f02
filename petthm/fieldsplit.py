"""Field splits of a problem's unknowns for PCFIELDSPLIT, and the Python PC
that rebuilds them on the reduced systems of the VI Newton methods.

* ``field_splits``: one index set per field, named by the field (the
  fieldsplit prefix ``-fieldsplit_u_...``), with the rigid-body modes of
  ``u`` composed as "nearnullspace" for GAMG (petsc-notes "Field split").
* ``VIFieldSplit``: ``-pc_type python -pc_python_type
  petthm.fieldsplit.VIFieldSplit``.  ``vinewtonrsls`` solves on the
  inactive set, which changes with the contact state; a PCFIELDSPLIT set up
  once would keep index sets of the wrong space (petsc-notes "Contact and
  SNES VI").
"""
from __future__ import annotations

import weakref

import numpy as np
from petsc4py import PETSc

from . import compat
from .errors import InputError

#: the attribute of the PC through which ``solver.TimeStepper`` gives
#: ``VIFieldSplit`` the (problem, SNES) it serves
SERVES = "petthm_vi_fieldsplit"


def field_splits(problem, space: np.ndarray | None = None) -> list[tuple[str, PETSc.IS]]:
    """(field name, sorted global indices) of every field, the rigid-body
    modes of ``u`` composed on its index set as "nearnullspace".
    ``space``: this rank's part of the sorted global unknowns of a reduced
    system (the inactive set of a VI solve); the index sets are then
    restricted to it and numbered in the reduced system."""
    dm = problem.dm
    names, isets, _ = dm.createFieldDecomposition()
    offset = 0 if space is None else _space_offset(dm, space)
    out = []
    for name, iset in zip(names, isets):
        if space is not None:
            idx = iset.getIndices()
            pos = np.searchsorted(space, idx[np.isin(idx, space)]) + offset
            iset = PETSc.IS().createGeneral(pos.astype(compat.INT), comm=dm.comm)
        if name == "u":
            iset.compose("nearnullspace", rigid_body_modes(problem, iset, space, offset))
        out.append((name, iset))
    return out


def rigid_body_modes(problem, iset: PETSc.IS, space: np.ndarray | None = None,
                     offset: int = 0) -> PETSc.NullSpace:
    """Translations and rotations of the u unknowns in ``iset`` (owned,
    sorted indices; components fixed by rollers are absent, so the vectors
    are built per unknown, not with a block size), orthonormalised.
    ``space``, ``offset``: the reduced system ``iset`` numbers (see
    ``field_splits``); default: all unknowns."""
    disc = problem.disc
    d = disc.mesh.dim
    dofs = disc.field_local_dofs("u")                            # (n, d) local
    x = disc.field_node_coordinates("u")
    x = x - x.mean(axis=0) if len(x) else x
    gidx = disc.global_index[dofs]
    own = disc._owned(gidx) & ~np.isin(dofs, problem.constraints.constrained_local())
    if space is not None:
        own &= np.isin(gidx, space)
    target = gidx[own] if space is None else np.searchsorted(space, gidx[own]) + offset
    rows = np.searchsorted(iset.getIndices(), target)
    comp = np.broadcast_to(np.arange(d), dofs.shape)[own]
    xs = np.broadcast_to(x[:, None, :], dofs.shape + (d,))[own]
    n = iset.getLocalSize()
    comm = problem.dm.comm
    vecs = []
    for m in rigid_modes(comp, xs):
        v = PETSc.Vec().createMPI((n, PETSc.DECIDE), comm=comm)
        v.getArray()[rows] = m
        vecs.append(v)
    return orthonormal_nullspace(vecs, comm)


def rigid_modes(comp: np.ndarray, x: np.ndarray) -> list[np.ndarray]:
    """Translations and rotations of displacement unknowns of components
    ``comp`` at points ``x`` (one row per unknown)."""
    d = x.shape[1]
    modes = [np.asarray(comp == k, dtype=float) for k in range(d)]
    for a, b in ([(0, 1)] if d == 2 else [(0, 1), (1, 2), (2, 0)]):    # rotation in the (a, b) plane
        modes.append(np.where(comp == a, -x[:, b], 0.0) + np.where(comp == b, x[:, a], 0.0))
    return modes


def orthonormal_nullspace(vecs: list, comm) -> PETSc.NullSpace:
    """A MatNullSpace of the vectors, orthonormalised (modified Gram-Schmidt;
    dependent ones dropped)."""
    out = []
    for v in vecs:
        for w in out:
            v.axpy(-v.dot(w), w)
        nv = v.norm()
        if nv > 1e-12:
            v.scale(1.0 / nv)
            out.append(v)
    return PETSc.NullSpace().create(vectors=out, comm=comm)


def _space_offset(dm, space: np.ndarray) -> int:
    """First row of this rank in a reduced system of which it holds ``space``."""
    return dm.comm.tompi4py().exscan(len(space)) or 0


def serve(pc: PETSc.PC, problem, snes: PETSc.SNES) -> None:
    """Tell the PC's ``VIFieldSplit`` which problem and SNES it serves (kept
    on the PC: PETSc replaces the Python context whenever it reads the
    options; weak references, so that the PC does not keep its own SNES
    alive past PETSc's finalisation)."""
    pc.setAttr(SERVES, (weakref.ref(problem), weakref.ref(snes)))


class VIFieldSplit:
    """Field split for the reduced systems of PETSc's VI Newton methods.

    At every set-up an inner PCFIELDSPLIT is rebuilt: one split per field
    restricted to ``SNES.getVIInactiveSet()`` (all unknowns for
    ``vinewtonssls``), named by the field, the rigid-body modes on u.  The
    inner PC takes its options with the prefix ``vi_``
    (``-vi_pc_fieldsplit_type schur``, ``-vi_fieldsplit_u_pc_type gamg``, ...).

    ``-vi_groups NAME=F1+F2,NAME2=...`` merges fields into named splits
    (fields the scene does not have are skipped, empty groups dropped), so
    that one two-split Schur recipe serves u with lam alone and u with
    {lam, pf, Tf, Tm}: ``-vi_groups u=u,rest=lam+pm+pf+Tm+Tf``."""

    def __init__(self):
        self.inner = None

    def setUp(self, pc):
        A, P = pc.getOperators()
        served = pc.getAttr(SERVES)
        problem, snes = (served[0](), served[1]()) if served is not None else (None, None)
        if problem is None or snes is None:
            raise RuntimeError("VIFieldSplit is set up by petthm's TimeStepper only")
        space = None
        if snes.getType() == "vinewtonrsls" and P.getSize()[0] != problem.X.getSize():
            space = np.asarray(snes.getVIInactiveSet().getIndices(), dtype=compat.INT)
        splits = field_splits(problem, space)
        splits = self._grouped([(n, s) for n, s in splits if s.getSize() > 0], pc)
        if self.inner is not None:
            self.inner.destroy()
        self.inner = PETSc.PC().create(comm=pc.getComm())
        self.inner.setOptionsPrefix((pc.getOptionsPrefix() or "") + "vi_")
        self.inner.setOperators(A, P)
        self.inner.setType("fieldsplit")
        self.inner.setFieldSplitIS(*splits)
        self.inner.setFromOptions()
        self.inner.setUp()

    @staticmethod
    def _grouped(splits: list, pc) -> list:
        """The splits merged by ``-vi_groups`` (see the class docstring)."""
        text = PETSc.Options((pc.getOptionsPrefix() or "") + "vi_").getString("groups", "")
        if not text:
            return splits
        by_name = dict(splits)
        grouped = {f for item in text.split(",") for f in item.partition("=")[2].split("+")}
        missing = [n for n in by_name if n not in grouped]
        if missing:
            raise InputError(f"option -vi_groups = {text} leaves out the field(s) {', '.join(missing)}")
        out = []
        for item in text.split(","):
            name, _, members = item.partition("=")
            parts = [by_name[f] for f in members.split("+") if f in by_name]
            if not name or not members:
                raise InputError(f"option -vi_groups: '{item}' is not NAME=FIELD+FIELD...")
            if len(parts) == 1:
                out.append((name, parts[0]))
            elif parts:
                idx = np.unique(np.concatenate([p.getIndices() for p in parts])).astype(compat.INT)
                out.append((name, PETSc.IS().createGeneral(idx, comm=pc.getComm())))
        return out

    def reset(self, pc):
        if self.inner is not None:
            self.inner.destroy()
            self.inner = None

    def apply(self, pc, x, y):
        self.inner.apply(x, y)
