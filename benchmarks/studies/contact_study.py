"""Mechanics studies (issue 4): CSV, PNG and markdown tables.

    python benchmarks/studies/contact_study.py [--out output/contact] [--study sneddon,vi,mandel]
                                    [--plot-only]

* ``sneddon``: error against run time for the Griffith (2D) and penny (3D)
  cracks, P1 and P2, three or four crack mesh sizes each: the error of the
  opening at the centre and the relative L2 error of the opening over
  r < 0.95 R (verification.md section 4), with each run's wall time.
* ``vi``: ``partial_opening`` on three meshes with both VI Newton methods
  (vinewtonrsls, vinewtonssls), with the direct solver and with the
  block preconditioner options/solvers/block.opts: Newton and
  Krylov iterations per step,
  failed solves, the end of the open zone and the opening at the centre,
  and the largest difference of the opening profile from the finest mesh.
* ``pairing``: the contact pairings of docs/verification/contact.md (dual, the default,
  and consistent, P1 lam) on Scene 2's coarse unstructured meshes (fracture
  40 m and 20 m, to 1e7 s) with P1 and P2 u: the aperture identity, the
  largest opening of a closed node, the second difference of lam away from
  the wells and the front, lam and the aperture at the injector, wall time.
  (The sneddon study runs both pairings too.)
* ``inclined``: the frictional inclined crack (options/scenes/
  inclined_crack.opts) on crack meshes a/10 ... a/80, P1 and P2: the
  relative L2 error of the slip over |x| < 0.95 a and the slip at the
  centre against the mode II profile, with each run's wall time.
* ``--compare-lam COARSE FINE``: two Scene 2 runs' nodal lam at their
  common output times (fracture.h5), the coarse one against the fine one
  interpolated (a smooth reference for the coarse run's nodal values), over
  the nodes more than 40 m from the wells and inside r < 90 m.
* ``mandel``: error against run time for Mandel's problem, u of degree 1
  and 2 (pm P1), three structured meshes: the largest nodal pressure error
  over c t/a^2 = 0.01 ... 1 and the error of the Mandel-Cryer peak, both
  relative to p0 (verification.md section 6), with each run's wall time.

Each run is ``python -m petthm SCENE``; the study reads only the runs'
summary.json and history.csv files.
"""
from __future__ import annotations

import argparse
import csv
import os
import sys
from pathlib import Path

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
import numpy as np
from study_tables import ROOT, read_history, run_petthm, write_csv  # noqa: E402

SNEDDON = {2: ["-thm_sneddon_dim", "2", "-thm_sneddon_radius", "50"], 3: []}
SNEDDON_SIZES = {2: [0.1, 0.05, 0.025, 0.0125], 3: [0.2, 0.1, 0.05]}
VI_SIZES = [0.05, 0.025, 0.0125]
PAIRINGS = ["dual", "consistent"]
INCLINED_SIZES = {2: [0.1, 0.05, 0.025, 0.0125], 3: [0.2, 0.1, 0.05, 0.025]}
PAIRING_MESHES = {40: 20, 20: 10}          # Scene 2 fracture size: well size (m)
MANDEL_SIZES = [1.0, 0.5, 0.25]
VI_METHODS = ["vinewtonrsls", "vinewtonssls"]
VI_SOLVERS = {"direct": [], "fieldsplit": ["-options_file", os.path.join(ROOT, "options", "solvers",
                                                                         "block.opts")]}


