#!/bin/bash
# usage: win3.sh NAME [options]: coarse Scene 3 case 2 level 3, 4 steps from its 2-year checkpoint
here=$(cd $(dirname $0) && pwd)
name=$1; shift
out=/tmp/s10/s3/w-$name; rm -rf $out; cp -r /tmp/s10/s3/L3-base $out
cd ${SRC:-/work/main}
OPENBLAS_NUM_THREADS=1 /usr/bin/time -f '%e %M' -o $out/time.txt .venv/bin/python -m petthm inclined_penny -options_file options/scenes/inclined_penny_coarse.opts -thm_scene3_case 2 -thm_direct_max_unknowns 0 -thm_scene3_fracture_size 12.5 -thm_scene3_well_size 3.75 -thm_mesh_size 100 -thm_restart $out ${TF:--thm_final_time 8e7} -thm_pc_reuse off -log_view :$out/log.txt "$@" > $out/out.txt 2>&1
python3 $here/summ3.py $out $name
