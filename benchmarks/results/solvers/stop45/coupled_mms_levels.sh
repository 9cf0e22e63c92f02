#!/bin/bash
# The coupled MMS (every field) on its block recipe (CoupledMMS.block_recipe), 3D P1 SUPG,
# three mesh sizes (7 197 / ~20 k / 61 217 unknowns), open and closed; the block path forced on
# every level (-thm_direct_max_unknowns 0).  Usage: coupled_mms_levels.sh [OUTDIR] [extra options]
# Run from the repository root.  Logs and each run's history.csv go to OUTDIR (default
# benchmarks/results/solvers/stop45/coupled_mms).
out=${1:-benchmarks/results/solvers/stop45/coupled_mms}; shift
mkdir -p "$out"
for state in open closed; do
  for h in 0.09 0.06 0.04; do
    name=${state}_$h
    .venv/bin/python -m petthm coupled_mms -thm_coupled_mms_dim 3 -thm_fe_degree 1 \
      -thm_coupled_mms_state $state -thm_coupled_mms_supg 1 -thm_mesh_size $h \
      -thm_direct_max_unknowns 0 -ksp_converged_reason -thm_output_dir /tmp/s45/mms/$name "$@" \
      > "$out/$name.txt" 2>&1
    cp /tmp/s45/mms/$name/history.csv "$out/${name}_history.csv" 2>/dev/null
  done
done