def sneddon_study(out):
    rows = []
    for pairing in PAIRINGS:
        for dim in (2, 3):
            for degree in (1, 2):
                for h in SNEDDON_SIZES[dim]:
                    d = os.path.join(out, "runs", f"sneddon{dim}d_P{degree}_h{h}_{pairing}")
                    s = run_petthm("sneddon", d, *SNEDDON[dim], "-thm_fe_degree", degree,
                                   "-thm_sneddon_crack_size", h, "-thm_contact_pairing", pairing)
                    e = s["error"]
                    rows.append({"pairing": pairing, "dim": dim, "degree": degree, "crack_size_over_R": h,
                                 "cells": s["cells"], "dofs": sum(s["dofs"].values()),
                                 "wall_s": round(s["wall_time"]["total"], 2),
                                 "centre_error": e["centre_error"], "l2_error": e["opening_l2_error"]})
                    print(
                        f"sneddon {pairing} {dim}D P{degree} h={h}: {rows[-1]['wall_s']} s, "
                        f"centre {e['centre_error']:.2e}, "
                        f"L2 {e['opening_l2_error']:.2e}", flush=True)
    write_csv(os.path.join(out, "sneddon.csv"), rows)
    return rows


def pairing_study(out):
    rows = []
    for pairing in PAIRINGS:
        for degree in (1, 2):
            for size, well in PAIRING_MESHES.items():
                d = os.path.join(out, "runs", f"scene2_{pairing}_P{degree}_h{size}")
                s = run_petthm("penny_impermeable", d, "-options_file",
                               os.path.join(ROOT, "options", "scenes", "penny_impermeable.opts"),
                               "-thm_scene2_fracture_size", size, "-thm_scene2_well_size", well,
                               "-thm_scene2_layer", 0, "-thm_fe_degree", degree, "-thm_final_time", 1e7,
                               "-thm_contact_pairing", pairing, "-thm_heat_transport", "supg")
                h = read_history(d)
                rough = h["lam_roughness"].astype(float)
                rows.append({"pairing": pairing, "degree": degree, "fracture_size_m": size,
                             "dofs": sum(s["dofs"].values()), "wall_s": round(s["wall_time"]["total"], 2),
                             "aperture_identity": float(h["aperture_identity"].astype(float).max()),
                             "closed_opening": float(h["closed_opening"].astype(float).max()),
                             "lam_roughness": float(np.nanmax(rough)) if np.isfinite(rough).any() else "",
                             "lam_injector_MPa": float(h["lam_injector"].astype(float)[-1]) / 1e6,
                             "aperture_injector_mm": 1e3 * float(h["aperture_injector"].astype(float)[-1])})
                print("scene2", rows[-1], flush=True)
    write_csv(os.path.join(out, "pairing_scene2.csv"), rows)
    return rows


def inclined_study(out):
    rows = []
    for dim, degree in ((2, 1), (2, 2), (3, 2)):
        for h in INCLINED_SIZES[dim]:
            d = os.path.join(out, "runs", f"inclined{dim}d_P{degree}_h{h}")
            s = run_petthm("inclined_crack", d, "-options_file",
                           os.path.join(ROOT, "options", "scenes", "inclined_crack.opts"),
                           "-thm_inclined_dim", dim, "-thm_fe_degree", degree, "-thm_inclined_crack_size", h)
            pc = s["provenance"]["options"].get("-pc_type", "")
            rows.append({"dim": dim, "degree": degree, "crack_size_over_a": h,
                         "dofs": sum(s["dofs"].values()), "solver": "block" if pc == "python" else "direct",
                         "wall_s": round(s["wall_time"]["total"], 2), "slip_l2_error": s["slip_l2_error"],
                         "centre_error": abs(s["slip_centre"] / s["slip_centre_exact"] - 1.0),
                         "lam_error": s["lam_error"], "law_error": s["law_error"]})
            print("inclined", rows[-1], flush=True)
    write_csv(os.path.join(out, "inclined.csv"), rows)
    return rows


