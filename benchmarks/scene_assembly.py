"""Residual and Jacobian evaluation time of one scene's problem (1 rank).

    python benchmarks/scene_assembly.py SCENE [--repeat 7] [--profile] [PETSc/petthm options]

    python benchmarks/scene_assembly.py penny_impermeable \\
        -options_file options/scenes/penny_impermeable.opts -thm_output_dir /tmp/bench

Sets the scene up once (mesh, discretisation), times the matrix's creation
(the COO pattern and its preallocation), then times ``Problem.jacobian_values``
(the COO values of a re-assembly: what every Jacobian after the first costs),
the same with MatSetValuesCOO and MatAssembly into the matrix, and
``Problem.local_residual`` at the initial state with a random rate, and each
region's assembler alone (a full assembly, constant terms included).  Prints medians; ``--profile`` adds a
cProfile of three evaluations of each.  Run it with OPENBLAS_NUM_THREADS=1
on a quiet machine and compare two versions side by side (docs/performance/index.md).
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time

import petsc4py

ours = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ours.add_argument("scene")
ours.add_argument("--repeat", type=int, default=7)
ours.add_argument("--profile", action="store_true")
args, petsc_args = ours.parse_known_args()
petsc4py.init([sys.argv[0]] + petsc_args)
import numpy as np  # noqa: E402

from petthm import compat  # noqa: E402
from petthm.run.driver import Run, make_scene  # noqa: E402


def median_ms(f, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return 1e3 * statistics.median(times)


def main():
    run = Run(make_scene(args.scene))
    _, problem, *_ = run.setup(run.build_mesh())
    problem.discard_matrix()                         # the set-up made it: again, from nothing
    t0 = time.perf_counter()
    J = problem.create_matrix()
    t_matrix = time.perf_counter() - t0
    xl, xdl = problem.local_arrays(problem.X, 0.0)
    xl = xl.copy()
    xdl = np.random.default_rng(0).standard_normal(xdl.size) * 1e-3
    shift = 1e-3
    problem.jacobian_values(xl, xdl, 0.0, shift)                 # the first, full assembly
    jac = median_ms(lambda: problem.jacobian_values(xl, xdl, 0.0, shift), args.repeat)

    def into_matrix():
        compat.coo_set_values(J, problem.jacobian_values(xl, xdl, 0.0, shift))
        J.assemble()
    into = median_ms(into_matrix, args.repeat)
    res = median_ms(lambda: problem.local_residual(xl, xdl, 0.0, shift), args.repeat)
    print(f"{args.scene}: {problem.X.getSize()} unknowns | matrix creation {1e3 * t_matrix:.1f} ms | "
          f"Jacobian re-assembly {jac:.1f} ms, into the matrix {into:.1f} ms "
          f"(creation = {1e3 * t_matrix / into:.2f} of these) | residual {res:.1f} ms "
          f"(medians of {args.repeat})")
    for region, a in problem.assemblers.items():
        j = median_ms(lambda a=a: a.jacobian_values(xl, xdl, 0.0, shift), max(3, args.repeat // 2))
        r = median_ms(lambda a=a: a.residual(xl, xdl, 0.0, shift), max(3, args.repeat // 2))
        print(f"  region {region}: full Jacobian {j:.1f} ms, residual {r:.1f} ms, {a.nnz} COO entries")
    if args.profile:
        import cProfile
        import pstats
        prof = cProfile.Profile()
        prof.enable()
        for _ in range(3):
            problem.jacobian_values(xl, xdl, 0.0, shift)
            problem.local_residual(xl, xdl, 0.0, shift)
        prof.disable()
        pstats.Stats(prof).sort_stats("tottime").print_stats(20)


if __name__ == "__main__":
    main()
