"""Scene 3 of the paper (``inclined_penny``): the three cases to 30 years, the
equivalents of the paper's Figs. 8-12, and the table of its statements.

    python scripts/scene3_study.py [--variant coarse|medium|default] [--cases 1,2,3] [--jobs 1]
                                   [--out DIR] [--plot-only] [--demo] [-- extra petthm options]

Each case runs ``python -m petthm inclined_penny -options_file
options/scenes/inclined_penny[_coarse].opts -thm_scene3_case N``; the figures
and tables are made from the runs' output files only (history.csv,
summary.json, fracture.h5, fields.h5):
  scene3_fig8_10_{Tf,aperture,lam}.png  the fracture at 10, 20, 30 years, one row per case
                                        (in the fracture's plane: along the dip and along y)
  scene3_fig11_Tm.png                   Tm on the horizontal plane through the perforations at 30 years
  scene3_fig12_history.png              the largest aperture increase and the production
                                        temperature change against time
  scene3.csv / scene3.md                per case: the numbers behind the paper's statements
"""
from __future__ import annotations

import argparse
import math
import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from study_tables import ROOT, markdown, output_with, read_history, read_summary, run_petthm, write_csv

YEAR = 365.25 * 86400.0
_COARSE = os.path.join(ROOT, "options", "scenes", "inclined_penny_coarse.opts")
#: variant -> (options file, more options): coarse (2826 cells, P1 u), medium (11911 cells, P1 u),
#: default (the paper's P2 u on the default mesh)
VARIANTS = {"coarse": (_COARSE, []),
            "medium": (_COARSE, ["-thm_scene3_fracture_size", 25, "-thm_scene3_well_size", 7.5,
                                 "-thm_mesh_size", 200]),
            "default": (os.path.join(ROOT, "options", "scenes", "inclined_penny.opts"), [])}
#: a production temperature this far below T0 counts as the thermal breakthrough (K)
BREAKTHROUGH = 1.0


def run_dir(out, case):
    return os.path.join(out, "runs", f"case{case}")


def run(out, variant, case, extra):
    opts, more = VARIANTS[variant]
    run_petthm("inclined_penny", run_dir(out, case), "-options_file", opts, *more, "-thm_scene3_case", case,
               *extra)
    print(f"case {case}: done", flush=True)


def parameters(d) -> dict:
    return {k.lstrip("-"): v for k, v in read_summary(d)["provenance"]["parameters"].items()}


def row(case, d) -> dict:
    h, s, p = read_history(d), read_summary(d), parameters(d)
    t = h["time"] / YEAR
    T0 = p["thm_initial_temperature"]
    drop = T0 - h["production_temperature"]
    k = int(np.argmax(h["aperture_increase_max"]))
    late = np.flatnonzero(drop >= BREAKTHROUGH)
    bal = s["balance_max"]
    lam0 = _initial_row(d)["lam_min"]
    a_init = max(p["thm_fracture_aperture"] - lam0 / p["thm_fracture_normal_stiffness"],
                 p["thm_fracture_residual_fraction"] * p["thm_fracture_aperture"])
    return {"case": case, "T0_degC": T0, "lam0_MPa": round(lam0 / 1e6, 3),
            "a_init_mm": round(a_init * 1e3, 4),
            "da_max_mm": round(float(h["aperture_increase_max"][k]) * 1e3, 4),
            "da_max_ratio": round(float(h["aperture_increase_ratio"][k]), 3),
            "da_peak_years": round(float(t[k]), 2),
            **_maxima_columns(aperture_maxima(t, h["aperture_increase_max"])),
            "da_30y_mm": round(float(h["aperture_increase_max"][-1]) * 1e3, 4),
            "dT_prod_30y": round(float(drop[-1]), 3),
            "breakthrough_years": round(float(t[late[0]]), 2) if len(late) else float("nan"),
            "raised_area_30y_m2": round(float(h["raised_area"][-1]), 0),
            "p_inj_30y_MPa": round(float(h["injection_pressure"][-1]) / 1e6, 3),
            "lam_min_30y_MPa": round(float(h["lam_min"][-1]) / 1e6, 2),
            "aperture_identity": bal.get("aperture_identity", float("nan")),
            "mass_balance": bal.get("mass_balance", float("nan")),
            "energy_balance": bal.get("energy_balance", float("nan")),
            **{f"{f}_{k}": (s.get("bounds") or {}).get(f, {}).get(key, float("nan"))
               for f in ("Tf", "Tm") for k, key in (("below_K", "below"), ("above_K", "above"),
                                                    ("bounds_violation", "violation_fraction"))},
            "cells": s["cells"], "steps": s["steps"], "rejected": s["rejected_steps"],
            "wall_s": round(s["wall_time"]["total"], 1), "status": s["status"]}


