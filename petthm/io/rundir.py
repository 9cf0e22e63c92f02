"""The output folder of a run: its lock, its manifest, and the rule that a
run never replaces another run's output without being asked (manual:
"Output folder", manual, user guide).

* **Lock.**  Rank 0 holds an advisory lock (``fcntl.flock``) on
  ``DIR/.petthm.lock`` for the life of the run, with ``host:pid`` written in
  the file.  The kernel releases it when the process ends, however it ends,
  so a killed run leaves no stale lock.  A second run into a locked folder
  stops at once, naming the holder.  On a file system without locks the
  run says so once and goes on.
* **Manifest.**  ``DIR/manifest.json`` lists every file the runs in this
  folder wrote (a name is added before its file is created, so a killed
  run's files are listed too).  A folder whose manifest lists files holds
  another run's output: a new run there stops with an error that names
  ``-thm_restart`` (continue it) and ``-thm_overwrite`` (replace it).  With
  ``-thm_overwrite`` the files of the manifest are removed first, and
  nothing else: a user's mesh, options file or job log stays.  A folder of
  a petthm without manifests is recognised by its ``summary.json``,
  ``history.csv`` or ``checkpoint.h5``; its manifest is those of the names
  below that exist (``mesh.msh`` when its ``summary.json`` says that the
  run generated it).
"""
from __future__ import annotations

import errno
import json
import os
import socket

from petthm.errors import InputError, WriteFailure

LOCK = ".petthm.lock"
MANIFEST = "manifest.json"
#: the files by which a folder of a petthm without manifests is recognised
SIGNS_OF_A_RUN = ("summary.json", "history.csv", "checkpoint.h5")
#: the names such a petthm wrote (temporary files included)
LEGACY_NAMES = ("summary.json", "summary.json.tmp", "history.csv", "history.csv.tmp", "checkpoint.h5",
                "checkpoint.h5.tmp", "fracture_final.npz", "profile_1e8.json")
LEGACY_STEMS = ("fields", "fields_p1", "fracture", "fracture_p1")
#: errno values of a file system without advisory locks
NO_LOCKS = (errno.ENOLCK, errno.EOPNOTSUPP, errno.ENOSYS, errno.EINVAL)


def with_temporary(names) -> list[str]:
    """``names`` and the temporary file each is written through (``NAME.tmp``)."""
    return [n for name in names for n in (name, name + ".tmp")]


