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

from . import __version__, compat, params as P
from .constraints import boundary_entries
from . import checkpoint
from .errors import InputError, petsc_option_errors
from .fields import Discretisation
from .mesh import Mesh, distribute, label_boundaries, read_plex
from .model import Domain
from .monitors import contact_node_fields, hit
from .output import FieldWriter, History, write_summary
from .problem import Problem
from .scenes.base import REGISTRY
from .recipes import solver_defaults_by_size
from .solver import (SOLVER_DEFAULTS, StepControl, TimeStepper, error_control_defaults, failure_message,
                     propose_defaults, serial_plane_direct)

#: options PETSc reads only at finalize or start-up; never "unused"
_LATE_OPTIONS = ("log_view", "options_left", "options_file", "help", "malloc", "info",
                 "memory_view", "log_", "on_error", "no_signal_handler", "fp_trap",
                 "check_pointer_intensity", "viewer_binary", "history", "options_monitor", "mpi_")


#: a solver recipe may set the split of a field the scene does not have
_RECIPE_SPLITS = tuple(f"{pre}fieldsplit_{f}_" for f in ("u", "pm", "pf", "Tm", "Tf", "lam",
                                                         "rest") for pre in ("", "vi_"))


def _say(comm, msg):
    if comm.rank == 0:
        print(msg, flush=True)


def check_unused_petsc_options() -> None:
    """Raise InputError naming the first option nothing has read (a misspelling)."""
    from .solver import PROPOSED
    left = [o for o in compat.unused_options()
            if not o.startswith(_LATE_OPTIONS + _RECIPE_SPLITS) and o not in PROPOSED]
    if left:
        raise InputError(f"option -{left[0]} was not used by any solver or petthm component "
                         "(misspelt, or not valid for this scene)")


def drop_unused_proposals() -> None:
    """Remove the solver options petthm proposed that no solver read (e.g.
    the direct-solver defaults when a recipe picks another preconditioner),
    so that PETSc's report of unused options at exit names only the user's."""
    from .solver import PROPOSED
    opts = PETSc.Options()
    for o in compat.unused_options():
        if o in PROPOSED:
            opts.delValue(o)


def make_scene(name: str):
    from .scenes import load
    load(name)
    if name not in REGISTRY:
        raise InputError(f"unknown scene '{name}'; scenes: {', '.join(sorted(REGISTRY))}")
    cls = REGISTRY[name]
    run = P.read(P.RunParams)
    P.check_unknown_thm_options((P.RunParams,) + tuple(cls.parameters))
    return cls.read(run)


#: the PETSc and petthm events whose count and time summary.json reports
SOLVER_EVENTS = ("SNESSolve", "SNESJacobianEval", "KSPSolve", "PCSetUp", "PCApply", "thm.residual",
                 "thm.jacobian")


def solver_costs() -> dict:
    """{event: {"count", "time" (s, the largest over ranks)}} of the solve stage."""
    stage = PETSc.Log.Stage("solve")
    comm = PETSc.COMM_WORLD.tompi4py()
    out = {}
    for name in SOLVER_EVENTS:
        info = PETSc.Log.Event(name).getPerfInfo(stage)
        out[name] = {"count": int(info["count"]), "time": comm.allreduce(float(info["time"]), op=_mpi_max())}
    return out


def peak_memory_mb() -> dict:
    """Peak resident memory (MB): the largest rank's, rank 0's (which reads
    and meshes before the distribution) and the sum over ranks."""
    import resource
    mine = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0      # kB on Linux
    comm = PETSc.COMM_WORLD.tompi4py()
    return {"max_rank": comm.allreduce(mine, op=_mpi_max()), "rank0": comm.bcast(mine, root=0),
            "total": comm.allreduce(mine)}


def _mpi_max():
    from mpi4py import MPI
    return MPI.MAX


