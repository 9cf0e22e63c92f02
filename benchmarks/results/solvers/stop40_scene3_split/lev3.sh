#!/bin/bash
# usage: lev3.sh L1|L2|L3 NAME [options]: coarse Scene 3 case 2 (stop 36's levels) to 2 years, block path
here=$(cd $(dirname $0) && pwd)
lev=$1; name=$2; shift 2
case $lev in
 L1) sz="-thm_scene3_fracture_size 50 -thm_scene3_well_size 15 -thm_mesh_size 300";;
 L2) sz="-thm_scene3_fracture_size 25 -thm_scene3_well_size 7.5 -thm_mesh_size 150";;
 L3) sz="-thm_scene3_fracture_size 12.5 -thm_scene3_well_size 3.75 -thm_mesh_size 100";;
esac
out=/tmp/s10/s3/$lev-$name; rm -rf $out; mkdir -p $out
cd ${SRC:-/work/main}
OPENBLAS_NUM_THREADS=1 /usr/bin/time -f '%e %M' -o $out/time.txt .venv/bin/python -m petthm inclined_penny -options_file options/scenes/inclined_penny_coarse.opts -thm_scene3_case 2 -thm_direct_max_unknowns 0 $sz -thm_final_time ${TF:-63113904} -thm_output_dir $out -log_view :$out/log.txt "$@" > $out/out.txt 2>&1
python3 $here/summ3.py $out $lev-$name
