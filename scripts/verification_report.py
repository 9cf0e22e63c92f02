"""The verification and stability report (issue 16 item 6): every
verification case at three resolutions, and the stiff and extreme cases.

    python scripts/verification_report.py [--out output/verification_report]
                                          [--cases NAME,NAME] [--stability-only | --convergence-only]
                                          [--jobs 1] [--doc docs/verification/report.md]

Convergence: each case runs at levels 0, 1, 2, every mesh size of the case
halved from one level to the next (its other options fixed); the table has,
per level, the unknowns, the wall time and the errors the scene reports
(``summary.json``), and the least-squares slope of log(error) against
log(h), h the level's relative mesh size, next to the rate the
discretisation should reach where the error is the discretisation's
(manufactured solutions: the element order; exact cases: round-off at every
level; benchmarks whose error has other limits, such as the time step or
what the analytical solution leaves out, have no expected rate).  One
work-precision plot: every case's first error against its wall time.

Stability: the stiff and extreme cases of ``STABILITY``, each run once; the
table has its outcome (status, steps and rejected steps, no NaN in the
history, Tf within its bounds where the scene checks them, the case's own
check).  Each is also a test (``tests/verification/test_stability.py`` runs
them; the column "test" names it).

Wall times are single runs on the machine the script runs on, one case at a
time per core; the report says when it was written and from which commit.
"""
from __future__ import annotations

import argparse
import csv
import math
import os
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from study_tables import ROOT, read_summary  # noqa: E402


@dataclass
class Case:
    """A verification case: ``sizes`` are the mesh-size options at level 0,
    halved per level; ``errors``: (error key, expected rate or None, "exact"
    for round-off at every level)."""
    name: str
    scene: str
    options: tuple
    sizes: dict
    errors: tuple
    note: str = ""


#: SUPG for P1 temperatures (their default is the limited scheme; manual, theory: the default and its cost)
SUPG = ("-thm_heat_transport", "supg")


def _mms(dim, degree, size, **extra):
    return Case(f"heat MMS {dim}D P{degree}", "heat_mms",
                ("-thm_mms_dim", dim, "-thm_fe_degree", degree, *SUPG), {"-thm_mesh_size": size},
                (("Tm_l2_rel", degree + 1), ("Tm_h1_rel", degree)), "advection-diffusion, SUPG")


def _coupled(degree, state, supg, size):
    rates = tuple((f"{f}_l2", degree + 1) for f in ("u", "pm", "Tm", "pf", "Tf"))
    return Case(f"coupled MMS 2D P{degree} {state}{' SUPG' if supg else ''}", "coupled_mms",
                ("-thm_fe_degree", degree, "-thm_coupled_mms_state", state, "-thm_coupled_mms_supg", supg,
                 *(SUPG if supg else ()), "-thm_direct_max_unknowns", 1000000), {"-thm_mesh_size": size},
                rates,
                "u, pm, Tm, pf, Tf, lam with a fracture (docs/verification/coupled-mms.md)")


