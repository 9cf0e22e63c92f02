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
    import petsc4py
    petsc4py.init([sys.argv[0]] + rest)
    from .app import run_scene
    from .errors import InputError
    from .scenes import load_all
    load_all()
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
