#!/bin/bash
# usage: LEV=L1|L2 base.sh: the level's run to step 68 (2.146e8 s), the window's base checkpoint
case ${LEV:?} in
 L1) sz="-thm_scene2_fracture_size 20 -thm_scene2_well_size 10 -thm_mesh_size 150";;
 L2) sz="-thm_scene2_fracture_size 10 -thm_scene2_well_size 5 -thm_mesh_size 75";;
esac
mkdir -p /tmp/s42/$LEV; cd ${SRC:-/tmp/s42/src}
OPENBLAS_NUM_THREADS=1 .venv/bin/python -m petthm penny_impermeable -options_file options/scenes/penny_impermeable.opts -thm_fe_degree 2 -thm_scene2_layer 2 -thm_scene2_layer_growth 2.5 -thm_direct_max_unknowns 0 $sz -thm_final_time 2.14596e8 -thm_output_dir /tmp/s42/$LEV/base > /tmp/s42/$LEV/base.out 2>&1