CONVERGENCE = [
    _mms(2, 1, 0.1), _mms(2, 2, 0.2), _mms(3, 1, 0.25),
    _coupled(1, "open", 1, 0.125), _coupled(2, "closed", 0, 0.25),
    Case("heat erfc (half-space)", "heat_erfc", (), {"-thm_erfc_surface_size": 0.04},
         (("Tm_max_rel", None),), "conduction after a surface step (Carslaw & Jaeger); the time steps set "
         "the error (the same on every mesh)"),
    Case("fracture flow patch", "fracture_flow_patch", (), {"-thm_mesh_size": 40.0},
         (("pf_max_rel", "exact"), ("flux_rel", "exact")), "linear pressure along a fracture"),
    Case("radial flow", "radial_flow", (), {"-thm_radial_well_size": 2.0},
         (("pf_rel_beyond_5h", None),), "log profile around a point injector (3b); the point source's "
         "near field and the far mesh set the error"),
    Case("leakoff 1D", "leakoff_1d", (), {"-thm_leakoff_fracture_size": 0.1},
         (("leakoff_rel_t1000", None), ("leakoff_rel_t100000", None)),
         "cumulative leakoff ~ sqrt(t); the first steps' time error remains at 1e5 s"),
    Case("leakoff heat", "leakoff_heat", ("-thm_fe_degree", 1, *SUPG),
         {"-thm_leakoff_heat_fracture_size": 2.0},
         (("outlet_max_rel", None),), "outlet temperature with uniform leakoff (2); P1, time steps fixed: "
         "below 0.2 % the time error sets the error"),
    Case("Lauwerier", "lauwerier", (), {"-thm_lauwerier_fracture_size": 2.0},
         (("outlet_max_rel_t_ge_1e4", None), ("profile_max_rel_t1e+07", None)),
         "outlet and profile against Lauwerier (1); the time steps fixed "
         "(docs/verification/lauwerier-study.md)"),
    Case("Sneddon 2D (Griffith crack)", "sneddon", ("-thm_sneddon_dim", 2),
         {"-thm_sneddon_crack_size": 0.1}, (("centre_error", None), ("opening_l2_error", None)),
         "opening of a pressurised crack (4); the finite box (20 c) and the tip singularity limit the "
         "rate"),
    Case("contact patch 2D", "contact_patch", ("-thm_contact_dim", 2), {"-thm_mesh_size": 5.0},
         (("lam_error", "exact"), ("aperture_error", "exact")), "lam = sigma - p (5)"),
    Case("Terzaghi", "terzaghi", (), {"-thm_mesh_size": 1.0},
         (("p_l2_rel_Tv0.1", None), ("settlement_rel_Tv0.1", None)),
         "1D consolidation (6); the time steps set the error from level 1 on"),
    Case("Mandel", "mandel", (), {"-thm_mesh_size": 1.0},
         (("p_max_rel", None), ("mandel_cryer_peak_rel_p0", None)),
         "Mandel-Cryer effect (6); the time steps set the error from level 1 on"),
    Case("thermal stress", "thermal_stress", (), {"-thm_thermal_surface_size": 0.2},
         (("T_max_rel_t1e+07", None), ("stress_l2_rel_t1e+07", None)),
         "constrained half-space (7b); the time steps set the error (the same on every mesh)"),
    Case("gravity column P2", "gravity_column", ("-thm_fe_degree", 2), {"-thm_mesh_size": 10.0},
         (("u_max_rel", "exact"),), "quadratic settlement, exact for P2"),
    Case("friction patch 2D", "friction_patch", ("-thm_friction_dim", 2), {"-thm_mesh_size": 5.0},
         (("slip_error", "exact"), ("tau_error", "exact")), "uniform slip at tau = c0 + mu lam"),
    Case("inclined frictional crack 2D", "inclined_crack", (), {"-thm_inclined_crack_size": 0.1},
         (("slip_l2_error", None),), "slip against the mode II Griffith profile; tip singularity"),
]


@dataclass
class Stability:
    """A stiff or extreme case: ``expect`` "completed" or "failed" (a clean
    stop with ``message`` in summary.json's message); ``checks``: summary
    error keys with their largest accepted value."""
    name: str
    scene: str
    options: tuple
    expect: str = "completed"
    message: str = ""
    checks: dict = field(default_factory=dict)
    at_least: dict = field(default_factory=dict)
    bounds: float | None = 1e-2        # Tf within [Tinj, T0] to this fraction of the range (None: reported)
    test: str = "tests/verification/test_stability.py"


_SCENE3_TEST = "tests/verification/test_scene3.py::test_scene3_stiff_and_extreme_cases"
_JOINT_TEST = "tests/verification/test_contact.py::test_contact_patch_joint_stiffness"
#: Tf within [Tinj, T0] to 1e-3 of the range (the default heat transport is bound-preserving;
#: SUPG leaves the interval by 1-2 % of the range in the coarse mesh's first days)
_SCENE3_BOUNDS = 1e-3
_COARSE3 = ("-options_file", "options/scenes/inclined_penny_coarse.opts", "-thm_fe_degree", 1,
            "-thm_final_time", 3 * 86400)
_SCENE2 = ("-options_file", "options/scenes/penny_impermeable.opts", "-thm_scene2_fracture_size", 40,
           "-thm_scene2_well_size", 20, "-thm_scene2_layer", 0)

