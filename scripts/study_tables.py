"""Shared helpers of the study scripts: run one ``python -m petthm`` case,
read back its history and summary, and write a CSV of result rows and a
markdown table of selected, formatted columns."""
from __future__ import annotations

import csv
import json
import os
import subprocess
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


#: what mpiexec needs to start ranks as root and more ranks than cores (Open MPI)
MPI_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "OMPI_MCA_rmaps_base_oversubscribe": "1"}


def run_petthm(scene: str, out_dir: str, *opts, ranks: int = 1) -> dict:
    """Run ``python -m petthm SCENE -thm_output_dir OUT_DIR -thm_quiet OPTS``
    from the repository root (under ``mpiexec -n RANKS`` when ranks > 1) with
    one BLAS/OpenMP thread per rank (so that studies may run cases side by
    side) and return its summary.json.  A study owns its run folders: a rerun
    replaces its earlier run there (-thm_overwrite).  A failed run prints its
    output and stops the study."""
    cmd = [sys.executable, "-m", "petthm", scene, "-thm_output_dir", out_dir, "-thm_quiet", "-thm_overwrite",
           *map(str, opts)]
    if ranks > 1:
        cmd = ["mpiexec", "-n", str(ranks)] + cmd
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", **MPI_ENV)
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, env=env)
    if p.returncode:
        print(p.stdout, p.stderr, file=sys.stderr)
        raise SystemExit(f"{' '.join(cmd)} failed")
    return read_summary(out_dir)


def read_summary(out_dir: str) -> dict:
    with open(os.path.join(out_dir, "summary.json")) as f:
        return json.load(f)


def read_history(out_dir: str) -> dict[str, np.ndarray]:
    """The run's history.csv as float columns, without the initial-state row
    (an empty cell, a monitor not evaluated at that step, is NaN)."""
    with open(os.path.join(out_dir, "history.csv")) as f:
        rows = list(csv.DictReader(f))
    return {k: np.array([float(r[k]) if r[k] != "" else np.nan for r in rows[1:]]) for k in rows[0] if k}


def output_with(run: str, stem: str, name: str) -> str:
    """The output file of run folder ``run`` that holds field ``name``: ``stem``.h5, or
    ``stem``_p1.h5 where a P2 run writes its P1 fields (pf, Tf, pm, Tm beside P2 u)."""
    import h5py
    for path in (os.path.join(run, f"{stem}.h5"), os.path.join(run, f"{stem}_p1.h5")):
        if os.path.exists(path):
            with h5py.File(path, "r") as h5:
                if name in h5["fields"]:
                    return path
    raise SystemExit(f"no {stem}.h5 or {stem}_p1.h5 with the field {name} in {run}")


def write_csv(path: str, rows: list[dict]) -> None:
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def markdown(columns: list[tuple[str, str, str]], rows: list[dict]) -> str:
    """``columns``: (header, row key, format spec) triples."""
    lines = ["| " + " | ".join(h for h, _, _ in columns) + " |", "|" + "---|" * len(columns)]
    for r in rows:
        lines.append("| " + " | ".join(format(r[k], f) for _, k, f in columns) + " |")
    return "\n".join(lines)


def write_markdown(path: str, title: str, table: str) -> None:
    with open(path, "w") as f:
        f.write(f"# {title}\n\n{table}\n")
