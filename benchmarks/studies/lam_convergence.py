"""Convergence of the contact traction on the closed coupled manufactured
solution in 3D (manual, verification: coupled MMS, "The contact traction"):
the L2 error of the multiplier ``lam`` and of the traction recovered from the
rock's stress (``lam_recovered``, kernels/contact.RecoveredTraction) on three
or more meshes, with the slope of each refinement and the fields the
aperture carries (pf, Tf).

    python benchmarks/studies/lam_convergence.py --degree 1 --sizes 0.0625,0.03125,0.015625 \\
        --ranks 1,1,2 --out DIR [--record FILE] [--evaluate] [-- petthm options]

P1 runs with SUPG heat (``-thm_heat_transport supg``), P2 with Galerkin heat
(``-thm_coupled_mms_supg 0``), as the manual's tables of the coupled MMS.
``--ranks``: the ranks of each level (mpiexec).  ``--evaluate``: the run
folders hold finished runs; recompute each one's errors from its final state
(checkpoint.h5, with the current monitors) instead of running it again.
Writes lam_convergence.csv and lam_convergence.md in DIR, and with
``--record`` the CSV there too (benchmarks/records/, from which the manual's
table is made).
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
import numpy as np
from study_tables import MPI_ENV, ROOT, markdown, run_petthm, write_csv, write_markdown  # noqa: E402

FIELDS = ("lam", "lam_recovered", "pf", "Tf", "u")


def options(degree: int, size: float, extra=()) -> list:
    """The petthm options of one level."""
    heat = ("-thm_heat_transport", "supg") if degree == 1 else ("-thm_coupled_mms_supg", 0)
    return ["-options_file", os.path.join(ROOT, "options", "scenes", "coupled_mms.opts"),
            "-thm_coupled_mms_dim", 3, "-thm_coupled_mms_state", "closed", "-thm_fe_degree", degree,
            "-thm_mesh_size", size, *heat, *extra]


def evaluate(folder: str, opts: list, ranks: int) -> dict:
    """The errors of a finished run's final state (its checkpoint), with the current monitors."""
    cmd = [sys.executable, os.path.abspath(__file__), "--evaluate-folder", folder, "--",
           *map(str, opts), "-thm_mesh_file", os.path.join(folder, "mesh.msh"),
           "-thm_output_dir", os.path.join(folder, "evaluated"), "-thm_quiet", "-thm_overwrite"]
    if ranks > 1:
        cmd = ["mpiexec", "-n", str(ranks)] + cmd
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, env=dict(os.environ, **MPI_ENV))
    if p.returncode:
        print(p.stdout, p.stderr, file=sys.stderr)
        raise SystemExit(f"{' '.join(cmd)} failed")
    with open(os.path.join(folder, "summary.json")) as f:
        summary = json.load(f)
    summary.update(json.loads(p.stdout.strip().splitlines()[-1]))
    return summary


def _evaluate_here(folder: str) -> None:
    """(Under mpiexec) set the scene up with the options on the command line,
    load the folder's checkpoint and print the scene monitor's report (rank 0)."""
    import petsc4py
    petsc4py.init(sys.argv)
    from petsc4py import PETSc

    from petthm.io import checkpoint
    from petthm.run.driver import Run, make_scene
    run = Run(make_scene("coupled_mms"))
    run.open_folder()
    _, problem, _, _, monitor = run.setup(run.build_mesh())
    meta = checkpoint.read(folder, problem.X, problem.dm, "coupled_mms")
    report = monitor.report(problem, meta["time"])
    if PETSc.COMM_WORLD.rank == 0:
        print(json.dumps({"error": report["error"], "h_max": report["h_max"]}))


def slopes(h, e) -> list[float]:
    """The slope of each refinement (nan for the first level)."""
    h, e = np.asarray(h, dtype=float), np.asarray(e, dtype=float)
    return [float("nan")] + list(np.log(e[:-1] / e[1:]) / np.log(h[:-1] / h[1:]))


def main():
    if "--evaluate-folder" in sys.argv:
        _evaluate_here(sys.argv[sys.argv.index("--evaluate-folder") + 1])
        return
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--degree", type=int, choices=(1, 2), default=1)
    ap.add_argument("--sizes", default="0.0625,0.03125,0.015625")
    ap.add_argument("--ranks", default="", help="ranks per level, comma-separated (default 1 each)")
    ap.add_argument("--out", default=os.path.join(ROOT, "output", "lam_convergence"))
    ap.add_argument("--record", default="", help="also write the CSV here")
    ap.add_argument("--evaluate", action="store_true", help="recompute the errors of finished runs")
    ap.add_argument("extra", nargs="*", help="more petthm options (after --)")
    a = ap.parse_args()
    sizes = [float(x) for x in a.sizes.split(",")]
    ranks = [int(x) for x in a.ranks.split(",")] if a.ranks else [1] * len(sizes)
    rows = []
    for size, n in zip(sizes, ranks, strict=True):
        folder = os.path.join(a.out, "runs", f"p{a.degree}_h{size:g}")
        opts = options(a.degree, size, a.extra)
        s = evaluate(folder, opts, n) if a.evaluate else run_petthm("coupled_mms", folder, *opts, ranks=n)
        row = {"degree": a.degree, "mesh_size": size, "ranks": n, "h_max": s["h_max"],
               "unknowns": sum(s["dofs"].values()), "wall_s": s["wall_time"]["total"]}
        row.update({f"{f}_l2": s["error"][f"{f}_l2"] for f in FIELDS})
        rows.append(row)
        print(f"P{a.degree} h={row['h_max']:.4f} {row['unknowns']} unknowns {row['wall_s']:.0f} s",
              " ".join(f"{f}:{row[f + '_l2']:.3e}" for f in FIELDS), flush=True)
    h = [r["h_max"] for r in rows]
    for f in FIELDS:
        for r, sl in zip(rows, slopes(h, [r[f"{f}_l2"] for r in rows]), strict=True):
            r[f"{f}_slope"] = sl
            r[f"{f}_shown"] = f"{r[f'{f}_l2']:.3e}" + ("" if np.isnan(sl) else f" ({sl:.2f})")
    os.makedirs(a.out, exist_ok=True)
    record = [{k: v for k, v in r.items() if not k.endswith("_shown")} for r in rows]
    write_csv(os.path.join(a.out, "lam_convergence.csv"), record)
    if a.record:
        write_csv(a.record, record)
    cols = [("h_max", "h_max", ".4f"), ("unknowns", "unknowns", "d"), ("ranks", "ranks", "d"),
            ("wall s", "wall_s", ".0f")]
    cols += [(f"{f} L2 (slope)", f"{f}_shown", "s") for f in FIELDS]
    write_markdown(os.path.join(a.out, "lam_convergence.md"),
                   f"Contact traction, 3D P{a.degree} closed coupled MMS", markdown(cols, rows))


if __name__ == "__main__":
    main()
