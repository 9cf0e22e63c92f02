"""TS (backward Euler) + SNES + KSP around a ``problem.Problem``: solver
step control, VI bounds and field splits, monitors (the solver options it
starts from: ``solvers.options``).

theory manual, "Time stepping and solvers": monolithic Newton inside backward Euler; user-set
first step, growth factor and largest step; a failed nonlinear solve is
retried with a step four times smaller (PETSc's TSAdapt does this), up to
``-ts_max_reject`` times, after which the run stops with the last accepted
state.
"""
from __future__ import annotations

import dataclasses
import math
import sys
import traceback
from collections.abc import Callable

from petsc4py import PETSc

from petthm.discretisation.problem import Problem
from petthm.errors import InputError, WriteFailure
from petthm.solvers import fieldsplit
from petthm.solvers.courant import FrontStepLimit
from petthm.solvers.fieldsplit import VIFieldSplit  # noqa: F401  (-pc_python_type petthm.solvers.timestepper.VIFieldSplit)
from petthm.solvers.options import Proposals
from petthm.solvers.predictor import LinearPredictor
from petthm.solvers.settling import Settling
from petthm.solvers.snes_hooks import BiactiveRelease, PreconditionerReuse, SNESUpdates
from petthm.solvers.stepcontrol import RECOVERY, StepControl, error_control_defaults  # noqa: F401  (re-exported)
from petthm.solvers.viconvergence import DefaultConvergence, VIConvergence


def failure_message(ts: PETSc.TS) -> str:
    """Why a run stopped: the TS reason, and the last SNES and KSP reasons."""
    snes = ts.getSNES()
    parts = [f"TS {_reason_name(PETSc.TS.ConvergedReason, ts.getConvergedReason())} at "
             f"t = {ts.getTime():.6g} s (last step tried {ts.getTimeStep():.3g} s, "
             f"{ts.getStepRejections()} rejected in all)",
             f"SNES {_reason_name(PETSc.SNES.ConvergedReason, snes.getConvergedReason())} "
             f"after {snes.getIterationNumber()} Newton iterations",
             f"KSP {_reason_name(PETSc.KSP.ConvergedReason, snes.getKSP().getConvergedReason())}"]
    return "; ".join(parts)


def _reason_name(kind, value: int) -> str:
    names = [k for k in dir(kind) if not k.startswith("_") and getattr(kind, k) == value]
    preferred = [k for k in names if not k.endswith("_ITERATING")] or names
    return f"{preferred[0] if preferred else 'REASON'} ({int(value)})"


#: preconditioners that are a direct solve (``-thm_pc_reuse auto`` reuses them)
DIRECT_PCS = ("lu", "cholesky", "redundant")


