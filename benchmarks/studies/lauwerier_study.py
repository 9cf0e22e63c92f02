"""Error against run time for the ``lauwerier`` scene (P1 and P2, several
mesh/time-step resolutions): CSV, a work-precision PNG and a markdown table.

    python benchmarks/studies/lauwerier_study.py [--out output/lauwerier] [--levels 0,1,2,3,4]
                                      [--schemes beuler,bdf2] [--jobs 2] [--plot-only]

Each run is ``python -m petthm lauwerier`` with the options of its level;
the study reads only the runs' summary.json/history.csv files.  The outlet
error is max |T_out - T_Lauwerier| over t >= 1e6 s (kelvin), the profile
errors are the max over the fracture at 1e7 and 1e8 s (fraction of T0 - Tinj);
the wall time is the run's total wall time (one run at a time per core).
``bdf2`` runs the same levels with PETSc's variable-step BDF2 (-ts_type bdf
-ts_bdf_order 2) instead of backward Euler (the default), and
``beuler_fine_dt`` runs every level with the same small backward-Euler steps
(+1 %/step, at most 1e5 s), to separate the time-discretisation error from
the spatial one; ``beuler_error`` takes the steps from backward Euler's local
error estimate (``-thm_dt_control error``) with the level's ``-ts_atol``
(``ERROR_TOLERANCE``) and largest step.  The table has the outlet error over
t >= 1e4 s (the whole meaningful range; the plot's metric) and over
t >= 1e6 s (the earlier metric); ``beuler_layered`` runs the levels' fracture
sizes and steps on the layered mesh (``-thm_lauwerier_layer``: the fracture's
cells extruded to both sides in layers from 0.05 m growing by 1.5);
``bdf2_error`` and ``bdf2_error_layered`` take BDF2's steps from its own
error estimate (``BDF2_ERROR_TOLERANCE``) on the graded and the layered mesh;
a ``_wall`` suffix adds ``-thm_fracture_supg_wall_conduction true``.
The energy balance is evaluated for backward Euler only ('n/a' otherwise)."""
from __future__ import annotations

import argparse
import csv
import os
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from study_tables import ROOT, run_petthm, write_csv  # noqa: E402

DT_RANGE = 80.0           # T0 - Tinj of the default scene (K)

#: level -> (fracture mesh size m, far mesh size m, dt growth, dt_max s)
LEVELS = {0: (4.0, 20.0, 1.10, 4e6), 1: (2.0, 15.0, 1.07, 2e6), 2: (1.0, 10.0, 1.05, 1e6),
          3: (0.5, 10.0, 1.03, 5e5), 4: (0.25, 8.0, 1.02, 2.5e5)}
#: level -> -ts_atol of the ``beuler_error`` scheme (-thm_dt_control error; fraction of T0 - Tinj)
ERROR_TOLERANCE = {0: 1e-2, 1: 3e-3, 2: 1e-3, 3: 3e-4, 4: 1e-4}
#: level -> -ts_atol of the ``bdf2_error*`` schemes (BDF2's error estimate is of a higher order:
#: a tolerance as tight costs fewer steps)
BDF2_ERROR_TOLERANCE = {0: 1e-3, 1: 3e-4, 2: 1e-4, 3: 1e-4, 4: 1e-4}
SCHEMES = {"beuler": ("-", "backward Euler, schedule"), "bdf2": ("--", "BDF2, schedule"),
           "beuler_fine_dt": (":", "BE, fixed small steps"),
           "beuler_error": ("-.", "backward Euler, error control"),
           "beuler_layered": ((0, (3, 1, 1, 1)), "backward Euler, layered mesh"),
           "bdf2_error": ((0, (5, 2)), "BDF2, error control"),
           "bdf2_error_layered": ((0, (1, 1)), "BDF2, error control, layered mesh"),
           "bdf2_error_wall": ((0, (5, 1, 1, 1)), "BDF2, error control, SUPG wall conduction"),
           "bdf2_error_layered_wall": ((0, (2, 2)), "BDF2, error control, layered, SUPG wall conduction")}
#: the ``beuler_layered`` scheme's first layer (m: ~0.5 sqrt(kappa 1e4 s)) and layer growth
LAYER, LAYER_GROWTH = 0.05, 1.5


def _metric(x):
    """The outlet error over t >= 1e4 s (K), or over t >= 1e6 s for rows of older studies."""
    return float(x.get("outlet_error_1e4_K") or x["outlet_error_K"])