#: a local maximum of the aperture history counts where it stands this far above the lower of the
#: troughs beside it, as a fraction of the history's largest value
PROMINENCE = 0.01


def aperture_maxima(years, increase) -> dict:
    """The two maxima of the largest aperture increase in time (manual, the
    paper's scenes, Scene 3): the ``early`` one, the first local maximum
    that the history falls from by more than ``PROMINENCE`` (the injection
    pressure's transient), and the ``thermal`` one, the largest value after
    the lowest point that follows it (the cooled region's contraction), or
    of the whole history without an early one; each (value, years), nan
    where there is none (a history that falls to its end after the early
    maximum has no thermal one)."""
    from scipy.signal import find_peaks
    years, increase = np.asarray(years, dtype=float), np.asarray(increase, dtype=float)
    nan = (float("nan"), float("nan"))
    top = float(np.max(increase)) if increase.size else 0.0
    peaks, _ = find_peaks(increase, prominence=PROMINENCE * top) if top > 0 else (np.zeros(0, int), None)
    early, start = nan, 0
    if len(peaks):
        k = int(peaks[0])
        early = (float(increase[k]), float(years[k]))
        start = k + int(np.argmin(increase[k:]))
    rest = increase[start:]
    if len(peaks) and start == len(increase) - 1:
        return {"early": early, "thermal": nan}
    k = start + int(np.argmax(rest))
    return {"early": early, "thermal": (float(increase[k]), float(years[k]))}


def _maxima_columns(m: dict) -> dict:
    """``aperture_maxima`` as table columns (mm, years)."""
    return {f"da_{kind}_{unit}": round(m[kind][i] * scale, 4 if unit == "mm" else 2)
            for kind in ("early", "thermal") for i, unit, scale in ((0, "mm", 1e3), (1, "years", 1.0))}


def _initial_row(d) -> dict:
    """The history's first row (the initial state) as floats."""
    import csv
    with open(os.path.join(d, "history.csv")) as f:
        first = next(csv.DictReader(f))
    return {k: float(v) for k, v in first.items() if v not in ("", None)}


def converged_verdicts() -> dict[str, dict]:
    """The statements' verdicts on the mesh-converged runs, as the manual
    records them: {key: {"verdict", "section"}} (empty where not recorded)."""
    import csv
    path = os.path.join(ROOT, "benchmarks", "records", "scene3_verdicts.csv")
    if not os.path.exists(path):
        return {}
    with open(path) as f:
        return {r["key"]: r for r in csv.DictReader(f)}


def statements(rows) -> list[dict]:
    """The paper's statements about the three cases, each with the measured numbers."""
    by = {r["case"]: r for r in rows}
    if set(by) != {1, 2, 3}:
        return []
    c1, c2, c3 = by[1], by[2], by[3]
    return [
        {"key": "da_order",
         "statement": "maximum aperture increase: case 3 > case 2 > case 1 (absolute, mm)",
         "measured": f"{c3['da_max_mm']} / {c2['da_max_mm']} / {c1['da_max_mm']}",
         "holds": c3["da_max_mm"] > c2["da_max_mm"] > c1["da_max_mm"]},
        {"key": "da_ratio_order",
         "statement": "maximum aperture increase relative to the initial aperture: case 3 > case 2 > case 1",
         "measured": f"{c3['da_max_ratio']} / {c2['da_max_ratio']} / {c1['da_max_ratio']}",
         "holds": c3["da_max_ratio"] > c2["da_max_ratio"] > c1["da_max_ratio"]},
        {"key": "drop_order",
         "statement": "production temperature drop at 30 years: case 2 > case 3 > case 1 (K)",
         "measured": f"{c2['dT_prod_30y']} / {c3['dT_prod_30y']} / {c1['dT_prod_30y']}",
         "holds": c2["dT_prod_30y"] > c3["dT_prod_30y"] > c1["dT_prod_30y"]},
        {"key": "breakthrough",
         "statement": f"thermal breakthrough (drop >= {BREAKTHROUGH} K) earlier in case 3 than in case 1 "
                      "(years)",
         "measured": f"{c3['breakthrough_years']} / {c1['breakthrough_years']}",
         "holds": (c3["breakthrough_years"] < c1["breakthrough_years"]) or
                  (math.isfinite(c3["breakthrough_years"]) and not math.isfinite(c1["breakthrough_years"]))},
        {"key": "raised_area",
         "statement": "area of raised aperture (> 10 %) at 30 years smaller in case 3 than in case 2 (m2)",
         "measured": f"{c3['raised_area_30y_m2']} / {c2['raised_area_30y_m2']}",
         "holds": c3["raised_area_30y_m2"] < c2["raised_area_30y_m2"]},
        {"key": "peak",
         "statement": "the maximum aperture increase peaks (paper: around 7 years) and then declines: "
                      "its thermal maximum (after the injection pressure's early one) comes before 30 years",
         "measured": "; ".join(f"case {c}: early {_at(r, 'early')}, thermal {_at(r, 'thermal')}, "
                               f"{r['da_30y_mm']} mm at 30 y" for c, r in by.items()),
         "holds": all(r["da_thermal_years"] < 30.0 and r["da_30y_mm"] < r["da_thermal_mm"] for r in rows)},
    ]


