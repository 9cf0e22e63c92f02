"""What a run does after every accepted step (and for the initial state):
the history row, field output, checkpoints, the checks that stop a run
(the scene's verdict, a signal, ``-thm_max_wall``), the progress line
(manual: "Running"; ``app.Run`` owns the phases this calls back into)."""
from __future__ import annotations

import time

from petthm.io import checkpoint
from petthm.physics.monitors import hit


def _say(comm, msg):
    if comm.rank == 0:
        print(msg, flush=True)


class StepReport:
    """What happens after every accepted step (and for the initial state):
    the history row, field output, checkpoints, and the checks that stop a
    run (the scene's verdict, a signal, -thm_max_wall), then the progress line."""

    def __init__(self, run, problem, control, scene_monitor, writers, history, resume):
        self.run, self.problem, self.control = run, problem, control
        self.scene_monitor, self.writers, self.history = scene_monitor, writers, history
        self.resume = resume
        self.t_resume = resume["time"] if resume else None
        self.resumed_from = {"time": resume["time"], "step": int(resume["step"])} if resume else None
        self.rejected_before = int(resume.get("rejected", 0)) if resume else 0
        self.wall_before = float(resume.get("wall", 0.0)) if resume else 0.0
        self.stepper = None
        self.stop = checkpoint.StopRequest()
        self.its = (0, 0)
        self.settles = problem.has_tightening()        # the limited heat transport: passes per step
        self.passes = 0
        self.wall = time.perf_counter()
        self.last_t = 0.0
        self.rows = 0
        self.step_walls: list[float] = []
        self.interval = run.scene.run.output_interval or run.scene.time.output_interval

    def write_fields(self, t: float) -> None:
        run, problem = self.run, self.problem
        s, t1 = run._stage("output")
        for w, fields in self.writers:
            out = {f.name: f.output(problem.field_values(f.name, t=t)) for f in fields}
            names = {f.name for f in fields}
            for extra in problem.model.outputs:                   # e.g. the contact's opening, aperture, slip
                if extra.like in names:
                    out.update(extra.fields(problem, t))
            w.write(t, out)
        run._pop("output", s, t1)

    def _whole_run_sums(self, columns) -> tuple[int, ...] | None:
        """history.csv's sums of ``columns`` over the whole run (a restart's
        file holds the rows of the run it continues); None where the file
        lacks them (collective)."""
        import csv
        totals = None
        if self.run.comm.rank == 0:
            try:
                with open(self.history.path, newline="") as f:
                    rows = list(csv.DictReader(f))
                totals = tuple(sum(int(float(r[k] or 0)) for r in rows) for k in columns)
            except (OSError, KeyError, ValueError, TypeError):
                totals = None
        return self.run.mpi.bcast(totals, root=0)

    def whole_run_iterations(self) -> tuple[int, int]:
        """(Newton, Krylov) iterations of the whole run."""
        totals = self._whole_run_sums(("snes_its", "ksp_its"))
        return totals if totals is not None else self.stepper.iterations()

    def whole_run_settling_passes(self) -> int | None:
        """The limited heat transport's settling passes of the whole run
        (None without it)."""
        if not self.settles:
            return None
        totals = self._whole_run_sums(("settling_passes",))
        return totals[0] if totals is not None else self.stepper.settling.passes

    def __call__(self, step, t, X):
        run, stepper, control = self.run, self.stepper, self.control
        if self.rows and t == self.last_t:    # TS's last call after a failed step: no new state
            return
        self.rows += 1
        snes_its, ksp_its = stepper.iterations() if stepper else (0, 0)
        dn, dk = snes_its - self.its[0], ksp_its - self.its[1]
        self.its = (snes_its, ksp_its)
        dt = t - self.last_t
        self.last_t = t
        row = {"step": step, "time": t, "dt": dt, "snes_its": dn, "ksp_its": dk}
        if self.settles:
            passes = stepper.settling.passes if stepper else 0
            row["settling_passes"], self.passes = passes - self.passes, passes
        row["wall"] = time.perf_counter() - run.t_start + self.wall_before
        row.update(self.scene_monitor(self.problem, t, X))
        if self.resume and t == self.t_resume:            # the state the restart starts from is written
            return
        self.history.write(row)
        if step == 1:
            self.run.check_unused_options()
        if step % self.interval == 0 or t >= control.final_time * (1 - 1e-12) or hit(t, control.hit_times):
            self.write_fields(t)                          # and at the times the scene lands on
        if step > 0 and run._checkpoint_due(step):
            run._checkpoint(stepper, self)
        if self._stopped(step, t):
            return
        self._progress(step, t, dt, dn, dk)

    def _stopped(self, step: int, t: float) -> bool:
        """Stop after this step if the scene says the run cannot go on, a
        signal came, or -thm_max_wall has passed (the last two with a checkpoint)."""
        run, stepper = self.run, self.stepper
        reason = self.scene_monitor.stop_reason()
        if reason:
            stepper.fail(f"{reason} (t = {t:.6g} s, step {step})")
            return True
        received = self.stop.agreed(run.comm)
        limit = not received and run.past_wall_limit()
        if received or limit:
            run._checkpoint(stepper, self)
            cause = f"{received}" if received else f"-thm_max_wall {run.scene.run.max_wall:g} s"
            stepper.request_stop(f"stopped by {cause} at t = {t:.6g} s after step {step}; continue with "
                                 f"-thm_restart {run.outdir}",
                                 status="interrupted" if received else "stopped")
            return True
        return False

    def _progress(self, step, t, dt, dn, dk) -> None:
        now = time.perf_counter()
        self.step_walls = (self.step_walls + [now - self.wall])[-5:]
        self.wall = now
        if self.run.scene.run.quiet or step <= 0:
            return
        frac = t / self.control.final_time
        eta = self.control.steps_left(t, dt) * sum(self.step_walls) / len(self.step_walls)
        _say(self.run.comm, f"step {step:5d}  t = {t:.4e} s  dt = {dt:.3e} s  newton {dn:2d}  "
             f"krylov {dk:4d}  {100 * frac:5.1f} %  left ~{eta:7.1f} s")


__all__ = ["StepReport"]
