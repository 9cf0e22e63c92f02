"""Results-unchanged check for refactorings: run every scene on a coarse
setting from two source trees and compare what they computed.

    python scripts/compare_results.py run  TREE OUT      # every case from TREE into OUT/CASE
    python scripts/compare_results.py diff OUT_A OUT_B   # compare two such runs (markdown table)

Compared per case: every number of ``summary.json`` (except versions,
provenance and wall times), every column of ``history.csv`` except ``wall``,
and the final step of every field file (``fields*.h5``, ``fracture*.h5``;
nodes matched by coordinates).  The difference of a number is
|a - b| / max(|a|, |b|); a number whose magnitude is below ``FLOOR`` in
both runs (an error metric of an exact patch test, at round-off) is
reported as round-off and not as a relative difference.  Monitors that
measure a residual at the solver's tolerance (mass and energy balance
residuals, over/undershoots, bounds violations, the aperture identity; the
tests compare them with limits of 1e-6 and more) are compared absolutely:
|a - b| <= ``TOLERANCE_LEVEL``.  A field's difference is max|a - b| / max|a|.

Every case runs with ``-thm_pc_reuse off`` where the tree has it: the
reuse rule of ``auto`` decides by measured times, so two runs of the same
code may take different solver paths and differ at the solver's tolerance.

Cases are written with the option names of the older tree; ``RENAMED``
translates them for a tree that has the option contract of physics.md
section 12 (``TREE/petthm/physics/materials.py`` present).
"""
from __future__ import annotations

import csv
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

#: scene, case name, options (a coarse setting of every scene; variants cover option paths)
CASES = [
    ("heat_mms", "heat_mms_2d_p2", ["-thm_mesh_size", 0.25]),
    ("heat_mms", "heat_mms_3d_p1", ["-thm_mms_dim", 3, "-thm_mesh_size", 0.34, "-thm_fe_degree", 1]),
    ("heat_erfc", "heat_erfc", ["-thm_final_time", 1e4, "-thm_mesh_size", 0.5]),
    ("heat_advection", "heat_advection", ["-thm_final_time", 2e6]),
    ("heat_advection", "heat_advection_lu", ["-thm_final_time", 2e6, "-pc_type", "lu", "-ksp_type",
                                             "preonly"]),
    ("fracture_flow_patch", "fracture_flow_patch_2d", []),
    ("fracture_flow_patch", "fracture_flow_patch_3d", ["-thm_patch_dim", 3, "-thm_fe_degree", 1]),
    ("radial_flow", "radial_flow", ["-thm_mesh_size", 40, "-thm_radial_well_size", 4, "-thm_fe_degree", 1]),
    ("leakoff_1d", "leakoff_1d", ["-thm_final_time", 1e4, "-thm_mesh_size", 10, "-thm_fe_degree", 1]),
    ("lauwerier", "lauwerier_2d", ["-thm_final_time", 1e6, "-thm_mesh_size", 20,
                                   "-thm_lauwerier_fracture_size", 4]),
    ("lauwerier", "lauwerier_nusselt", ["-thm_final_time", 1e6, "-thm_mesh_size", 20, "-thm_fe_degree", 1,
                                        "-thm_lauwerier_fracture_size", 4,
                                        "-thm_fracture_heat_exchange", "nusselt"]),
    ("lauwerier", "lauwerier_3d", ["-thm_lauwerier_dim", 3, "-thm_mesh_size", 30, "-thm_fe_degree", 1,
                                   "-thm_lauwerier_fracture_size", 6, "-thm_final_time", 1e6]),
    ("leakoff_heat", "leakoff_heat", ["-thm_final_time", 1e6, "-thm_mesh_size", 20, "-thm_fe_degree", 1,
                                      "-thm_leakoff_heat_fracture_size", 4]),
    ("rigid_fracture", "rigid_fracture", ["-thm_fe_degree", 1, "-thm_final_time", 1e6, "-thm_mesh_size", 50,
                                          "-thm_scene1_fracture_size", 4, "-thm_rock_permeability", "1e-13"]),
    ("terzaghi", "terzaghi", ["-thm_final_time", 60, "-thm_mesh_size", 1.0]),
    ("mandel", "mandel", ["-thm_final_time", 30, "-thm_mesh_size", 1.0]),
    ("gravity_column", "gravity_column", []),
    ("thermal_stress", "thermal_stress", ["-thm_final_time", 1e6, "-thm_mesh_size", 10]),
    ("thermal_stress", "thermal_stress_heating", ["-thm_final_time", 1e5, "-thm_mesh_size", 10,
                                                  "-thm_thermomechanical_heating", 1]),
    ("sneddon", "sneddon_2d", ["-thm_sneddon_dim", 2, "-thm_sneddon_crack_size", 0.1]),
    ("sneddon", "sneddon_3d", ["-thm_sneddon_crack_size", 0.25, "-thm_fe_degree", 1,
                               "-thm_sneddon_normal_stress", 2e6]),  # + the crack pressure (ADDED)
    ("contact_patch", "contact_patch_2d", ["-thm_contact_dim", 2]),
    ("contact_patch", "contact_patch_3d", ["-thm_fe_degree", 1, "-thm_joint_stiffness", 5e10,
                                           "-thm_joint_aperture", 1e-3]),
    ("partial_opening", "partial_opening", ["-thm_partial_crack_size", 0.05]),
    ("fracture_inflation", "fracture_inflation", ["-thm_partial_crack_size", 0.1, "-thm_final_time", 500]),
    ("penny_impermeable", "penny_impermeable", [
        "-thm_fe_degree", 1, "-thm_scene2_fracture_size", 20, "-thm_scene2_well_size", 10,
        "-thm_scene2_layer", 2, "-thm_scene2_layer_growth", 2.5, "-thm_mesh_size", 150, "-thm_final_time",
        1e5]),
    ("penny_impermeable", "penny_nusselt_heating", [
        "-thm_fe_degree", 1, "-thm_scene2_fracture_size", 20, "-thm_scene2_well_size", 10,
        "-thm_scene2_layer", 2, "-thm_scene2_layer_growth", 2.5, "-thm_mesh_size", 150, "-thm_final_time",
        1e4,
        "-thm_fracture_heat_exchange", "nusselt", "-thm_thermomechanical_heating", 1,
        "-thm_scene2_normal_stress", 55e6]),
    ("inclined_penny", "inclined_penny", [
        "-thm_fe_degree", 1, "-thm_scene3_fracture_size", 50, "-thm_scene3_well_size", 15,
        "-thm_mesh_size", 300,
        "-thm_final_time", 2e6]),
]