class TimeStepper:
    """Backward-Euler TS on a ``Problem`` with growth-limited steps and monitors."""

    predictor: LinearPredictor | None = None     # Newton's start of a step (-thm_predictor)

    def __init__(self, problem: Problem, control: StepControl,
                 monitor: Callable[[int, float, float], None] | None = None,
                 proposals: Proposals | None = None):
        """``proposals``: the run's ``options.Proposals``, which petthm's Python
        preconditioners add their own proposals to (a new one if None)."""
        self.problem, self.control = problem, control
        ts = self.ts = PETSc.TS().create(comm=problem.dm.comm)
        ts.setDM(problem.dm)
        ts.setProblemType(PETSc.TS.ProblemType.NONLINEAR)
        ts.setType(PETSc.TS.Type.BEULER)
        ts.setIFunction(problem.ifunction, problem.dm.createGlobalVec())
        J = problem.create_matrix()
        ts.setIJacobian(problem.ijacobian, J, J)
        ts.setTime(0.0)
        ts.setTimeStep(control.dt_initial)
        ts.setMaxTime(control.final_time)
        ts.setMaxSteps(10 ** 9)
        ts.setExactFinalTime(PETSc.TS.ExactFinalTime.MATCHSTEP)
        ts.setMaxSNESFailures(-1)          # every failed solve is retried with a smaller step,
        ts.setMaxStepRejections(8)         # at most 8 times in a row (-ts_max_reject /
        ts.setFromOptions()                # -ts_max_step_rejections override)
        ts.setErrorIfStepFails(False)
        if not ts.getMaxTime() > 0.0:
            raise InputError(f"option -ts_max_time = {ts.getMaxTime():g}: the end time must be > 0 s "
                             "(or use -thm_final_time)")
        #: the schedule this stepper runs: the caller's, with -ts_max_time's end if given
        self.control = control = dataclasses.replace(control, final_time=ts.getMaxTime())
        self.snes = ts.getSNES()
        self.updates = SNESUpdates()
        self.snes.setUpdate(self.updates)
        self._set_convergence(problem)
        pc = ts.getSNES().getKSP().getPC()
        self.context = fieldsplit.SolverContext(problem, self.snes, proposals)
        self._set_field_splits(pc)
        # a reused factorisation is an inexact solve: a Krylov method must correct it
        krylov = ts.getSNES().getKSP().getType() != "preonly"
        # auto: not with friction, whose semismooth law's Jacobian jumps at every stick-slip
        # switch (friction_patch 3D on 2 ranks: 7 Newton with 93 Krylov per step reused, 7 with 7 not)
        wanted = control.pc_reuse == "on" or (control.pc_reuse == "auto" and pc.getType() in DIRECT_PCS
                                              and not problem.model.has("tau"))
        reuse = krylov and wanted
        self.reuse = PreconditionerReuse(ts, control.pc_reuse_max_krylov) if reuse else None
        if self.reuse is not None:
            self.updates.hooks.append(self.reuse)
        self.predictor = LinearPredictor(ts) if control.predictor == "linear" else None
        if self.predictor is not None:
            self.snes.setInitialGuess(self.predictor)
        ts.setPostStep(self._post_step)
        self._user_monitor = monitor
        ts.setMonitor(self._monitor)
        self.rejected = 0
        self.error = None
        self.stopped: str | None = None          # why the run was stopped (a signal, -thm_max_wall)
        self.stop_status = "interrupted"         # its status: interrupted (a signal) or stopped
        self.failure: str | None = None          # why the run was stopped as failed (not a TS reason)
        adaptive = PETSc.Options(ts.getOptionsPrefix()).getString("ts_adapt_type", "none") != "none"
        self._start_schedule(control, ts.getTimeStep(), adaptive)
        self._reported = None                    # (step, t) the user's monitor saw last

    def _start_schedule(self, control: StepControl, first_dt: float, adaptive: bool = False) -> None:
        """The step schedule's memory (``_post_step``), before the first step;
        ``adaptive``: the TS chooses the steps (-ts_adapt_type other than none:
        -thm_dt_control error), the schedule only lands them on the hit times."""
        self.control = control
        self.adaptive = adaptive
        self._last_dt_cut = None                 # the step a hit time cut short, to go on with
        self._proposed = first_dt                # the step proposed for the step being taken
        self._recover_to = None                  # the schedule's step, while a cut step grows back
        self._rejections_seen = 0
        self.front_limit = FrontStepLimit(getattr(self, "problem", None), control.courant)   # -thm_dt_courant

    def _set_field_splits(self, pc):
        """A field-split preconditioner gets one split per field, named by the
        field (-fieldsplit_u_..., -fieldsplit_pm_...), with the rigid-body
        modes on u, unless the options group fields themselves
        (-pc_fieldsplit_0_fields ...).  A Python PC (``VIFieldSplit``,
        ``ContactNullspacePC``) is given the run's ``SolverContext``."""
        if pc.getType() == "python":
            fieldsplit.serve(pc, self.context)
            return
        if pc.getType() != "fieldsplit" or PETSc.Options().hasName("pc_fieldsplit_0_fields"):
            return
        pc.setFieldSplitIS(*[(s.name, s.iset) for s in fieldsplit.field_splits(self.context)])

    def _set_convergence(self, problem: Problem) -> None:
        """The VI bounds and Newton's convergence test: SNES's own, the VI one
        with -snes_stol (``VIConvergence``), and around either the limited
        heat transport's settling of each step (``Settling``)."""
        self.convergence = None                  # a Python convergence test, where petthm sets one
        if problem.model.bounds:
            self._set_bounds(self.snes)
        self.settling = None
        if problem.has_tightening():
            self.settling = Settling(problem, self.ts, self.convergence or DefaultConvergence())
            self.settling.install(self.snes)

    def _set_bounds(self, snes):
        """Variable bounds (contact) need one of SNES's VI Newton methods."""
        if snes.getType() not in ("vinewtonrsls", "vinewtonssls"):
            raise InputError(f"-snes_type {snes.getType()} cannot honour the contact bounds of "
                             f"{', '.join(self.problem.model.bounds)}: use vinewtonrsls or vinewtonssls")
        lower, upper = self.problem.variable_bounds()
        snes.setVariableBounds(lower, upper)
        if snes.getType() == "vinewtonrsls":     # its default test ignores -snes_stol
            self.convergence = VIConvergence()
            self.convergence.install(snes)
        self.updates.hooks.append(BiactiveRelease(lower))

    def _post_step(self, ts):
        """Grow the step, clipped to the largest step and to the final time;
        free the PETSc objects Python let go of during the step (petsc4py
        keeps those of a parallel communicator until this collective call)."""
        PETSc.garbage_cleanup(ts.comm)
        if self.predictor is not None:
            self.predictor.accepted(ts.getTime(), ts.getSolution())
        c = self.control
        t = ts.getTime()
        if c.collapsed(ts.getTimeStep(), t):
            tries = ts.getStepRejections()
            cause = (f"after {tries} rejected tries" if tries else
                     f"none rejected: the schedule's growth factor {c.growth:g} < 1 shrank it")
            self.failure = (f"the time step collapsed to {ts.getTimeStep():.3g} s at t = {t:.6g} s "
                            f"(below {c.dt_floor():.3g} s, {cause}): the run cannot go on")
            self._stop_now()
            return
        if self.adaptive:                      # the TS's error estimate chose the next step
            self._land_on_hit_times(ts, t, self.front_limit(ts, ts.getTimeStep()))
            return
        taken = ts.getTimeStep()
        cut = ts.getStepRejections() > self._rejections_seen       # rejected tries cut this step
        self._rejections_seen = ts.getStepRejections()
        dt = min(taken * c.growth, c.dt_max)
        if cut and self._recover_to is None:     # a landing step cut again: back to the step it replaced
            self._recover_to = self._last_dt_cut if self._last_dt_cut is not None else self._proposed
        if self._recover_to is not None:        # grow back to where the schedule would be
            self._recover_to = min(self._recover_to * c.growth, c.dt_max)
            dt = min(max(RECOVERY, c.growth) * taken, self._recover_to)
            if dt >= self._recover_to * (1 - 1e-12):
                self._recover_to = None
        if self._last_dt_cut is not None and not cut:    # resume the growth sequence after a hit
            dt = min(self._last_dt_cut, c.dt_max)
        self._last_dt_cut = None
        self._land_on_hit_times(ts, t, self.front_limit(ts, dt))

    def _land_on_hit_times(self, ts, t: float, dt: float) -> None:
        """Propose the next step dt, cut to land on the next hit time or the
        final time (the step it cut is kept for after it); then the monitor.
        A target closer than two steps is reached in two equal steps, not in
        a full step and a sliver: a sliver 1e3 times shorter than the steps
        around it (Scene 3 at 20 years: 6 500 s after 0.2-year steps) fails
        its linear solve with a preconditioner kept from the long steps, and
        its rejection would restart the growth from the sliver."""
        landed = self._landing(t, dt)
        if landed != dt:
            self._last_dt_cut, dt = dt, landed
        remaining = self.control.final_time - t
        if remaining > 0:
            ts.setTimeStep(min(dt, remaining))
        self._proposed = dt
        self._monitor(ts, ts.getStepNumber(), t, ts.getSolution())

    def _landing(self, t: float, dt: float) -> float:
        """The step from t: dt, or cut to land on the next hit time or the
        final time (in two equal steps when it is closer than two)."""
        c = self.control
        upcoming = [h - t for h in (*c.hit_times, c.final_time) if h - t > 1e-9 * max(abs(t), 1.0)]
        gap = min(upcoming, default=math.inf)
        if gap < dt * (1 + 1e-9):
            return gap
        return 0.5 * gap if gap < 2.0 * dt else dt

    def _land_first_step(self) -> None:
        """The landing rule for the first step of a run or of a restart (a
        restart's step was proposed for the final time of the run it came
        from: resumed 0.3 s short of a new final time it took a full step and
        then a 0.3-s sliver); the step it cuts is kept for after the hit."""
        t, dt = self.ts.getTime(), self.ts.getTimeStep()
        landed = self._landing(t, dt)
        if landed < dt * (1 - 1e-12):
            if self._last_dt_cut is None:
                self._last_dt_cut = dt
            self.ts.setTimeStep(landed)
            self._proposed = landed

    def _monitor(self, ts, step, t, X):
        """Call the user's monitor once per state: from the post-step of
        every accepted step (so that a stop it asks for ends TSSolve at
        once: TS resets a reason set in TSMonitor when it starts the next
        step) and from TSMonitor for the initial state.  An exception stops
        the run cleanly and is re-raised by ``solve`` (exceptions must not
        cross the C callback).  In parallel a failure on some ranks only
        would leave the others waiting in the next step's collectives (and
        they may be inside the monitor's own), so the failing rank prints
        its traceback and aborts the whole run; an ``InputError`` (an unused
        option, found after the first step) is raised on every rank alike and
        ends the run as one."""
        if self._user_monitor is None or self.error is not None or self._reported == (step, t):
            return
        self._reported = (step, t)
        try:
            self._user_monitor(step, t, X)
        except Exception as e:  # noqa: BLE001 - re-raised after TSSolve returns
            if ts.comm.size > 1 and not isinstance(e, (InputError, WriteFailure)):
                _abort_all(ts.comm,
                           f"rank {ts.comm.rank}: the step monitor failed at step {step}, t = {t:.6g} s")
            self.error = e
            self._stop_now()

    def resume(self, t: float, dt: float, step: int, schedule: dict | None = None) -> None:
        """Continue a run from a checkpoint: its time, next step, step number
        and ``schedule_state``."""
        self.ts.setTime(t)
        self.ts.setTimeStep(dt)
        self.ts.setStepNumber(step)
        self._proposed = dt
        for name, value in (schedule or {}).items():
            setattr(self, "_" + name, None if math.isnan(value) else float(value))

    def schedule_state(self) -> dict:
        """What the step schedule remembers beyond the next step (NaN: nothing):
        the step a hit time cut short, the step a rejected step grows back to."""
        return {k: math.nan if getattr(self, "_" + k) is None else getattr(self, "_" + k)
                for k in ("last_dt_cut", "recover_to")}

    def request_stop(self, message: str, status: str = "interrupted") -> None:
        """Stop after the current step (from the monitor; collective): the
        run ends with ``status`` (interrupted: a signal; stopped: a limit
        the user set) and ``message``."""
        self.stopped = message
        self.stop_status = status
        self._stop_now()

    def fail(self, message: str) -> None:
        """Stop after the current step as failed (a monitor's verdict;
        collective): the run ends with status failed and ``message``."""
        self.failure = message
        self._stop_now()

    def _stop_now(self) -> None:
        """End TSSolve after the step just accepted: TS resets a converged
        reason set in a monitor when it starts the next step, but honours
        its step limit."""
        self.ts.setConvergedReason(PETSc.TS.ConvergedReason.CONVERGED_USER)
        self.ts.setMaxSteps(self.ts.getStepNumber())

    def solve(self) -> int:
        """Run to the final time; returns TS converged reason (negative: failed)."""
        self.front_limit.start(self.problem.X)
        self._land_first_step()
        self.ts.solve(self.problem.X)
        if self.error is not None:
            raise self.error
        self.rejected = self.ts.getStepRejections()
        return int(self.ts.getConvergedReason())

    def iterations(self) -> tuple[int, int]:
        return self.ts.getSNESIterations(), self.ts.getKSPIterations()

    def destroy(self) -> None:
        """Destroy the TS now, while Python runs: a Python PC in it must be
        reset before PETSc's finalisation (collective).  The wrappers PETSc
        passed to the callbacks left their references in petsc4py's garbage,
        which is cleaned up here too."""
        import gc
        comm = self.ts.comm
        if self.error is not None:         # its frames hold the callbacks' wrappers of the TS, which
            self.error.__traceback__ = None  # would outlive Python into PETSc's finalisation (a crash)
            gc.collect()
        self.ts.destroy()
        if self.predictor is not None:
            self.predictor.destroy()
        self.snes = None
        self.context.destroy()
        gc.collect()
        PETSc.garbage_cleanup(comm)


def _abort_all(comm, message: str) -> None:
    """Print the current exception's traceback with ``message`` and abort every rank."""
    traceback.print_exc()
    print(f"petthm: {message}; aborting all ranks", file=sys.stderr)
    sys.stderr.flush()
    comm.tompi4py().Abort(1)
