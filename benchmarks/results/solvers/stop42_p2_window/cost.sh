#!/bin/bash
# stop 42: level 2's window, the recipe and the candidate alternated (KSPSolve and CPU time side by side)
cd "$(dirname "$0")"
G=-vi_fieldsplit_mech_contact_
for rep in 1 2; do
  LEV=L2 ./winlev.sh cost_recipe_$rep
  LEV=L2 ./winlev.sh cost_cand_$rep ${G}pc_hypre_boomeramg_agg_nl 0 ${G}ksp_max_it 8 -vi_contact_schur off
done
