#!/bin/bash
# Every scene with displacement (Scenes 2 and 3 and the coupled MMS are measured elsewhere) on its
# options file, once by the direct solve and once by the block path (-thm_direct_max_unknowns 0:
# BLOCK_RECIPE with the scene's block_recipe), and the largest relative difference of the last
# history row.  Usage (repository root): [PY=python] sweep.sh OUTDIR [scene ...]
out=$1; shift
py=${PY:-.venv/bin/python}   # PY=...: another interpreter (the PETSc 3.26 venv)
scenes=${*:-contact_patch fracture_inflation friction_patch gravity_column inclined_crack mandel partial_opening sneddon terzaghi thermal_stress}
mkdir -p "$out"
for s in $scenes; do
  for path in direct block; do
    m=$([ $path = direct ] && echo 1000000000 || echo 0)
    timeout 900 $py -m petthm $s -options_file options/scenes/$s.opts -thm_direct_max_unknowns $m \
      -ksp_converged_reason -thm_output_dir "$out/$s/$path" > "$out/${s}_$path.txt" 2>&1
    echo "$s $path rc $?"
  done
done