STABILITY = [
    Stability("nu = 0.4999 (contact patch, P2 u)", "contact_patch",
              ("-thm_contact_dim", 2, "-thm_rock_poisson_ratio", 0.4999),
              checks={"lam_error": 1e-6, "aperture_error": 1e-10}),
    Stability("Kn = 1e8 Pa/m (soft joint: residual aperture)", "contact_patch",
              ("-thm_contact_dim", 2, "-thm_fracture_normal_stiffness", 1e8),
              checks={"lam_error": 1e-6, "aperture_error": 1e-10}, test=_JOINT_TEST),
    Stability("Kn = 1e14 Pa/m (stiff joint: six decades up)", "contact_patch",
              ("-thm_contact_dim", 2, "-thm_fracture_normal_stiffness", 1e14),
              checks={"lam_error": 1e-6, "aperture_error": 1e-10}, test=_JOINT_TEST),
    Stability("km = 1e-12 m2 (Scene 3 coarse, permeable)", "inclined_penny",
              (*_COARSE3, "-thm_rock_permeability", 1e-12), bounds=_SCENE3_BOUNDS, test=_SCENE3_TEST),
    Stability("km = 1e-18 m2 (Scene 3 coarse: the producer cannot give Q)", "inclined_penny",
              (*_COARSE3, "-thm_rock_permeability", 1e-18), expect="failed",
              message="-thm_production_rate", test=_SCENE3_TEST),
    Stability("incompressible Biot limit, first step 60 s (Scene 3 coarse)", "inclined_penny",
              (*_COARSE3, "-thm_rock_biot_coefficient", 1, "-thm_fluid_compressibility", 0,
               "-thm_rock_porosity", 0, "-thm_dt_initial", 60, "-thm_dt_growth", 2),
              bounds=_SCENE3_BOUNDS, test=_SCENE3_TEST),
    Stability("mu(T) of water at 250 degC (Scene 3 coarse case 2)", "inclined_penny",
              (*_COARSE3, "-thm_scene3_case", 2), bounds=_SCENE3_BOUNDS),
    Stability("cell Peclet >= 1e3 (advected front, P1)", "heat_advection",
              ("-thm_fe_degree", 1, "-thm_advection_velocity", "1e-4,0", "-thm_final_time", 1e6,
               "-thm_dt_initial", 2e4), checks={"bounds.Tm.violation_fraction": 1e-3},
              at_least={"cell_peclet_min": 1e3}),
    Stability("first step 1 s (Lauwerier)", "lauwerier", ("-thm_dt_initial", 1, "-thm_final_time", 2e5),
              checks={"outlet_max_rel_t_ge_1e4": 2e-2}),
    Stability("first step 1 s (Scene 2 coarse: contact, mu(T), thermal strain)", "penny_impermeable",
              (*_SCENE2, "-thm_dt_initial", 1, "-thm_final_time", 1e5)),
    Stability("first step 1e-6 of the consolidation time, alpha = 1, c_f = 0 (Terzaghi P2/P1, "
              "stabilised)", "terzaghi",
              ("-thm_rock_biot_coefficient", 1, "-thm_fluid_compressibility", 0,
               "-thm_terzaghi_start", "rest", "-thm_dt_initial", 2.22e-4, "-thm_final_time", 10,
               "-thm_terzaghi_pressure_degree", 1, "-thm_biot_stabilization", 1.0),
              checks={"p_overshoot_max_rel_load": 5e-2},
              test="tests/verification/test_poroelastic.py::test_terzaghi_first_step_pressure_oscillation"),
    Stability("first rock layer 0.22 m (Scene 3 coarse, layered: Newton on its round-off floor)",
              "inclined_penny", (*_COARSE3, "-thm_scene3_layer", 0.223, "-thm_scene3_layer_growth", 2,
                                 "-thm_dt_growth", 1.0),
              bounds=_SCENE3_BOUNDS,
              test="tests/verification/test_scene3.py::test_scene3_thin_first_layer_starts"),
    Stability("water at 250 degC in a fracture (Lauwerier, mu(T))", "lauwerier",     # at 5 MPa: liquid
              ("-thm_initial_temperature", 250, "-thm_initial_pressure", 5e6, "-thm_production_pressure", 5e6,
               "-thm_fluid_viscosity", "water", "-thm_final_time", 1e6,
               "-thm_mesh_size", 20, "-thm_lauwerier_fracture_size", 5)),     # coarse: higher cell Peclet
]


REUSE = False          # --reuse: a run folder with a summary.json is not run again


def run(scene: str, out: str, opts) -> tuple[dict | None, str, float]:
    """(summary or None, stderr's last line, wall seconds) of one run."""
    if REUSE and os.path.exists(os.path.join(out, "summary.json")):
        s = read_summary(out)
        return s, "", s["wall_time"]["total"]
    cmd = [sys.executable, "-m", "petthm", scene, "-thm_output_dir", out, "-thm_quiet", "-thm_overwrite",
           *map(str, opts)]
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")
    t0 = time.perf_counter()
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    last = (p.stderr.strip().splitlines() or [""])[-1]
    s = read_summary(out) if os.path.exists(os.path.join(out, "summary.json")) else None
    return s, last, wall


