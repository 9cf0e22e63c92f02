"""-thm_* options -> frozen, typed parameter objects with units and help.

A parameter set is a frozen dataclass whose fields are declared with
``param(default, unit, help, lo=, hi=)``.  ``read(cls)`` reads every field
from the PETSc options database once (option ``-thm_<field name>``, or the
``option`` given in the metadata), checks its range and returns the frozen
object.  Physical inputs are SI, except temperatures, which users give in
degrees Celsius (``unit="degC"``) and petthm converts to kelvin.
"""
from __future__ import annotations

import dataclasses
import difflib
import math
from collections.abc import Callable, Iterable, Sequence
from typing import Any

from petsc4py import PETSc

from petthm.errors import InputError

PREFIX = "thm_"
CELSIUS = 273.15

#: what an option sets (its ``kind``).  A restart continues the same
#: problem: an option of a kind in ``FIXED_ON_RESTART`` must keep its value
#: (``checkpoint.check_options``); the others may change.
PHYSICS, MESH, DISCRETISATION = "physics", "mesh", "discretisation"
TIME, SOLVER, OUTPUT, RUN = "time schedule", "solver", "output", "run control"
KINDS = (PHYSICS, MESH, DISCRETISATION, TIME, SOLVER, OUTPUT, RUN)
FIXED_ON_RESTART = (PHYSICS, MESH, DISCRETISATION)


def param(default: Any, unit: str, help: str, lo: float | None = None, hi: float | None = None,
          lo_open: bool = False, choices: tuple | None = None, option: str | None = None,
          parse: Callable[[str], Any] | None = None, *, kind: str):
    """Declare a parameter: default (SI, degC for temperatures), unit, help,
    accepted range; ``parse``: text -> value (raising InputError) for values
    that are not plain numbers (applied to the default too); ``kind``: one
    of ``KINDS``, what the option sets (a restart keeps physics, mesh and
    discretisation)."""
    if kind not in KINDS:
        raise ValueError(f"kind {kind!r} is not one of {', '.join(KINDS)}")
    return dataclasses.field(default=default, metadata=dict(
        unit=unit, help=help, lo=lo, hi=hi, lo_open=lo_open, choices=choices, option=option, parse=parse,
        kind=kind))


def option_name(f: dataclasses.Field) -> str:
    return f.metadata.get("option") or PREFIX + f.name


def _range_text(md) -> str:
    lo, hi = md.get("lo"), md.get("hi")
    if md.get("choices"):
        return "one of " + ", ".join(map(str, md["choices"]))
    left = "(" if md.get("lo_open") or lo is None else "["
    right = ")" if hi is None else "]"               # values must be finite
    return f"{left}{'-inf' if lo is None else f'{lo:g}'}, {'inf' if hi is None else f'{hi:g}'}{right}"


def _convert(f: dataclasses.Field, raw: str):
    name = option_name(f)
    if f.metadata.get("parse"):
        return f.metadata["parse"](raw)
    kind = type(f.default)
    try:
        if kind is bool:
            low = raw.strip().lower()
            if low in ("", "1", "true", "yes", "on"):
                return True
            if low in ("0", "false", "no", "off"):
                return False
            raise ValueError(raw)
        if kind is int:
            return int(raw)
        if kind is float:
            return float(raw)
        if kind is tuple:
            return tuple(float(v) for v in raw.split(","))
        return raw
    except ValueError:
        raise InputError(f"option -{name}: cannot read '{raw}' as {kind.__name__}") from None


def _check(f: dataclasses.Field, value) -> None:
    md = f.metadata
    name = option_name(f)
    if md.get("choices") and value not in md["choices"]:
        raise InputError(f"option -{name} = {value} is not {_range_text(md)}")
    vals = value if isinstance(value, tuple) else (value,)
    for v in vals:
        if not isinstance(v, (int, float)) or isinstance(v, bool):
            continue
        lo, hi = md.get("lo"), md.get("hi")
        bad = (lo is not None and (v < lo or (md.get("lo_open") and v == lo))) or \
              (hi is not None and v > hi) or not math.isfinite(v)
        if bad:
            raise InputError(f"option -{name} = {v} {md['unit']} is outside the accepted range "
                             f"{_range_text(md)}")


