"""Scene 1 of the paper (``rigid_fracture``): the matrix-permeability sweep
and its figures (paper Figs. 2 and 3).

    python scripts/scene1_sweep.py [--out output/scene1] [--jobs 2] [--plot-only] [-- OPTIONS]

Runs ``python -m petthm rigid_fracture`` for k = 0, 1e-16 ... 1e-12 m2 with
permeability normal to the fracture only ("1D leakoff", -thm_rock_permeability 0,k)
and the isotropic "2D" case at 1e-13 m2, then plots from the runs'
history.csv / profile_1e8.json only:
  scene1_production_temperature.png  production temperature vs time with the
                                     Lauwerier/Bodvarsson curve (Fig. 2)
  scene1_profile_1e8.png             Tf along the fracture at t = 1e8 s (Fig. 3)
and writes scene1.csv / scene1.md (production temperature at 1e8 and 1e9 s,
leakoff fraction, balances, wall time).  Extra options after ``--`` go to every run."""
from __future__ import annotations

import argparse
import json
import os
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
from study_tables import ROOT, markdown, read_history, read_summary, run_petthm, write_csv, write_markdown

CASES = [("k0", "0"), ("1d_1e-16", "0,1e-16"), ("1d_1e-15", "0,1e-15"), ("1d_1e-14", "0,1e-14"),
         ("1d_1e-13", "0,1e-13"), ("1d_1e-12", "0,1e-12"), ("2d_1e-13", "1e-13")]


def run(out, name, perm, extra):
    run_petthm("rigid_fracture", os.path.join(out, "runs", name), "-thm_rock_permeability", perm, *extra)
    print(f"{name}: done", flush=True)


def at(h, t, key):
    return float(np.interp(np.log(t), np.log(h["time"]), h[key]))


def lauwerier(t, x=100.0, q=1e-4, phi=0.1):
    """Bodvarsson/Lauwerier outlet temperature (t_d = 0) with the scene's rock
    ((rho C)_m and lambda_m of porosity phi), in degC."""
    from scipy.special import erfc
    rc = (1 - phi) * 2820 * 1170 + phi * 4.2e6
    lam = (1 - phi) * 2.88 + phi * 0.6
    kappa = lam / rc
    return 100.0 + (20.0 - 100.0) * erfc(lam * x / (4.2e6 * q * np.sqrt(kappa * t)))


def plots(out):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4.5))
    t = np.logspace(4, 9, 200)
    ax.semilogx(t, lauwerier(t), "k--", lw=1.2, label="Lauwerier/Bodvarsson (k = 0)")
    fig3, ax3 = plt.subplots(figsize=(7, 4.5))
    x = np.linspace(0, 100, 200)
    ax3.plot(x, lauwerier(1e8, x=np.maximum(x, 1e-9)), "k--", lw=1.2, label="Lauwerier/Bodvarsson (k = 0)")
    rows = []
    for name, perm in CASES:
        d = os.path.join(out, "runs", name)
        if not os.path.exists(os.path.join(d, "summary.json")):
            continue
        h, s = read_history(d), read_summary(d)
        label = "k = 0" if name == "k0" else (
            "1D " if name.startswith("1d") else "2D ") + name.split("_")[1] + " m2"
        ax.semilogx(h["time"], h["production_temperature"], label=label)
        prof = os.path.join(d, "profile_1e8.json")
        if os.path.exists(prof):
            p = json.loads(Path(prof).read_text())
            ax3.plot(p["x"], p["Tf"], label=label)
        rows.append({"case": name, "permeability": perm,
                     "T_prod_1e8": round(at(h, 1e8, "production_temperature"), 3),
                     "T_prod_1e9": round(float(h["production_temperature"][-1]), 3),
                     "leakoff_fraction_1e8": round(at(h, 1e8, "leakoff_fraction"), 4),
                     "mass_balance_max": s["balance_max"]["mass_balance"],
                     "energy_balance_max": s["balance_max"]["energy_balance"],
                     "Tf_bounds_violation": s["bounds"]["Tf"]["violation_fraction"],
                     "steps": s["steps"], "wall_s": round(s["wall_time"]["total"], 1)})
    ax.set_xlabel("time (s)")
    ax.set_ylabel("production temperature (degC)")
    ax.set_title("Scene 1: production temperature (cf. paper Fig. 2)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "scene1_production_temperature.png"), dpi=120)
    ax3.set_xlabel("x along the fracture (m)")
    ax3.set_ylabel("fracture temperature Tf (degC)")
    ax3.set_title("Scene 1: Tf along the fracture at t = 1e8 s (cf. paper Fig. 3)")
    ax3.grid(True, alpha=0.3)
    ax3.legend(fontsize=8)
    fig3.tight_layout()
    fig3.savefig(os.path.join(out, "scene1_profile_1e8.png"), dpi=120)
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(ROOT, "output", "scene1"))
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--plot-only", action="store_true")
    ap.add_argument("--cases", default=",".join(c for c, _ in CASES), help="subset of the cases")
    ap.add_argument("extra", nargs="*")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    if not a.plot_only:
        with ThreadPoolExecutor(a.jobs) as ex:
            todo = [c for c in CASES if c[0] in a.cases.split(",")]
            list(ex.map(lambda c: run(a.out, c[0], c[1], a.extra), todo))
    rows = plots(a.out)
    write_csv(os.path.join(a.out, "scene1.csv"), rows)
    md = markdown([("case", "case", ""), ("-thm_rock_permeability", "permeability", ""),
                   ("T_prod 1e8 s (degC)", "T_prod_1e8", ""), ("T_prod 1e9 s", "T_prod_1e9", ""),
                   ("leakoff fraction 1e8 s", "leakoff_fraction_1e8", ""),
                   ("mass bal.", "mass_balance_max", ".1e"),
                   ("energy bal.", "energy_balance_max", ".1e"),
                   ("Tf bound viol.", "Tf_bounds_violation", ".1e"),
                   ("steps", "steps", ""), ("wall (s)", "wall_s", "")], rows)
    write_markdown(os.path.join(a.out, "scene1.md"), "Scene 1 (rigid_fracture): permeability sweep", md)
    print(md)


if __name__ == "__main__":
    main()