def _at(r: dict, kind: str) -> str:
    """'V mm at T y' of one of the aperture's maxima, or 'none'."""
    v, y = r[f"da_{kind}_mm"], r[f"da_{kind}_years"]
    return "none" if not math.isfinite(v) else f"{v} mm at {y} y"


# -- figures -----------------------------------------------------------------------------------
def _series(path):
    """(geometry, topology, times, {name: [arrays]}) of an output .h5 written by petthm.io.output."""
    import h5py
    with h5py.File(path) as h5:
        times = np.asarray(h5.attrs["times"])
        fields = {n: [h5["fields"][n][str(k)][()] for k in range(len(times)) if str(k) in h5["fields"][n]]
                  for n in h5["fields"]}
        return h5["mesh/geometry"][()], h5["mesh/topology"][()], times, fields


def _in_plane(X, dip_deg):
    """Coordinates in the fracture's plane: along the dip (e_x rotated by the dip about y) and along y."""
    d = math.radians(dip_deg)
    return X @ np.array([math.cos(d), 0.0, -math.sin(d)]), X[:, 1]


def resolution(out, cases) -> str:
    """The runs' mesh and discretisation, for the figures' captions."""
    d = run_dir(out, cases[0])
    s, p = read_summary(d), parameters(d)
    from types import SimpleNamespace

    from petthm.physics.builders import heat_scheme
    from petthm.scenes.scene3 import TEMPERATURE_DEGREE
    # runs written before "auto" existed recorded their default, supg
    chosen = SimpleNamespace(heat_transport=p.get("thm_heat_transport", "supg"))
    return (f"{s['cells']} cells, P{p.get('thm_fe_degree', 2)} u, P1 p and T, heat transport "
            f"{heat_scheme(chosen, TEMPERATURE_DEGREE)}")


