"""Residual and Jacobian assembly throughput on P2 tetrahedral meshes (1 rank).

    python benchmarks/assembly.py [--cells 1e4 1e5 1e6] [--repeat 5] [--out benchmarks/results]

Operators: the scalar heat operator (mass + conduction) and a 3-component
isotropic-elasticity operator.  Times are medians of ``--repeat`` runs; the
Jacobian time includes computing the values, MatSetValuesCOO and
MatAssembly.  Writes ``assembly.csv`` and ``assembly.md`` (with a cProfile
of one Jacobian re-assembly of the largest mesh) to ``--out``.
"""
from __future__ import annotations

import argparse
import cProfile
import csv
import io
import os
import pstats
import statistics
import sys
import time

import petsc4py

petsc4py.init([sys.argv[0]])
import numpy as np  # noqa: E402
from petsc4py import PETSc  # noqa: E402

from petthm import compat, meshing  # noqa: E402
from petthm.assembly import Assembler, FieldScale  # noqa: E402
from petthm.fields import Discretisation, FieldSpec  # noqa: E402
from petthm.mesh import Mesh, distribute, read_plex  # noqa: E402
from petthm.model import CellJacobian, CellResidual, Model  # noqa: E402


def heat_operator():
    k = 2.9

    def f0(ctx):
        return 2e6 * ctx.dot("T")

    def f1(ctx):
        return k * ctx.grad("T")

    def g0(ctx):
        return np.full((1, 1, 1, 1), 2e6 * ctx.shift)        # constant over each cell

    def g3(ctx):
        return (k * np.eye(3))[None, None, None, :, None, :]
    return Model([FieldSpec("T", 1, 2)], [CellResidual("T", f0, f1)], [CellJacobian("T", "T", g0=g0, g3=g3)])


def elasticity_operator():
    lam, mu = 1.5e10, 1.5e10
    I = np.eye(3)
    C = lam * np.einsum("ae,bf->aebf", I, I) + mu * (np.einsum("ab,ef->aebf", I, I)
                                                     + np.einsum("af,eb->aebf", I, I))

    def f1(ctx):
        G = ctx.grad("u")
        eps = 0.5 * (G + np.swapaxes(G, 2, 3))
        return 2 * mu * eps + lam * np.trace(eps, axis1=2, axis2=3)[..., None, None] * I

    def g3(ctx):
        return C[None, None]
    return Model([FieldSpec("u", 3, 2)], [CellResidual("u", None, f1)], [CellJacobian("u", "u", g3=g3)])


def mesh_for(cells: float, workdir: str) -> tuple[str, float]:
    # a unit cube with size h has about 6 (1/h)^3 * 0.9 tetrahedra (gmsh, unstructured)
    h = (5.5 / cells) ** (1 / 3)
    path = os.path.join(workdir, f"cube_{int(cells)}.msh")
    if not os.path.exists(path):
        meshing.box(path, [1.0, 1.0, 1.0], h)
    return path, h


def timed(fn, repeat):
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts)


def bench(path, model, repeat):
    dm = distribute(read_plex(path, PETSc.COMM_WORLD))
    mesh = Mesh(dm)
    disc = Discretisation(mesh, model.fields)
    name = model.fields[0].name
    asm = Assembler(disc, model, {name: FieldScale()})
    t0 = time.perf_counter()
    A = asm.create_matrix()
    t_prealloc = time.perf_counter() - t0
    rng = np.random.default_rng(0)
    xl = rng.standard_normal(disc.nlocal)
    xdl = rng.standard_normal(disc.nlocal)

    def jac():
        compat.coo_set_values(A, asm.jacobian_values(xl, xdl, 0.0, 1.0))
        A.assemble()

    def res():
        asm.residual(xl, xdl, 0.0)

    jac()
    t_jac = timed(jac, repeat)
    t_res = timed(res, repeat)
    prof = cProfile.Profile()
    prof.enable()
    jac()
    prof.disable()
    s = io.StringIO()
    pstats.Stats(prof, stream=s).sort_stats("tottime").print_stats(8)
    info = A.getInfo()
    return dict(cells=mesh.ncells, dofs=A.getSize()[0], nnz=int(info["nz_used"]),
                coo_entries=asm.coo_rows.size, t_prealloc=t_prealloc, t_jacobian=t_jac,
                t_residual=t_res), s.getvalue()


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cells", type=float, nargs="+", default=[1e4, 1e5])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--out", default=os.path.join(os.path.dirname(__file__), "results"))
    ap.add_argument("--operators", nargs="+", default=["heat", "elasticity"])
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    rows, profile = [], ""
    for target in args.cells:
        path, h = mesh_for(target, args.out)
        for op in args.operators:
            model = heat_operator() if op == "heat" else elasticity_operator()
            r, prof = bench(path, model, args.repeat)
            r.update(operator=op, target_cells=int(target), h=h)
            rows.append(r)
            profile = prof if op == "heat" else profile
            print(f"{op:10s} cells {r['cells']:8d} dofs {r['dofs']:9d} nnz {r['nnz']:11d}  "
                  f"jacobian {r['t_jacobian']:.4f} s  residual {r['t_residual']:.4f} s", flush=True)
    cols = ["operator", "target_cells", "cells", "dofs", "nnz", "coo_entries", "t_prealloc",
            "t_jacobian", "t_residual"]
    with open(os.path.join(args.out, "assembly.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=cols, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    with open(os.path.join(args.out, "assembly.md"), "w") as f:
        f.write(f"# Assembly throughput (1 rank, P2 tetrahedra, PETSc {compat.version_string()})\n\n")
        f.write("Medians of %d runs. Jacobian = values + MatSetValuesCOO + MatAssembly.\n\n" % args.repeat)
        f.write("| operator | cells | dofs | nonzeros | Jacobian (s) | residual (s) | Mnz/s |\n")
        f.write("|---|---|---|---|---|---|---|\n")
        for r in rows:
            f.write(f"| {r['operator']} | {r['cells']} | {r['dofs']} | {r['nnz']} | "
                    f"{r['t_jacobian']:.4f} | {r['t_residual']:.4f} | "
                    f"{r['nnz'] / r['t_jacobian'] / 1e6:.1f} |\n")
        f.write("\n## Profile of one scalar Jacobian re-assembly (largest mesh)\n\n```\n")
        f.write(profile)
        f.write("```\n")


if __name__ == "__main__":
    main()
