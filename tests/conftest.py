import csv
import json
import os
import subprocess
import sys

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
#: Open MPI on one node: run as root, more ranks than cores, and the ob1 message layer (what Open
#: MPI falls back to here after probing UCX for a network: the probe costs every rank ~0.2 s).
#: Waiting ranks poll without yielding: beside another worker's serial run on two cores a yielding
#: rank loses the core for whole time slices (a 2-rank rigid_fracture run of 6.5 s alone: 13 s
#: beside a serial run polling, 147 s yielding)
MPI_ENV = dict(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1", OMPI_MCA_mpi_yield_when_idle="0",
               OMPI_MCA_pml="ob1")


#: what an MPI singleton (a process that initialised MPI without mpiexec) puts in its environment: a
#: child mpiexec that inherits it fails without a word
SINGLETON_PREFIXES = ("PMIX_", "OMPI_COMMAND", "OMPI_APP_CTX", "OMPI_MCA_ess", "OMPI_MCA_orte",
                      "OMPI_MCA_pmix")


def pytest_configure(config):
    """MPI (petsc4py) in the process that runs the tests; with pytest-xdist
    (``-n``) in each worker only, so that the workers and the mpiexec they
    start inherit no singleton's environment."""
    if getattr(config.option, "numprocesses", None) and not hasattr(config, "workerinput"):
        return
    for name in [k for k in os.environ if k.startswith(SINGLETON_PREFIXES)]:
        del os.environ[name]
    import petsc4py
    petsc4py.init([sys.argv[0]])


def read_text(path) -> str:
    with open(path) as f:
        return f.read()


def read_json(path):
    return json.loads(read_text(path))


def read_csv(path) -> list[dict]:
    """The rows of a CSV file (history.csv) as dicts."""
    return list(csv.DictReader(read_text(path).splitlines()))


def run_petthm(scene, outdir, *options, ranks=1, check=True, timeout=600):
    """Run ``python -m petthm SCENE`` (under mpiexec when ranks > 1); returns
    (CompletedProcess, summary dict or None)."""
    cmd = [sys.executable, "-m", "petthm", scene, "-thm_output_dir", str(outdir), "-thm_quiet",
           *map(str, options)]
    if ranks > 1:
        cmd = ["mpiexec", "-n", str(ranks)] + cmd
    env = dict(os.environ, **MPI_ENV)
    proc = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True, timeout=timeout)
    if check and proc.returncode != 0:
        raise AssertionError(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stdout}\n{proc.stderr}")
    path = os.path.join(outdir, "summary.json")
    summary = read_json(path) if os.path.exists(path) else None
    return proc, summary


#: a coarse lauwerier (254 cells, 128 steps to 1e6 s in ~0.3 s): for tests of the run, not its resolution
LAUWERIER_COARSE = ("lauwerier", "-options_file", f"{ROOT}/options/scenes/lauwerier.opts",
                    "-thm_mesh_size", 20, "-thm_lauwerier_fracture_size", 5)


def checkpoint_state(folder):
    """(checkpoint.h5's state in the order of the serial mesh's points, any rank count; its attributes)."""
    import h5py
    with h5py.File(os.path.join(folder, "checkpoint.h5"), "r") as h5:
        point, ndof, value = (np.concatenate([h5[name][k][...] for k in sorted(h5[name], key=int)])
                              for name in ("point", "ndof", "value"))
        meta = dict(h5.attrs)
    blocks = np.split(value, np.cumsum(ndof)[:-1])
    return np.concatenate([blocks[i] for i in np.argsort(point)]), meta


def folder_digests(folder) -> dict:
    """SHA-256 of every file in a folder but the lock (which names its last holder)."""
    import hashlib
    from pathlib import Path
    return {n: hashlib.sha256(Path(folder, n).read_bytes()).hexdigest()
            for n in sorted(os.listdir(folder))
            if os.path.isfile(os.path.join(folder, n)) and n != ".petthm.lock"}


def ranks_of(mpiexec_pid) -> list[int]:
    """The PIDs of the processes mpiexec started (its children)."""
    kids = []
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:
                stat = read_text(f"/proc/{d}/stat")
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == mpiexec_pid:
                kids.append(int(d))
    return kids


def build_problem(tmp_path, scene, **opts):
    """Set up (not run) a scene in this process with -thm_* options; returns its Problem."""
    from petthm.run.driver import Run, make_scene
    _only_options(thm_output_dir=str(tmp_path), **opts)
    run = Run(make_scene(scene))
    return run.setup(run.build_mesh())[1]


def _only_options(**opts):
    """Empty PETSc's options database, then set ``opts`` (-thm_* without the dash)."""
    from petsc4py import PETSc
    o = PETSc.Options()
    for k in list(o.getAll()):
        o.delValue(k)
    for k, v in opts.items():
        o.setValue(k, v)


def solved_problem(tmp_path, scene, **opts):
    """Run a scene in this process with -thm_* options; returns (scene, its Problem at the end)."""
    from petthm.run.driver import Run, make_scene
    _only_options(thm_output_dir=str(tmp_path), thm_quiet="1", **opts)
    run = Run(make_scene(scene))
    assert run.execute()["status"] == "completed"
    return run.scene, run.problem


def fitted_slope(h, e):
    """Least-squares slope of log(e) against log(h)."""
    return float(np.polyfit(np.log(h), np.log(e), 1)[0])


@pytest.fixture
def petthm_run():
    return run_petthm


def pytest_unconfigure(config):
    """Empty the options database that in-process tests filled (newer PETSc
    lists unused options at exit)."""
    from petsc4py import PETSc
    opts = PETSc.Options()
    for key in list(opts.getAll()):
        opts.delValue(key)


def solver_without_parallel_direct() -> tuple:
    """Without MUMPS or SuperLU_dist (PyPI's PETSc) the parallel direct solve
    is PETSc's LU on a gathered copy (11 min for Scene 2 on 2 ranks): serial
    and parallel runs then both use the contact field split (8 s), which
    compares the same parallel paths (VI, the split, the assembly)."""
    from petsc4py import PETSc
    if any(PETSc.Sys.hasExternalPackage(p) for p in ("mumps", "superlu_dist")):
        return ()
    return ("-options_file", f"{ROOT}/options/solvers/block.opts")