#: older option name -> the name of physics.md section 12 (trees with petthm/physics/materials.py)
RENAMED = {
    "-thm_joint_stiffness": "-thm_fracture_normal_stiffness",
    "-thm_joint_aperture": "-thm_fracture_aperture",
    "-thm_joint_residual_fraction": "-thm_fracture_residual_fraction",
    "-thm_sneddon_normal_stress": "-thm_insitu_stress",
    "-thm_contact_normal_stress": "-thm_insitu_stress",
    "-thm_partial_normal_stress": "-thm_insitu_stress",
    "-thm_scene2_normal_stress": "-thm_insitu_stress",
    "-thm_contact_pressure": "-thm_initial_pressure",
    "-thm_partial_pressure": "-thm_initial_pressure",
    "-thm_inflation_rate": "-thm_injection_rate",
    "-thm_inflation_compressibility": "-thm_fluid_compressibility",
    "-thm_inflation_viscosity": "-thm_fluid_viscosity",
}

#: options a tree with the section 12 contract needs in addition (sneddon: the crack's pressure
#: -thm_initial_pressure replaced -thm_sneddon_net_pressure; default net pressure 1e6 over 2e6)
ADDED = {"sneddon_3d": ["-thm_initial_pressure", 3e6]}

#: summary keys that are not results (versions, provenance, and the solver's costs: times,
#: memory, preconditioner rebuilds, which differ from run to run)
SKIP = ("petthm_version", "petsc_version", "petsc4py_version", "wall_time", "wall_time_whole_run",
        "provenance", "parameters", "options", "git_commit", "reason", "solver_costs", "peak_memory_mb",
        "pc_rebuilds_forced")
#: magnitudes below this are round-off (in SI units, all of petthm's monitored quantities are larger)
FLOOR = 1e-11
#: cases solved iteratively (GMRES + GAMG to the default snes/ksp tolerances of 1e-10): compared at
#: that level; their "_lu" twins solve the same equations directly and are compared at 1e-12
ITERATIVE = {"heat_advection": 1e-9}
ITERATION_KEYS = ("snes_its", "ksp_its", "snes_iterations", "ksp_iterations")
#: monitors at the solver's tolerance (see the module docstring), compared absolutely
TOLERANCE_KEYS = ("balance", "overshoot", "bounds_violation", "aperture_identity")
TOLERANCE_LEVEL = 1e-10