def mandel_study(out):
    rows = []
    for degree in (1, 2):
        for h in MANDEL_SIZES:
            d = os.path.join(out, "runs", f"mandel_P{degree}_h{h}")
            s = run_petthm("mandel", d, "-thm_fe_degree", degree, "-thm_mesh_size", h)
            e = s["error"]
            rows.append({"degree": degree, "mesh_size": h, "cells": s["cells"],
                         "dofs": sum(s["dofs"].values()),
                         "steps": s["steps"], "wall_s": round(s["wall_time"]["total"], 2),
                         "p_max_rel": e["p_max_rel"], "cryer_peak_rel": e["mandel_cryer_peak_rel_p0"]})
            print(f"mandel P{degree} h={h}: {rows[-1]['wall_s']} s, p error {e['p_max_rel']:.2e}, "
                  f"peak {e['mandel_cryer_peak_rel_p0']:.2e}", flush=True)
    write_csv(os.path.join(out, "mandel.csv"), rows)
    return rows


def plot_mandel(out, rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for ax, key, title, lim in zip(axes, ("p_max_rel", "cryer_peak_rel"),
                                   ("max nodal pressure error / p0", "Mandel-Cryer peak error / p0"),
                                   (1e-2, 5e-3), strict=False):
        for deg, mk in (("1", "s--"), ("2", "o-")):
            sel = [r for r in rows if str(r["degree"]) == deg]
            ax.loglog([float(r["wall_s"]) for r in sel], [float(r[key]) for r in sel], mk,
                      label=f"P{deg} u / P1 pm")
        ax.axhline(lim, color="grey", lw=0.8, ls=":")
        ax.set_xlabel("wall time (s)")
        ax.set_ylabel("error / p0")
        ax.set_title(title)
        ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(out, "mandel_work_precision.png"), dpi=120)


def vi_study(out):
    rows, profiles = [], {}
    for solver, sopts in VI_SOLVERS.items():
        for h in VI_SIZES:
            for method in VI_METHODS:
                rows.append(_vi_run(out, solver, sopts, h, method, profiles))
    finest = profiles[("direct", "vinewtonrsls", VI_SIZES[-1])]
    xs = np.linspace(0.0, 0.99 * 50.0, 400)
    ref = np.interp(xs, finest["x"], finest["opening"])
    for r in rows:
        p = profiles[(r["solver"], r["method"], r["crack_size_over_c"])]
        r["profile_diff_to_finest_mm"] = 1e3 * float(np.abs(np.interp(xs, p["x"], p["opening"]) - ref).max())
    write_csv(os.path.join(out, "partial_opening.csv"), rows)
    return rows


def _vi_run(out, solver, sopts, h, method, profiles):
    """One partial_opening run; its row of the table (and its opening profile)."""
    d = os.path.join(out, "runs", f"partial_{solver}_{method}_h{h}")
    s = run_petthm("partial_opening", d, "-thm_partial_crack_size", h, "-snes_type", method, *sopts)
    hist = read_history(d)
    its, kits = hist["snes_its"].astype(int).tolist(), hist["ksp_its"].astype(int).tolist()
    profiles[(solver, method, h)] = s["profile"]
    print(f"partial_opening {solver} {method} h={h}: Newton {its}, Krylov {kits}, "
          f"open to {s['open_length']:.3f} m", flush=True)
    return {"solver": solver, "method": method, "crack_size_over_c": h, "steps": s["steps"],
            "rejected": s.get("rejected_steps", 0), "newton_per_step": " ".join(map(str, its)),
            "krylov_per_step": " ".join(map(str, kits)), "newton_max": max(its), "newton_total": sum(its),
            "krylov_total": sum(kits), "wall_s": round(s["wall_time"]["total"], 2),
            "open_length_m": s["open_length"], "opening_centre_mm": 1e3 * s["opening_centre"],
            "nodes_open": s["nodes_open"]}


