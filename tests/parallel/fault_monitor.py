"""Fault injection for tests/parallel/test_parallel.py: ``python fault_monitor.py RANK
OUTDIR`` runs ``heat_erfc`` with a scene monitor that raises on rank RANK
only, at its third call."""
import sys

from petthm.__main__ import main


def _inject(rank: int) -> None:
    from petthm.scenes import heat
    cls = heat._ErfcMonitor
    original, calls = cls.__call__, [0]

    def monitor(self, problem, t, X=None):
        calls[0] += 1
        if calls[0] == 3 and problem.dm.comm.rank == rank:
            raise RuntimeError(f"injected monitor failure on rank {rank}")
        return original(self, problem, t, X)
    cls.__call__ = monitor


if __name__ == "__main__":
    rank, outdir = int(sys.argv[1]), sys.argv[2]
    sys.argv = ["petthm", "heat_erfc", "-thm_output_dir", outdir, "-thm_quiet"]
    import petsc4py
    petsc4py.init(sys.argv)             # as main would: before the scenes import PETSc
    _inject(rank)
    sys.exit(main())
