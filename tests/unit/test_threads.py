"""One BLAS thread per rank unless the user asks for more (petthm/__init__.py,
docs/performance.md "One BLAS thread per rank")."""
import ctypes.util
import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

#: the thread count of the OpenBLAS that numpy and PETSc loaded, in a fresh process
PROBE = ("import ctypes, petthm, numpy; from petsc4py import PETSc; "
         "print(ctypes.CDLL('libopenblas.so.0').openblas_get_num_threads())")


def _openblas_threads(**env):
    base = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    out = subprocess.run([sys.executable, "-c", PROBE], cwd=ROOT, env=dict(base, **env),
                         capture_output=True, text=True, timeout=120, check=True)
    return int(out.stdout.split()[-1])


@pytest.mark.skipif(ctypes.util.find_library("openblas") is None, reason="no OpenBLAS on this machine")
def test_blas_runs_one_thread_per_rank_unless_the_user_sets_it():
    assert _openblas_threads() == 1
    # control: the probe sees a thread count the user set (the variable is not overridden)
    assert _openblas_threads(OPENBLAS_NUM_THREADS="2") == 2
