"""Render a nodal field of a 2D run (fields.xdmf) to PNG with matplotlib.

    python scripts/plot_field.py OUTPUT_DIR [FIELD] [--step K] [--png FILE]

Reads only the XDMF/HDF5 output (no PETSc needed).  P2 triangles are split
into four linear sub-triangles for plotting.
"""
import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.tri as mtri  # noqa: E402
import meshio  # noqa: E402
import numpy as np  # noqa: E402

P2_SPLIT = np.array([[0, 3, 5], [3, 1, 4], [5, 4, 2], [3, 4, 5]])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("outdir")
    ap.add_argument("field", nargs="?", default="Tm")
    ap.add_argument("--step", type=int, default=-1)
    ap.add_argument("--png", default=None)
    a = ap.parse_args()
    with meshio.xdmf.TimeSeriesReader(os.path.join(a.outdir, "fields.xdmf")) as r:
        points, cells = r.read_points_cells()
        k = a.step % r.num_steps
        t, pd, _ = r.read_data(k)
    c = cells[0]
    tris = c.data[:, P2_SPLIT].reshape(-1, 3) if c.type == "triangle6" else c.data
    if c.type not in ("triangle", "triangle6"):
        raise SystemExit("plot_field.py draws 2D runs only")
    tri = mtri.Triangulation(points[:, 0], points[:, 1], tris)
    fig, ax = plt.subplots(figsize=(8, 3.2))
    cs = ax.tricontourf(tri, pd[a.field], levels=24, cmap="coolwarm")
    fig.colorbar(cs, ax=ax, label=f"{a.field} (degC)" if a.field.startswith("T") else a.field)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"{os.path.basename(os.path.normpath(a.outdir))}: {a.field} at t = {t:.3g} s")
    fig.tight_layout()
    png = a.png or os.path.join(a.outdir, f"{a.field}.png")
    fig.savefig(png, dpi=120)
    print(png)


if __name__ == "__main__":
    main()
