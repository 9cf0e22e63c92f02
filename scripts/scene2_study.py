"""Scene 2 of the paper (``penny_impermeable``): the runs to t = 1e9 s, the
paper's Figs. 5 and 6, and a sensitivity study (mesh, layers, domain size,
heat exchange mode, time step, traction at the front).

    python scripts/scene2_study.py [--out output/scene2] [--jobs 1] [--cases a,b] [--plot-only]

Each case runs ``python -m petthm penny_impermeable -options_file
options/scenes/penny_impermeable.opts`` with its own options, then this
script plots from the runs' history.csv and fracture_final.npz only:
  scene2_fig5_maps.png      Tf, aperture and contact traction on the fracture
                            at t = 1e9 s (the default case; mirrored about y = 0)
  scene2_fig6_injector.png  injection pressure and aperture at the injector vs time
and writes scene2.csv / scene2.md (targets at 1e9 s, the injection-pressure
peak, the a(lam) identity, balances, wall time)."""
from __future__ import annotations

import argparse
import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from study_tables import ROOT, markdown, read_history, read_summary, run_petthm, write_csv, write_markdown

OPTS = os.path.join(ROOT, "options", "scenes", "penny_impermeable.opts")
DEFAULT = "h10"
CASES = {
    "h10": ("default: layered mesh, fracture 10 m, wells 5 m, first layer 0.5 m", []),
    "h20": ("fracture 20 m, wells 10 m", ["-thm_scene2_fracture_size", "20", "-thm_scene2_well_size", "10"]),
    "thin": ("first layer 0.25 m growing by 1.3",
             ["-thm_scene2_layer", "0.25", "-thm_scene2_layer_growth", "1.3"]),
    "tet": ("isotropic tetrahedra (no layers)", ["-thm_scene2_layer", "0"]),
    "box5": ("domain 5 R", ["-thm_scene2_box", "5"]),
    "nusselt": ("wall exchange hw = Nu lambda_f / (2 a), local a",
                ["-thm_fracture_heat_exchange", "nusselt"]),
    "dt": ("steps x1.1 up to 5e6 s", ["-thm_dt_growth", "1.1", "-thm_dt_max", "5e6"]),
    "tip0": ("lam = 0 at the front", ["-thm_scene2_tip_traction", "zero"]),
    "err": ("steps from the local error estimate (-thm_dt_control error, -ts_atol 1e-2)",
            ["-thm_dt_control", "error", "-ts_atol", "1e-2"]),
}
PAPER = {"lam_injector": 30e6, "aperture_injector": 0.3e-3}
#: the coarse case of ``make demo`` (--demo): the paper's Scene 2 to 1e9 s in about a minute
DEMO = ("demo: fracture 20 m, wells 10 m (coarse)", ["-thm_scene2_fracture_size", "20",
                                                    "-thm_scene2_well_size", "10"])


def run(out, name, extra):
    run_petthm("penny_impermeable", os.path.join(out, "runs", name), "-options_file", OPTS, *CASES[name][1],
               *extra)
    print(f"{name}: done", flush=True)


def row(name, d):
    h, s = read_history(d), read_summary(d)
    k = int(np.argmax(h["injection_pressure"]))
    p = h["injection_pressure"]
    return {"case": name, "what": CASES[name][0], "cells": s["cells"],
            "lam_injector_MPa": round(h["lam_injector"][-1] / 1e6, 2),
            "lam_error": round(h["lam_injector"][-1] / PAPER["lam_injector"] - 1, 3),
            "aperture_injector_mm": round(h["aperture_injector"][-1] * 1e3, 4),
            "aperture_error": round(h["aperture_injector"][-1] / PAPER["aperture_injector"] - 1, 3),
            "lam_injector_1e5_MPa": round(float(np.interp(5.0, np.log10(h["time"]),
                                                          h["lam_injector"])) / 1e6, 2),
            "p_inj_peak_time": float(f"{h['time'][k]:.2g}"),
            "p_inj_rise_MPa": round((p[k] - p[0]) / 1e6, 3), "p_inj_fall_MPa": round((p[k] - p[-1]) / 1e6, 3),
            "T_prod_1e9": round(float(h["production_temperature"][-1]), 2),
            "aperture_identity": s["balance_max"]["aperture_identity"],
            "mass_balance_max": s["balance_max"]["mass_balance"],
            "energy_balance_max": s["balance_max"]["energy_balance"],
            "Tf_bounds_violation": s["bounds"]["Tf"]["violation_fraction"],
            "steps": s["steps"], "rejected": s["rejected_steps"], "newton": s["snes_iterations"],
            "wall_s": round(s["wall_time"]["total"], 1)}


def fig6(out, names):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 7), sharex=True)
    for name in names:
        h = read_history(os.path.join(out, "runs", name))
        lw = 2.0 if name == DEFAULT else 1.0
        ax1.semilogx(h["time"], h["injection_pressure"] / 1e6, lw=lw, label=f"{name}: {CASES[name][0]}")
        ax2.semilogx(h["time"], h["aperture_injector"] * 1e3, lw=lw, label=name)
    ax2.axhline(0.3, color="k", ls="--", lw=1, label="paper at 1e9 s (about 0.3 mm)")
    ax1.set_ylabel("injection pressure (MPa)")
    ax2.set_ylabel("aperture at the injector (mm)")
    ax2.set_xlabel("time (s)")
    ax1.set_title("Scene 2: injection pressure and aperture at the injector (cf. paper Fig. 6)")
    for ax in (ax1, ax2):
        ax.grid(True, which="both", alpha=0.3)
    ax1.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "scene2_fig6_injector.png"), dpi=120)