def git_commit() -> str | None:
    """The petthm source's git commit (+ "-dirty" with uncommitted changes), or None."""
    import subprocess
    here = os.path.dirname(os.path.abspath(__file__))
    try:
        rev = subprocess.run(["git", "-C", here, "rev-parse", "HEAD"], capture_output=True, text=True,
                             timeout=10)
        if rev.returncode:
            return None
        dirty = subprocess.run(["git", "-C", here, "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=10).stdout.strip()
        return rev.stdout.strip() + ("-dirty" if dirty else "")
    except (OSError, subprocess.SubprocessError):
        return None


def options_in_effect() -> dict[str, str]:
    """Every PETSc option in the database (the user's and petthm's proposals)."""
    return {"-" + k: v for k, v in sorted(PETSc.Options().getAll().items())}


class Run:
    """One simulation of a scene (collective on PETSc.COMM_WORLD)."""

    def __init__(self, scene):
        self.scene = scene
        self.comm = PETSc.COMM_WORLD
        self.mpi = self.comm.tompi4py()
        run = scene.run
        if run.restart:
            if run.output_dir and os.path.abspath(run.output_dir) != os.path.abspath(run.restart):
                raise InputError(f"options -thm_restart = {run.restart} and -thm_output_dir = "
                                 f"{run.output_dir}: a restart goes on in the folder of the run it "
                                 "continues (give -thm_restart alone)")
            if not os.path.isdir(run.restart):
                raise InputError(f"option -thm_restart = {run.restart}: no such folder")
            checkpoint.check(run.restart, scene.name)
        self.outdir = scene.output_dir
        self.stage_wall = {}
        self.t_start = time.perf_counter()
        self._last_checkpoint = self.t_start
        self.mesh_path = run.mesh_file
        written = os.path.join(run.restart, "mesh.msh") if run.restart else ""
        if not self.mesh_path and written and os.path.isfile(written):
            self.mesh_path = written                  # the very mesh of the run a restart continues
        self.problem: Problem | None = None
        PETSc.Log.begin()                   # event counts and times for summary.json's solver_costs

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
        self._on_rank0(lambda: os.makedirs(self.outdir, exist_ok=True), OSError,
                       lambda e: f"option -thm_output_dir = {self.outdir}: the folder cannot be created "
                                 f"({e.strerror or e})")
        path = self.mesh_path
        if not path:
            path = os.path.join(self.outdir, "mesh.msh")
            size = run.mesh_size or scene.time.mesh_size
            from .meshing import set_cell_limit

            def generate():
                set_cell_limit(run.max_cells)
                scene.generate_mesh(path, size)
            self._on_rank0(generate, InputError, str)
        with petsc_option_errors(f"the mesh file '{path}'"):
            dm = read_plex(path, self.comm)
        want, option = scene.mesh_dimension()
        if want and dm.getDimension() != want:
            raise InputError(f"mesh '{path}' is {dm.getDimension()}D, but scene {scene.name} is {want}D"
                             + (f" (option -{option} = {want})" if option else ""))
        with self._user_mesh_fits(dm.getDimension()):
            label_boundaries(dm, scene.boundaries())
        from .fracture import split_fractures
        dm, _ = split_fractures(dm)
        mesh = Mesh(distribute(dm))
        self._pop("mesh", st, t0)
        self.mesh_path = path
        return mesh

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
        an ``InputError`` (``message(exception)``) on every rank alike."""
        error = None
        if self.comm.rank == 0:
            try:
                action()
            except errors as e:
                error = message(e)
        error = self.mpi.bcast(error, root=0)
        if error:
            raise InputError(error)

    def _check_fractures(self, mesh: Mesh, model) -> None:
        wants = any(f.region is Domain.FRACTURE for f in model.fields)
        if wants and mesh.fracture is None:
            raise InputError(f"mesh '{self.mesh_path}' has no fracture (physical group 10, 11, ... of "
                             f"facets), which scene {self.scene.name} needs")
        if not wants and mesh.fracture is not None:
            raise InputError(f"mesh '{self.mesh_path}' has fractures (physical groups 10, 11, ...), "
                             f"but scene {self.scene.name} has no fracture physics")

    #: rock layers thinner than this fraction of the fracture's cells: the wall term over/undershoots
    THIN_WALL_LAYER = 0.05

    def _warn_thin_wall_layers(self, mesh: Mesh) -> None:
        """-thm_fracture_supg_wall_conduction on a mesh whose rock cells next
        to the fracture are much thinner than its cells: a one-line warning
        (measured: Tf left [Tinj, T0] by 0.1-1.3 % at ratios 0.005-0.02 in
        Scene 1 and by 6 % at 0.025 in Scene 2, 0 % at 0.05; docs/fracture_th.md)."""
        if not getattr(self.scene.p, "fracture_supg_wall_conduction", False) or mesh.fracture is None:
            return
        ratio = mesh.fracture.thinnest_wall_layer()
        if ratio < self.THIN_WALL_LAYER:
            _say(self.comm, f"petthm: warning: -thm_fracture_supg_wall_conduction on rock layers "
                 f"{ratio:.3g} times as thick as the fracture's cells (< {self.THIN_WALL_LAYER:g}): "
                 "Tf left [Tinj, T0] by up to 6 % on meshes with such layers; check "
                 "Tf_bounds_violation (docs/fracture_th.md)")

    def setup(self, mesh: Mesh):
        scene, run = self.scene, self.scene.run
        st, t0 = self._stage("setup")
        with self._user_mesh_fits(mesh.dim):
            setup = scene.build(mesh, run.fe_degree)
        model = setup.model
        self._check_fractures(mesh, model)
        self._warn_thin_wall_layers(mesh)
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
        rs = problem.auto_residual_scales(0.0, 1.0 / control.dt_initial)
        scene_defaults = dict(SOLVER_DEFAULTS, **scene.solver_defaults(self.comm),
                              **(error_control_defaults(control) if run.dt_control == "error" else {}))
        scene_defaults = serial_plane_direct(scene_defaults, mesh.dim, self.comm.size, bool(model.bounds))
        snes_type = PETSc.Options().getString("snes_type", scene_defaults["snes_type"])
        propose_defaults(solver_defaults_by_size(scene_defaults, model.has("u"), problem.X.getSize(),
                                                 run.direct_max_unknowns, scene.block_recipe(snes_type)))
        self._pop("setup", st, t0)
        self.problem = problem
        return disc, problem, control, rs, setup.monitor

    def execute(self) -> dict:
        scene, run = self.scene, self.scene.run
        comm = self.comm
        mesh = self.build_mesh()
        disc, problem, control, rscales, scene_monitor = self.setup(mesh)
        sizes = disc.global_sizes()
        _say(comm, f"petthm {__version__} | scene {scene.name} | {comm.size} rank(s) | "
             f"{mesh.global_cell_count()} cells | P{run.fe_degree} | dofs "
             + ", ".join(f"{k}={v}" for k, v in sizes.items()))
        _say(comm, "scales: " + ", ".join(
            f"{k}: x = {problem.scales[k].offset:g} + {problem.scales[k].scale:g} x_hat, "
            f"residual / {rscales[k]:.3e}" for k in sizes))

        st, t0 = self._stage("output")
        groups = {}                        # one writer per (region, degree): fields, fields_p1, fracture
        for f in disc.fields:
            groups.setdefault((f.region, f.degree), []).append(f)
        top = {r: max(d for rr, d in groups if rr == r) for r, _ in groups}
        resume = self._restore(problem) if run.restart else None
        t_resume = resume["time"] if resume else None
        writers = [(FieldWriter(disc, self.outdir, d, ("fields" if r is Domain.MATRIX else "fracture")
                                + ("" if d == top[r] else f"_p{d}"), r, resume_at=t_resume), fields)
                   for (r, d), fields in groups.items()]
        columns = ["step", "time", "dt", "snes_its", "ksp_its", "wall"] + list(scene.history_columns)
        history = History(os.path.join(self.outdir, "history.csv"), columns, comm.rank, append=bool(resume))
        stop = checkpoint.StopRequest()
        self._pop("output", st, t0)
        interval = run.output_interval or scene.time.output_interval
        stepper = None
        state = {"its": (0, 0), "wall": time.perf_counter(), "last_t": 0.0, "rows": 0, "step_walls": []}

        def write_fields(t):
            s, t1 = self._stage("output")
            for w, fields in writers:
                out = {f.name: self._si_out(problem, f.name, t) for f in fields}
                if any(f.name == "lam" for f in fields):          # opening, aperture, slip, ...
                    out.update({k: v for k, v in contact_node_fields(problem, t=t).items()
                                if k not in ("weight", "slipping_area")})
                w.write(t, out)
            self._pop("output", s, t1)

        def monitor(step, t, X):
            if state["rows"] and t == state["last_t"]:    # TS's last call after a failed step: no new state
                return
            state["rows"] += 1
            snes_its, ksp_its = stepper.iterations() if stepper else (0, 0)
            dn, dk = snes_its - state["its"][0], ksp_its - state["its"][1]
            state["its"] = (snes_its, ksp_its)
            dt = t - state["last_t"]
            state["last_t"] = t
            wall = time.perf_counter() - self.t_start
            row = {"step": step, "time": t, "dt": dt, "snes_its": dn, "ksp_its": dk, "wall": wall}
            row.update(scene_monitor(problem, t, X))
            if resume and t == t_resume:                  # the state the restart starts from is written
                return
            history.write(row)
            if step == 1:
                check_unused_petsc_options()
            if step % interval == 0 or t >= control.final_time * (1 - 1e-12) or hit(t, control.hit_times):
                write_fields(t)                           # and at the times the scene lands on
            if step > 0 and self._checkpoint_due(step):
                self._checkpoint(stepper)
            reason = scene_monitor.stop_reason()
            if reason:
                stepper.fail(f"{reason} (t = {t:.6g} s, step {step})")
                return
            received = stop.agreed(comm)
            if received:
                self._checkpoint(stepper)
                stepper.request_stop(f"stopped by {received} at t = {t:.6g} s after step {step}; "
                                     f"continue with -thm_restart {self.outdir}")
            now = time.perf_counter()
            state["step_walls"] = (state["step_walls"] + [now - state["wall"]])[-5:]
            state["wall"] = now
            if not run.quiet and step > 0:
                frac = t / control.final_time
                eta = control.steps_left(t, dt) * sum(state["step_walls"]) / len(state["step_walls"])
                _say(comm, f"step {step:5d}  t = {t:.4e} s  dt = {dt:.3e} s  newton {dn:2d}  "
                     f"krylov {dk:4d}  {100 * frac:5.1f} %  left ~{eta:7.1f} s")

        with petsc_option_errors("the solver options (-ts_*, -snes_*, -ksp_*, -pc_*)"):
            stepper = TimeStepper(problem, control, monitor)
        if resume:
            stepper.resume(resume["time"], resume["dt"], resume["step"],
                           {k: resume[k] for k in stepper.schedule_state() if k in resume})
        st, t0 = self._stage("solve")
        state["wall"] = time.perf_counter()
        stop.install()
        try:
            reason = stepper.solve()
        except InputError:             # raised on every rank alike in a Python PC's set-up (-vi_groups)
            stepper.destroy()          # now: a Python PC left mid-set-up crashed PETSc's exit
            raise
        except PETSc.Error as e:       # PETSc >= 3.20 hands it back as error 101, the InputError its cause
            if not isinstance(e.__cause__, InputError):
                raise
            stepper.destroy()
            raise e.__cause__ from None
        finally:
            stop.restore()
        self._pop("solve", st, t0)
        drop_unused_proposals()
        t_final = stepper.ts.getTime()
        failed = reason <= 0 or stepper.failure is not None
        status = "interrupted" if stepper.stopped else "failed" if failed else "completed"
        summary = {
            "scene": scene.name, "status": status,
            "reason": str(reason) + ("" if reason > 0 else " (TS diverged; last accepted state saved)"),
            "petthm_version": __version__, "petsc_version": compat.version_string(),
            "petsc4py_version": __import__("petsc4py").__version__,
            "ranks": comm.size, "cells": mesh.global_cell_count(), "fe_degree": run.fe_degree,
            "fields": [f.name for f in disc.fields], "dofs": sizes,
            "steps": stepper.ts.getStepNumber(), "rejected_steps": stepper.rejected,
            "snes_iterations": stepper.iterations()[0], "ksp_iterations": stepper.iterations()[1],
            "final_time": t_final,
            "message": stepper.stopped or stepper.failure or
            (None if reason > 0 else failure_message(stepper.ts)),
        }
        st, t0 = self._stage("output")
        summary.update(scene_monitor.report(problem, t_final))
        summary["provenance"] = {"git_commit": git_commit(), "mesh": self.mesh_path,
                                 "parameters": P.values_in_effect(run) | P.values_in_effect(scene.p),
                                 "options": options_in_effect()}
        if status == "failed":
            write_fields(t_final)
        if not stepper.stopped:
            self._checkpoint(stepper)                     # the last accepted state
        history.close()
        stepper.destroy()
        self._pop("output", st, t0)
        summary["wall_time"] = dict(self.stage_wall, total=time.perf_counter() - self.t_start)
        summary["solver_costs"] = solver_costs()
        summary["peak_memory_mb"] = peak_memory_mb()
        summary["pc_rebuilds_forced"] = stepper.reuse.rebuilds if stepper.reuse is not None else None
        write_summary(os.path.join(self.outdir, "summary.json"), summary, comm.rank)
        if summary["message"]:
            _say(comm, f"petthm: the run stopped: {summary['message']}")
        _say(comm, f"{status}: t = {t_final:.4e} s in {summary['steps']} steps "
             f"({summary['rejected_steps']} rejected), {summary['wall_time']['total']:.2f} s, "
             f"peak memory {summary['peak_memory_mb']['max_rank']:.0f} MB per rank; output in {self.outdir}")
        return summary

    def _restore(self, problem) -> dict:
        """Load the checkpoint of the run a restart continues (the state
        after problem set-up: the same scales, proposals and initial
        conditions as the original run) and drop its history rows after it."""
        meta = checkpoint.read(self.outdir, problem.X, problem.dm, self.scene.name)
        if self.comm.rank == 0:
            checkpoint.truncate_history(os.path.join(self.outdir, "history.csv"), meta["time"])
        _say(self.comm, f"restart from {os.path.join(self.outdir, checkpoint.FILE)}: "
             f"t = {meta['time']:.6g} s, step {meta['step']}")
        return meta

    def _checkpoint_due(self, step: int) -> bool:
        """Every -thm_checkpoint_interval steps, or when -thm_checkpoint_wall
        seconds have passed since the last checkpoint (rank 0's clock decides)."""
        run = self.scene.run
        if run.checkpoint_interval and step % run.checkpoint_interval == 0:
            return True
        return bool(run.checkpoint_wall) and self.comm.tompi4py().bcast(
            time.perf_counter() - self._last_checkpoint >= run.checkpoint_wall, root=0)

    def _checkpoint(self, stepper) -> None:
        self._last_checkpoint = time.perf_counter()
        ts = stepper.ts
        checkpoint.write(self.outdir, self.problem.X, self.problem.dm, {
            "scene": self.scene.name, "time": ts.getTime(), "dt": ts.getTimeStep(),
            "step": ts.getStepNumber(), "rejected": ts.getStepRejections(),
            **stepper.schedule_state()})

    @staticmethod
    def _si_out(problem, name, t):
        v = problem.field_values(name, t=t)
        return v - P.CELSIUS if name.startswith("T") else v


def run_scene(name: str) -> dict:
    scene = make_scene(name)
    return Run(scene).execute()
