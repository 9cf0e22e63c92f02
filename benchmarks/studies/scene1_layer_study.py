"""Scene 1 (``rigid_fracture``) on a graded and on layered meshes: the
production temperature's error against run time.

    python benchmarks/studies/scene1_layer_study.py [--out output/scene1_layers] [--jobs 1]
                                         [--variants graded,layer_0.05,...] [--plot-only]

Each case is scored against its finest run (``REFERENCE``: 0.02 m first
layer, 0.5 m on the fracture, BDF2): the largest |T_prod - T_ref| over
1e4 <= t <= 1e9 s (the range the peer comparison of docs/verification/peer-ogs.md
scores) and over t >= 1e6 s.  The impermeable case is also compared with
the Lauwerier/Bodvarsson outlet temperature (``scene1_sweep.lauwerier``),
a model with conduction across the fracture only: its difference from the
reference run is the isotropic conduction the scene has, not an error.
Each variant runs once per case, one core each (``--jobs 2``: two side by
side; wall times of one study are comparable with each other).  Writes
scene1_layers.csv / scene1_layers.md.
"""
from __future__ import annotations

import argparse
import os
import sys
from concurrent.futures import ThreadPoolExecutor

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
import numpy as np
from scene1_sweep import lauwerier  # noqa: E402
from study_tables import ROOT, markdown, read_history, read_summary, run_petthm, write_csv, write_markdown  # noqa: E402

BDF2 = ("-ts_type", "bdf", "-ts_bdf_order", "2")
#: name -> options (the scene's defaults otherwise: P2, graded mesh at 1 m on the fracture, 25 m far)
VARIANTS = {
    "graded": (),
    "graded_f0.5": ("-thm_scene1_fracture_size", "0.5"),
    "layer_0.05": ("-thm_scene1_layer", "0.05"),
    "layer_0.05_f2": ("-thm_scene1_layer", "0.05", "-thm_scene1_fracture_size", "2"),
    "layer_0.05_p1": ("-thm_scene1_layer", "0.05", "-thm_fe_degree", "1"),
    "graded_bdf2": BDF2,
    "graded_f0.5_bdf2": ("-thm_scene1_fracture_size", "0.5") + BDF2,
    "layer_0.05_f2_bdf2": ("-thm_scene1_layer", "0.05", "-thm_scene1_fracture_size", "2") + BDF2,
    "layer_0.05_bdf2": ("-thm_scene1_layer", "0.05") + BDF2,
    "layer_0.05_g1.6_bdf2": ("-thm_scene1_layer", "0.05", "-thm_scene1_layer_growth", "1.6") + BDF2,
    "layer_0.1_g1.6_bdf2": ("-thm_scene1_layer", "0.1", "-thm_scene1_layer_growth", "1.6") + BDF2,
    "layer_0.02_bdf2": ("-thm_scene1_layer", "0.02", "-thm_scene1_fracture_size", "0.5",
                        "-ts_type", "bdf", "-ts_bdf_order", "2"),
}
WALL = ("-thm_fracture_supg_wall_conduction", "true")
VARIANTS.update({f"{k}_wall": v + WALL for k, v in list(VARIANTS.items())
                 if k in ("graded_bdf2", "graded_f0.5_bdf2", "layer_0.05_g1.6_bdf2", "layer_0.02_bdf2")})
#: the reference run of the permeable case (finest in space and second order in time)
REFERENCE = "layer_0.02_bdf2"
CASES = {"k0": "0", "1d_1e-13": "0,1e-13"}


def run(out: str, case: str, variant: str) -> None:
    run_petthm("rigid_fracture", os.path.join(out, "runs", case, variant), "-options_file",
               os.path.join(ROOT, "options", "scenes", "rigid_fracture.opts"),
               "-thm_rock_permeability", CASES[case], "-thm_heat_transport", "supg", *VARIANTS[variant])
    print(f"{case} {variant}: done", flush=True)


def errors(t: np.ndarray, T: np.ndarray, ref) -> tuple[float, float]:
    """Largest |T - ref(t)| over 1e4 <= t <= 1e9 s and over t >= 1e6 s."""
    e = np.abs(T - ref(t))
    return float(e[(t >= 1e4) & (t <= 1e9)].max()), float(e[t >= 1e6].max())


def row(out: str, case: str, variant: str) -> dict:
    d = os.path.join(out, "runs", case, variant)
    h, s = read_history(d), read_summary(d)
    t, T = h["time"], h["production_temperature"]
    e_all, e_late = errors(t, T, reference(out, case))
    r = {"case": case, "variant": variant, "cells": s.get("cells"), "dofs": sum(s["dofs"].values()),
         "steps": s["steps"], "wall_s": round(s["wall_time"]["total"], 1), "error_1e4_K": e_all,
         "error_1e6_K": e_late, "lauwerier_1e4_K": float("nan")}
    if case == "k0":
        r["lauwerier_1e4_K"] = errors(t, T, lauwerier)[0]
    return r


def reference(out: str, case: str):
    """T_prod(t) of the case's reference run (log-time interpolation)."""
    h = read_history(os.path.join(out, "runs", case, REFERENCE))
    lt, T = np.log(h["time"]), h["production_temperature"]
    return lambda t: np.interp(np.log(t), lt, T)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(ROOT, "output", "scene1_layers"))
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--variants", default=",".join(VARIANTS))
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--plot-only", action="store_true", help="tables from the runs already there")
    a = ap.parse_args()
    variants, cases = a.variants.split(","), a.cases.split(",")
    if not a.plot_only:
        todo = [(c, v) for c in cases for v in variants]
        with ThreadPoolExecutor(a.jobs) as ex:
            list(ex.map(lambda cv: run(a.out, *cv), todo))
    rows = []
    for c in cases:            # the runs there are (a variant not run for a case is left out)
        rows += [row(a.out, c, v) for v in variants
                 if os.path.exists(os.path.join(a.out, "runs", c, v, "summary.json"))]
    write_csv(os.path.join(a.out, "scene1_layers.csv"), rows)
    md = markdown([("case", "case", ""), ("variant", "variant", ""), ("cells", "cells", ""),
                   ("unknowns", "dofs", ""), ("steps", "steps", ""), ("wall (s)", "wall_s", ""),
                   ("max error 1e4-1e9 s (K)", "error_1e4_K", ".3f"),
                   ("max error 1e6-1e9 s (K)", "error_1e6_K", ".3f"),
                   ("k0: max diff. from Lauwerier 1e4-1e9 s (K)", "lauwerier_1e4_K", ".3f")], rows)
    write_markdown(os.path.join(a.out, "scene1_layers.md"), "Scene 1: graded against layered meshes", md)
    print(md)


if __name__ == "__main__":
    main()
