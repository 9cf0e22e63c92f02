#!/bin/bash
cd /work/main
export ROOT=/tmp/s41/w3 SRC=/tmp/s41/src MESH="-thm_fe_degree 2 -thm_scene2_layer 2 -thm_scene2_layer_growth 2.5 -thm_scene2_fracture_size 5 -thm_scene2_well_size 2.5 -thm_mesh_size 37.5" TF="-thm_final_time 2.546e8"
W=benchmarks/results/solvers/stop38_long_steps/win.sh
G=-vi_fieldsplit_mech_contact_
bash $W recipe
bash $W flowheat_lu -vi_fieldsplit_flow_heat_pc_type lu
bash $W cg8 ${G}ksp_max_it 8
bash $W pmg ${G}pmg 1 ${G}pc_type mg