def error_of(s: dict, key: str):
    """A number of the summary: ``error.KEY``, else ``KEY`` (dotted: a nested entry)."""
    e = s.get("error") or {}
    v = e.get(key, s.get(key))
    if v is None and "." in key:
        v = s
        for part in key.split("."):
            v = v.get(part) if isinstance(v, dict) else None
    return None if v is None else float(v)


def convergence_rows(case: Case, out: str, levels) -> list[dict]:
    rows = []
    for k in levels:
        opts = list(case.options)
        for opt, h0 in case.sizes.items():
            opts += [opt, h0 / 2 ** k]
        d = os.path.join(out, "runs", _slug(case.name), f"L{k}")
        s, last, wall = run(case.scene, d, opts)
        row = {"case": case.name, "level": k, "h": 1.0 / 2 ** k, "status": s["status"] if s else last,
               "cells": s["cells"] if s else "", "unknowns": sum(s["dofs"].values()) if s else "",
               "steps": s["steps"] if s else "", "wall_s": round(s["wall_time"]["total"], 3) if s else wall}
        for key, _ in case.errors:
            row[key] = error_of(s, key) if s else None
        rows.append(row)
        errs = ", ".join(f"{key} {row[key]:.3e}" for key, _ in case.errors if row[key] is not None)
        print(f"{case.name} L{k}: {row['status']}, {row['unknowns']} unknowns, {row['wall_s']} s, {errs}",
              flush=True)
    return rows


def slope(rows, key) -> float | None:
    pts = [(r["h"], r[key]) for r in rows if r.get(key) not in (None, "") and float(r[key]) > 0]
    if len(pts) < 2:
        return None
    h, e = np.array(pts, dtype=float).T
    return float(np.polyfit(np.log(h), np.log(e), 1)[0])


def verdict(expected, rows, key) -> str:
    values = [float(r[key]) for r in rows if r.get(key) not in (None, "")]
    if not values or len(values) < len(rows):
        return "missing"
    if expected == "exact":
        return "round-off" if max(values) <= 1e-9 else "NOT exact"
    if expected is None:
        return "-"
    s = slope(rows, key)
    return "met" if s is not None and s >= expected - 0.2 else "below"


def stability_row(case: Stability, out: str) -> dict:
    d = os.path.join(out, "runs", "stability", _slug(case.name))
    s, last, wall = run(case.scene, d, case.options)
    row = {"case": case.name, "scene": case.scene, "expect": case.expect, "test": case.test,
           "bounds_required": case.bounds is not None}
    if s is None:
        row.update(status=f"no summary: {last}", passed=False)
        return row
    finite = _history_finite(d)
    bounds = error_of(s, "bounds.Tf.violation_fraction")
    checks = {k: error_of(s, k) for k in (*case.checks, *case.at_least)}
    ok_checks = all(checks[k] is not None and checks[k] <= v for k, v in case.checks.items()) and \
        all(checks[k] is not None and checks[k] >= v for k, v in case.at_least.items())
    if case.expect == "failed":
        passed = s["status"] == "failed" and case.message in (s.get("message") or "") and finite
    else:
        passed = s["status"] == "completed" and finite and ok_checks and \
            (bounds is None or case.bounds is None or bounds <= case.bounds)
    row.update(status=s["status"], steps=s["steps"], rejected=s["rejected_steps"], finite=finite,
               tf_bounds=bounds, checks=", ".join(f"{k} {v:.2e}" for k, v in checks.items() if v is not None),
               message=(s.get("message") or "")[:120], wall_s=round(s["wall_time"]["total"], 2),
               passed=passed)
    return row


def _history_finite(d: str) -> bool:
    path = os.path.join(d, "history.csv")
    if not os.path.exists(path):
        return False
    with open(path) as f:
        for r in csv.DictReader(f):
            for k, v in r.items():
                if k and v not in ("", "nan"):
                    try:
                        if not math.isfinite(float(v)):
                            return False
                    except ValueError:
                        pass
                elif v == "nan" and k in ("mass_balance", "energy_balance", "time"):
                    return False
    return True


def _slug(name: str) -> str:
    return "".join(c if c.isalnum() else "_" for c in name).strip("_").lower()


def _fmt(v, spec=".2e"):
    if v is None or v == "":
        return "-"
    return format(float(v), spec) if isinstance(v, (float, int, np.floating)) else str(v)


