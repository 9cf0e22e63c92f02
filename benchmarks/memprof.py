"""Resident memory of a run by phase (manual: performance, "Memory").

    MEMPROF_OUT=memprof.txt python benchmarks/memprof.py SCENE [options]

Runs ``python -m petthm SCENE [options]`` in this process and samples its
resident set size (``/proc/self/statm``) every 50 ms, each sample labelled
with petthm's current log stage (``Run._stage``: mesh, setup, output,
solve; ``after-X`` after stage X) and, within the set-up, the construction
of the ``Problem``.  At exit it writes, per label, the resident set on
entering it and its peak, then a trace of (seconds, MB, label) once per
second, to ``$MEMPROF_OUT`` (default /tmp/memprof.txt).  Linux, one rank."""
import atexit
import os
import runpy
import sys
import threading
import time

import petsc4py

sys.argv = ["petthm", *sys.argv[1:]]
petsc4py.init(["petthm", *sys.argv[2:]])
import petthm.discretisation.problem as problem_module  # noqa: E402
import petthm.run.driver as driver  # noqa: E402

PAGE = os.sysconf("SC_PAGE_SIZE")


class Sampler:
    """The resident set every 50 ms, by the phase the run is in."""

    def __init__(self):
        self.phase, self.peaks, self.order, self.trace = "start", {}, [], []
        self.t0 = time.time()

    @staticmethod
    def rss() -> float:
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * PAGE / 2**20

    def run(self) -> None:
        while True:
            r, p = self.rss(), self.phase
            if p not in self.peaks:
                self.peaks[p] = [r, r]
                self.order.append(p)
            self.peaks[p][1] = max(self.peaks[p][1], r)
            self.trace.append((time.time() - self.t0, r, p))
            time.sleep(0.05)

    def report(self) -> None:
        with open(os.environ.get("MEMPROF_OUT", "/tmp/memprof.txt"), "w") as f:
            for p in self.order:
                f.write(f"{p:28s} enter {self.peaks[p][0]:9.0f} MB  peak {self.peaks[p][1]:9.0f} MB\n")
            f.write("trace (s, MB, phase) every 1 s:\n")
            last = -1
            for t, r, p in self.trace:
                if int(t) != last:
                    last = int(t)
                    f.write(f"{t:7.1f} {r:8.0f} {p}\n")


def label_phases(sampler: Sampler) -> None:
    """Wrap the run's stages and the Problem's construction to set the phase."""
    stage, pop = driver.Run._stage, driver.Run._pop
    init = problem_module.Problem.__init__

    def _stage(self, name):
        sampler.phase = name
        return stage(self, name)

    def _pop(self, name, st, t0):
        sampler.phase = "after-" + name
        return pop(self, name, st, t0)

    def _init(self, *args, **kwargs):
        sampler.phase = "setup:Problem"
        init(self, *args, **kwargs)
        sampler.phase = "setup:after-Problem"
    driver.Run._stage, driver.Run._pop, problem_module.Problem.__init__ = _stage, _pop, _init


if __name__ == "__main__":
    sampler = Sampler()
    threading.Thread(target=sampler.run, daemon=True).start()
    label_phases(sampler)
    atexit.register(sampler.report)
    runpy.run_module("petthm", run_name="__main__")
