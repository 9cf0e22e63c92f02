"""What the Python heap holds during a run (manual: performance, "Memory").

    TM_OUT=tm.txt python benchmarks/tmprof.py SCENE [options]

Runs ``python -m petthm SCENE [options]`` in this process with
``tracemalloc`` and appends to ``$TM_OUT`` (default /tmp/tm.txt) a snapshot
on entering the first output stage (after the set-up), on entering the
solve and at exit: the traced total and peak, the 25 largest allocation
sites by line and the 12 largest by traceback.  It sees Python's
allocations (numpy arrays included), not PETSc's."""
import atexit
import os
import runpy
import sys
import tracemalloc

import petsc4py

sys.argv = ["petthm", *sys.argv[1:]]
petsc4py.init(["petthm", *sys.argv[2:]])
tracemalloc.start(6)
import petthm.run.driver as driver  # noqa: E402


def dump(tag: str) -> None:
    snap = tracemalloc.take_snapshot()
    now, peak = tracemalloc.get_traced_memory()
    with open(os.environ.get("TM_OUT", "/tmp/tm.txt"), "a") as f:
        f.write(f"== {tag}: traced now {now / 2**20:.0f} MB, peak {peak / 2**20:.0f} MB\n")
        for st in snap.statistics("lineno")[:25]:
            f.write(f"{st.size / 2**20:9.1f} MB {st.count:8d}  {st.traceback[0]}\n")
        f.write("-- by traceback:\n")
        for st in snap.statistics("traceback")[:12]:
            frames = " <- ".join(f"{fr.filename.split('/')[-1]}:{fr.lineno}" for fr in st.traceback[:6])
            f.write(f"{st.size / 2**20:9.1f} MB  {frames}\n")


def watch_stages() -> None:
    stage, seen = driver.Run._stage, set()

    def _stage(self, name):
        if name in ("output", "solve") and name not in seen:
            seen.add(name)
            dump("entering " + name)
        return stage(self, name)
    driver.Run._stage = _stage


if __name__ == "__main__":
    watch_stages()
    atexit.register(lambda: dump("exit"))
    runpy.run_module("petthm", run_name="__main__")
