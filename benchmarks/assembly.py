"""Residual and Jacobian assembly throughput on P2 tetrahedral meshes (1 rank).

    python benchmarks/assembly.py [--cells 1e4 2.5e4 1e5 1e6] [--repeat 5] [--out output/assembly]
                                  [--petsc-c] [--vector-max-cells 2e5]

Operators: the scalar heat operator (mass + conduction) with a constant
conductivity (``heat``) and with k(T) at every quadrature point
(``heat_kT``: the case with per-point coefficients, as the scenes' mu(T)),
and a 3-component isotropic-elasticity operator.  Times are medians of ``--repeat`` runs; the
Jacobian time includes computing the values, MatSetValuesCOO and
MatAssembly.  Writes ``assembly.csv`` and ``assembly.md`` (with a cProfile
of one Jacobian re-assembly of the largest mesh) to ``--out``.

``--petsc-c`` also runs PETSc's own C assembly (``src/snes/tutorials`` ex12,
P2 Poisson, and ex17, P2 elasticity, built by ``petsc_c_assembly.sh`` from
Debian's libpetsc3.18-dev-examples) on the same mesh files and reports the
ratio petthm time / PETSc C time per Jacobian assembly.  The vector operator
is skipped above ``--vector-max-cells`` (its COO arrays need ~9x the memory
of the scalar one: about 30 GB at 1e6 cells, more than this machine has);
PETSc's ex17 above ``--petsc-c-vector-max-cells`` (PETSc 3.18's PetscFE
treats the 3-component P2 space as 30 vector basis functions and needs about
70 s per Jacobian at 1e4 cells, 340 s at 1e5).
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
from pathlib import Path

import petsc4py

petsc4py.init([sys.argv[0]])
import numpy as np  # noqa: E402
from petsc4py import PETSc  # noqa: E402

from petthm import compat  # noqa: E402
from petthm.discretisation.assembly import Assembler, FieldScale  # noqa: E402
from petthm.discretisation.fields import Discretisation, FieldSpec  # noqa: E402
from petthm.discretisation.model import CellJacobian, CellResidual, Model  # noqa: E402
from petthm.mesh import generate as meshing  # noqa: E402
from petthm.mesh.plex import Mesh, distribute, read_plex  # noqa: E402


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


def heat_kT_operator():
    """The heat operator with a temperature-dependent conductivity k(T) =
    k0 (1 + beta (T - T0)), evaluated at every quadrature point (as the
    scenes' mu(T) and exchange coefficients are): the honest case for the
    ratio to a C assembly, next to the cell-constant one."""
    k0, beta, T0 = 2.9, -1e-3, 0.0

    def k(ctx):
        return k0 * (1.0 + beta * (ctx.value("T")[..., 0] - T0))             # (nc, nq)

    def f0(ctx):
        return 2e6 * ctx.dot("T")

    def f1(ctx):
        return k(ctx)[..., None, None] * ctx.grad("T")

    def g0(ctx):
        return np.full((1, 1, 1, 1), 2e6 * ctx.shift)

    def g2(ctx):                                                             # d f1 / d T: k' grad T
        return (k0 * beta * ctx.grad("T"))[:, :, :, :, None]

    def g3(ctx):
        return k(ctx)[:, :, None, None, None, None] * np.eye(3)[None, None, None, :, None, :]
    return Model([FieldSpec("T", 1, 2)], [CellResidual("T", f0, f1)],
                 [CellJacobian("T", "T", g0=g0, g2=g2, g3=g3)])


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


def petsc_c_times(mesh_path, examples):
    """Per-call Jacobian/residual times of PETSc's C examples on a mesh (via petsc_c_assembly.sh)."""
    import subprocess
    script = os.path.join(os.path.dirname(os.path.abspath(__file__)), "petsc_c_assembly.sh")
    env = dict(os.environ, EXAMPLES=" ".join(examples))
    out = subprocess.run(["bash", script, mesh_path], capture_output=True, text=True, check=True,
                         env=env).stdout
    times = {}
    for line in out.splitlines():
        parts = line.split(",")
        if len(parts) == 7 and parts[0].startswith("ex"):
            times[parts[0]] = {"jacobian": float(parts[4]), "residual": float(parts[5])}
    return times


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
    A = compat.coo_matrix(dm, *asm.coo_pattern(), copy=False)          # as Problem.create_matrix does
    #                   (the summed pattern's node pairs are made here, when first asked for)
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
                coo_entries=asm.nnz, element_entries=asm.nvalues, t_prealloc=t_prealloc, t_jacobian=t_jac,
                t_residual=t_res), s.getvalue()


