"""What summary.json records besides the results (manual, user guide):
the solver's event counts and times, the peak memory, the git commit of
the source and the options in effect."""
from __future__ import annotations

import os

from petsc4py import PETSc

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


__all__ = ["SOLVER_EVENTS", "solver_costs", "peak_memory_mb", "git_commit", "options_in_effect"]
