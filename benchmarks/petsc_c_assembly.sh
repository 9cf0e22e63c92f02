#!/usr/bin/env bash
# Baseline: PETSc's own C finite-element assembly (DMPlex + PetscFE, PETSc 3.18)
# on the same gmsh meshes as benchmarks/assembly.py, one MPI rank.
#
#   benchmarks/petsc_c_assembly.sh MESH.msh [MESH.msh ...]
#
# For each mesh prints one CSV line per example (HEADER=1 adds a header line):
#   example,mesh,cells,dofs,jacobian_seconds,residual_seconds,jacobian_count
#   ex12 = Poisson, P2 scalar;  ex17 = linear elasticity (-sol_type elas_quad), P2 vector (3 comp.)
# Env: BUILD (default benchmarks/build-petsc-c, git-ignored; logs go to $BUILD/logs),
#      NIT (Newton iterations = Jacobian evaluations, default 2), EXAMPLES (default "ex12 ex17"),
#      JAC_EVENT / RES_EVENT (-log_view events timed, defaults below), EXTRA (more PETSc options).
#
# Timed events (total time / count from -log_view):
#   DMPlexJacobianFE = DMPlexComputeJacobian_Internal: cell geometry, pointwise g0..g3 at the
#     quadrature points, element matrices, MatSetValues, and MatAssemblyBegin/End (nested inside,
#     checked with -log_trace; ~40 us).  It excludes what SNESJacobianEval adds around it:
#     MatZeroEntries and the global-to-local scatter + Dirichlet-value projection.
#     Set JAC_EVENT=SNESJacobianEval for that outer time.
#   DMPlexResidualFE = the same for the residual (excludes scatter/BC insertion of SNESFunctionEval).
# dofs = rows of the assembled matrix: PETSc removes Dirichlet (constrained) dofs from the global
#   system, so this is smaller than the full P2 count (vertices+edges)*components.
# Solver: newtonls with basic line search, -ksp_type preonly -pc_type none (the "solve" is a copy)
#   and all tolerances 0 so exactly NIT Newton steps run: NIT Jacobians and NIT+1 residuals.
#   The matrix is created and its nonzero pattern filled (DMPlexPrealloc) before the first
#   Jacobian, so call 1 does no mallocs; still it was ~10% slower than later calls (ex12, 10k cells,
#   -log_trace: 0.58 s vs 0.52, 0.51 s). The per-call time averages all NIT calls.
# Quadrature: PETSc's default for P2 tets, 27-point collapsed Gauss-Jacobi (petthm: 14 points).
# ex17 is slow in 3.18: PetscFE treats a 3-component P2 space as 30 vector-valued basis functions
#   and the element-matrix update loops over all (basis x component)^2 pairs (~81x ex12's work).
set -euo pipefail
meshes=(); for m in "$@"; do meshes+=("$(realpath "$m")"); done
cd "$(dirname "$0")/.."
BUILD=${BUILD:-benchmarks/build-petsc-c}
NIT=${NIT:-2}
EXAMPLES=${EXAMPLES:-"ex12 ex17"}
JAC_EVENT=${JAC_EVENT:-DMPlexJacobianFE}
RES_EVENT=${RES_EVENT:-DMPlexResidualFE}
PETSC_DIR=${PETSC_DIR:-/usr/lib/petsc}
SRC=/usr/share/petsc/3.18/share/petsc/examples/src/snes/tutorials   # libpetsc3.18-dev-examples
[ "$(id -u)" = 0 ] && export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
mkdir -p "$BUILD/logs"

# (a) compile with the compiler/flags of PETSc's own makefiles (conf/variables), once
petscvar() { printf 'include $(PETSC_DIR)/lib/petsc/conf/variables\nv:\n\t@echo $(%s)\n' "$1" |
             make -s --no-print-directory -f - PETSC_DIR="$PETSC_DIR" v; }
for ex in $EXAMPLES; do
  if [ ! -x "$BUILD/$ex" ] || [ "$SRC/$ex.c" -nt "$BUILD/$ex" ]; then
    $(petscvar PCC) $(petscvar PCC_FLAGS) $(petscvar PETSC_CC_INCLUDES) -o "$BUILD/$ex" "$SRC/$ex.c" \
      $(petscvar PETSC_WITH_EXTERNAL_LIB) >&2
  fi
done

# (b) run; -dm_plex_boundary_label marker marks all boundary faces "marker"=1, which both
# examples use for their Dirichlet BC (the gmsh meshes carry no physical groups).
opts() {
  case $1 in
    ex12) echo "-petscspace_degree 2" ;;
    ex17) echo "-sol_type elas_quad -displacement_petscspace_degree 2" ;;
  esac
}
# -log_view row "Event Count Ratio Time ...": print "count time/count" for event $2
ev() { awk -v e="$2" '$1 == e { printf "%d %.6g\n", $2, $4 / $2; exit }' "$1"; }
[ "${HEADER:-0}" = 1 ] && echo "example,mesh,cells,dofs,jacobian_seconds,residual_seconds,jacobian_count"
for msh in "${meshes[@]}"; do
  for ex in $EXAMPLES; do
    log="$BUILD/logs/${ex}_$(basename "$msh" .msh).log"
    t0=$(date +%s)
    mpiexec -n 1 "$BUILD/$ex" -dm_plex_filename "$msh" -dm_plex_boundary_label marker $(opts $ex) \
      -snes_type newtonls -snes_linesearch_type basic -snes_max_it "$NIT" -snes_atol 0 -snes_rtol 0 \
      -snes_stol 0 -snes_divergence_tolerance -1 -ksp_type preonly -pc_type none \
      -dm_view -snes_view -log_view ${EXTRA:-} > "$log" 2>&1 || { echo "$ex failed, see $log" >&2; exit 1; }
    cells=$(awk '/Number of 3-cells/ { print $NF; exit }' "$log")
    dofs=$(grep -m1 -o 'rows=[0-9]*' "$log" | cut -d= -f2)
    read -r jn jt <<< "$(ev "$log" "$JAC_EVENT")"
    read -r rn rt <<< "$(ev "$log" "$RES_EVENT")"
    echo "$ex,$(basename "$msh"),$cells,$dofs,$jt,$rt,$jn"
    echo "# $ex $(basename "$msh"): $(( $(date +%s) - t0 )) s wall, log $log" >&2
  done
done
