"""Where the water goes between Scene 3's wells: the volumetric flow across the
plane y = 0, midway between the injector (y = -s/2) and the producer
(y = +s/2), through the rock and through the fracture, at each output time
of a run, from its output files only (fields.h5, fracture.h5, summary.json).

    python scripts/scene3_flow_split.py RUN_DIR [RUN_DIR ...] [--slab 20] [--out FILE.md]

Darcy's law in the rock, q = -(k/mu(Tm)) grad pm, and the cubic law in the
fracture, q = -(a^3 / (12 mu(Tf))) grad_s pf (physics.md sections 4-5), with
the P1 gradient of the nodal values per cell.  The flow across the plane is
the flux's y component averaged over a slab |y| < slab/2 around it:
Q = (1/slab) * sum over the cells whose centroid lies in the slab of q_y times
the cell's volume (rock) or area (fracture).  Where the flow is steady (no
storage between the plane and the slab's faces) this is the flow through the
plane; the slab smooths the per-cell gradients.  Positive: from the injector
towards the producer.  The rates are in m3/s, against the wells' Q.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from study_tables import output_with  # noqa: E402

from petthm.io.output import read_output  # noqa: E402
from petthm.physics.fluid import Viscosity  # noqa: E402

YEAR = 365.25 * 86400.0
CELSIUS = 273.15


def p1_gradients(X: np.ndarray, cells: np.ndarray, values: np.ndarray):
    """(gradient, measure, centroid) of the P1 interpolant on each simplex;
    on triangles in 3D the gradient is the tangential one."""
    P = X[cells]                                           # (nc, k+1, 3)
    E = P[:, 1:] - P[:, :1]                                # (nc, k, 3) edge vectors
    dv = values[cells][:, 1:] - values[cells][:, :1]       # (nc, k)
    G = np.einsum("cij,ckj->cik", E, E)                    # (nc, k, k) metric
    coef = np.linalg.solve(G, dv[..., None])[..., 0]       # grad = E^T coef
    grad = np.einsum("ck,ckj->cj", coef, E)
    measure = np.sqrt(np.abs(np.linalg.det(G))) / {2: 1.0, 3: 2.0, 4: 6.0}[cells.shape[1]]
    return grad, measure, P.mean(axis=1)


def field_at(run: str, stem: str, step: int, name: str, vertices: int):
    """(X, cells by their vertices, t, values) of field ``name`` at output ``step``
    (``study_tables.output_with``: a P2 run writes its P1 fields to ``stem``_p1.h5; both files list
    the same cells in the same order)."""
    X, cells, t, F = read_output(output_with(run, stem, name), step)
    return X, cells[:, :vertices], t, F[name]


def viscosity_of(text: str) -> Viscosity:
    """The run's viscosity from its provenance (the repr of ``Viscosity``)."""
    if "water=True" in text:
        return Viscosity(water=True)
    return Viscosity(float(text.split("value=")[1].split(",")[0].rstrip(")")))


def flow_split(run: str, slab: float) -> list[dict]:
    """Rock and fracture flow across y = 0 at every output time of ``run``."""
    prov = json.loads(Path(os.path.join(run, "summary.json")).read_text())["provenance"]["parameters"]
    k = float(np.ravel(prov["-thm_rock_permeability"])[0])          # isotropic (Scene 3)
    visc = viscosity_of(str(prov["-thm_fluid_viscosity"]))
    import h5py
    with h5py.File(os.path.join(run, "fields.h5"), "r") as h5:
        ntimes = len(h5.attrs["times"])
    rows = []
    for step in range(ntimes):
        X, cells, t, pm = field_at(run, "fields", step, "pm", 4)
        Tm = field_at(run, "fields", step, "Tm", 4)[3]
        Xf, tris, _, pf = field_at(run, "fracture", step, "pf", 3)
        Tf = field_at(run, "fracture", step, "Tf", 3)[3]
        _, a_tris, _, aperture = field_at(run, "fracture", step, "aperture", 3)
        g, vol, c = p1_gradients(X, cells, pm)
        mu = visc.mu(Tm[cells].mean(axis=1) + CELSIUS)
        sel = np.abs(c[:, 1]) < 0.5 * slab
        q_rock = float(np.sum(-(k / mu[sel]) * g[sel, 1] * vol[sel]) / slab)
        gf, area, cf = p1_gradients(Xf, tris, pf)
        a3 = (aperture[a_tris] ** 3).mean(axis=1)
        muf = visc.mu(Tf[tris].mean(axis=1) + CELSIUS)
        on = np.abs(cf[:, 1]) < 0.5 * slab
        q_frac = float(np.sum(-(a3[on] / (12.0 * muf[on])) * gf[on, 1] * area[on]) / slab)
        rows.append({"run": run, "years": t / YEAR, "rock": q_rock, "fracture": q_frac})
    return rows


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--slab", type=float, default=20.0, help="thickness of the slab about y = 0 (m)")
    ap.add_argument("--out", default="")
    a = ap.parse_args()
    lines = [f"Flow across y = 0 (slab {a.slab:g} m), m3/s; positive towards the producer", "",
             "| run | years | rock | fracture | fracture share |", "|---|---|---|---|---|"]
    for run in a.runs:
        for r in flow_split(run, a.slab):
            if r["years"] <= 0:
                continue
            total = r["rock"] + r["fracture"]
            share = r["fracture"] / total if total else float("nan")
            lines.append(f"| {run} | {r['years']:.2f} | {r['rock']:.3e} | {r['fracture']:.3e} "
                         f"| {share:.2f} |")
    text = "\n".join(lines) + "\n"
    print(text)
    if a.out:
        Path(a.out).write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
