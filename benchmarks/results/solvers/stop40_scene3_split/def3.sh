#!/bin/bash
# usage: def3.sh NAME [options]: Scene 3 default (P2 u) case 2 to 2 years, block path by size
here=$(cd $(dirname $0) && pwd)
name=$1; shift
out=/tmp/s10/s3/def-$name; rm -rf $out; mkdir -p $out
cd ${SRC:-/work/main}
OPENBLAS_NUM_THREADS=1 /usr/bin/time -f '%e %M' -o $out/time.txt .venv/bin/python -m petthm inclined_penny -options_file options/scenes/inclined_penny.opts -thm_scene3_case 2 -thm_final_time ${TF:-63113904} -thm_output_dir $out -log_view :$out/log.txt "$@" > $out/out.txt 2>&1
python3 $here/summ3.py $out def-$name
