#!/bin/bash
# usage: pair.sh TAG: the item-8 pair on the committed code, side by side
cd /tmp/s9
if [ "${ORDER:-bm}" = bm ]; then
  bash full9.sh blk_$1 -thm_direct_max_unknowns 0 > pair_blk_$1.txt 2>&1 &
  sleep 1; bash full9.sh mum_$1 ${MUMPS:--thm_pc_reuse off} > pair_mum_$1.txt 2>&1 &
else
  bash full9.sh mum_$1 ${MUMPS:--thm_pc_reuse off} > pair_mum_$1.txt 2>&1 &
  sleep 1; bash full9.sh blk_$1 -thm_direct_max_unknowns 0 > pair_blk_$1.txt 2>&1 &
fi
wait
cat pair_blk_$1.txt pair_mum_$1.txt
