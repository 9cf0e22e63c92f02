"""tracemalloc snapshot of what the process holds at the first 'output' stage (after set-up) and at the end."""
import os, sys, runpy, tracemalloc
sys.argv = ["petthm"] + sys.argv[1:]
import petsc4py; petsc4py.init(["petthm"] + sys.argv[2:])
tracemalloc.start(6)
import petthm.run.driver as A
orig_stage = A.Run._stage
seen = []
def dump(tag):
    snap = tracemalloc.take_snapshot()
    cur, peak = tracemalloc.get_traced_memory()
    with open(os.environ.get("TM_OUT", "/tmp/tm.txt"), "a") as f:
        f.write(f"== {tag}: traced now {cur/2**20:.0f} MB, peak {peak/2**20:.0f} MB\n")
        for st in snap.statistics("lineno")[:25]:
            f.write(f"{st.size/2**20:9.1f} MB {st.count:8d}  {st.traceback[0]}\n")
        f.write("-- by 4-frame traceback:\n")
        for st in snap.statistics("traceback")[:12]:
            f.write(f"{st.size/2**20:9.1f} MB  " + " <- ".join(f"{fr.filename.split('/')[-1]}:{fr.lineno}" for fr in st.traceback[:6]) + "\n")
def _stage(self, name):
    if name in ("output", "solve") and name not in seen:
        seen.append(name); dump("entering " + name)
    return orig_stage(self, name)
A.Run._stage = _stage
import atexit; atexit.register(lambda: dump("exit"))
runpy.run_module("petthm", run_name="__main__")