def convergence_markdown(cases, rows) -> list[str]:
    out = ["| case | errors | levels: unknowns | wall (s) | error per level | fitted rate | expected | |",
           "|---|---|---|---|---|---|---|---|"]
    for case in cases:
        rs = [r for r in rows if r["case"] == case.name]
        if not rs:
            continue
        for i, (key, expected) in enumerate(case.errors):
            errs = " / ".join(_fmt(r.get(key)) for r in rs)
            s = slope(rs, key) if expected != "exact" else None
            out.append(f"| {case.name if i == 0 else ''} | `{key}` | "
                       f"{' / '.join(str(r['unknowns']) for r in rs) if i == 0 else ''} | "
                       f"{' / '.join(_fmt(r['wall_s'], '.2f') for r in rs) if i == 0 else ''} | {errs} | "
                       f"{_fmt(s, '.2f')} | {expected if expected is not None else '-'} | "
                       f"{verdict(expected, rs, key)} |")
    return out


def stability_markdown(rows) -> list[str]:
    out = ["| case | expected | status | steps (rejected) | history finite | Tf bounds | checks | wall (s) | "
           "passed | test |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['case']} | {r['expect']} | {r['status']} | {r.get('steps', '-')} "
                   f"({r.get('rejected', '-')}) | {r.get('finite', '-')} | {_fmt(r.get('tf_bounds'))}"
                   f"{'' if r.get('bounds_required', True) else ' (reported)'} | "
                   f"{r.get('checks') or '-'} | {r.get('wall_s', '-')} | {'yes' if r['passed'] else 'NO'} | "
                   f"`{r['test']}` |")
    return out


def plot(cases, rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(8, 6))
    for case in cases:
        key, expected = case.errors[0]
        rs = [r for r in rows
              if r["case"] == case.name and r.get(key) not in (None, "") and float(r[key]) > 0]
        if len(rs) < 2 or expected == "exact":
            continue
        ax.loglog([float(r["wall_s"]) for r in rs], [float(r[key]) for r in rs], "o-", label=case.name, ms=4)
    ax.set_xlabel("wall time (s, 1 rank)")
    ax.set_ylabel("error (the case's first error, relative)")
    ax.set_title("verification cases: error against run time (levels 0-2)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def _write_csv(path, rows):
    keys = list(dict.fromkeys(k for r in rows for k in r))
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, keys)
        w.writeheader()
        w.writerows(rows)


def _commit() -> str:
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                              text=True).stdout.strip()
    except OSError:
        return "?"


def kept_convergence_section(doc: str) -> list[str]:
    """--stability-only: the convergence section of the report in ``doc``,
    kept as it was, with the line that says which run wrote it."""
    if not os.path.exists(doc):
        return []
    text = Path(doc).read_text().splitlines()
    written = next((ln for ln in text if ln.startswith("Written by")), "")
    start = text.index("## Convergence") if "## Convergence" in text else None
    if start is None:
        return []
    end = text.index("## Stiff and extreme cases") if "## Stiff and extreme cases" in text else len(text)
    body = text[start + 1:end]
    kept = [ln for ln in body if ln.startswith("(Kept from")]      # the section was kept before: its origin
    if kept:
        note = kept[0]
    else:
        origin = written.split(").", 1)[0].replace("Written by", "Kept from the report written by") + ")"
        note = f"({origin}; `--stability-only` ran the stiff and extreme cases alone.)"
    body = [ln for ln in body if not ln.startswith("(Kept from")]
    while body and not body[0].strip():
        body = body[1:]
    return [text[start], "", note, "", *body]


#: the records of benchmarks/studies/lam_convergence.py: (degree, file, the least slope of each refinement)
TRACTION_RECORDS = ((1, "lam_convergence_p1.csv", 0.9), (2, "lam_convergence_p2.csv", 1.8))


