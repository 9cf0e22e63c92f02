"""petthm: PETSc-based thermo-hydro-mechanics of fractured geothermal reservoirs."""
import os

__version__ = "0.1.0"

#: Thread counts of the BLAS/OpenMP libraries under numpy, PETSc and MUMPS,
#: set to one unless the user set them (docs/performance.md, "One BLAS thread
#: per rank").
BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def _one_blas_thread_per_rank() -> None:
    """An MPI run places one rank per core; a multithreaded BLAS (Debian's
    OpenBLAS is the pthread build) then starts more threads than cores, and
    its threads spin on cores the ranks need.  Measured on Scene 3 with two
    other processes on two cores: VecNorm 1.02 s against 0.020 s, VecAXPY
    1.79 s against 0.071 s over the same calls, and ``numpy.linalg.inv`` of
    26 113 3x3 matrices 1.4-17 s against 7 ms.  The variables are read when
    the libraries load, so this runs on ``import petthm``, before numpy or
    petsc4py are imported by petthm; a value the user set is kept."""
    for name in BLAS_THREAD_VARIABLES:
        os.environ.setdefault(name, "1")


_one_blas_thread_per_rank()
