"""Solver study: one scene with several solver settings, refinement levels
and rank counts; CSV and a markdown table of what each costs.

    python scripts/solver_study.py SCENE --levels "A;B;C" --solvers "NAME=OPTS;NAME=OPTS" \\
        [--ranks 1,2] [--common "OPTS"] [--out DIR]

* ``--levels``: the mesh refinement levels, each a string of petthm options
  (e.g. ``-thm_mesh_size 40`` or ``-dm_refine 1``), separated by ``;``.
* ``--solvers``: named option sets, ``NAME=OPTIONS`` separated by ``;``;
  OPTIONS may hold ``-options_file FILE`` (e.g. ``options/solvers/block.opts``).
* ``--common``: options of every run (final time, scene options).
* ``--ranks``: rank counts (``mpiexec -n``).

Each run writes its own output folder under ``DIR/runs``; the table has, per
run: unknowns, steps, rejected steps, Newton iterations per step, Krylov
iterations per Newton iteration (mean and largest over the steps), PCSetUp
count and time, KSPSolve time, total wall time, peak memory per rank and
the run's status.  Rows of runs that failed say so (the run's message in the
CSV).  Example (partial_opening, the direct solve and the contact field split, two meshes)::

    python scripts/solver_study.py partial_opening \\
        --levels "-thm_partial_crack_size 0.05;-thm_partial_crack_size 0.025" \\
        --solvers "lu=;block=-options_file options/solvers/block.opts" --ranks 1
"""
from __future__ import annotations

import argparse
import os
import shlex
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from study_tables import MPI_ENV as ROOT_MPI_ENV  # noqa: E402
from study_tables import ROOT, markdown, read_history, read_summary, write_csv, write_markdown  # noqa: E402

MPI_ENV = dict(ROOT_MPI_ENV, OMPI_MCA_mpi_yield_when_idle="1", OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1")

COLUMNS = [("solver", "solver", ""), ("level", "level", ""), ("ranks", "ranks", ""),
           ("unknowns", "unknowns", ""),
           ("steps", "steps", ""), ("rejected", "rejected", ""), ("Newton / step", "newton_per_step", ".2f"),
           ("Krylov / Newton", "krylov_per_newton", ".1f"),
           ("max Krylov / Newton", "krylov_per_newton_max", ".1f"),
           ("PC set-ups", "pc_setups", ""), ("PCSetUp (s)", "pc_setup_s", ".2f"),
           ("KSPSolve (s)", "ksp_solve_s", ".2f"), ("wall (s)", "wall_s", ".2f"),
           ("peak MB / rank", "peak_mb_rank", ".0f"), ("peak MB rank 0", "peak_mb_rank0", ".0f"),
           ("status", "status", "")]


def run_case(scene, out, opts, ranks):
    cmd = [sys.executable, "-m", "petthm", scene, "-thm_output_dir", out, "-thm_quiet", "-thm_overwrite",
           *opts]
    if ranks > 1:
        cmd = ["mpiexec", "-n", str(ranks)] + cmd
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, env=dict(os.environ, **MPI_ENV))
    return p


def row_of(name, level, ranks, out, proc):
    if not os.path.exists(os.path.join(out, "summary.json")):
        err = (proc.stderr.strip().splitlines() or ["no summary"])[-1]
        return {"solver": name, "level": level, "ranks": ranks, "unknowns": 0, "steps": 0, "rejected": 0,
                "newton_per_step": 0.0, "krylov_per_newton": 0.0, "krylov_per_newton_max": 0.0,
                "pc_setups": 0,
                "pc_setup_s": 0.0, "ksp_solve_s": 0.0, "wall_s": 0.0, "peak_mb_rank": 0.0,
                "status": f"error: {err[:80]}"}
    s = read_summary(out)
    h = read_history(out)
    newton, krylov = h["snes_its"], h["ksp_its"]
    per = [k / n for k, n in zip(krylov, newton, strict=False) if n > 0]
    costs = s.get("solver_costs", {})
    return {"solver": name, "level": level, "ranks": ranks, "unknowns": sum(s["dofs"].values()),
            "steps": s["steps"], "rejected": s["rejected_steps"],
            "newton_per_step": float(newton.mean()) if len(newton) else 0.0,
            "krylov_per_newton": s["ksp_iterations"] / max(s["snes_iterations"], 1),
            "krylov_per_newton_max": max(per) if per else 0.0,
            "pc_setups": costs.get("PCSetUp", {}).get("count", 0),
            "pc_setup_s": costs.get("PCSetUp", {}).get("time", 0.0),
            "ksp_solve_s": costs.get("KSPSolve", {}).get("time", 0.0),
            "wall_s": s["wall_time"]["total"],
            "peak_mb_rank": s.get("peak_memory_mb", {}).get("max_rank", 0.0),
            "peak_mb_rank0": s.get("peak_memory_mb", {}).get("rank0", 0.0),
            "status": s["status"]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene")
    ap.add_argument("--levels", default="", help="petthm options per refinement level, separated by ';'")
    ap.add_argument("--solvers", default="default=", help="NAME=OPTIONS sets separated by ';'")
    ap.add_argument("--ranks", default="1")
    ap.add_argument("--common", default="")
    ap.add_argument("--out", default="")
    a = ap.parse_args(argv)
    out = a.out or os.path.join(ROOT, "output", f"solver_study_{a.scene}")
    levels = [lv.strip() for lv in a.levels.split(";")] if a.levels else [""]
    solvers = [s.partition("=")[::2] for s in a.solvers.split(";") if s.strip()]
    rows = []
    for name, sopts in solvers:
        for k, level in enumerate(levels):
            for ranks in (int(r) for r in a.ranks.split(",")):
                d = os.path.join(out, "runs", f"{name.strip()}_L{k}_n{ranks}")
                opts = shlex.split(a.common) + shlex.split(level) + shlex.split(sopts)
                proc = run_case(a.scene, d, opts, ranks)
                rows.append(row_of(name.strip(), k, ranks, d, proc))
                r = rows[-1]
                print(
                    f"{r['solver']} L{k} n{ranks}: {r['unknowns']} unknowns, "
                    f"{r['newton_per_step']:.2f} Newton/step, "
                    f"{r['krylov_per_newton']:.1f} Krylov/Newton, {r['wall_s']:.1f} s, {r['status']}",
                    flush=True)
    write_csv(os.path.join(out, "solver_study.csv"), rows)
    table = markdown(COLUMNS, rows)
    levels_text = "\n".join(f"* level {k}: `{lv}`" for k, lv in enumerate(levels))
    write_markdown(os.path.join(out, "solver_study.md"), f"Solver study: {a.scene}",
                   f"Common options: `{a.common}`\n\n{levels_text}\n\n" + table)
    print(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
