"""Command line: ``[mpiexec -n N] python -m petthm SCENE [-options_file F] [options]``."""
from __future__ import annotations

import os
import sys

USAGE = "usage: python -m petthm SCENE [-options_file FILE] [-thm_* and PETSc options]"


def _help_requested(argv):
    return any(a in ("-help", "--help", "-h") for a in argv)


def _scene_help(name, args=()):
    from petthm import params as P
    from petthm.scenes import scene_class
    cls = scene_class(name)
    mesh = next((args[i + 1] for i, a in enumerate(args[:-1]) if a.lower() == "-thm_mesh_file"), "")
    named = cls.named_help(mesh)
    lines = [f"{name}: {cls.description}", "", "parameters (-option  default  unit  meaning):",
             P.help_text((P.RunParams,) + tuple(cls.parameters)), *([named] if named else []), "",
             _water_help(cls),
             f"time defaults: final {cls.time.final_time:g} s, first step {cls.time.dt_initial:g} s, "
             f"growth {cls.time.dt_growth:g}, largest step {cls.time.dt_max:g} s",
             "solver: any PETSc option (-ts_*, -snes_*, -ksp_*, -pc_*, -fieldsplit_*), "
             "or -options_file options/solvers/*.opts"]
    return "\n".join(lines)


def _water_help(cls) -> str:
    """How the scene's pressures are given, and the pressure of its water without a pressure field."""
    kind = "gauge (absolute = gauge + 101 325 Pa)" if cls.gauge_pressure else "absolute"
    text = f"pressures: {kind}; [kind]: what an option sets (a restart keeps physics, mesh, discretisation)"
    if cls.water_pressure is not None:
        text += f"; the scene's water is at {cls.water_pressure:g} Pa (no pressure field)"
    return text


def _list_help():
    from petthm.scenes import all_scenes
    scenes = all_scenes()
    lines = [USAGE, "", "scenes:"]
    lines += [f"  {n:<18} {scenes[n].description}" for n in sorted(scenes)]
    lines += ["", "python -m petthm SCENE -help lists a scene's parameters with units and defaults."]
    return "\n".join(lines)


def _help(scene, rest, rank) -> int:
    """-help: the scenes, or one scene's options (with a deck's mesh: its names' options too)."""
    from petthm.errors import InputError
    from petthm.scenes import MODULES
    if scene and scene not in MODULES:
        return _fail(f"unknown scene '{scene}'; scenes: {', '.join(sorted(MODULES))}", rank)
    if rank == 0:
        try:
            print(_scene_help(scene, rest) if scene else _list_help())
        except InputError as e:
            return _fail(str(e), rank)
    return 0


def _fail(msg: str, rank: int) -> int:
    if rank == 0:
        print(f"petthm: error: {msg}", file=sys.stderr, flush=True)
    return 2


def _is_option(token: str) -> bool:
    """A token that names an option (-name), not a value (a word, or a
    number such as -5 or -1e3, which PETSc reads as a value too)."""
    if not token.startswith("-") or token == "-":
        return False
    try:
        float(token)
    except ValueError:
        return True
    return False


def _extra_value_error(name: str, values: list[str], where: str) -> str:
    return (f"{where}option {name} takes one value, not {len(values)} ({' '.join(values)}): a list is "
            "written with commas and no spaces (-name a,b,c)")


def check_arguments(args: list[str]) -> str | None:
    """The first problem of the command line after the scene, or None: each
    argument is an option (-name) followed by at most one value.  A stray
    word is refused (PETSc would ignore it), with "did you mean
    -options_file" for a file; a second value too (PETSc would drop it)."""
    i = 0
    while i < len(args):
        token = args[i]
        if not _is_option(token):
            hint = f" (did you mean -options_file {token}?)" if os.path.isfile(token) or \
                token.endswith(".opts") else ""
            return (f"unexpected argument '{token}'{hint}: arguments after the scene are options, "
                    "-name [value]")
        j = i + 1
        while j < len(args) and not _is_option(args[j]):
            j += 1
        if j - i > 2:
            return _extra_value_error(token, args[i + 1:j], "")
        i = j
    return None


