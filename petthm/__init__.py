"""petthm: PETSc-based thermo-hydro-mechanics of fractured geothermal reservoirs."""
import os

__version__ = "0.1.0"

#: thread counts of the BLAS/OpenMP libraries under numpy, PETSc and MUMPS
BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
#: rank counts MPI launchers export to their processes: Open MPI (mpiexec), MPICH/Hydra and
#: Intel MPI, SLURM's srun
LAUNCHER_RANK_VARIABLES = ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "MPI_LOCALNRANKS", "SLURM_STEP_NUM_TASKS")


def launcher_ranks(environ=os.environ) -> int:
    """The number of ranks an MPI launcher started this process among (1:
    not started by one); read before MPI is initialised."""
    counts = [environ.get(v, "1") for v in LAUNCHER_RANK_VARIABLES]
    return max((int(c) for c in counts if c.isdigit()), default=1)


def _one_blas_thread_per_rank() -> None:
    """Under an MPI launcher with more than one rank, one BLAS thread per
    rank unless the user set the thread counts (manual, performance, "BLAS
    threads").  Ranks fill the cores; Debian's OpenBLAS (the pthread build)
    starts a thread per core in every rank and its threads spin on the
    cores the other ranks need (Scene 3 with three processes on two cores:
    VecNorm 1.02 s against 0.020 s, VecAXPY 1.79 s against 0.071 s over the
    same calls; ``numpy.linalg.inv`` of 26 113 3x3 matrices 1.4-17 s against
    7 ms).  A serial run keeps the library's threads: MUMPS's dense fronts
    use them (Scene 2 with MUMPS on an idle 2-core machine: 35 s against
    42 s with one thread).  The variables are read when the libraries load,
    so this runs on ``import petthm``, before petthm imports numpy or
    petsc4py."""
    if launcher_ranks() > 1:
        for name in BLAS_THREAD_VARIABLES:
            os.environ.setdefault(name, "1")


_one_blas_thread_per_rank()