def compare_lam(coarse: str, fine: str, lam0: float = 40e6):
    """max and mean |lam_coarse - lam_fine| / lam0 at the common output times (see the docstring)."""
    import re

    import h5py
    from scipy.interpolate import LinearNDInterpolator

    def times(d):
        text = Path(os.path.join(d, "fracture.xdmf")).read_text()
        return [float(t) for t in re.findall(r'<Time Value="([^"]+)"', text)]
    with h5py.File(os.path.join(coarse, "fracture.h5")) as f, \
            h5py.File(os.path.join(fine, "fracture.h5")) as g:
        xc, xf = f["mesh/geometry"][()][:, :2], g["mesh/geometry"][()][:, :2]
        wells = np.array([[-50.0, 0.0], [50.0, 0.0]])
        sel = (np.min(np.linalg.norm(xc[:, None, :] - wells[None], axis=2), axis=1) > 40.0) & \
            (np.linalg.norm(xc, axis=1) < 90.0)
        tf = times(fine)
        for k, t in enumerate(times(coarse)):
            if t not in tf:
                continue
            lc, lf = f[f"fields/lam/{k}"][()], g[f"fields/lam/{tf.index(t)}"][()]
            ref = LinearNDInterpolator(xf, lf)(xc)
            ok = sel & np.isfinite(ref)
            d = np.abs(lc - ref)[ok] / lam0
            print(f"t = {t:.3g} s: {ok.sum()} nodes, max {d.max():.4f}, mean {d.mean():.4f} of lam0")


def read_csv(path):
    return list(csv.DictReader(Path(path).read_text().splitlines()))


def plot_sneddon(out, rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for ax, key, title in zip(axes, ("centre_error", "l2_error"),
                              ("opening at the centre", "opening, L2 over r < 0.95 R"), strict=False):
        for dim in ("2", "3"):
            for deg, mk in (("1", "s--"), ("2", "o-")):
                for pairing in PAIRINGS:
                    sel = [r for r in rows if str(r["dim"]) == dim and str(r["degree"]) == deg
                           and r.get("pairing", "dual") == pairing]
                    ax.loglog([float(r["wall_s"]) for r in sel], [float(r[key]) for r in sel], mk,
                              label=f"{dim}D P{deg} {pairing}", alpha=1.0 if pairing == "dual" else 0.4)
        ax.axhline(2e-2 if key == "centre_error" else 3e-2, color="grey", lw=0.8, ls=":")
        ax.set_xlabel("wall time (s)")
        ax.set_ylabel("relative error")
        ax.set_title(title)
        ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(out, "sneddon_work_precision.png"), dpi=120)


