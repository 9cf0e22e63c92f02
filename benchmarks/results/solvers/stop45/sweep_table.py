"""The table of sweep.sh: per scene, unknowns, steps (rejected), Newton and Krylov iterations
of both paths, the block path's Krylov per Newton and its linear solves that did not converge,
and the largest relative difference of the last history rows (columns other than step
counters and wall times) among the columns above 1e-9 in magnitude; the columns below it by both
paths (a patch test's errors: 1e-14 by one path, 1e-12 by the other) have their largest value
reported beside it.
Usage: sweep_table.py OUTDIR"""
import csv
import os
import sys

from levels_table import counts

SKIP = {"step", "snes_its", "ksp_its", "wall"}


def run(out, scene, path):
    c = counts(open(os.path.join(out, f"{scene}_{path}.txt")).read())
    hist = os.path.join(out, scene, path, "history.csv")
    rows = list(csv.DictReader(open(hist))) if os.path.exists(hist) else []
    return dict(c, last=rows[-1] if rows else {})


def difference(a, b):
    """(largest relative difference of the columns above 1e-9, largest value of those below)."""
    worst, small = 0.0, 0.0
    for k, v in a.items():
        if k in SKIP or k not in b:
            continue
        try:
            x, y = float(v), float(b[k])
        except ValueError:
            continue
        if max(abs(x), abs(y)) < 1e-9:
            small = max(small, abs(x), abs(y))
        else:
            worst = max(worst, abs(x - y) / max(abs(x), abs(y)))
    return worst, small


out = sys.argv[1]
scenes = sorted({f.rsplit("_", 1)[0] for f in os.listdir(out) if f.endswith("_block.txt")})
print("| scene | unknowns | direct: steps (rejected), Newton | block: steps (rejected), Newton, Krylov | "
      "Krylov per Newton | not converged | largest rel. difference | largest column below 1e-9 |")
print("|---|---|---|---|---|---|---|---|")
for s in scenes:
    d, b = run(out, s, "direct"), run(out, s, "block")
    fmt = lambda r: f"{r['done'][0]} ({r['done'][1]})" if r["done"] else "failed"  # noqa: E731
    print(f"| {s} | {b['n']} | {fmt(d)}, {d['newton']} | {fmt(b)}, {b['newton']}, {b['krylov']} | "
          f"{b['krylov'] / max(b['newton'], 1):.1f} | {b['bad']} | "
          "{:.1e} | {:.1e} |".format(*difference(d["last"], b["last"])))
