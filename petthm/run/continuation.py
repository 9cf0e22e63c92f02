"""What a restart continues (``-thm_restart DIR``; manual: "Stopping and
continuing", manual, user guide).

A restart continues the same problem in the folder of the run it
continues: the checkpoint records every option in effect with its kind
(``params.KINDS``) and the SHA-256 of the mesh file, and a restart whose
physics, mesh or discretisation options (``params.FIXED_ON_RESTART``:
PETSc's ``-dm_*`` and ``-ts_type`` included) or mesh file differ is an
``InputError`` listing each difference; solver, output and run-control
options and a later end time may change.  A run that has reached its end
time is left as it is.  ``restore`` loads the state, the monitors' carried
state (``scenes.base.Monitor.carried``) and drops the history rows after it.
"""
from __future__ import annotations

import json
import os

from petsc4py import PETSc

from petthm import params as P
from petthm.errors import InputError
from petthm.io import checkpoint
from petthm.io.output import on_root


def end_time(scene) -> float:
    """The run's end time: -ts_max_time if given, else the scene's (-thm_final_time or its default)."""
    opts = PETSc.Options()
    return opts.getReal("ts_max_time") if opts.hasName("ts_max_time") else scene.final_time


def option_record(scene, proposals) -> dict:
    """Every option in effect with its kind (``params.option_record``; of the
    PETSc options the user's, not the ``proposals``), as JSON reads it back."""
    record = P.option_record(scene.parameter_sets(), proposals.users_options())
    return json.loads(json.dumps(record, default=str))


def _say(comm, msg):
    if comm.rank == 0:
        print(msg, flush=True)


class Continuation:
    """The run a restart continues: its folder (``scene.run.restart``) and
    its checkpoint's metadata ``saved``, checked on construction (the
    folder exists and is the output folder, the checkpoint is readable and
    of this scene)."""

    def __init__(self, scene, comm, proposals):
        self.scene, self.comm, self.proposals = scene, comm, proposals
        run = scene.run
        self.folder = run.restart
        if run.output_dir and os.path.abspath(run.output_dir) != os.path.abspath(run.restart):
            raise InputError(f"options -thm_restart = {run.restart} and -thm_output_dir = "
                             f"{run.output_dir}: a restart goes on in the folder of the run it "
                             "continues (give -thm_restart alone)")
        if run.overwrite:
            raise InputError(f"options -thm_restart = {run.restart} and -thm_overwrite: a restart "
                             "continues the run in its folder, -thm_overwrite replaces it (give one of them)")
        if not os.path.isdir(run.restart):
            raise InputError(f"option -thm_restart = {run.restart}: no such folder")
        self.saved = checkpoint.check(run.restart, scene.name)

    def mesh_file(self) -> str:
        """The mesh the continued run wrote (``DIR/mesh.msh``), or "" if there is none."""
        written = os.path.join(self.folder, "mesh.msh")
        return written if os.path.isfile(written) else ""

    def check_options(self) -> None:
        """The physics, mesh and discretisation options of the checkpoint's
        record must not change (an ``InputError`` listing each difference)."""
        raw = checkpoint.read_record(self.folder, "options")
        if raw is None:
            _say(self.comm, f"petthm: note: {self.folder}/{checkpoint.FILE} records no options (an older "
                 "petthm): the restart's options are not checked against the run it continues")
            return
        now = option_record(self.scene, self.proposals)
        changes = checkpoint.option_changes(json.loads(raw.decode()), now)
        if changes:
            raise InputError(f"option -thm_restart = {self.folder}: a restart continues the same problem, "
                             f"but {'this option differs' if len(changes) == 1 else 'these options differ'} "
                             f"from the checkpoint's: {'; '.join(changes)} (start a new run for "
                             "that: another -thm_output_dir, or -thm_overwrite)")

    def check_mesh(self, path: str, digest: str | None) -> None:
        """The restart reads the mesh file the checkpoint's run read (its SHA-256 ``digest``)."""
        saved = self.saved.get("mesh_sha256")
        if saved and digest != saved:
            raise InputError(f"option -thm_restart = {self.folder}: the mesh file '{path}' is not the one "
                             "the checkpoint's run read (its contents changed): restore that mesh, or "
                             "start a new run")

    def already_at_end(self) -> dict | None:
        """A run that has reached the end time: a summary that says so (the
        folder is left as it is); past it: an ``InputError``; else None."""
        t_saved, t_end = float(self.saved["time"]), end_time(self.scene)
        if t_saved > t_end * (1 + 1e-12):
            raise InputError(f"option -thm_restart = {self.folder}: the run is at t = {t_saved:.6g} s, past "
                             f"the end time {t_end:.6g} s (-thm_final_time, -ts_max_time); give a later "
                             "end time to continue it")
        if t_saved < t_end * (1 - 1e-12):
            return None
        message = (f"the run in {self.folder} has reached its end time t = {t_end:.6g} s: nothing to "
                   "continue (give a later end time, -thm_final_time, to run on); its output is unchanged")
        _say(self.comm, message)
        return {"scene": self.scene.name, "status": "completed", "exit_code": 0, "final_time": t_saved,
                "message": message}

    def restore(self, problem, monitor) -> dict:
        """Load the checkpoint into ``problem`` (after its set-up: the same
        scales, proposals and initial conditions as the original run) and
        the monitors' carried state into ``monitor``; drop the history rows
        after it; its metadata (collective)."""
        meta = checkpoint.read(self.folder, problem.X, problem.dm, self.scene.name)
        state = checkpoint.read_record(self.folder, "monitor")
        if state is not None:
            monitor.restore(checkpoint.unpack_state(state, os.path.join(self.folder, checkpoint.FILE)))
        history = os.path.join(self.folder, "history.csv")
        on_root(self.comm, lambda: checkpoint.truncate_history(history, meta["time"]), history)
        _say(self.comm, f"restart from {os.path.join(self.folder, checkpoint.FILE)}: "
             f"t = {meta['time']:.6g} s, step {meta['step']}")
        return meta


__all__ = ["Continuation", "end_time", "option_record"]
