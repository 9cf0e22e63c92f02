"""Convergence study of the full coupled manufactured solution (``coupled_mms``,
verification.md section 8): errors of every field against the mesh size,
fitted rates, and the wall time of each run (error against run time).

    python benchmarks/studies/coupled_mms_study.py [--cases 2:1:open:1,...] [--out DIR] [--sizes H1,H2,...]
                                        [-- petthm options]

A case is DIM:DEGREE:STATE:SUPG with its mesh sizes from ``SIZES``; the
default set is every combination the acceptance asks for (2D and 3D, P1
and P2, open and closed) with SUPG on (``-thm_heat_transport supg``: P1
temperatures take the limited scheme by default; pass
``-- -thm_heat_transport limited`` for it) and, for P2, also off (the
Galerkin form: SUPG's residual is not consistent at P2, see the manual's
verification).  Writes coupled_mms.csv (one row per run) and
coupled_mms.md (errors, fitted slopes over all sizes, the slope of the last
refinement) in OUT (default output/coupled_mms).
"""
from __future__ import annotations

import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
import numpy as np
from study_tables import ROOT, markdown, run_petthm, write_csv, write_markdown  # noqa: E402

#: lam_recovered: the traction recovered from the rock's stress (kernels/contact.RecoveredTraction)
FIELDS = ("u", "lam", "lam_recovered", "pf", "pm", "Tf", "Tm")
#: mesh sizes per (dim, degree): >= 3 refinements each
SIZES = {(2, 1): (0.125, 0.0625, 0.03125, 0.015625), (2, 2): (0.25, 0.125, 0.0625, 0.03125),
         (3, 1): (0.125, 0.0625, 0.03125), (3, 2): (0.25, 0.125, 0.0625)}
DEFAULT_CASES = [f"{d}:{p}:{s}:{g}" for d in (2, 3) for p in (1, 2) for s in ("open", "closed")
                 for g in ((1, 0) if p == 2 else (1,))]


def slope(h, e, last: bool = False) -> float:
    h, e = np.asarray(h, dtype=float), np.asarray(e, dtype=float)
    if len(e) < 2 or np.any(e <= 0):
        return float("nan")              # one mesh (--sizes H): no slope
    if last:
        return float(np.log(e[-2] / e[-1]) / np.log(h[-2] / h[-1]))
    return float(np.polyfit(np.log(h), np.log(e), 1)[0])


def run_case(case: str, out: str, extra=(), sizes=None) -> tuple[list[dict], list[dict]]:
    dim, degree, state, supg = case.split(":")
    rows = []
    for size in sizes or SIZES[(int(dim), int(degree))]:
        d = os.path.join(out, "runs", f"{dim}d_p{degree}_{state}_supg{supg}_h{size:g}")
        s = run_petthm("coupled_mms", d, "-thm_coupled_mms_dim", dim, "-thm_fe_degree", degree,
                       "-thm_coupled_mms_state", state, "-thm_coupled_mms_supg", supg,
                       "-thm_mesh_size", size, *(("-thm_heat_transport", "supg") if supg == "1" else ()),
                       *extra)
        row = {"dim": int(dim), "degree": int(degree), "state": state, "supg": int(supg), "mesh_size": size,
               "h_max": s["h_max"], "cells": s["cells"], "wall_s": s["wall_time"]["total"],
               "newton": s["snes_iterations"]}
        for f in FIELDS:
            for n in ("l2", "h1", "l2_rel", "h1_rel"):
                row[f"{f}_{n}"] = s["error"][f"{f}_{n}"]
        rows.append(row)
        print(case, f"h={row['h_max']:.4f}", f"{row['wall_s']:.1f} s",
              " ".join(f"{f}:{row[f + '_l2_rel']:.2e}" for f in FIELDS), flush=True)
    h = [r["h_max"] for r in rows]
    rates = []
    for f in FIELDS:
        if state == "open" and f.startswith("lam"):
            continue                      # lam = 0: its error is whether a node closed, not a rate
        rates.append({"case": f"{dim}D P{degree} {state} supg={supg}", "field": f,
                      "l2_fit": slope(h, [r[f"{f}_l2"] for r in rows]),
                      "h1_fit": slope(h, [r[f"{f}_h1"] for r in rows]),
                      "l2_last": slope(h, [r[f"{f}_l2"] for r in rows], True),
                      "h1_last": slope(h, [r[f"{f}_h1"] for r in rows], True),
                      "l2_rel_finest": rows[-1][f"{f}_l2_rel"], "wall_finest_s": rows[-1]["wall_s"]})
    return rows, rates


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", default=",".join(DEFAULT_CASES))
    ap.add_argument("--out", default=os.path.join(ROOT, "output", "coupled_mms"))
    ap.add_argument("--sizes", default="", help="mesh sizes for every case, comma-separated "
                    "(default: SIZES by dimension and degree)")
    ap.add_argument("extra", nargs="*",
                    help="more petthm options (after --), e.g. -thm_direct_max_unknowns 1000000")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    runs, rates = [], []
    for case in a.cases.split(","):
        r, s = run_case(case, a.out, a.extra, [float(x) for x in a.sizes.split(",") if x])
        runs += r
        rates += s
        write_csv(os.path.join(a.out, "coupled_mms.csv"), runs)
        write_csv(os.path.join(a.out, "coupled_mms_rates.csv"), rates)
        cols = [("case", "case", "s"), ("field", "field", "s"), ("L2 slope (fit)", "l2_fit", ".2f"),
                ("H1 slope (fit)", "h1_fit", ".2f"), ("L2 slope (last)", "l2_last", ".2f"),
                ("H1 slope (last)", "h1_last", ".2f"), ("L2 rel. error, finest", "l2_rel_finest", ".2e"),
                ("wall s, finest", "wall_finest_s", ".1f")]
        write_markdown(os.path.join(a.out, "coupled_mms.md"),
                       "Full coupled MMS (coupled_mms): fitted convergence slopes", markdown(cols, rates))


if __name__ == "__main__":
    main()
