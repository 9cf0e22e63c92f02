"""The run lifecycle: options -> mesh -> set-up -> time loop -> output.

Each phase is a PETSc log stage (``-log_view`` shows mesh, setup, solve,
output; the residual and Jacobian assembly are the events ``thm.residual``
and ``thm.jacobian``).  Rank 0 prints one progress line per step and writes
``summary.json`` (with the provenance: every parameter and PETSc option in
effect and the petthm git commit), ``history.csv`` and the XDMF/HDF5 fields.

A mesh with fracture physical groups (``meshing.FRACTURE_TAG0`` and up) is
split along them (cohesive cells); a scene whose model has fracture fields
needs such a mesh, and one without fracture physics refuses it.
"""
from __future__ import annotations

import contextlib
import os
import time

from petsc4py import PETSc

from petthm import __version__, compat
from petthm import params as P
from petthm.discretisation.constraints import boundary_entries
from petthm.discretisation.fields import Discretisation
from petthm.discretisation.model import Domain
from petthm.discretisation.problem import Problem
from petthm.errors import InputError, WriteFailure, petsc_option_errors
from petthm.io import checkpoint
from petthm.io.output import FieldWriter, History, write_summary
from petthm.io.rundir import RunFolder, with_temporary
from petthm.mesh.plex import (
    Mesh,
    bounding_box,
    check_every_rank_has_cells,
    distribute,
    read_plex,
)
from petthm.run.continuation import Continuation, end_time, option_record
from petthm.run.provenance import git_commit, options_in_effect, peak_memory_mb, solver_costs
from petthm.run.ranges import FieldRanges, WithRanges
from petthm.run.stepreport import StepReport
from petthm.scenes import MODULES, scene_class
from petthm.solvers.options import Proposals, proposed_options
from petthm.solvers.timestepper import StepControl, TimeStepper, failure_message


def _say(comm, msg):
    if comm.rank == 0:
        print(msg, flush=True)


def make_scene(name: str):
    cls = scene_class(name)
    if cls is None:
        raise InputError(f"unknown scene '{name}'; scenes: {', '.join(sorted(MODULES))}")
    run = P.read(P.RunParams)
    P.check_unknown_thm_options((P.RunParams,) + tuple(cls.parameters), extra=cls.named_options(run))
    scene = cls.read(run)
    scene.check_inputs()
    return scene


