"""RSS by phase: samples /proc/self/statm every 50 ms; phase = petthm's log stage,
refined by wrapping Problem's set-up and the first solver set-up. Usage: python memprof.py SCENE [options]"""
import os, sys, threading, time, runpy
sys.argv = ["petthm"] + sys.argv[1:]
import petsc4py; petsc4py.init(["petthm"] + sys.argv[2:])
PAGE = os.sysconf("SC_PAGE_SIZE")
phase = ["start"]; peaks = {}; order = []; t0 = time.time(); trace = []
def rss():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * PAGE / 2**20
def sampler():
    while True:
        r = rss(); p = phase[0]
        if p not in peaks: peaks[p] = [r, r]; order.append(p)
        peaks[p][1] = max(peaks[p][1], r)
        trace.append((time.time() - t0, r, p))
        time.sleep(0.05)
threading.Thread(target=sampler, daemon=True).start()
import petthm.run.driver as A
orig_stage, orig_pop = A.Run._stage, A.Run._pop
def _stage(self, name):
    phase[0] = name; return orig_stage(self, name)
def _pop(self, name, st, t0_):
    phase[0] = "after-" + name; return orig_pop(self, name, st, t0_)
A.Run._stage, A.Run._pop = _stage, _pop
import petthm.discretisation.problem as P
orig_init = P.Problem.__init__
def init(self, *a, **k):
    phase[0] = "setup:Problem"; orig_init(self, *a, **k); phase[0] = "setup:after-Problem"
P.Problem.__init__ = init
import atexit
def report():
    out = os.environ.get("MEMPROF_OUT", "/tmp/memprof.txt")
    with open(out, "w") as f:
        for p in order:
            f.write(f"{p:28s} enter {peaks[p][0]:9.0f} MB  peak {peaks[p][1]:9.0f} MB\n")
        f.write("trace (s, MB, phase) every 1 s:\n")
        last = -1
        for t, r, p in trace:
            if int(t) != last:
                last = int(t); f.write(f"{t:7.1f} {r:8.0f} {p}\n")
atexit.register(report)
runpy.run_module("petthm", run_name="__main__")