def _default(f: dataclasses.Field):
    parse = f.metadata.get("parse")
    return parse(f.default) if parse else f.default


def read(cls, options: PETSc.Options | None = None):
    """Read a parameter dataclass from the options database."""
    opts = options or PETSc.Options()
    values = {}
    for f in dataclasses.fields(cls):
        name = option_name(f)
        if opts.hasName(name):
            values[f.name] = _convert(f, opts.getString(name, ""))
        else:
            values[f.name] = _default(f)
        _check(f, values[f.name])
    return cls(**values)


def merged(groups: Iterable[type], base: type = object) -> type:
    """One frozen dataclass with every field of ``groups`` (each option once)."""
    fields, seen = [], {}
    for g in groups:
        for f in dataclasses.fields(g):
            if f.name in seen:
                raise TypeError(f"parameter {f.name} is in both {seen[f.name]} and {g.__name__}")
            seen[f.name] = g.__name__
            fields.append((f.name, f.type, dataclasses.field(default=f.default, metadata=f.metadata)))
    return dataclasses.make_dataclass("SceneParameters", fields, bases=(base,), frozen=True)


def read_all(groups: Sequence[type], base: type = object, options: PETSc.Options | None = None):
    """Read several parameter groups into one frozen object (see ``merged``)."""
    return read(merged(groups, base), options)


def values_in_effect(p) -> dict:
    """{option: value} of a parameter object (values as numbers, lists or text)."""
    out = {}
    for f in dataclasses.fields(p):
        v = getattr(p, f.name)
        out["-" + option_name(f)] = v if isinstance(v, (int, float, str, bool)) else \
            list(v) if isinstance(v, tuple) else str(v)
    return out


def option_kind(f: dataclasses.Field) -> str:
    return f.metadata["kind"]


#: PETSc option prefixes that set the time discretisation (a restart keeps them)
_TIME_SCHEMES = ("ts_type", "ts_bdf_", "ts_theta_", "ts_alpha_", "ts_arkimex_", "ts_rk_", "ts_rosw_")
#: PETSc option prefixes that set how the run is run or reported
_RUN_CONTROL = ("ts_max_steps", "options_", "log_", "help", "malloc", "info", "history", "on_error",
                "no_signal_handler", "fp_trap", "memory_view", "mpi_")


def petsc_option_kind(name: str) -> str:
    """The kind of a PETSc option (``KINDS``): ``-dm_*`` (refinement, the
    plex's options) set the mesh, ``-ts_type`` and the schemes' options the
    time discretisation, ``-ts_max_time`` the schedule's end; viewers and
    monitors are output; the rest configures the solvers."""
    if name.startswith("dm_") and "view" not in name and "check" not in name:
        return MESH
    if name.startswith(_TIME_SCHEMES):
        return DISCRETISATION
    if name == "ts_max_time":
        return TIME
    if name.startswith(_RUN_CONTROL):
        return RUN
    if "view" in name or "monitor" in name:
        return OUTPUT
    return SOLVER


def option_record(parameter_sets, petsc_options: dict[str, str]) -> dict:
    """{-option: {"kind", "value"}} of every -thm_* option of the parameter
    objects (the value in effect, as ``values_in_effect`` gives it) and of
    the given PETSc options (name without the dash: value): what a
    checkpoint records so that a restart can be checked against it."""
    out = {}
    for p in parameter_sets:
        kinds = {"-" + option_name(f): option_kind(f) for f in dataclasses.fields(p)}
        out.update({k: {"kind": kinds[k], "value": v} for k, v in values_in_effect(p).items()})
    for name, value in petsc_options.items():
        if not name.startswith(PREFIX):
            out["-" + name] = {"kind": petsc_option_kind(name), "value": value}
    return out


def with_defaults(cls, **defaults):
    """A copy of a parameter dataclass with other default values (same options)."""
    fields = []
    for f in dataclasses.fields(cls):
        default = defaults.get(f.name, f.default)
        fields.append((f.name, f.type, dataclasses.field(default=default, metadata=f.metadata)))
    return dataclasses.make_dataclass(cls.__name__, fields, frozen=True, namespace={"__doc__": cls.__doc__})