def fig8_10(out, cases):
    """Tf, the aperture and the contact traction on the fracture at 10, 20 and 30
    years: a row per case, a column per time, one colour scale per field."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.tri import Triangulation
    panels = {"Tf": ("Tf (degC)", "coolwarm", 1.0), "aperture": ("aperture (mm)", "viridis", 1e3),
              "lam": ("contact traction (MPa)", "magma", 1e-6)}
    years = (10, 20, 30)
    caption = resolution(out, cases)
    for name, (title, cmap, scale) in panels.items():
        shown = {}
        for c in cases:
            d = run_dir(out, c)
            X, topo, times, f = _series(output_with(d, "fracture", name))
            p = parameters(d)
            xi, eta = _in_plane(X, p["thm_scene3_dip"])
            for y in years:
                k = int(np.argmin(np.abs(times - y * YEAR)))
                if abs(times[k] - y * YEAR) <= 1e-6 * YEAR:
                    shown[c, y] = (Triangulation(xi, eta, topo[:, :3]), f[name][k] * scale, p)
        values = np.concatenate([v for _, v, _ in shown.values()]) if shown else np.zeros(1)
        lo, hi = float(values.min()), float(values.max())
        levels = np.linspace(lo, hi if hi > lo else lo + 1e-12, 21)
        fig, axs = plt.subplots(len(cases), 3, figsize=(13, 3.7 * len(cases)), squeeze=False,
                                layout="constrained")
        cs = None
        for i, c in enumerate(cases):
            for j, y in enumerate(years):
                ax = axs[i, j]
                if (c, y) not in shown:
                    ax.set_title(f"case {c}: no output at {y} years")
                    continue
                tri, v, p = shown[c, y]
                cs = ax.tricontourf(tri, v, levels=levels, cmap=cmap)
                ax.set_aspect("equal")
                ax.set_title(f"case {c}, {y} years")
                h = p["thm_scene3_well_spacing"] / 2
                ax.plot([0, 0], [-h, h], "k^", ms=6)
                ax.set_xlabel("along the dip (m)")
            axs[i, 0].set_ylabel("along the strike y (m)")
        if cs is not None:
            fig.colorbar(cs, ax=axs, shrink=0.9, label=title)
        fig.suptitle(f"Scene 3: {title} on the fracture (cf. paper Figs. 8-10); wells above y = -150 "
                     f"(injector) and +150 m (producer)\n{caption}")
        fig.savefig(os.path.join(out, f"scene3_fig8_10_{name}.png"), dpi=100)
        plt.close(fig)


def fig11(out, cases):
    """Tm on the horizontal plane z = the middle of the perforations, at the last output time."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from scipy.interpolate import LinearNDInterpolator
    fig, axs = plt.subplots(1, len(cases), figsize=(5.2 * len(cases), 4.6), squeeze=False)
    for ax, c in zip(axs[0], cases, strict=False):
        d = run_dir(out, c)
        p = parameters(d)
        X, _, times, f = _series(output_with(d, "fields", "Tm"))
        z0 = p["thm_scene3_well_standoff"] + p["thm_scene3_perforation"] / 2
        R = p["thm_scene3_radius"]
        slab = np.abs(X[:, 2] - z0) < max(2 * p["thm_scene3_fracture_size"], 30.0)
        near = slab & (np.abs(X[:, 0]) < 1.5 * R) & (np.abs(X[:, 1]) < 1.5 * R)
        interp = LinearNDInterpolator(X[near], f["Tm"][-1][near])
        g = np.linspace(-1.2 * R, 1.2 * R, 161)
        gx, gy = np.meshgrid(g, g)
        T = interp(gx, gy, np.full_like(gx, z0))
        cs = ax.contourf(gx, gy, T, levels=20, cmap="coolwarm")
        fig.colorbar(cs, ax=ax, shrink=0.85)
        dip = math.radians(p["thm_scene3_dip"])
        xf = -z0 / math.tan(dip)                       # the fracture's trace on the plane: x = -z0 / tan(dip)
        half = math.sqrt(max(R ** 2 - (z0 / math.sin(dip)) ** 2, 0.0))
        ax.plot([xf, xf], [-half, half], "k-", lw=1.5)
        h = p["thm_scene3_well_spacing"] / 2
        ax.plot([0, 0], [-h, h], "k^", ms=6)
        ax.set_aspect("equal")
        ax.set_title(f"case {c}: Tm (degC) at z = {z0:g} m, {times[-1] / YEAR:.0f} years")
        ax.set_xlabel("x (m)")
    axs[0, 0].set_ylabel("y (m)")
    fig.suptitle("Scene 3: rock temperature on the horizontal plane through the perforations (cf. Fig. 11); "
                 "line: the fracture's trace")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "scene3_fig11_Tm.png"), dpi=100)
    plt.close(fig)


def fig12(out, cases):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax1 = plt.subplots(figsize=(8, 5))
    ax2 = ax1.twinx()
    for c, color in zip(cases, ("tab:blue", "tab:orange", "tab:green"), strict=False):
        d = run_dir(out, c)
        h, p = read_history(d), parameters(d)
        t = h["time"] / YEAR
        ax1.plot(t, h["aperture_increase_ratio"], "-", color=color,
                 label=f"case {c}: max (a - a_init) / a_init")
        k = int(np.argmax(h["aperture_increase_ratio"]))
        ax1.plot(t[k], h["aperture_increase_ratio"][k], "o", color=color, mfc="none", ms=9)
        ax1.annotate(f"{t[k]:.1f} y", (t[k], h["aperture_increase_ratio"][k]), textcoords="offset points",
                     xytext=(4, 6), fontsize=8, color=color)
        ax2.plot(t, h["production_temperature"] - p["thm_initial_temperature"], "--", color=color,
                 label=f"case {c}: production temperature change")
    ax1.set_xlabel("time (years)")
    ax1.set_ylabel("maximum aperture change / initial aperture (solid)")
    ax2.set_ylabel("production temperature change (K, dashed)")
    lines = ax1.get_legend_handles_labels()
    more = ax2.get_legend_handles_labels()
    ax1.legend(lines[0] + more[0], lines[1] + more[1], fontsize=8, loc="center right")
    ax1.set_title(f"Scene 3 (cf. paper Fig. 12); circles: each case's largest increase\n"
                  f"{resolution(out, cases)}", fontsize=10)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "scene3_fig12_history.png"), dpi=110)
    plt.close(fig)


