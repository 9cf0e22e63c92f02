#!/bin/bash
# usage: LEV=L1|L2|L3 winlev.sh NAME [extra options...]: win.sh's window (three steps from the
# step-68 checkpoint at 2.146e8 s) on another level; the line goes to windows_LEV.txt
cd "$(dirname "$0")"
here=$PWD
case ${LEV:?} in
 L1) sz="-thm_scene2_fracture_size 20 -thm_scene2_well_size 10 -thm_mesh_size 150";;
 L2) sz="-thm_scene2_fracture_size 10 -thm_scene2_well_size 5 -thm_mesh_size 75";;
 L3) sz="-thm_scene2_fracture_size 5 -thm_scene2_well_size 2.5 -thm_mesh_size 37.5";;
esac
export ROOT=/tmp/s42/$LEV SRC=${SRC:-/tmp/s42/src}
export MESH="-thm_fe_degree 2 -thm_scene2_layer 2 -thm_scene2_layer_growth 2.5 $sz"
export TF="-thm_final_time 2.546e8"
bash ../stop38_long_steps/win.sh "$@" >> $here/windows_$LEV.txt