def known_options(classes: Iterable[type]) -> set[str]:
    return {option_name(f) for cls in classes for f in dataclasses.fields(cls)}


def check_unknown_thm_options(classes: Iterable[type], options: PETSc.Options | None = None,
                              extra: Iterable[str] = ()) -> None:
    """Every -thm_ option given must belong to one of ``classes`` or be one
    of ``extra`` (names without the dash: the options of named groups,
    ``named_options``); names match without regard to case, as PETSc's do."""
    opts = options or PETSc.Options()
    known = known_options(classes) | {e.lower() for e in extra}
    for key in sorted(opts.getAll()):
        if key.lower().startswith(PREFIX) and key.lower() not in known:
            raise InputError(f"unknown option -{key}{did_you_mean(key, sorted(known), prefix='-')}")


def did_you_mean(word: str, names: Iterable[str], prefix: str = "") -> str:
    """' (did you mean PREFIX NAME?)' for the name of ``names`` closest to
    ``word`` (without regard to case), or '' where none is close."""
    close = difflib.get_close_matches(word.lower(), [n.lower() for n in names], n=1)
    return f" (did you mean {prefix}{close[0]}?)" if close else ""


def named_option(kind: str, name: str, suffix: str) -> str:
    """The option (without the dash, lower case) of one named group's value:
    ``thm_KIND_NAME_SUFFIX`` (../shared/docs/reservoir.md section 2)."""
    return f"{PREFIX}{kind}_{name}_{suffix}".lower()


def _suffix(field_name: str, strip: str) -> str:
    return field_name[len(strip):] if strip and field_name.startswith(strip) else field_name


def named_options(cls, fields: Iterable[str], kind: str, names: Iterable[str], strip: str = "") -> set[str]:
    """The options ``read_named`` reads for ``names``: one per field of
    ``fields`` (of the parameter dataclass ``cls``) and name."""
    present = {f.name for f in dataclasses.fields(cls)}
    return {named_option(kind, n, _suffix(f, strip)) for f in fields if f in present for n in names}


def read_named(p, fields: Iterable[str], kind: str, name: str, strip: str = "",
               options: PETSc.Options | None = None):
    """``p`` (a parameter object holding the global values) with each of
    ``fields`` overridden where the named group's option is given:
    ``-thm_KIND_NAME_SUFFIX``, SUFFIX the field's name less ``strip`` (a
    region's ``-thm_region_NAME_rock_porosity`` overrides
    ``-thm_rock_porosity``; a fracture's ``-thm_fracture_NAME_aperture``,
    with ``strip="fracture_"``, ``-thm_fracture_aperture``).  Read, converted
    and range-checked as the global option is; an error names the group's
    option."""
    opts = options or PETSc.Options()
    by_name = {f.name: f for f in dataclasses.fields(p)}
    values = {}
    for field_name in fields:
        f = by_name[field_name]
        option = named_option(kind, name, _suffix(field_name, strip))
        if not opts.hasName(option):
            continue
        g = dataclasses.field(default=f.default, metadata={**f.metadata, "option": option})
        values[field_name] = _convert(g, opts.getString(option, ""))
        _check(g, values[field_name])
    return dataclasses.replace(p, **values)


def help_text(classes: Iterable[type]) -> str:
    """One line per parameter: option, default, unit, help."""
    lines = []
    for cls in classes:
        lines.append(f"  {cls.__doc__.strip().splitlines()[0]}")
        for f in dataclasses.fields(cls):
            md = f.metadata
            d = f.default
            d = ",".join(map(str, d)) if isinstance(d, tuple) else d
            d = f"{d:g}" if isinstance(d, float) else d
            rng = _range_text(md) if (md.get("lo") is not None or md.get("hi") is not None
                                      or md.get("choices")) else ""
            lines.append(f"    -{option_name(f):<34} {str(d):>12} {md['unit']:<10} {md['help']}"
                         + (f"  {rng}" if rng else "") + f"  [{md['kind']}]")
    return "\n".join(lines)


