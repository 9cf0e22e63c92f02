#!/bin/bash
# usage: windef.sh NAME [options]: Scene 3 default case 2, steps from the 2-year checkpoint of def-new
here=$(cd $(dirname $0) && pwd)
name=$1; shift
out=/tmp/s10/s3/wd-$name; rm -rf $out; cp -r /tmp/s10/s3/def-new $out
cd ${SRC:-/work/main}
OPENBLAS_NUM_THREADS=1 /usr/bin/time -f '%e %M' -o $out/time.txt .venv/bin/python -m petthm inclined_penny -options_file options/scenes/inclined_penny.opts -thm_scene3_case 2 -thm_restart $out ${TF:--thm_final_time 7.6e7} -thm_pc_reuse off -log_view :$out/log.txt "$@" > $out/out.txt 2>&1
python3 $here/summ3.py $out wd-$name
