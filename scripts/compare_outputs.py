"""Compare the last outputs of two runs' field files, node by node.

    python scripts/compare_outputs.py RUN_A RUN_B [--tolerance 1e-8]

For every ``fields*.h5`` and ``fracture*.h5`` in both output folders, reads
the last output on its own mesh (``petthm.io.output.read_output``), matches the
nodes by their coordinates (the numbering differs between rank counts and
partitions; the + and - copies of a fracture node share coordinates, so
their values are compared as sorted pairs) and prints, per field, the
largest difference and that relative to the field's largest magnitude.
Exit code 1 when a mesh differs or a difference exceeds both the relative
tolerance and ``--atol``: e.g. a run on 2
ranks against the serial run (issue 15: the ranks write their own parts).
"""
from __future__ import annotations

import argparse
import glob
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from petthm.io.output import read_output  # noqa: E402


def by_coordinates(path: str):
    """(coordinates, time, {field: values}) of the last output, nodes sorted by
    coordinates, and nodes at the same coordinates by the field's value."""
    xyz, _, t, fields = read_output(path)
    keys = np.round(xyz, 9).T[::-1]
    out = {}
    for k, v in fields.items():
        first = v if v.ndim == 1 else v[:, 0]
        out[k] = v[np.lexsort((first, *keys))]
    return xyz[np.lexsort(keys)], t, out


def compare(a: str, b: str, tolerance: float, atol: float = 0.0) -> int:
    worst_status = 0
    names = sorted({os.path.basename(p) for d in (a, b) for p in glob.glob(os.path.join(d, "f*.h5"))})
    for name in names:
        pa, pb = os.path.join(a, name), os.path.join(b, name)
        if not (os.path.isfile(pa) and os.path.isfile(pb)):
            print(f"{name}: only in {a if os.path.isfile(pa) else b}")
            worst_status = 1
            continue
        (xa, ta, fa), (xb, tb, fb) = by_coordinates(pa), by_coordinates(pb)
        if xa.shape != xb.shape or not np.allclose(xa, xb, rtol=0, atol=1e-9 * np.abs(xa).max()):
            print(f"{name}: the meshes differ ({len(xa)} and {len(xb)} nodes)")
            worst_status = 1
            continue
        if not np.isclose(ta, tb, rtol=1e-12, atol=0.0):
            print(f"{name}: the last outputs are at different times ({ta:.6g} and {tb:.6g} s)")
            worst_status = 1
        for field in sorted(set(fa) & set(fb)):
            va, vb = fa[field], fb[field]
            diff, scale = float(np.abs(va - vb).max()), float(np.abs(va).max())
            rel = diff / max(scale, 1e-300)
            bad = rel > tolerance and diff > atol
            flag = "  > tolerance" if bad else ""
            worst_status |= int(bad)
            print(f"{name}:{field:16s} t = {ta:.6g} / {tb:.6g} s  max |a| = {scale:.3g}  "
                  f"max |a - b| = {diff:.2e}  relative {rel:.2e}{flag}")
    return worst_status


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--tolerance", type=float, default=1e-8, help="relative to the field's largest value")
    ap.add_argument("--atol", type=float, default=0.0, help="differences below this (SI) pass too")
    a = ap.parse_args()
    return compare(a.a, a.b, a.tolerance, a.atol)


if __name__ == "__main__":
    sys.exit(main())
