"""Scene 3's mesh convergence: the three cases on graded meshes refined as a
whole by a constant ratio, the observed order, the extrapolated value and
Roache's grid convergence index of each smooth headline quantity.

    python scripts/scene3_convergence.py [--levels=-2,-1,0,1] [--ratio 1.3] [--cases 1,2,3]
                                         [--jobs 2] [--out DIR] [--table-only] [-- extra petthm options]

Level k runs ``options/scenes/inclined_penny.opts`` (the default mesh: 20 m
on the fracture, 5 m at the wells, 150 m far away, graded between) with
every mesh size multiplied by ratio**(-k): level 0 is the default
resolution, level 1 is finer.  A run folder that holds a finished run is
kept; one that holds a stopped run is continued with -thm_restart, so the
study can be stopped and continued.  The effective refinement ratio of
two levels is (cells ratio)**(1/3).  With the three finest levels that
finished, each quantity gets (Celik et al. 2008, J. Fluids Eng. 130):
the observed order p, the extrapolated value, and the fine-grid GCI
1.25 |e21| / (r21**p - 1); each level is marked where it lies within 5 %
of the extrapolated value (0.05 K for temperature drops, issue 49).
Quantities that jump between events (the time of the largest aperture
increase, its early maximum (the injection pressure's) and its thermal
one, the smallest traction) are listed per level.  Writes
DIR/scene3_convergence.{csv,md}.
"""
from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from scene3_study import aperture_maxima
from study_tables import ROOT, read_history, read_summary, write_csv

YEAR = 365.25 * 86400.0
OPTIONS = os.path.join(ROOT, "options", "scenes", "inclined_penny.opts")
#: the default mesh sizes (m) that each level scales
SIZES = {"-thm_scene3_fracture_size": 20.0, "-thm_scene3_well_size": 5.0, "-thm_mesh_size": 150.0}
#: a level is converged for a quantity within this fraction of the extrapolated value ...
TOLERANCE = 0.05
#: ... or within this many kelvin for a temperature drop
FLOOR_K = 0.05
#: smooth quantities: name -> (unit, is a temperature drop)
SMOOTH = {"dT_prod_10y": ("K", True), "dT_prod_20y": ("K", True), "dT_prod_30y": ("K", True),
          "da_max_mm": ("mm", False), "raised_area_30y_m2": ("m2", False), "p_inj_30y_MPa": ("MPa", False)}
#: quantities that jump between events, per level: the two maxima of the aperture history
#: (scene3_study.aperture_maxima: the injection pressure's early one, the thermal one) and the
#: smallest traction
EVENTS = {"da_peak_years": "years", "da_early_mm": "mm", "da_early_years": "years", "da_thermal_mm": "mm",
          "da_thermal_years": "years", "lam_min_30y_MPa": "MPa"}


def level_options(level: int, ratio: float) -> list:
    f = ratio ** (-level)
    return [x for k, v in SIZES.items() for x in (k, f"{v * f:.6g}")]


def run_dir(out: str, level: int, case: int) -> str:
    return os.path.join(out, "runs", f"level{level:+d}", f"case{case}")


def finished(d: str) -> bool:
    try:
        return read_summary(d)["status"] == "completed"
    except (OSError, ValueError, KeyError):
        return False


def run(out: str, level: int, case: int, ratio: float, extra: list) -> None:
    """Run (or continue) one case at one level on one core."""
    d = run_dir(out, level, case)
    if finished(d):
        return
    opts = ["-options_file", OPTIONS, *level_options(level, ratio), "-thm_scene3_case", str(case), *extra]
    if os.path.exists(os.path.join(d, "checkpoint.h5")):
        where = ["-thm_restart", d]
    else:
        os.makedirs(d, exist_ok=True)
        where = ["-thm_output_dir", d, "-thm_overwrite"]
    cmd = [sys.executable, "-m", "petthm", "inclined_penny", *where, "-thm_quiet", *opts]
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, env=env)
    print(f"level {level:+d} case {case}: {'done' if p.returncode == 0 else 'failed'}", flush=True)
    if p.returncode:
        print(p.stdout[-2000:], p.stderr[-2000:], file=sys.stderr)


def quantities(d: str) -> dict:
    """The headline quantities of one run (history.csv, summary.json)."""
    h, s = read_history(d), read_summary(d)
    params = {k.lstrip("-"): v for k, v in s["provenance"]["parameters"].items()}
    t = h["time"] / YEAR
    drop = params["thm_initial_temperature"] - h["production_temperature"]
    k = int(np.argmax(h["aperture_increase_max"]))
    out = {f"dT_prod_{y}y": float(np.interp(y, t, drop)) for y in (10, 20, 30)}
    maxima = aperture_maxima(t, h["aperture_increase_max"])
    for kind in ("early", "thermal"):
        out[f"da_{kind}_mm"], out[f"da_{kind}_years"] = maxima[kind][0] * 1e3, maxima[kind][1]
    out.update(da_max_mm=float(h["aperture_increase_max"][k]) * 1e3, da_peak_years=float(t[k]),
               raised_area_30y_m2=float(h["raised_area"][-1]),
               p_inj_30y_MPa=float(h["injection_pressure"][-1]) / 1e6,
               lam_min_30y_MPa=float(h["lam_min"][-1]) / 1e6, cells=int(s["cells"]),
               wall_s=float(s["wall_time"]["total"]))
    return out