def _tokens(text: str) -> list[str]:
    """The words of an options-file line as PETSc splits it (a double-quoted
    string is one word)."""
    import re
    return [t.strip('"') for t in re.findall(r'"[^"]*"|\S+', text)]


def bad_options_file(path: str, seen: tuple = ()) -> str | None:
    """A one-line error for the first line of an options file that PETSc
    would refuse or cut short, or None: a line is '-name [value]' ('#' starts
    a comment, 'alias' lines are PETSc's); a second value on a line is an
    error (PETSc would drop it silently); -options_file lines are followed."""
    try:
        with open(path, errors="replace") as f:
            lines = f.read().splitlines()
    except OSError as e:
        return f"options file '{path}' cannot be read ({e.strerror}) (-options_file)"
    for n, line in enumerate(lines, 1):
        words = _tokens(line.split("#", 1)[0])
        if not words or words[0] in ("alias", "!", "%") or words[0].startswith(("!", "%")):
            continue
        where = f"options file '{path}' line {n}: "
        if not _is_option(words[0]):
            return (f"{where}'{' '.join(words)[:40]}' is not an option (a line is '-name [value]'; '#' "
                    "starts a comment) (-options_file)")
        if len(words) > 2:
            return _extra_value_error(words[0], words[1:], where)
        if words[0] == "-options_file" and len(words) == 2 and os.path.abspath(words[1]) not in seen:
            nested = bad_options_file(words[1], seen + (os.path.abspath(path),)) \
                if os.path.isfile(words[1]) else f"{where}options file '{words[1]}' does not exist"
            if nested:
                return nested
    return None


#: environment variables a launcher (mpiexec, srun) sets: a process without any of them is an MPI singleton
LAUNCHER_VARIABLES = ("OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE", "MPI_LOCALNRANKS")


def isolate_singleton(environ=os.environ) -> None:
    """A run started without mpiexec is one process that talks only to
    itself.  Open MPI is told so: no support daemon
    (``ess_singleton_isolated``: petthm never spawns processes) and the
    ob1 message layer rather than probing the network (UCX) for peers it
    will never have.  Measured (manual, performance): the daemon 0.27 s,
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
        return _help(scene, rest, rank)
    if scene is None:
        return _fail(f"no scene given\n{USAGE}\n(python -m petthm -help lists the scenes)", rank)
    bad = check_arguments(rest)
    if bad:
        return _fail(bad, rank)
    for i, a in enumerate(rest):
        if a == "-options_file":
            if i + 1 >= len(rest) or not os.path.isfile(rest[i + 1]):
                name = rest[i + 1] if i + 1 < len(rest) else ""
                return _fail(f"options file '{name}' does not exist (-options_file)", rank)
            bad = bad_options_file(rest[i + 1])
            if bad:
                return _fail(bad, rank)
    isolate_singleton()
    import petsc4py
    try:
        petsc4py.init([sys.argv[0]] + rest)          # PETSc reads the options files here
        from petsc4py import PETSc  # noqa: F401
    except Exception as e:           # petsc4py.PETSc.Error (the module may not be there to name it)
        return _fail(f"PETSc could not start with these options (error {e})", rank)
    from petsc4py import PETSc

    from petthm.errors import InputError, WriteFailure
    from petthm.run.driver import run_scene
    try:
        summary = run_scene(scene)
    except InputError as e:          # raised on every rank alike
        return _fail(str(e), PETSc.COMM_WORLD.rank)
    except WriteFailure as e:        # raised on every rank alike: the run could not write its files
        _fail(str(e), PETSc.COMM_WORLD.rank)
        return 1
    except Exception:                # a rank-local failure must not leave the others waiting
        import traceback
        traceback.print_exc()
        sys.stderr.flush()
        if PETSc.COMM_WORLD.size > 1:
            PETSc.COMM_WORLD.tompi4py().Abort(1)
        raise
    return summary.get("exit_code", 1)


if __name__ == "__main__":
    sys.exit(main())