def write_report(rows, profile, repeat, out):
    """assembly.md: the table (with PETSc C times and ratios where measured) and a profile."""
    with open(os.path.join(out, "assembly.md"), "w") as f:
        f.write(f"# Assembly throughput (1 rank, P2 tetrahedra, PETSc {compat.version_string()})\n\n")
        f.write(f"Medians of {repeat} runs. Jacobian = values + MatSetValuesCOO + MatAssembly.\n\n")
        f.write("| operator | cells | dofs | nonzeros | Jacobian (s) | residual (s) | Mnz/s "
                "| PETSc C Jacobian (s) | ratio Jacobian | PETSc C residual (s) | ratio residual |\n")
        f.write("|---|---|---|---|---|---|---|---|---|---|---|\n")
        for r in rows:
            c = (f"{float(r['petsc_c_jacobian']):.4g} | {float(r['ratio_jacobian']):.3g} | "
                 f"{float(r['petsc_c_residual']):.4g} | {float(r['ratio_residual']):.3g}") \
                if r.get("ratio_jacobian") not in (None, "") else "- | - | - | -"
            f.write(f"| {r['operator']} | {r['cells']} | {r['dofs']} | {r['nnz']} | "
                    f"{float(r['t_jacobian']):.4f} | {float(r['t_residual']):.4f} | "
                    f"{int(r['nnz']) / float(r['t_jacobian']) / 1e6:.1f} | {c} |\n")
        f.write("\nratio = petthm time / PETSc C time (< 1: petthm faster). PETSc's ex12/ex17 "
                "(DMPlexJacobianFE / DMPlexResidualFE events, mean of 2 calls, one run) constrain "
                "the boundary dofs (fewer rows) and integrate with a 27-point rule on P2 "
                "tetrahedra; petthm uses a 14-point degree-5 rule and no constraints here, "
                "and exploits cell-constant coefficients (affine element matrices). The machine "
                "is shared: single runs vary by 30-50 %.\n")
        if profile:
            f.write("\n## Profile of one scalar Jacobian re-assembly (largest mesh)\n\n```\n")
            f.write(profile)
            f.write("```\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cells", type=float, nargs="+", default=[1e4, 2.5e4, 1e5, 1e6])
    ap.add_argument("--petsc-c", action="store_true", help="compare with PETSc's C ex12/ex17")
    ap.add_argument("--vector-max-cells", type=float, default=2e5)
    ap.add_argument("--petsc-c-vector-max-cells", type=float, default=1.5e4,
                    help="largest mesh for PETSc's ex17 (it takes ~70 s per Jacobian at 1e4 cells)")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..",
                                                  "output", "assembly"))
    ap.add_argument("--operators", nargs="+", default=["heat", "heat_kT", "elasticity"],
                    choices=["heat", "heat_kT", "elasticity"])
    ap.add_argument("--report-from", help="only rewrite assembly.md from this assembly.csv")
    args = ap.parse_args()
    if args.report_from:
        rows = list(csv.DictReader(Path(args.report_from).read_text().splitlines()))
        write_report(rows, "", args.repeat, args.out)
        return
    os.makedirs(args.out, exist_ok=True)
    rows, profile = [], ""
    for target in args.cells:
        path, h = mesh_for(target, args.out)
        examples = ["ex12"] + (["ex17"] if target <= args.petsc_c_vector_max_cells else [])
        c_times = petsc_c_times(path, examples) if args.petsc_c else {}
        for op in args.operators:
            if op == "elasticity" and target > args.vector_max_cells:
                continue
            model = {"heat": heat_operator, "heat_kT": heat_kT_operator}.get(op, elasticity_operator)()
            r, prof = bench(path, model, args.repeat)
            r.update(operator=op, target_cells=int(target), h=h)
            c = c_times.get("ex12" if op.startswith("heat") else "ex17")
            if c:
                r.update(petsc_c_jacobian=c["jacobian"], petsc_c_residual=c["residual"],
                         ratio_jacobian=r["t_jacobian"] / c["jacobian"],
                         ratio_residual=r["t_residual"] / c["residual"])
            rows.append(r)
            profile = prof if op == "heat" else profile
            print(f"{op:10s} cells {r['cells']:8d} dofs {r['dofs']:9d} nnz {r['nnz']:11d}  "
                  f"jacobian {r['t_jacobian']:.4f} s  residual {r['t_residual']:.4f} s", flush=True)
    cols = ["operator", "target_cells", "cells", "dofs", "nnz", "coo_entries", "element_entries",
            "t_prealloc",
            "t_jacobian", "t_residual", "petsc_c_jacobian", "petsc_c_residual", "ratio_jacobian",
            "ratio_residual"]
    with open(os.path.join(args.out, "assembly.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=cols, extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)
    write_report(rows, profile, args.repeat, args.out)


if __name__ == "__main__":
    main()