def richardson(phi: list[float], cells: list[int]) -> dict:
    """Observed order, extrapolated value and fine GCI from three levels,
    coarse to fine (Celik et al. 2008: a fixed-point iteration for p when
    the ratios differ)."""
    f3, f2, f1 = phi
    r21 = (cells[2] / cells[1]) ** (1 / 3)
    r32 = (cells[1] / cells[0]) ** (1 / 3)
    e21, e32 = f2 - f1, f3 - f2
    if e21 == 0.0 or e32 == 0.0:
        return {"p": float("nan"), "extrapolated": f1, "gci": 0.0, "monotone": e21 == e32 == 0.0}
    s = math.copysign(1.0, e32 / e21)
    p = 1.0
    for _ in range(100):
        q = math.log((r21 ** p - s) / (r32 ** p - s)) if (r21 ** p - s) / (r32 ** p - s) > 0 else 0.0
        p_new = abs(math.log(abs(e32 / e21)) + q) / math.log(r21)
        if abs(p_new - p) < 1e-10:
            break
        p = p_new
    ext = (r21 ** p * f1 - f2) / (r21 ** p - 1)
    gci = 1.25 * abs(e21 / f1) / (r21 ** p - 1) if f1 else float("nan")
    return {"p": p, "extrapolated": ext, "gci": gci, "monotone": s > 0}


def converged(value: float, ext: float, drop: bool) -> bool:
    tol = max(TOLERANCE * abs(ext), FLOOR_K if drop else 0.0)
    return abs(value - ext) <= tol


def table(out: str, levels: list[int], cases: list[int]) -> str:
    rows, lines = [], []
    for case in cases:
        done = [lv for lv in levels if finished(run_dir(out, lv, case))]
        q = {lv: quantities(run_dir(out, lv, case)) for lv in done}
        lines += [f"### Case {case}", "",
                  "levels finished: " + ", ".join(f"{lv:+d} ({q[lv]['cells']} cells, {q[lv]['wall_s']:.0f} s)"
                                                  for lv in done), ""]
        head = "| quantity | " + " | ".join(f"level {lv:+d}" for lv in done) + \
               " | observed order | extrapolated | GCI fine | within 5 % (levels) |"
        lines += [head, "|" + "---|" * (len(done) + 5)]
        for name, (unit, drop) in SMOOTH.items():
            vals = [q[lv][name] for lv in done]
            rich = richardson(vals[-3:], [q[lv]["cells"] for lv in done[-3:]]) if len(done) >= 3 else None
            ok = [f"{lv:+d}" for lv in done if rich and converged(q[lv][name], rich["extrapolated"], drop)]
            cells = " | ".join(f"{v:.4g}" for v in vals)
            if rich:
                osc = "" if rich["monotone"] else " (oscillatory)"
                lines.append(f"| {name} ({unit}) | {cells} | {rich['p']:.2f}{osc} "
                             f"| {rich['extrapolated']:.4g} "
                             f"| {100 * rich['gci']:.2g} % | {', '.join(ok) or 'none'} |")
            else:
                lines.append(f"| {name} ({unit}) | {cells} | | | | |")
            rows.append({"case": case, "quantity": name, **{f"level{lv:+d}": q[lv][name] for lv in done},
                         **({k: rich[k] for k in ("p", "extrapolated", "gci")} if rich else {})})
        for name, unit in EVENTS.items():
            lines.append(f"| {name} ({unit}, per level) | " +
                         " | ".join(f"{q[lv][name]:.4g}" for lv in done) + " | | | | |")
            rows.append({"case": case, "quantity": name, **{f"level{lv:+d}": q[lv][name] for lv in done}})
        lines.append("")
    write_csv(os.path.join(out, "scene3_convergence.csv"), rows)
    text = "\n".join(lines)
    with open(os.path.join(out, "scene3_convergence.md"), "w") as f:
        f.write(text + "\n")
    return text


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--levels", default="-2,-1,0,1")
    ap.add_argument("--ratio", type=float, default=1.3)
    ap.add_argument("--cases", default="1,2,3")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--out", default=os.path.join(ROOT, "output", "scene3_convergence"))
    ap.add_argument("--table-only", action="store_true")
    ap.add_argument("extra", nargs="*")
    a = ap.parse_args()
    try:
        levels = sorted(int(v) for v in a.levels.split(",") if v)
        cases = [int(c) for c in a.cases.split(",") if c]
    except ValueError:
        raise SystemExit("scene3_convergence.py: --levels and --cases take integers (a,b,c)") from None
    if not set(cases) <= {1, 2, 3} or a.ratio <= 1.0:
        raise SystemExit("scene3_convergence.py: --cases takes 1, 2 and/or 3; --ratio is above 1")
    if not a.table_only:
        jobs = [(lv, c) for lv in levels for c in cases]          # coarse levels first
        with ThreadPoolExecutor(a.jobs) as ex:
            list(ex.map(lambda j: run(a.out, j[0], j[1], a.ratio, a.extra), jobs))
    print(table(a.out, levels, cases))


if __name__ == "__main__":
    main()
