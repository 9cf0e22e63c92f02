#!/bin/bash
# usage: win.sh NAME [extra options...]: Scene 2 P2 level 3, three steps (2e7, 1e7, 1e7 s) from
# its step-68 checkpoint (stop 41), the size rule's block path; one line appended to windows.txt
cd "$(dirname "$0")"
here=$PWD
export ROOT=${ROOT:-/tmp/s42} SRC=${SRC:-/work/main}
export MESH="-thm_fe_degree 2 -thm_scene2_layer 2 -thm_scene2_layer_growth 2.5 -thm_scene2_fracture_size 5 -thm_scene2_well_size 2.5 -thm_mesh_size 37.5"
export TF="-thm_final_time 2.546e8"
bash ../stop38_long_steps/win.sh "$@" >> $here/windows.txt