def run_one(out, degree, level, scheme="beuler"):
    fs, ms, g, dtmax = LEVELS[level]
    d = os.path.join(out, f"P{degree}_L{level}" + ("" if scheme == "beuler" else f"_{scheme}"))
    dt = ("-thm_dt_growth", g, "-thm_dt_max", dtmax)
    if scheme == "beuler_fine_dt":       # the same small steps at every level: spatial error only
        dt = ("-thm_dt_growth", 1.01, "-thm_dt_max", 1e5)
    bdf2 = ("-ts_type", "bdf", "-ts_bdf_order", 2) if scheme.startswith("bdf2") else ()
    mesh = ()
    if "_layered" in scheme:             # the level's steps and fracture size on a layered mesh
        mesh = ("-thm_lauwerier_layer", LAYER, "-thm_lauwerier_layer_growth", LAYER_GROWTH)
    if scheme.endswith("_wall"):         # the rock's wall conduction in the fracture's SUPG residual
        mesh += ("-thm_fracture_supg_wall_conduction", "true")
    atol = None
    if "_error" in scheme:               # steps from the local error estimate, tolerance by level
        atol = (BDF2_ERROR_TOLERANCE if bdf2 else ERROR_TOLERANCE)[level]
        dt = ("-thm_dt_control", "error", "-ts_atol", atol, "-thm_dt_max", dtmax)
    s = run_petthm("lauwerier", d, "-thm_fe_degree", degree, "-thm_lauwerier_fracture_size", fs,
                   "-thm_mesh_size", ms, "-thm_heat_transport", "supg", *dt, *bdf2, *mesh)
    e = s["error"]
    row = {"scheme": scheme, "degree": degree, "level": level, "fracture_size": fs, "mesh_size": ms,
           "dt_growth": g if atol is None else f"atol {atol:g}",
           "dt_max": dtmax, "cells": s["cells"], "dofs": sum(s["dofs"].values()), "steps": s["steps"],
           "wall_s": round(s["wall_time"]["total"], 2),
           "outlet_error_K": e["outlet_max_rel_t_ge_1e6"] * DT_RANGE,
           "outlet_error_1e4_K": e["outlet_max_rel_t_ge_1e4"] * DT_RANGE,
           "rejected": s["rejected_steps"],
           "profile_1e7": e["profile_max_rel_t1e+07"], "profile_1e8": e["profile_max_rel_t1e+08"],
           "energy_balance_max": s["balance_max"]["energy_balance"]}
    print(f"{scheme} P{degree} level {level}: {row['wall_s']} s, outlet error "
          f"{row['outlet_error_1e4_K']:.3f} K (t >= 1e4 s), {row['outlet_error_K']:.3f} K (t >= 1e6 s)",
          flush=True)
    return row


def plot(rows, out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for scheme, (ls, label) in SCHEMES.items():
      for deg, mk in ((1, "o"), (2, "s")):
        r = sorted((x for x in rows if int(x["degree"]) == deg and x.get("scheme", "beuler") == scheme),
                   key=lambda x: float(x["wall_s"]))
        if not r:
            continue
        ax.loglog([float(x["wall_s"]) for x in r], [_metric(x) for x in r], marker=mk, linestyle=ls,
                  label=f"P{deg} {label}")
        for x in r:
            ax.annotate(f"L{x['level']}", (float(x["wall_s"]), _metric(x)), fontsize=7)
    ax.axhline(0.1, color="gray", ls=":", label="0.1 K")
    ax.set_xlabel("wall time (s, 1 rank)")
    ax.set_ylabel("max outlet error for t >= 1e4 s (K)")
    ax.set_title("lauwerier: error against run time")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(out, "lauwerier_work_precision.png"), dpi=120)


def table(rows) -> str:
    lines = ["| time | P | level | fracture h (m) | dt growth / max (s) | cells | dofs | steps | wall (s) | "
             "outlet error t >= 1e4 s (K) | outlet error t >= 1e6 s (K) | profile 1e7 | profile 1e8 | "
             "energy balance |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for x in sorted(rows, key=lambda x: (x.get("scheme", "beuler"), int(x["degree"]), int(x["level"]))):
        bal = float(x["energy_balance_max"])
        lines.append(
            f"| {x.get('scheme', 'beuler')} | {x['degree']} | {x['level']} | {x['fracture_size']} | "
            f"{x['dt_growth']} / "
            f"{float(x['dt_max']):.2g} | {x['cells']} | {x['dofs']} | {x['steps']} | {x['wall_s']} | "
            f"{x.get('outlet_error_1e4_K') and format(float(x['outlet_error_1e4_K']), '.3f') or 'n/a'} | "
            f"{float(x['outlet_error_K']):.3f} | {float(x['profile_1e7']):.2e} | "
            f"{float(x['profile_1e8']):.2e} | {'n/a' if bal != bal else f'{bal:.1e}'} |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(ROOT, "output", "lauwerier"))
    ap.add_argument("--levels", default="0,1,2,3,4")
    ap.add_argument("--degrees", default="1,2")
    ap.add_argument("--schemes", default="beuler,bdf2")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--plot-only", action="store_true")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    path = os.path.join(a.out, "lauwerier_study.csv")
    if not a.plot_only:
        cases = [(d, lv, sc) for sc in a.schemes.split(",") for d in map(int, a.degrees.split(","))
                 for lv in map(int, a.levels.split(","))]
        with ThreadPoolExecutor(a.jobs) as ex:
            rows = list(ex.map(lambda c: run_one(os.path.join(a.out, "runs"), *c), cases))
        if os.path.exists(path):          # keep rows of other schemes/levels from earlier runs
            done = {(r["scheme"], int(r["degree"]), int(r["level"])) for r in rows}
            rows += [r for r in csv.DictReader(Path(path).read_text().splitlines())
                     if (r.get("scheme", "beuler"), int(r["degree"]), int(r["level"])) not in done]
        write_csv(path, [{**r, "scheme": r.get("scheme") or "beuler"} for r in rows])
    rows = list(csv.DictReader(Path(path).read_text().splitlines()))
    plot(rows, a.out)
    md = table(rows)
    with open(os.path.join(a.out, "lauwerier_study.md"), "w") as f:
        f.write("# lauwerier: error against run time\n\n" + md + "\n")
    print(md)


if __name__ == "__main__":
    main()