def _translate(tree: str, case: str, opts: list) -> list:
    if not any(os.path.exists(os.path.join(tree, "petthm", *d, "materials.py")) for d in ((), ("physics",))):
        return list(opts)
    return [RENAMED.get(o, o) if isinstance(o, str) else o for o in opts] + ADDED.get(case, [])


def _knows(tree: str, option: str) -> bool:
    """Whether the tree declares the run-control option -thm_OPTION (in params.py)."""
    with open(os.path.join(tree, "petthm", "params.py")) as f:
        return f"    {option}:" in f.read()


def run(tree: str, out: str, only: list[str]) -> None:
    tree, out = os.path.abspath(tree), os.path.abspath(out)
    env = dict(os.environ, PYTHONPATH=tree, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    for scene, case, opts in CASES:
        if only and case not in only:
            continue
        d = os.path.join(out, case)
        replace = ["-thm_overwrite"] if any(os.path.exists(os.path.join(tree, "petthm", *d, "rundir.py"))
                                            for d in ((), ("io",))) else []
        replace += ["-thm_pc_reuse", "off"] if _knows(tree, "pc_reuse") else []
        cmd = [sys.executable, "-m", "petthm", scene, "-thm_output_dir", d, "-thm_quiet", *replace,
               *map(str, _translate(tree, case, opts))]
        p = subprocess.run(cmd, cwd=tree, env=env, capture_output=True, text=True)
        path = os.path.join(d, "summary.json")
        s = json.loads(Path(path).read_text()) if os.path.exists(path) else {}
        print(
            f"{case:28s} rc {p.returncode} {s.get('status')} {s.get('wall_time', {}).get('total', 0):7.1f} s",
              flush=True)
        if p.returncode:
            print(p.stdout[-2000:], p.stderr[-4000:], file=sys.stderr)


def _numbers(obj, prefix=""):
    """Flatten the numbers of a JSON object: {dotted key: float}."""
    out = {}
    if isinstance(obj, dict):
        for k, v in obj.items():
            if not prefix and k in SKIP:
                continue
            out.update(_numbers(v, f"{prefix}{k}."))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            out.update(_numbers(v, f"{prefix}{i}."))
    elif isinstance(obj, (int, float)) and not isinstance(obj, bool):
        out[prefix[:-1]] = float(obj)
    elif obj is None or isinstance(obj, (str, bool)):
        out[prefix[:-1]] = obj
    return out


def _rel(a, b, key="", level=TOLERANCE_LEVEL):
    """(relative difference, round-off?) of two numbers (or equal/unequal non-numbers)."""
    if not isinstance(a, float) or not isinstance(b, float):
        return (0.0 if a == b else math.inf), False
    if any(k in key for k in TOLERANCE_KEYS) and abs(a - b) <= level:
        return 0.0, "tolerance"
    if math.isnan(a) and math.isnan(b):
        return 0.0, False
    if max(abs(a), abs(b)) < FLOOR:
        return 0.0, "round-off"
    return abs(a - b) / max(abs(a), abs(b)), False


def _history(d):
    with open(os.path.join(d, "history.csv")) as f:
        rows = list(csv.DictReader(f))
    out = {}
    for k in (rows[0] if rows else {}):
        if k == "wall":
            continue
        vals = []
        for r in rows:
            try:
                vals.append(float(r[k]))
            except ValueError:
                vals.append(r[k])
        out[k] = vals
    return out


def _final_fields(d):
    import h5py

    from petthm.io.output import read_output
    out = {}
    for name in sorted(os.listdir(d)):
        if not name.endswith(".h5") or name == "checkpoint.h5":
            continue
        with h5py.File(os.path.join(d, name), "r") as h5:
            if "times" not in h5.attrs:
                continue
            nsteps = len(h5.attrs["times"])
        xyz, _, _, fields = read_output(os.path.join(d, name))   # the last output, on its own mesh
        order = np.lexsort(np.round(xyz, 9).T[::-1])
        for f, v in fields.items():
            out[f"{name}:{f}"] = (np.sort(v[order], axis=0), nsteps)  # + and - copies of a node coincide
    return out


def _compare_summaries(da: str, db: str, case: str, level: float):
    """(largest difference, where, the values below FLOOR in both) of two summary.json."""
    sa, sb = (_numbers(json.loads(Path(os.path.join(x, "summary.json")).read_text())) for x in (da, db))
    worst, where, roundoff = 0.0, "", []
    skip = ITERATION_KEYS if case in ITERATIVE else ()    # iteration counts near a tolerance: not results
    for k in sorted(set(sa) | set(sb)):
        if k in skip:
            continue
        r, ro = _rel(sa.get(k), sb.get(k), k, level)
        if ro == "round-off" and sa.get(k) != sb.get(k):
            roundoff.append(f"{k} {sa.get(k):.1e}/{sb.get(k):.1e}")
        if r > worst:
            worst, where = r, f"summary {k}: {sa.get(k)} vs {sb.get(k)}"
    return worst, where, roundoff


def _compare_histories(da: str, db: str, case: str, level: float):
    """(largest difference, where, {tolerance-level column: largest abs. difference}) of two history.csv."""
    ha, hb = _history(da), _history(db)
    worst, where, tol_diff = 0.0, "", {}
    skip = ITERATION_KEYS if case in ITERATIVE else ()
    for k in sorted(set(ha) | set(hb)):
        if k in skip:
            continue
        va, vb = ha.get(k, []), hb.get(k, [])
        if len(va) != len(vb):
            worst, where = math.inf, f"history {k}: {len(va)} vs {len(vb)} rows"
            continue
        for i, (x, y) in enumerate(zip(va, vb, strict=True)):
            r, ro = _rel(x, y, k, level)
            if ro == "tolerance" and x != y:
                tol_diff[k] = max(tol_diff.get(k, 0.0), abs(x - y))
            if r > worst:
                worst, where = r, f"history {k} row {i}: {x} vs {y}"
    return worst, where, tol_diff


def _compare_fields(da: str, db: str):
    """(largest relative difference, where) of the final outputs of two runs."""
    fa, fb = _final_fields(da), _final_fields(db)
    worst, where = 0.0, ""
    for k in sorted(set(fa) | set(fb)):
        if k not in fa or k not in fb or fa[k][0].shape != fb[k][0].shape:
            worst, where = math.inf, f"{k} missing or of another size"
            continue
        r = float(np.abs(fa[k][0] - fb[k][0]).max()) / max(np.abs(fa[k][0]).max(), 1e-300)
        if r > worst:
            worst, where = r, k
    return worst, where


def diff(a: str, b: str) -> int:
    rows = []
    for _scene, case, _ in CASES:
        da, db = os.path.join(a, case), os.path.join(b, case)
        if not all(os.path.exists(os.path.join(d, "summary.json")) for d in (da, db)):
            rows.append((case, "missing", "", "", ""))
            continue
        level = max(TOLERANCE_LEVEL, ITERATIVE.get(case, 0.0))
        worst, where, roundoff = _compare_summaries(da, db, case, level)
        hworst, hwhere, tol_diff = _compare_histories(da, db, case, level)
        if hworst > worst:
            worst, where = hworst, hwhere
        fworst, fwhere = _compare_fields(da, db)
        notes = [f"below {FLOOR:g} in both: {', '.join(roundoff)}"] if roundoff else []
        notes += [f"tolerance-level {k}: max abs. difference {v:.1e}" for k, v in sorted(tol_diff.items())]
        rows.append((case, f"{worst:.1e}", where, f"{fworst:.1e}",
                     fwhere + (f" ({'; '.join(notes)})" if notes else "")))
    print("| case | summary + history | largest at | final fields | largest at |")
    print("|---|---|---|---|---|")
    for r in rows:
        print("| " + " | ".join(r) + " |")
    bad = [r for r in rows if r[1] == "missing" or max(float(r[1]), float(r[3])) > ITERATIVE.get(r[0], 1e-12)]
    return 1 if bad else 0


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if len(argv) >= 3 and argv[0] == "run":
        run(argv[1], argv[2], argv[3:])
        return 0
    if len(argv) == 3 and argv[0] == "diff":
        return diff(argv[1], argv[2])
    print(__doc__)
    return 2


if __name__ == "__main__":
    sys.exit(main())