def traction_section(records: str = os.path.join(ROOT, "benchmarks", "records")) -> list[str]:
    """The contact traction's convergence in 3D (closed coupled MMS), from
    the records of benchmarks/studies/lam_convergence.py in ``records``: too
    long to run here (the finest P1 mesh: ~1 M unknowns)."""
    lines = []
    for degree, name, least in TRACTION_RECORDS:
        path = os.path.join(records, name)
        if not os.path.exists(path):
            continue
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
        if not lines:
            lines = ["## The contact traction in 3D", "",
                     "The closed coupled MMS in 3D (docs/verification/coupled-mms.md, \"The contact "
                     "traction\"), from the records in benchmarks/records/ of "
                     "`python benchmarks/studies/lam_convergence.py` (the command of each is in that page). "
                     "L2 errors, the slope of each refinement in brackets; expected: the traction "
                     "recovered from the rock's stress at slope >= 0.9 (P1) and >= 1.8 (P2) on every "
                     "refinement.", "",
                     "| case | h_max | unknowns | lam | lam_recovered | pf | Tf | |",
                     "|---|---|---|---|---|---|---|---|"]
        for k, r in enumerate(rows):
            cells = []
            for f in ("lam", "lam_recovered", "pf", "Tf"):
                sl = float(r[f"{f}_slope"])
                cells.append(f"{float(r[f + '_l2']):.3e}" + ("" if math.isnan(sl) else f" ({sl:.2f})"))
            sl = float(r["lam_recovered_slope"])
            verdict = "" if math.isnan(sl) else ("met" if sl >= least else "not met")
            case = f"3D P{degree} closed" if k == 0 else ""
            lines.append(f"| {case} | {float(r['h_max']):.4f} | "
                         f"{r['unknowns']} | {' | '.join(cells)} | {verdict} |")
    return lines + [""] if lines else []


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(ROOT, "output", "verification_report"))
    ap.add_argument("--doc", default=os.path.join(ROOT, "docs", "verification", "report.md"))
    ap.add_argument("--cases", default="", help="names (or parts of names) of the cases to run")
    ap.add_argument("--reuse", action="store_true",
                    help="take the runs whose folder in --out/runs has a summary.json from there")
    ap.add_argument("--levels", default="0,1,2")
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--stability-only", action="store_true")
    ap.add_argument("--convergence-only", action="store_true")
    a = ap.parse_args()
    global REUSE
    REUSE = a.reuse
    os.makedirs(a.out, exist_ok=True)
    pick = [c.strip().lower() for c in a.cases.split(",") if c.strip()]
    cases = [c for c in CONVERGENCE if not pick or any(p in c.name.lower() for p in pick)]
    stab = [c for c in STABILITY if not pick or any(p in c.name.lower() for p in pick)]
    levels = [int(k) for k in a.levels.split(",")]
    t0 = time.time()
    conv_rows, stab_rows = [], []
    with ThreadPoolExecutor(a.jobs) as ex:
        if not a.stability_only:
            conv_rows = [r for rs in ex.map(lambda c: convergence_rows(c, a.out, levels), cases) for r in rs]
        if not a.convergence_only:
            stab_rows = list(ex.map(lambda c: stability_row(c, a.out), stab))
    if conv_rows:
        _write_csv(os.path.join(a.out, "convergence.csv"), conv_rows)
        plot(cases, conv_rows, os.path.join(os.path.dirname(os.path.abspath(a.doc)) if a.doc else a.out,
                                            "verification-work-precision.png"))
    if stab_rows:
        _write_csv(os.path.join(a.out, "stability.csv"), stab_rows)
    lines = ["# Verification and stability report", "",
             f"Written by `python scripts/verification_report.py` on {time.strftime('%Y-%m-%d')} from commit "
             f"{_commit()} in {time.time() - t0:.0f} s ({a.jobs} case(s) at a time on this machine; wall "
             f"times are single runs{'; runs found in the output folder were reused' if REUSE else ''}).  "
             "Convergence: levels 0, 1, 2 halve every mesh size of the case; "
             "the fitted rate is the slope of log(error) against log(h); expected: the element order for "
             "manufactured solutions (met: within 0.2), round-off for exact cases, '-' for benchmarks "
             "whose error has other limits (time steps, a finite box, what the analytical solution leaves "
             "out).", ""]
    if conv_rows:
        lines += ["## Convergence", "", *convergence_markdown(cases, conv_rows), "",
                  *[f"* {c.name}: {c.note}." for c in cases if c.note], "",
                  "![work-precision](verification-work-precision.png)",
                  ""]
    elif a.stability_only and not pick:
        lines += kept_convergence_section(a.doc)
    if stab_rows:
        lines += ["## Stiff and extreme cases", "", *stability_markdown(stab_rows), ""]
    lines += traction_section()
    if a.doc and not pick:
        with open(a.doc, "w") as f:
            f.write("\n".join(lines) + "\n")
        print(f"report: {a.doc}")
    else:
        print("\n".join(lines))
    return 0 if all(r["passed"] for r in stab_rows) else 1


if __name__ == "__main__":
    sys.exit(main())
