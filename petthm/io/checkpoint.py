"""Checkpoint, restart and stop requests (manual, user guide).

``checkpoint.h5`` in the output folder holds what a run needs to continue:
the state X (each rank's owned mesh points' values), the time, the next step size, the step number and the
number of rejected steps, with the scene, the rank count and the global
size to check a restart against.  Each rank writes its own part (the ranks
take turns on the one file: nothing of field size is gathered on a rank);
the file is replaced atomically, so a run killed while writing keeps the
previous checkpoint.  h5py is used rather than PETSc's HDF5 viewer, which
the PyPI build of PETSc lacks.

Values are stored by mesh point, keyed by the point's number in the serial
mesh the run distributed (``mesh.original_points``): the partitioners are
not deterministic from run to run, and a restart may use another rank
count.  A restart (``-thm_restart DIR``) rebuilds the same problem from
the same options and the mesh the run wrote (``DIR/mesh.msh``); a
checkpoint that does not fit it stops with a one-line error.

``StopRequest``: SIGTERM (what SLURM sends at the time limit, or earlier
with ``--signal``), SIGINT and SIGUSR1 set a flag; the run checks it after
every accepted step (the ranks agree: any rank's signal stops them all),
writes a checkpoint and stops with status ``interrupted``.
"""
from __future__ import annotations

import contextlib
import os
import signal

import numpy as np

from petthm.errors import InputError, WriteFailure, os_error_text
from petthm.io.output import check_space, history_number, in_turns, on_root

FILE = "checkpoint.h5"
SIGNALS = ("SIGTERM", "SIGINT", "SIGUSR1")


#: the attribute of a DM that keeps its ``_point_blocks`` (the layout does not change during a run)
BLOCKS = "petthm_point_blocks"


def _point_blocks(dm):
    """The local vector's layout by point: (serial point number, offset,
    dof count) of the points with dofs; and which of them this rank owns
    (computed once per DM: a loop over the points)."""
    cached = dm.getAttr(BLOCKS)
    if cached is None:
        cached = _layout(dm)
        dm.setAttr(BLOCKS, cached)
    return cached


def _layout(dm):
    from petthm.compat import get_local_section
    from petthm.mesh.plex import original_points
    sec = get_local_section(dm)
    p0, p1 = dm.getChart()
    points = np.arange(p0, p1)
    ndof = np.array([sec.getDof(p) for p in points], dtype=np.int64)
    offset = np.array([sec.getOffset(p) for p in points], dtype=np.int64)
    owned = np.ones(len(points), dtype=bool)
    leaves = dm.getPointSF().getGraph()[1] if dm.comm.size > 1 else None
    if leaves is not None and len(leaves):
        owned[np.asarray(leaves) - p0] = False
    keep = ndof > 0
    return original_points(dm)[keep], offset[keep], ndof[keep], owned[keep]


def write(directory: str, X, dm, meta: dict, records: dict[str, bytes] | None = None) -> None:
    """Write ``checkpoint.h5`` (see the module docstring); ``meta``: time,
    dt, step, rejected, scene, ... (attributes); ``records``: byte strings
    rank 0 stores as datasets (the options in effect, the monitors' state).
    The file is written as ``checkpoint.h5.tmp`` and renamed: a run killed
    or out of disk space while writing keeps the previous checkpoint
    (collective; a failed write is a ``WriteFailure`` on every rank)."""
    import h5py
    comm = X.getComm().tompi4py()
    path = os.path.join(directory, FILE)
    tmp = path + ".tmp"
    key, offset, ndof, owned = _point_blocks(dm)
    Xl = dm.getLocalVec()
    dm.globalToLocal(X, Xl)
    values = Xl.getArray(readonly=True)
    idx = _block_indices(offset[owned], ndof[owned])
    part = {"point": key[owned], "ndof": ndof[owned], "value": values[idx].copy()}
    dm.restoreLocalVec(Xl)
    blobs = {k: np.frombuffer(v, dtype=np.uint8) for k, v in (records or {}).items()}

    def write_part(r):
        with h5py.File(tmp, "w" if r == 0 else "a") as h5:
            if r == 0:
                for k, v in dict(meta, ranks=comm.size, size=X.getSize()).items():
                    h5.attrs[k] = v
                for k, v in blobs.items():
                    h5[k] = v
            for name, arr in part.items():
                h5[f"{name}/{r}"] = arr
    try:
        check_space(comm, tmp, sum(a.nbytes for a in part.values()) + sum(b.nbytes for b in blobs.values()))
        in_turns(comm, write_part, tmp)
        on_root(comm, lambda: os.replace(tmp, path), path)
    except WriteFailure:
        if comm.rank == 0 and os.path.exists(tmp):
            os.remove(tmp)
        raise


