"""Fault injection for tests/test_parallel.py: ``python fault_monitor.py RANK
OUTDIR`` runs ``heat_erfc`` with a scene monitor that raises on rank RANK
only, at its third call."""
import sys

from petthm.__main__ import main
from petthm.scenes import load_all
from petthm.scenes.base import REGISTRY


def _inject(rank: int) -> None:
    cls = REGISTRY["heat_erfc"]
    original, calls = cls.monitors, [0]

    def monitors(self, problem, t, X=None):
        calls[0] += 1
        if calls[0] == 3 and problem.dm.comm.rank == rank:
            raise RuntimeError(f"injected monitor failure on rank {rank}")
        return original(self, problem, t, X)
    cls.monitors = monitors


if __name__ == "__main__":
    load_all()
    _inject(int(sys.argv[1]))
    sys.argv = ["petthm", "heat_erfc", "-thm_output_dir", sys.argv[2], "-thm_quiet"]
    sys.exit(main())
