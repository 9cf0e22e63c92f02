"""One BLAS thread per rank under an MPI launcher, unless the user asks for
more; a serial run keeps the library's threads (petthm/__init__.py,
docs/performance/index.md "BLAS threads")."""
import ctypes.util
import os
import subprocess
import sys

import pytest

from petthm import BLAS_THREAD_VARIABLES, LAUNCHER_RANK_VARIABLES, launcher_ranks

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _openblas_threads(imports="petthm, numpy", **env):
    """The thread count of the OpenBLAS that numpy and PETSc loaded, in a fresh process."""
    probe = (f"import ctypes, {imports}; from petsc4py import PETSc; "
             "print(ctypes.CDLL('libopenblas.so.0').openblas_get_num_threads())")
    base = {k: v for k, v in os.environ.items() if k not in BLAS_THREAD_VARIABLES + LAUNCHER_RANK_VARIABLES}
    out = subprocess.run([sys.executable, "-c", probe], cwd=ROOT, env=dict(base, **env),
                         capture_output=True, text=True, timeout=120, check=True)
    return int(out.stdout.split()[-1])


def test_launcher_ranks_are_read_from_the_launchers_variables():
    assert launcher_ranks({}) == 1
    assert launcher_ranks({"OMPI_COMM_WORLD_SIZE": "4"}) == 4
    assert launcher_ranks({"PMI_SIZE": "8", "SLURM_STEP_NUM_TASKS": "8"}) == 8
    assert launcher_ranks({"SLURM_STEP_NUM_TASKS": "junk"}) == 1


@pytest.mark.skipif(ctypes.util.find_library("openblas") is None, reason="no OpenBLAS on this machine")
def test_blas_runs_one_thread_per_rank_under_a_launcher_unless_the_user_sets_it():
    library_default = _openblas_threads(imports="numpy")
    assert _openblas_threads() == library_default                       # serial: the library's own
    assert _openblas_threads(OMPI_COMM_WORLD_SIZE="2") == 1              # two ranks: one thread each
    assert _openblas_threads(PMI_SIZE="2") == 1
    # the user's setting is kept (and the probe sees a count above one where one is set)
    assert _openblas_threads(OMPI_COMM_WORLD_SIZE="2", OPENBLAS_NUM_THREADS="2") == 2