def fig5(out, name):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.tri import Triangulation
    z = np.load(os.path.join(out, "runs", name, "fracture_final.npz"))
    v, T = z["vertices"], z["Tf"]
    fig, axs = plt.subplots(1, 3, figsize=(15, 4.6))

    def mirrored(xy, val):
        """The half model y >= 0 mirrored about the symmetry plane."""
        x = np.concatenate([xy[:, 0], xy[:, 0]])
        y = np.concatenate([xy[:, 1], -xy[:, 1]])
        keep = np.unique(np.round(np.column_stack([x, y]), 9), axis=0, return_index=True)[1]
        return x[keep], y[keep], np.concatenate([val, val])[keep]
    panels = [(T[:, :2], T[:, 2], "Tf (degC)", "coolwarm"),
              (v[:, :2], v[:, 4] * 1e3, "aperture (mm)", "viridis"),
              (v[:, :2], v[:, 3] / 1e6, "contact traction lam (MPa)", "magma")]
    for ax, (xy, val, title, cmap) in zip(axs, panels, strict=False):
        x, y, c = mirrored(xy, val)
        tri = Triangulation(x, y)
        cs = ax.tricontourf(tri, c, levels=20, cmap=cmap)
        fig.colorbar(cs, ax=ax, shrink=0.85)
        ax.plot([-50, 50], [0, 0], "k^", ms=6)
        ax.set_aspect("equal")
        ax.set_title(title)
        ax.set_xlabel("x (m)")
    axs[0].set_ylabel("y (m)")
    fig.suptitle("Scene 2 at t = 1e9 s (cf. paper Fig. 5); injector at x = -50 m, producer at x = 50 m")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "scene2_fig5_maps.png"), dpi=110)


def demo(out, extra):
    """``make demo``: the paper's Scene 2 on a coarse mesh to 1e9 s (about a
    minute on a laptop core), its Figs. 5 and 6 as PNG, and the targets."""
    import time
    CASES["demo"] = DEMO
    os.makedirs(out, exist_ok=True)
    print(f"Scene 2 of Salimzadeh et al. (2018), coarse ({DEMO[0]}), to t = 1e9 s ...", flush=True)
    start = time.perf_counter()
    run(out, "demo", extra)
    r = row("demo", os.path.join(out, "runs", "demo"))
    fig6(out, ["demo"])
    fig5(out, "demo")
    print(f"run: {time.perf_counter() - start:.0f} s; at 1e9 s contact traction at the injector "
          f"{r['lam_injector_MPa']} MPa (paper ~30), aperture {r['aperture_injector_mm']} mm (paper ~0.3)")
    for name in ("scene2_fig5_maps.png", "scene2_fig6_injector.png"):
        print("figure:", os.path.join(out, name))
    print("run output (summary.json, history.csv, fields.xdmf, fracture.xdmf):",
          os.path.join(out, "runs", "demo"))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(ROOT, "output", "scene2"))
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--plot-only", action="store_true")
    ap.add_argument("--cases", default=",".join(CASES), help="subset of: " + ",".join(CASES))
    ap.add_argument("--demo", action="store_true",
                    help="run the coarse case only (into --out, default output/demo), plot Figs. 5, 6")
    ap.add_argument("extra", nargs="*")
    a = ap.parse_args()
    if a.demo:
        out = a.out if a.out != ap.get_default("out") else os.path.join(ROOT, "output", "demo")
        return demo(out, a.extra)
    os.makedirs(a.out, exist_ok=True)
    names = [c for c in a.cases.split(",") if c]
    unknown = [c for c in names if c not in CASES]
    if unknown:
        raise SystemExit(f"scene2_study.py: unknown case(s) {unknown}; accepted: {', '.join(CASES)}")
    if not a.plot_only:
        with ThreadPoolExecutor(a.jobs) as ex:
            list(ex.map(lambda c: run(a.out, c, a.extra), names))
    done = [c for c in CASES if os.path.exists(os.path.join(a.out, "runs", c, "summary.json"))]
    rows = [row(c, os.path.join(a.out, "runs", c)) for c in done]
    fig6(a.out, done)
    if DEFAULT in done:
        fig5(a.out, DEFAULT)
    write_csv(os.path.join(a.out, "scene2.csv"), rows)
    md = markdown([("case", "case", ""), ("what", "what", ""), ("cells", "cells", ""),
                   ("lam inj. 1e9 s (MPa)", "lam_injector_MPa", ""), ("vs 30 MPa", "lam_error", "+.1%"),
                   ("a inj. 1e9 s (mm)", "aperture_injector_mm", ""), ("vs 0.3 mm", "aperture_error", "+.1%"),
                   ("lam inj. 1e5 s (MPa)", "lam_injector_1e5_MPa", ""),
                   ("p_inj peak at (s)", "p_inj_peak_time", ".1e"), ("rise (MPa)", "p_inj_rise_MPa", ""),
                   ("fall after peak (MPa)", "p_inj_fall_MPa", ""), ("T_prod 1e9 s (degC)", "T_prod_1e9", ""),
                   ("a(lam) identity", "aperture_identity", ".1e"), ("mass bal.", "mass_balance_max", ".1e"),
                   ("energy bal.", "energy_balance_max", ".1e"),
                   ("Tf bound viol.", "Tf_bounds_violation", ".1e"),
                   ("steps", "steps", ""), ("Newton", "newton", ""), ("wall (s)", "wall_s", "")], rows)
    write_markdown(os.path.join(a.out, "scene2.md"), "Scene 2 (penny_impermeable): targets and sensitivity",
                   md)
    print(md)


if __name__ == "__main__":
    main()
