"""Faults injected into a petthm run (tests/reliability/test_disk.py):

    python faults.py MODE N SCENE [options]

runs ``python -m petthm SCENE [options]`` with

* ``kill-in-checkpoint``: at the N-th checkpoint, the process kills itself
  (SIGKILL) after it has begun ``checkpoint.h5.tmp`` and before the file is
  complete and renamed: a kill -9 in the middle of a checkpoint write;
* ``no-space``: from the N-th output on, the file system reports no free
  space (for machines where a test cannot mount a small tmpfs);
* ``forget-carried``: the checkpoints hold none of the monitors' carried
  state (N unused): the negative control of the whole-run summary of a
  restarted run (tests/reliability/test_restart_consistency.py).
"""
import os
import signal
import sys


def _kill_in_checkpoint(n: int) -> None:
    import h5py

    from petthm.io import checkpoint
    original, calls = checkpoint.in_turns, [0]

    def in_turns(comm, write, path=""):
        if path.endswith("checkpoint.h5.tmp"):
            calls[0] += 1
            if calls[0] == n:
                with h5py.File(path, "w") as h5:          # a checkpoint begun, not finished
                    h5.attrs["scene"] = "partial"
                os.kill(os.getpid(), signal.SIGKILL)
        return original(comm, write, path)
    checkpoint.in_turns = in_turns


def _no_space(n: int) -> None:
    from petthm.io import output
    original, calls = output.os.statvfs, [0]

    class Full:
        f_bavail, f_frsize = 0, 4096

    def statvfs(path):
        calls[0] += 1
        return Full() if calls[0] >= n else original(path)
    output.os.statvfs = statvfs


def _forget_carried(n: int) -> None:
    from petthm.run import ranges
    ranges.WithRanges.carried_state = lambda self: {}


if __name__ == "__main__":
    mode, n, args = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
    import petsc4py

    from petthm.__main__ import isolate_singleton, main
    isolate_singleton()
    petsc4py.init([sys.argv[0]] + args[1:])          # what main does, before the patches import PETSc
    modes = {"kill-in-checkpoint": _kill_in_checkpoint, "no-space": _no_space,
             "forget-carried": _forget_carried}
    modes[mode](n)
    sys.exit(main(args))