COLUMNS = [("case", "case", ""), ("T0 (degC)", "T0_degC", ""), ("lam0 (MPa)", "lam0_MPa", ""),
           ("a init (mm)", "a_init_mm", ""), ("max da (mm)", "da_max_mm", ""),
           ("max da / a", "da_max_ratio", ""),
           ("peak (years)", "da_peak_years", ""), ("early max (mm)", "da_early_mm", ""),
           ("its time (years)", "da_early_years", ""), ("thermal max (mm)", "da_thermal_mm", ""),
           ("its time (years)", "da_thermal_years", ""), ("da 30 y (mm)", "da_30y_mm", ""),
           ("dT prod 30 y (K)", "dT_prod_30y", ""), ("breakthrough (years)", "breakthrough_years", ""),
           ("raised area 30 y (m2)", "raised_area_30y_m2", ""), ("p inj 30 y (MPa)", "p_inj_30y_MPa", ""),
           ("lam min 30 y (MPa)", "lam_min_30y_MPa", ""), ("a(lam) identity", "aperture_identity", ".1e"),
           ("mass bal.", "mass_balance", ".1e"), ("energy bal.", "energy_balance", ".1e"),
           ("Tf below Tinj (K)", "Tf_below_K", ".2f"), ("Tf above T0 (K)", "Tf_above_K", ".2f"),
           ("Tm below Tinj (K)", "Tm_below_K", ".2f"), ("Tm above T0 (K)", "Tm_above_K", ".2f"),
           ("cells", "cells", ""), ("steps", "steps", ""),
           ("wall (s)", "wall_s", ""), ("status", "status", "")]


def report(out, variant, cases):
    rows = [row(c, run_dir(out, c)) for c in cases]
    write_csv(os.path.join(out, "scene3.csv"), rows)
    table = markdown(COLUMNS, rows)
    st = statements(rows)
    verdicts = converged_verdicts()
    text = [f"# Scene 3 (inclined_penny, {variant}): the three cases to 30 years", "", table, ""]
    if st:
        for r in st:
            r["verdict"] = "yes" if r["holds"] else "no"
        for r in st:
            v = verdicts.get(r["key"], {})
            r["converged"] = v.get("verdict", "not recorded")
            r["section"] = v.get("section", "")
        text += ["## The paper's statements", "",
                 f"'holds on these runs': on this run's ({variant}) mesh; 'converged': the verdict on the "
                 "mesh-converged runs recorded in the manual (benchmarks/records/scene3_verdicts.csv), and "
                 "the manual's section (the paper's scenes, Scene 3) that explains it.", "",
                 markdown([("statement", "statement", ""), ("measured", "measured", ""),
                           ("holds on these runs", "verdict", ""), ("converged", "converged", ""),
                           ("manual", "section", "")],
                          st), ""]
    with open(os.path.join(out, "scene3.md"), "w") as f:
        f.write("\n".join(text))
    print("\n".join(text))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--variant", choices=tuple(VARIANTS), default="coarse")
    ap.add_argument("--out", default="")
    ap.add_argument("--cases", default="1,2,3")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--plot-only", action="store_true")
    ap.add_argument("--demo", action="store_true",
                    help="make demo: the three cases of the coarse variant, all at once, into output/demo")
    ap.add_argument("extra", nargs="*")
    a = ap.parse_args()
    if a.demo:
        a.variant, a.jobs, a.cases = "coarse", max(a.jobs, 3), "1,2,3"
        a.out = a.out or os.path.join(ROOT, "output", "demo")
        print("Scene 3 of Salimzadeh et al. (2018), coarse: the three cases to 30 years, at once ...",
              flush=True)
    out = a.out or os.path.join(ROOT, "output", f"scene3_{a.variant}")
    try:
        cases = [int(c) for c in a.cases.split(",") if c]
    except ValueError:
        raise SystemExit(f"scene3_study.py: --cases takes 1, 2 and/or 3 (got {a.cases})") from None
    if not set(cases) <= {1, 2, 3}:
        raise SystemExit(f"scene3_study.py: --cases takes 1, 2 and/or 3 (got {a.cases})")
    os.makedirs(out, exist_ok=True)
    if not a.plot_only:
        with ThreadPoolExecutor(a.jobs) as ex:
            list(ex.map(lambda c: run(out, a.variant, c, a.extra), cases))
    done = [c for c in cases if os.path.exists(os.path.join(run_dir(out, c), "summary.json"))]
    report(out, a.variant, done)
    fig12(out, done)
    fig8_10(out, done)
    fig11(out, done)
    print("figures in", out, "(scene3_fig8_10_*.png, scene3_fig11_Tm.png, scene3_fig12_history.png);",
          "runs (summary.json, history.csv, fields.xdmf, fracture.xdmf) in", os.path.join(out, "runs"))


if __name__ == "__main__":
    main()