def markdown(out, sneddon_rows, vi_rows, mandel_rows=(), pairing_rows=(), inclined_rows=()):
    lines = []
    if inclined_rows:
        lines += ["| inclined crack | P | h/a | dofs | solver | wall (s) | slip L2 error "
                  "| slip error at the centre | max abs(lam - sigma_n) / sigma_n "
                  "| max abs(abs(tau) / (mu_f lam) - 1) |",
                  "|---|---|---|---|---|---|---|---|---|---|"]
        for r in inclined_rows:
            lines.append(
                f"| {r.get('dim', 2)}D | {r['degree']} | {r['crack_size_over_a']} | {r['dofs']} | "
                f"{r.get('solver', 'direct')} | "
                f"{float(r['wall_s']):.2f} | "
                f"{float(r['slip_l2_error']):.2e} | {float(r['centre_error']):.2e} | "
                f"{float(r['lam_error']):.2e} | {float(r['law_error']):.1e} |")
        lines.append("")
    if pairing_rows:
        lines += ["| Scene 2 to 1e7 s | P | fracture mesh (m) | dofs | wall (s) | aperture identity "
                  "| closed opening / a_ref | lam 2nd difference / lam0 | lam inj. (MPa) | a inj. (mm) |",
                  "|---|---|---|---|---|---|---|---|---|---|"]
        for r in pairing_rows:
            rough = r["lam_roughness"]
            rough = f"{float(rough):.2e}" if rough not in ("", "nan") else "(P1 lam)"
            lines.append(
                f"| {r['pairing']} | {r['degree']} | {r['fracture_size_m']} | {r['dofs']} | "
                f"{float(r['wall_s']):.1f} | {float(r['aperture_identity']):.2e} | "
                f"{float(r['closed_opening']):.2e} | {rough} | {float(r['lam_injector_MPa']):.3f} | "
                f"{float(r['aperture_injector_mm']):.4f} |")
        lines.append("")
    if mandel_rows:
        lines += [
            "| mandel | mesh (m) | cells | dofs | steps | wall (s) | max p error / p0 "
            "| Cryer peak error / p0 |",
            "|---|---|---|---|---|---|---|---|"]
        for r in mandel_rows:
            lines.append(
                f"| P{r['degree']} u / P1 pm | {r['mesh_size']} | {r['cells']} | {r['dofs']} | "
                f"{r['steps']} | {float(r['wall_s']):.2f} | {float(r['p_max_rel']):.2e} | "
                f"{float(r['cryer_peak_rel']):.2e} |")
        lines.append("")
    if sneddon_rows:
        lines += ["| pairing | crack | P | h/R | cells | dofs | wall (s) | w(0) error | L2 error |",
                  "|---|---|---|---|---|---|---|---|---|"]
        for r in sneddon_rows:
            name = "Griffith 2D" if str(r["dim"]) == "2" else "penny 3D"
            lines.append(
                f"| {r.get('pairing', 'dual')} | {name} | {r['degree']} | {r['crack_size_over_R']} | "
                f"{r['cells']} | {r['dofs']} | "
                f"{float(r['wall_s']):.2f} | {float(r['centre_error']):.2e} | {float(r['l2_error']):.2e} |")
        lines.append("")
    if vi_rows:
        lines += ["| solver | method | h/c | Newton per step | max | Krylov per step | rejected | wall (s) | "
                  "open to (m) | w(0) (mm) | profile diff to finest (mm) |",
                  "|---|---|---|---|---|---|---|---|---|---|---|"]
        for r in vi_rows:
            lines.append(
                f"| {r['solver']} | {r['method']} | {r['crack_size_over_c']} | {r['newton_per_step']} | "
                f"{r['newton_max']} | {r['krylov_per_step']} | {r['rejected']} | {float(r['wall_s']):.2f} | "
                f"{float(r['open_length_m']):.3f} | {float(r['opening_centre_mm']):.4f} | "
                f"{float(r['profile_diff_to_finest_mm']):.2e} |")
    with open(os.path.join(out, "tables.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=os.path.join(ROOT, "output", "contact"))
    ap.add_argument("--study", default="sneddon,vi,mandel,pairing,inclined")
    ap.add_argument("--plot-only", action="store_true")
    ap.add_argument("--compare-lam", nargs=2, metavar=("COARSE", "FINE"))
    a = ap.parse_args(argv)
    if a.compare_lam:
        return compare_lam(*a.compare_lam)
    studies = a.study.split(",")
    os.makedirs(a.out, exist_ok=True)
    sn = os.path.join(a.out, "sneddon.csv")
    vi = os.path.join(a.out, "partial_opening.csv")
    if not a.plot_only:
        if "sneddon" in studies:
            sneddon_study(a.out)
        if "vi" in studies:
            vi_study(a.out)
        if "mandel" in studies:
            mandel_study(a.out)
        if "pairing" in studies:
            pairing_study(a.out)
        if "inclined" in studies:
            inclined_study(a.out)
    sn_rows = read_csv(sn) if os.path.exists(sn) else []
    vi_rows = read_csv(vi) if os.path.exists(vi) else []
    mn = os.path.join(a.out, "mandel.csv")
    mn_rows = read_csv(mn) if os.path.exists(mn) else []
    pr = os.path.join(a.out, "pairing_scene2.csv")
    pr_rows = read_csv(pr) if os.path.exists(pr) else []
    ic = os.path.join(a.out, "inclined.csv")
    ic_rows = read_csv(ic) if os.path.exists(ic) else []
    if sn_rows:
        plot_sneddon(a.out, sn_rows)
    if mn_rows:
        plot_mandel(a.out, mn_rows)
    markdown(a.out, sn_rows, vi_rows, mn_rows, pr_rows, ic_rows)


if __name__ == "__main__":
    main()