def read_record(directory: str, name: str) -> bytes | None:
    """A byte string ``write`` stored in ``DIR/checkpoint.h5`` (None if it has none)."""
    import h5py
    path = os.path.join(directory, FILE)
    try:
        with h5py.File(path, "r") as h5:
            return bytes(h5[name][...].tobytes()) if name in h5 else None
    except (OSError, KeyError, ValueError, RuntimeError) as e:
        raise InputError(_damaged(path, e)) from None


def _damaged(path: str, error: BaseException) -> str:
    return (f"{path} is not a readable checkpoint ({os_error_text(error)}): it is truncated or damaged; "
            "restore it, or start a new run (another -thm_output_dir, or -thm_overwrite)")


def _match(saved_point, saved_ndof, key, ndof):
    """(position in the saved blocks, found) of each local point's block."""
    if not len(saved_point):
        return np.zeros(len(key), dtype=int), np.zeros(len(key), dtype=bool)
    order = np.argsort(saved_point)
    where = order[np.clip(np.searchsorted(saved_point, key, sorter=order), 0, len(order) - 1)]
    return where, (key >= 0) & (saved_point[where] == key) & (saved_ndof[where] == ndof)


def _block_indices(offset: np.ndarray, ndof: np.ndarray) -> np.ndarray:
    """The entries offset[i] ... offset[i] + ndof[i] - 1 of every block, in order."""
    start = np.repeat(offset - np.concatenate([[0], np.cumsum(ndof)[:-1]]), ndof)
    return start + np.arange(int(ndof.sum()))


def check(directory: str, scene: str) -> dict:
    """The metadata of ``DIR/checkpoint.h5``, checked before the run is
    built: the file exists, can be read, is a checkpoint and is of this scene."""
    import h5py
    path = os.path.join(directory, FILE)
    if not os.path.isfile(path):
        raise InputError(f"option -thm_restart = {directory}: no {FILE} there (a run writes it every "
                         "-thm_checkpoint_interval steps, at its end and when stopped by a signal)")
    try:
        with h5py.File(path, "r") as h5:
            meta = {k: (v.item() if hasattr(v, "item") else v) for k, v in h5.attrs.items()}
            complete = all(name in h5 for name in ("point", "ndof", "value"))
    except (OSError, KeyError, ValueError, RuntimeError) as e:
        raise InputError(_damaged(path, e)) from None
    missing = [k for k in ("scene", "time", "dt", "step", "size") if k not in meta]
    if missing or not complete:
        raise InputError(_damaged(path, KeyError(f"it lacks {', '.join(missing) or 'the state'}")))
    if meta.get("scene") != scene:
        raise InputError(f"option -thm_restart = {directory}: the checkpoint is of scene "
                         f"{meta.get('scene')}, not {scene}")
    return meta


def read(directory: str, X, dm, scene: str) -> dict:
    """Load X from ``DIR/checkpoint.h5`` and return its metadata (collective).
    Values are matched by the serial mesh's point numbers, so any rank count
    and partition can read them; a missing or damaged file, another scene or
    another problem is an ``InputError``."""
    import h5py
    meta = check(directory, scene)
    path = os.path.join(directory, FILE)
    try:
        with h5py.File(path, "r") as h5:
            saved = {name: np.concatenate([h5[name][r][...] for r in sorted(h5[name], key=int)])
                     for name in ("point", "ndof", "value")}
    except (OSError, KeyError, ValueError, RuntimeError) as e:
        raise InputError(_damaged(path, e)) from None
    if len(saved["value"]) != int(saved["ndof"].sum()) or len(saved["point"]) != len(saved["ndof"]):
        raise InputError(_damaged(path, ValueError("its state is incomplete")))
    key, offset, ndof, _ = _point_blocks(dm)
    where, found = _match(saved["point"], saved["ndof"], key, ndof)
    missing = int(X.getComm().tompi4py().allreduce(int((~found).sum())))
    if meta.get("size") != X.getSize() or missing:
        raise InputError(f"option -thm_restart = {directory}: the checkpoint ({meta.get('size')} "
                         f"unknowns) does not fit this problem ({X.getSize()} unknowns, {missing} mesh "
                         "points without a value): restart with the options of the original run "
                         "(its summary.json lists them)")
    start = np.concatenate([[0], np.cumsum(saved["ndof"])[:-1]])
    Xl = dm.getLocalVec()
    Xl.set(0.0)
    Xl.getArray()[_block_indices(offset, ndof)] = saved["value"][_block_indices(start[where], ndof)]
    dm.localToGlobal(Xl, X)
    dm.restoreLocalVec(Xl)
    return meta


