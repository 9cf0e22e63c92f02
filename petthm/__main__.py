"""Command line: ``[mpiexec -n N] python -m petthm SCENE [-options_file F] [options]``."""
from __future__ import annotations

import os
import sys

USAGE = "usage: python -m petthm SCENE [-options_file FILE] [-thm_* and PETSc options]"


def _help_requested(argv):
    return any(a in ("-help", "--help", "-h") for a in argv)


def _scene_help(name):
    from . import params as P
    from .scenes import load_all
    from .scenes.base import REGISTRY
    load_all()
    cls = REGISTRY[name]
    lines = [f"{name}: {cls.description}", "", "parameters (-option  default  unit  meaning):",
             P.help_text((P.RunParams,) + tuple(cls.parameters)), "",
             f"time defaults: final {cls.time.final_time:g} s, first step {cls.time.dt_initial:g} s, "
             f"growth {cls.time.dt_growth:g}, largest step {cls.time.dt_max:g} s",
             "solver: any PETSc option (-ts_*, -snes_*, -ksp_*, -pc_*, -fieldsplit_*), "
             "or -options_file options/solvers/*.opts"]
    return "\n".join(lines)


def _list_help():
    from .scenes import load_all
    from .scenes.base import REGISTRY
    load_all()
    lines = [USAGE, "", "scenes:"]
    lines += [f"  {n:<18} {REGISTRY[n].description}" for n in sorted(REGISTRY)]
    lines += ["", "python -m petthm SCENE -help lists a scene's parameters with units and defaults."]
    return "\n".join(lines)


def _fail(msg: str, rank: int) -> int:
    if rank == 0:
        print(f"petthm: error: {msg}", file=sys.stderr, flush=True)
    return 2


def _bad_options_line(path: str) -> str | None:
    """A one-line error for the first line of an options file that PETSc
    would refuse at start-up (a line is '-name [value]' or 'alias ...'; '#'
    starts a comment), or None."""
    try:
        with open(path, errors="replace") as f:
            lines = f.read().splitlines()
    except OSError as e:
        return f"options file '{path}' cannot be read ({e.strerror}) (-options_file)"
    for n, line in enumerate(lines, 1):
        text = line.split("#", 1)[0].strip()
        if text and not text.startswith(("-", "alias", "!", "%")):
            return (f"options file '{path}' line {n}: '{text[:40]}' is not an option "
                    "(a line is '-name [value]'; '#' starts a comment) (-options_file)")
    return None


#: environment variables a launcher (mpiexec, srun) sets: a process without any of them is an MPI singleton
LAUNCHER_VARIABLES = ("OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE", "MPI_LOCALNRANKS")


def isolate_singleton(environ=os.environ) -> None:
    """A run started without mpiexec is one process that talks only to
    itself.  Open MPI is told so: no support daemon
    (``ess_singleton_isolated``: petthm never spawns processes) and the
    ob1 message layer rather than probing the network (UCX) for peers it
    will never have.  Measured (docs/performance.md): the daemon 0.27 s,
    the probe 0.20 s of a small run's start.  A value the user set wins;
    other MPI libraries ignore the variables."""
    if not any(v in environ for v in LAUNCHER_VARIABLES):
        environ.setdefault("OMPI_MCA_ess_singleton_isolated", "1")
        environ.setdefault("OMPI_MCA_pml", "ob1")


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    scene = argv[0] if argv and not argv[0].startswith("-") else None
    rest = argv[1:] if scene else argv
    rank = int(os.environ.get("OMPI_COMM_WORLD_RANK", os.environ.get("PMI_RANK", "0")))
    if _help_requested(argv):
        from .scenes import load_all
        from .scenes.base import REGISTRY
        load_all()
        if scene and scene not in REGISTRY:
            return _fail(f"unknown scene '{scene}'; scenes: {', '.join(sorted(REGISTRY))}", rank)
        if rank == 0:
            print(_scene_help(scene) if scene else _list_help())
        return 0
    if scene is None:
        return _fail(f"no scene given\n{USAGE}\n(python -m petthm -help lists the scenes)", rank)
    for i, a in enumerate(rest):
        if a == "-options_file":
            if i + 1 >= len(rest) or not os.path.isfile(rest[i + 1]):
                name = rest[i + 1] if i + 1 < len(rest) else ""
                return _fail(f"options file '{name}' does not exist (-options_file)", rank)
            bad = _bad_options_line(rest[i + 1])
            if bad:
                return _fail(bad, rank)
    isolate_singleton()
    import petsc4py
    try:
        petsc4py.init([sys.argv[0]] + rest)          # PETSc reads the options files here
        from petsc4py import PETSc  # noqa: F401
    except Exception as e:           # petsc4py.PETSc.Error (the module may not be there to name it)
        return _fail(f"PETSc could not start with these options (error {e})", rank)
    from .app import run_scene
    from .errors import InputError
    from .scenes import load
    load(scene)
    from petsc4py import PETSc
    try:
        summary = run_scene(scene)
    except InputError as e:          # raised on every rank alike
        return _fail(str(e), PETSc.COMM_WORLD.rank)
    except Exception:                # a rank-local failure must not leave the others waiting
        import traceback
        traceback.print_exc()
        sys.stderr.flush()
        if PETSc.COMM_WORLD.size > 1:
            PETSc.COMM_WORLD.tompi4py().Abort(1)
        raise
    return {"completed": 0, "interrupted": 3}.get(summary["status"], 1)


if __name__ == "__main__":
    sys.exit(main())