@dataclasses.dataclass(frozen=True)
class RunParams:
    """Run control (all scenes)"""
    output_dir: str = param("", "-", "output folder (default output/SCENE); a folder with another run's "
                            "output is refused (see -thm_overwrite, -thm_restart)", kind=OUTPUT)
    overwrite: bool = param(False, "-", "replace the output of an earlier run in the output folder (the "
                            "files of its manifest; nothing else in the folder is touched)", kind=RUN)
    mesh_file: str = param("", "-", "gmsh mesh file to use instead of the scene's generated mesh", kind=MESH)
    mesh_size: float = param(0.0, "m", "characteristic mesh size (0: scene default; at most the "
                             "domain's largest extent)", lo=0.0, kind=MESH)
    fe_degree: int = param(2, "-", "Lagrange degree of the matrix fields", choices=(1, 2),
                           kind=DISCRETISATION)
    quadrature_degree: int = param(0, "-", "quadrature degree (0: 2 x element degree)", lo=0, hi=20,
                                   kind=DISCRETISATION)
    final_time: float = param(0.0, "s", "end time (0: scene default)", lo=0.0, kind=TIME)
    dt_initial: float = param(0.0, "s", "first time step (0: scene default)", lo=0.0, kind=TIME)
    dt_growth: float = param(0.0, "-", "time-step growth factor per step (0: scene default)", lo=0.0,
                             kind=TIME)
    dt_max: float = param(0.0, "s", "largest time step (0: scene default)", lo=0.0, kind=TIME)
    dt_control: str = param("schedule", "-", "time steps from the scene's schedule (first step, growth, "
                            "largest step), or from an estimate of backward Euler's local error "
                            "(PETSc's TS adaptivity: -ts_adapt_*, tolerance -ts_atol on the scaled "
                            "unknowns, default 1e-3 of each field's range)", choices=("schedule", "error"),
                            kind=TIME)
    dt_courant: float = param(0.0, "cells", "also limit each next step so that a temperature front "
                              "(fracture Tf; rock Tm where water flows through it) moves at most this "
                              "many cells per step, from the last step's change (0: no limit)", lo=0.0,
                              kind=TIME)
    output_interval: int = param(0, "steps", "write fields every N steps (0: scene default)", lo=0,
                                 kind=OUTPUT)
    quiet: bool = param(False, "-", "no per-step progress line", kind=OUTPUT)
    max_cells: int = param(5_000_000, "cells", "refuse a generated mesh that would have more cells "
                           "than this (checked before meshing, from the far-field size)", lo=1, kind=RUN)
    checkpoint_interval: int = param(10, "steps", "write checkpoint.h5 every N accepted steps (0: only "
                                     "at the end and when a signal stops the run)", lo=0, kind=OUTPUT)
    checkpoint_wall: float = param(0.0, "s", "also write checkpoint.h5 when this much wall time has "
                                   "passed since the last one (0: by steps only)", lo=0.0, kind=OUTPUT)
    max_wall: float = param(0.0, "s", "stop cleanly after the first step that ends past this much wall "
                            "time, with a checkpoint (status stopped, exit code 3; 0: no limit)", lo=0.0,
                            kind=RUN)
    restart: str = param("", "-", "continue the run whose output folder this is, from its "
                         "checkpoint.h5 (same physics, mesh and discretisation; output goes on in that "
                         "folder)", kind=RUN)
    predictor: str = param("linear", "-", "Newton's first iterate of a time step: linear (on the line "
                           "through the last two accepted states) or none (the last state)",
                           choices=("linear", "none"), kind=SOLVER)
    pc_reuse: str = param("auto", "-", "reuse the preconditioner across Newton iterations and time "
                          "steps, rebuilt when the extra Krylov iterations have cost a set-up or a step "
                          "fails: on, off, or auto (on for a direct solve without friction)",
                          choices=("auto", "on", "off"), kind=SOLVER)
    pc_reuse_max_krylov: int = param(0, "-", "rebuild a reused preconditioner after a linear solve with "
                                     "more iterations than this (0: the cost rule of -thm_pc_reuse)", lo=0,
                                     kind=SOLVER)
    direct_max_unknowns: int = param(50000, "-", "scenes with displacement propose the block "
                                     "preconditioner of options/solvers/block.opts above this many "
                                     "unknowns and a direct solve up to it (manual, solver guide)", lo=0,
                                     kind=SOLVER)