class RunFolder:
    """The output folder of one run (see the module docstring).  ``open``
    is collective; the lock and the manifest live on rank 0."""

    def __init__(self, path: str, comm):
        self.path = path
        self.comm = comm
        self.mpi = comm.tompi4py()
        self._lock = None                       # the open lock file (rank 0), held until ``close``
        self._files: list[str] = []             # the manifest's names (rank 0)
        self.notes: list[str] = []              # what ``open`` has to say (rank 0), e.g. no locks

    # -- collective ---------------------------------------------------------------------
    def open(self, continuing: bool, overwrite: bool) -> None:
        """Create the folder, take its lock and check what it holds:
        ``continuing`` (a restart) expects the output of the run it continues;
        otherwise a folder with another run's output is an ``InputError``
        unless ``overwrite``, which removes that output's files first."""
        error = None
        if self.comm.rank == 0:
            try:
                self._open_on_root(continuing, overwrite)
            except InputError as e:
                error = ("input", str(e))
            except OSError as e:
                error = ("write", f"the output folder {self.path} cannot be used ({e.strerror or e})")
        error = self.mpi.bcast(error, root=0)
        if error:
            self.close()
            raise (InputError if error[0] == "input" else WriteFailure)(error[1])

    def claim(self, names) -> None:
        """Add ``names`` (files in the folder) to the manifest before they are
        written (collective: rank 0 writes; a failed write is a
        ``WriteFailure`` on every rank)."""
        from petthm.io.output import on_root

        def add():
            new = [n for n in names if n not in self._files]
            if new:
                self._files += new
                self._write_manifest()
        on_root(self.comm, add, os.path.join(self.path, MANIFEST))

    def close(self) -> None:
        """Release the lock (the end of the run; also done by the process's end)."""
        if self._lock is not None:
            self._lock.close()
            self._lock = None

    # -- rank 0 -------------------------------------------------------------------------
    def _open_on_root(self, continuing: bool, overwrite: bool) -> None:
        try:
            os.makedirs(self.path, exist_ok=True)
        except OSError as e:
            raise InputError(f"option -thm_output_dir = {self.path}: the folder cannot be created "
                             f"({e.strerror or e})") from None
        self._take_lock()
        listed = self._listed()
        if continuing:                          # the manifest stays as it is until a new name comes
            self._files = listed
            if not os.path.isfile(os.path.join(self.path, MANIFEST)):
                self._write_manifest()
            return
        earlier = [n for n in listed if os.path.exists(os.path.join(self.path, n))]
        if earlier and not overwrite:
            raise InputError(f"the output folder {self.path} holds the output of another run "
                             f"({', '.join(earlier[:3])}{', ...' if len(earlier) > 3 else ''}): continue it "
                             f"with -thm_restart {self.path}, replace it with -thm_overwrite, or choose "
                             "another -thm_output_dir")
        elif earlier:
            self._remove(earlier)
        self._write_manifest()

    def _take_lock(self) -> None:
        import fcntl
        path = os.path.join(self.path, LOCK)
        f = open(path, "a+")                    # noqa: SIM115 - held open: the lock lives as long as it
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            f.seek(0)
            holder = f.read().strip() or "unknown"
            f.close()
            raise InputError(f"the output folder {self.path} is in use by the run {holder} (lock "
                             f"{path}); wait for it to end, or choose another -thm_output_dir") from None
        except OSError as e:
            if e.errno not in NO_LOCKS:
                f.close()
                raise
            self.notes.append(f"petthm: note: the file system of {self.path} has no locks ({e.strerror}): "
                              "nothing stops a second run from writing into this folder")
            f.close()
            return
        f.seek(0)
        f.truncate()
        f.write(f"{socket.gethostname()}:{os.getpid()}\n")
        f.flush()
        self._lock = f

    def _listed(self) -> list[str]:
        """The names the folder's manifest lists (see the module docstring:
        a folder of a petthm without manifests has one made up)."""
        path = os.path.join(self.path, MANIFEST)
        if os.path.isfile(path):
            try:
                with open(path) as f:
                    names = json.load(f)["files"]
                if not all(isinstance(n, str) and os.path.basename(n) == n for n in names):
                    raise ValueError(names)
            except (OSError, ValueError, KeyError, TypeError):
                raise InputError(f"the manifest {path} cannot be read (not petthm's, or damaged): move "
                                 "it away, or choose another -thm_output_dir") from None
            return list(names)
        if not any(os.path.exists(os.path.join(self.path, n)) for n in SIGNS_OF_A_RUN):
            return []
        names = list(LEGACY_NAMES) + with_temporary(
            [s + e for s in LEGACY_STEMS for e in (".h5", ".xdmf")])
        if self._legacy_generated_mesh():
            names.append("mesh.msh")
        return [n for n in names if os.path.exists(os.path.join(self.path, n))]

    def _legacy_generated_mesh(self) -> bool:
        try:
            with open(os.path.join(self.path, "summary.json")) as f:
                mesh = json.load(f)["provenance"]["mesh"]
        except (OSError, ValueError, KeyError, TypeError):
            return False
        return os.path.abspath(mesh) == os.path.abspath(os.path.join(self.path, "mesh.msh"))

    def _remove(self, names) -> None:
        for n in names:
            p = os.path.join(self.path, n)
            if os.path.isfile(p) or os.path.islink(p):
                os.remove(p)
        self._files = []

    def _write_manifest(self) -> None:
        path = os.path.join(self.path, MANIFEST)
        with open(path + ".tmp", "w") as f:
            json.dump({"written_by": "petthm", "files": self._files}, f, indent=1)
        os.replace(path + ".tmp", path)


__all__ = ["RunFolder", "LOCK", "MANIFEST", "with_temporary"]
