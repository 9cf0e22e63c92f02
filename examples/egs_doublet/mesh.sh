#!/usr/bin/env bash
# The EGS doublet's mesh: a box of granite 2-3 km deep, four vertical stimulated
# fractures 600 m x 500 m, two horizontal wells 300 m apart crossing all four.
set -euo pipefail
cd "$(dirname "$0")"
mkdir -p ../../output/egs_doublet_mesh      # the mesh and the tool's starter options, out of the tree
fractures=()
for x in 300 450 600 750; do
  fractures+=(--fracture "f$x:$x,-300,-2750/$x,300,-2750/$x,300,-2250/$x,-300,-2250")
done
python -m petthm.run.deckbox --lower 0,-600,-3000 --upper 1050,600,-2000 --size 75 \
    --well inj:200,-150,-2500/850,-150,-2500 --well prod:200,150,-2500/850,150,-2500 \
    "${fractures[@]}" --out ../../output/egs_doublet_mesh/egs_doublet.msh