class Run:
    """One simulation of a scene (collective on PETSc.COMM_WORLD)."""

    def __init__(self, scene):
        self.scene = scene
        self.comm = PETSc.COMM_WORLD
        self.mpi = self.comm.tompi4py()
        run = scene.run
        self.proposals = Proposals()                  # the solver options petthm inserts (solvers.options)
        self.continuation = Continuation(scene, self.comm, self.proposals) if run.restart else None
        self.outdir = scene.output_dir
        self.folder = RunFolder(self.outdir, self.comm)
        self._folder_open = False
        self._claimed: list[str] = []             # the files this run added to the folder's manifest
        self.stage_wall = {}
        self.t_start = time.perf_counter()
        self._last_checkpoint = self.t_start
        self.mesh_path = run.mesh_file or (self.continuation.mesh_file() if self.continuation else "")
        self.mesh_digest: str | None = None
        self.problem: Problem | None = None
        self.monitor = None                           # the scene's Monitor (``setup``)
        PETSc.Log.begin()                   # event counts and times for summary.json's solver_costs

    # -- the output folder and what a restart continues -------------------------------------
    def open_folder(self) -> None:
        """Lock the output folder and check what it holds (``rundir``); a
        restart then checks that its options keep the problem of the
        checkpoint (collective, once)."""
        if self._folder_open:
            return
        run = self.scene.run
        self.folder.open(continuing=bool(run.restart), overwrite=run.overwrite)
        self._folder_open = True
        for note in self.folder.notes:
            _say(self.comm, note)
        if self.continuation is not None:
            self.continuation.check_options()

    def claim(self, names) -> None:
        """Record files in the folder's manifest before they are written."""
        self.folder.claim(names)
        self._claimed += [n for n in names if n not in self._claimed]

    def remove_own_output(self) -> None:
        """After an input error: remove the files this run wrote (a new run's
        only: a restart's folder holds the run it continues), so that the
        corrected command can start in the same folder (collective)."""
        if self.continuation is not None or not self._folder_open:
            return
        if self.comm.rank == 0:
            for name in self._claimed:
                path = os.path.join(self.outdir, name)
                if os.path.isfile(path):
                    os.remove(path)
        self.comm.barrier()

    # -- phases ----------------------------------------------------------------
    def _stage(self, name):
        st = PETSc.Log.Stage(name)
        st.push()
        return st, time.perf_counter()

    def _pop(self, name, st, t0):
        st.pop()
        self.stage_wall[name] = self.stage_wall.get(name, 0.0) + time.perf_counter() - t0

    def build_mesh(self) -> Mesh:
        scene, run = self.scene, self.scene.run
        st, t0 = self._stage("mesh")
        self.open_folder()
        path = self.mesh_path
        if not path:
            path = os.path.join(self.outdir, "mesh.msh")
            self.claim(["mesh.msh"])
            size = run.mesh_size or scene.time.mesh_size
            from petthm.mesh.limits import cell_limit

            def generate():
                with cell_limit(run.max_cells):
                    scene.generate_mesh(path, size)
            self._on_rank0(generate, (InputError, OSError),
                           lambda e: str(e) if isinstance(e, InputError) else
                           f"cannot write {path}: {e.strerror or e}")
        self.mesh_digest = self._digest(path)
        if self.continuation is not None:
            self.continuation.check_mesh(path, self.mesh_digest)
        with petsc_option_errors(f"the mesh file '{path}'"):
            dm = read_plex(path, self.comm)
        want, option = scene.mesh_dimension()
        if want and dm.getDimension() != want:
            raise InputError(f"mesh '{path}' is {dm.getDimension()}D, but scene {scene.name} is {want}D"
                             + (f" (option -{option} = {want})" if option else ""))
        scene.check_against_domain(*bounding_box(dm))
        with self._user_mesh_fits(dm.getDimension()):
            scene.label_mesh(dm)
        from petthm.mesh.fracture import split_fractures
        dm, _ = split_fractures(dm, scene.fracture_tags())
        dm = distribute(dm)
        check_every_rank_has_cells(dm)
        mesh = Mesh(dm)
        self._pop("mesh", st, t0)
        self.mesh_path = path
        return mesh

    def _digest(self, path: str) -> str | None:
        """The SHA-256 of the mesh file (rank 0 reads it; None if it cannot)."""
        digest = None
        if self.comm.rank == 0 and os.path.isfile(path):
            with contextlib.suppress(OSError):
                digest = checkpoint.file_digest(path)
        return self.mpi.bcast(digest, root=0)

    @contextlib.contextmanager
    def _user_mesh_fits(self, dim: int):
        """With a user's mesh file (-thm_mesh_file): a scene whose boundaries
        or physics cannot be set up on it (another dimension, a missing
        physical group) is an ``InputError`` naming the file, not a traceback
        from deep inside the set-up.  The scene's own meshes always fit."""
        try:
            yield
        except (ValueError, IndexError, AttributeError, KeyError) as e:
            if not self.scene.run.mesh_file:
                raise
            raise InputError(f"mesh '{self.mesh_path}' ({dim}D) does not fit scene {self.scene.name} "
                             f"({type(e).__name__}: {e}); use a mesh of the scene's dimension and physical "
                             "groups (-thm_mesh_file), or none for the scene's own") from None

    def _on_rank0(self, action, errors, message) -> None:
        """Run ``action`` on rank 0; an exception of type ``errors`` becomes
        an ``InputError`` (``message(exception)``) on every rank alike, an
        ``OSError`` a ``WriteFailure``."""
        error = None
        if self.comm.rank == 0:
            try:
                action()
            except errors as e:
                error = (isinstance(e, OSError), message(e))
        error = self.mpi.bcast(error, root=0)
        if error:
            raise (WriteFailure if error[0] else InputError)(error[1])

    def _check_fractures(self, mesh: Mesh, model) -> None:
        wants = any(f.region is Domain.FRACTURE for f in model.fields)
        if wants and mesh.fracture is None:
            raise InputError(f"mesh '{self.mesh_path}' has no fracture (physical group 10, 11, ... of "
                             f"facets), which scene {self.scene.name} needs")
        if not wants and mesh.fracture is not None:
            raise InputError(f"mesh '{self.mesh_path}' has fractures (physical groups 10, 11, ...), "
                             f"but scene {self.scene.name} has no fracture physics")

    def setup(self, mesh: Mesh):
        scene, run = self.scene, self.scene.run
        st, t0 = self._stage("setup")
        with self._user_mesh_fits(mesh.dim):
            setup = scene.build(mesh, run.fe_degree)
        model = setup.model
        self._check_fractures(mesh, model)
        for check in model.mesh_checks:
            warning = check(mesh)
            if warning:
                _say(self.comm, f"petthm: warning: {warning}")
        regions = {Domain.FRACTURE: mesh.fracture} if mesh.fracture is not None else {}
        disc = Discretisation(mesh, model.fields, boundary_entries(setup.dirichlet), regions=regions,
                              ties=model.ties)
        problem = Problem(disc, model, setup.scales, setup.dirichlet, run.quadrature_degree or None)
        problem.set_initial(setup.initial)
        td = scene.time
        control = StepControl(final_time=scene.final_time,
                              dt_initial=run.dt_initial or td.dt_initial,
                              growth=run.dt_growth or td.dt_growth,
                              dt_max=run.dt_max or td.dt_max,
                              hit_times=tuple(scene.hit_times()),
                              pc_reuse=run.pc_reuse, pc_reuse_max_krylov=run.pc_reuse_max_krylov,
                              predictor=run.predictor,
                              courant=run.dt_courant)
        if run.dt_control == "schedule":
            control.check_reachable(end_time(scene), "thm_dt_growth" if run.dt_growth else "")
        rs = problem.auto_residual_scales(0.0, 1.0 / control.dt_initial)
        self.proposals.propose(proposed_options(scene, model.has("u"), bool(model.bounds), mesh.dim,
                                                self.comm.size, problem.X.getSize(), control, self.comm))
        self._pop("setup", st, t0)
        self.problem = problem
        self.monitor = WithRanges(setup.monitor, FieldRanges(model))
        return disc, problem, control, rs, self.monitor

    def execute(self) -> dict:
        if self.continuation is not None:
            self.open_folder()
            done = self.continuation.already_at_end()
            if done is not None:
                return done
        mesh = self.build_mesh()
        disc, problem, control, rscales, scene_monitor = self.setup(mesh)
        self._print_start(mesh, disc, problem, rscales)
        st, t0 = self._stage("output")
        resume = self.continuation.restore(problem, self.monitor) if self.continuation else None
        writers, history = self._start_output(disc, problem, scene_monitor, resume)
        self._pop("output", st, t0)
        steps = StepReport(self, problem, control, scene_monitor, writers, history, resume)
        with petsc_option_errors("the solver options (-ts_*, -snes_*, -ksp_*, -pc_*)"):
            stepper = TimeStepper(problem, control, steps, self.proposals)
        steps.stepper, steps.control = stepper, stepper.control           # the end time -ts_max_time sets
        if resume:
            stepper.resume(resume["time"], resume["dt"], resume["step"],
                           {k: resume[k] for k in stepper.schedule_state() if k in resume})
        reason, write_failure = self._solve(stepper, steps)
        return self._finish(mesh, disc, stepper, reason, write_failure, steps, history, stepper.control)

    def _print_start(self, mesh, disc, problem, rscales) -> None:
        sizes = disc.global_sizes()
        _say(self.comm, f"petthm {__version__} | scene {self.scene.name} | {self.comm.size} rank(s) | "
             f"{mesh.global_cell_count()} cells | P{self.scene.run.fe_degree} | dofs "
             + ", ".join(f"{k}={v}" for k, v in sizes.items()))
        _say(self.comm, "scales: " + ", ".join(
            f"{k}: x = {problem.scales[k].offset:g} + {problem.scales[k].scale:g} x_hat, "
            f"residual / {rscales[k]:.3e}" for k in sizes))

    def _start_output(self, disc, problem, scene_monitor, resume):
        """The field writers (one per region and degree: fields, fields_p1,
        fracture) and history.csv; every file the run writes is in the
        folder's manifest before it is created."""
        groups = {}
        for f in disc.fields:
            groups.setdefault((f.region, f.degree), []).append(f)
        top = {r: max(d for rr, d in groups if rr == r) for r, _ in groups}
        stems = {(r, d): ("fields" if r is Domain.MATRIX else "fracture") + ("" if d == top[r] else f"_p{d}")
                 for r, d in groups}
        self.claim(with_temporary(["history.csv", "summary.json", checkpoint.FILE]
                                  + [s + e for s in stems.values() for e in (".h5", ".xdmf")]
                                  + list(scene_monitor.files)))
        t_resume = resume["time"] if resume else None
        writers = [(FieldWriter(disc, self.outdir, d, stems[r, d], r, resume_at=t_resume), fields)
                   for (r, d), fields in groups.items()]
        passes = ["settling_passes"] if problem.has_tightening() else []    # the limited heat transport
        columns = (["step", "time", "dt", "snes_its", "ksp_its", *passes, "wall"]
                   + list(self.scene.history_columns) + scene_monitor.ranges.columns())
        history = History(os.path.join(self.outdir, "history.csv"), columns, self.comm, append=bool(resume))
        return writers, history

    def _solve(self, stepper, steps) -> tuple[int, WriteFailure | None]:
        """Run the time stepper; (TS reason, the write failure that stopped it or None)."""
        st, t0 = self._stage("solve")
        steps.wall = time.perf_counter()
        steps.stop.install()
        failure = None
        try:
            reason = stepper.solve()
        except InputError:             # raised on every rank alike in a Python PC's set-up (-vi_groups)
            stepper.destroy()          # now: a Python PC left mid-set-up crashed PETSc's exit
            raise
        except WriteFailure as e:      # raised on every rank alike by the step's output
            failure, reason = e, -1
        except PETSc.Error as e:       # PETSc >= 3.20 hands it back as error 101, the InputError its cause
            if not isinstance(e.__cause__, InputError):
                raise
            stepper.destroy()
            raise e.__cause__ from None
        finally:
            steps.stop.restore()
        self._pop("solve", st, t0)
        return reason, failure

    def _status(self, stepper, reason: int, t_final: float, control) -> tuple[str, int, str | None]:
        """(status, exit code, message) of the run (manual, user guide)."""
        if stepper.stopped:
            return stepper.stop_status, 3, stepper.stopped
        if reason <= 0 or stepper.failure is not None:
            return "failed", 1, stepper.failure or failure_message(stepper.ts)
        if reason == PETSc.TS.ConvergedReason.CONVERGED_ITS and t_final < control.final_time * (1 - 1e-12):
            return "stopped", 4, (f"stopped by -ts_max_steps {stepper.ts.getStepNumber()} at t = "
                                  f"{t_final:.6g} s, before the end time {control.final_time:.6g} s; "
                                  f"continue with -thm_restart {self.outdir}")
        return "completed", 0, None

    def _finish(self, mesh, disc, stepper, reason, write_failure, steps, history, control) -> dict:
        scene, run, comm = self.scene, self.scene.run, self.comm
        self.proposals.drop_unused()
        t_final = stepper.ts.getTime()
        status, code, message = self._status(stepper, reason, t_final, control)
        if write_failure is not None:
            status, code = "failed", 1
            message = (f"{write_failure}; the last checkpoint ({self._checkpoint_time_text()}) is intact: "
                       f"free space, then continue with -thm_restart {self.outdir}")
        its = steps.whole_run_iterations()
        summary = {
            "scene": scene.name, "status": status, "exit_code": code,
            "reason": str(reason) + ("" if reason > 0 else " (TS diverged; last accepted state saved)"),
            "petthm_version": __version__, "petsc_version": compat.version_string(),
            "petsc4py_version": __import__("petsc4py").__version__,
            "ranks": comm.size, "cells": mesh.global_cell_count(), "fe_degree": run.fe_degree,
            "fields": [f.name for f in disc.fields], "dofs": disc.global_sizes(),
            "steps": stepper.ts.getStepNumber(), "rejected_steps": steps.rejected_before + stepper.rejected,
            "snes_iterations": its[0], "ksp_iterations": its[1],
            "final_time": t_final, "message": message,
        }
        if steps.resumed_from is not None:
            summary["restarted_from"] = steps.resumed_from
        st, t0 = self._stage("output")
        try:
            summary.update(self.monitor.report(self.problem, t_final))
            summary["provenance"] = {"git_commit": git_commit(), "mesh": self.mesh_path,
                                     "mesh_sha256": self.mesh_digest,
                                     "parameters": {k: v for p in scene.parameter_sets()
                                                    for k, v in P.values_in_effect(p).items()},
                                     "options": options_in_effect()}
            if write_failure is None:
                if status == "failed":
                    steps.write_fields(t_final)
                if not stepper.stopped:
                    self._checkpoint(stepper, steps)          # the last accepted state
        except WriteFailure as e:
            write_failure = write_failure or e
            summary.update(status="failed", exit_code=1, message=f"{e}; the last checkpoint "
                           f"({self._checkpoint_time_text()}) is intact: free space, then continue with "
                           f"-thm_restart {self.outdir}")
        history.close()
        stepper.destroy()
        self._pop("output", st, t0)
        summary["wall_time"] = dict(self.stage_wall, total=time.perf_counter() - self.t_start)
        summary["wall_time_whole_run"] = steps.wall_before + summary["wall_time"]["total"]
        summary["solver_costs"] = solver_costs()
        summary["peak_memory_mb"] = peak_memory_mb()
        summary["pc_rebuilds_forced"] = stepper.reuse.rebuilds if stepper.reuse is not None else None
        summary["limiter_settling_passes"] = steps.whole_run_settling_passes()
        try:
            write_summary(os.path.join(self.outdir, "summary.json"), summary, comm)
        except WriteFailure as e:
            _say(comm, f"petthm: {e} (summary.json not written)")
        self._say_end(summary, write_failure is not None)
        return summary

    def _say_end(self, summary: dict, write_failure: bool) -> None:
        """The last lines: why the run stopped (a write failure as the one
        line ``petthm: error:`` on stderr), the errors against the scene's
        reference, the status."""
        import sys
        comm = self.comm
        if write_failure and comm.rank == 0:
            print(f"petthm: error: {summary['message']}", file=sys.stderr, flush=True)
        elif summary["message"]:
            _say(comm, f"petthm: the run stopped: {summary['message']}")
        errors = {k: v for k, v in (summary.get("error") or {}).items() if v is not None}
        if errors:
            _say(comm, "errors against the reference: " + ", ".join(
                f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}" for k, v in errors.items()))
        _say(comm, f"{summary['status']}: t = {summary['final_time']:.4e} s in {summary['steps']} steps "
             f"({summary['rejected_steps']} rejected), {summary['wall_time']['total']:.2f} s, "
             f"peak memory {summary['peak_memory_mb']['max_rank']:.0f} MB per rank; output in {self.outdir}")

    def _checkpoint_time_text(self) -> str:
        import h5py
        text = "none written"
        if self.comm.rank == 0:
            try:
                with h5py.File(os.path.join(self.outdir, checkpoint.FILE), "r") as h5:
                    text = f"t = {float(h5.attrs['time']):.6g} s"
            except (OSError, KeyError):
                pass
        return self.mpi.bcast(text, root=0)

    def _checkpoint_due(self, step: int) -> bool:
        """Every -thm_checkpoint_interval steps, or when -thm_checkpoint_wall
        seconds have passed since the last checkpoint (rank 0's clock decides)."""
        run = self.scene.run
        if run.checkpoint_interval and step % run.checkpoint_interval == 0:
            return True
        return bool(run.checkpoint_wall) and self.mpi.bcast(
            time.perf_counter() - self._last_checkpoint >= run.checkpoint_wall, root=0)

    def past_wall_limit(self) -> bool:
        """Whether -thm_max_wall seconds have passed since the start (rank 0's clock decides)."""
        limit = self.scene.run.max_wall
        return bool(limit) and self.mpi.bcast(time.perf_counter() - self.t_start >= limit, root=0)

    def _checkpoint(self, stepper, steps) -> None:
        import json
        self._last_checkpoint = time.perf_counter()
        ts = stepper.ts
        meta = {"scene": self.scene.name, "time": ts.getTime(), "dt": ts.getTimeStep(),
                "step": ts.getStepNumber(), "rejected": steps.rejected_before + ts.getStepRejections(),
                "wall": steps.wall_before + time.perf_counter() - self.t_start,
                **({"mesh_sha256": self.mesh_digest} if self.mesh_digest else {}),
                **stepper.schedule_state()}
        records = {"options": json.dumps(option_record(self.scene, self.proposals)).encode(),
                   "monitor": checkpoint.pack_state(self.monitor.carried_state())}
        checkpoint.write(self.outdir, self.problem.X, self.problem.dm, meta, records)

    def check_unused_options(self) -> None:
        self.proposals.check_unused()



def run_scene(name: str) -> dict:
    """Run a scene from the options database; the summary (its ``exit_code``:
    manual, user guide).  A run refused for its input removes the files
    it wrote itself, so that the corrected command can start in the same folder."""
    run = Run(make_scene(name))
    try:
        return run.execute()
    except InputError:
        run.remove_own_output()
        raise