# -- what a restart must keep ------------------------------------------------------------------
def option_changes(saved: dict, now: dict) -> list[str]:
    """The options of a kind in ``params.FIXED_ON_RESTART`` whose value
    differs between the checkpoint's record ``saved`` and this run's ``now``
    (records of ``params.option_record``), as "-name old -> new (kind)"."""
    from petthm.params import FIXED_ON_RESTART
    out = []
    for name in sorted(set(saved) | set(now)):
        old, new = saved.get(name), now.get(name)
        kind = (new or old)["kind"]
        if kind not in FIXED_ON_RESTART:
            continue
        was = "(not set)" if old is None else old["value"]
        is_ = "(not set)" if new is None else new["value"]
        if was != is_:
            out.append(f"{name} {_show(was)} -> {_show(is_)} ({kind})")
    return out


def _show(value) -> str:
    return ",".join(map(str, value)) if isinstance(value, list) else str(value)


def file_digest(path: str) -> str:
    """The SHA-256 of a file's contents (the mesh a run read)."""
    import hashlib
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


# -- the monitors' state ------------------------------------------------------------------------
def pack_state(state: dict) -> bytes:
    """The monitors' carried state (plain data: numbers, strings, lists,
    tuples, dicts, numpy arrays, ``Worst``) as bytes for the checkpoint."""
    import pickle
    return pickle.dumps(state, protocol=4)


def unpack_state(data: bytes, path: str) -> dict:
    """``pack_state``'s bytes back, admitting plain data only (a checkpoint
    cannot make the run execute code)."""
    import io
    import pickle

    class PlainData(pickle.Unpickler):
        def find_class(self, module, name):
            if (module, name) in _PLAIN_CLASSES:
                return super().find_class(module, name)
            raise pickle.UnpicklingError(f"{module}.{name} is not plain data")
    try:
        return PlainData(io.BytesIO(data)).load()
    except Exception as e:  # noqa: BLE001 - any damage of the record is the same error for the user
        raise InputError(_damaged(path, ValueError(f"its monitor record: {e}"))) from None


#: the classes a monitor's carried state may hold (``unpack_state``)
_PLAIN_CLASSES = {("builtins", "dict"), ("builtins", "list"), ("builtins", "tuple"), ("builtins", "set"),
                  ("builtins", "float"), ("builtins", "int"), ("builtins", "complex"),
                  ("numpy", "ndarray"), ("numpy", "dtype"), ("numpy.core.multiarray", "_reconstruct"),
                  ("numpy.core.multiarray", "scalar"), ("numpy._core.multiarray", "_reconstruct"),
                  ("numpy._core.multiarray", "scalar"), ("petthm.physics.monitors", "Worst"),
                  ("copyreg", "_reconstructor"), ("builtins", "object")}


class StopRequest:
    """The signals that ask a run to stop after its current step (see the
    module docstring).  ``install`` keeps the previous handlers, ``restore``
    puts them back."""

    def __init__(self):
        self.received: str | None = None
        self._previous: dict = {}

    def install(self) -> None:
        for name in SIGNALS:
            sig = getattr(signal, name)
            with contextlib.suppress(ValueError):  # not the main thread (an embedding application)
                self._previous[sig] = signal.signal(sig, self._handle)

    def _handle(self, signum, frame) -> None:
        self.received = signal.Signals(signum).name

    def restore(self) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)
        self._previous = {}

    def agreed(self, comm) -> str | None:
        """The signal any rank received (collective), or None."""
        names = comm.tompi4py().allgather(self.received)
        return next((n for n in names if n), None)


def truncate_history(path: str, t: float) -> None:
    """Drop the rows of ``history.csv`` after time t (written after the
    checkpoint a restart continues from).  The rows' times are t as the
    history writes it (12 significant digits, ``output.history_number``),
    so t is compared in that form: rounded up, 1102.6564319570314 is
    1102.65643196, 2.7e-12 above t, and the checkpoint's own row must stay
    (the restart does not write it again)."""
    import csv
    if not os.path.isfile(path):
        return
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        return
    col = rows[0].index("time") if "time" in rows[0] else 1
    last = float(history_number(float(t)))
    keep = [rows[0]] + [r for r in rows[1:] if r and float(r[col]) <= last]
    with open(path + ".tmp", "w", newline="") as f:
        csv.writer(f).writerows(keep)
    os.replace(path + ".tmp", path)


__all__ = ["write", "read", "check", "read_record", "option_changes", "file_digest", "pack_state",
           "unpack_state", "StopRequest", "truncate_history", "FILE"]
