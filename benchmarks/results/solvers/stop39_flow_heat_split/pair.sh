#!/bin/bash
# usage: pair.sh TAG: the item-8 pair on the committed code, side by side
# (full.sh passes -thm_direct_max_unknowns 0; the MUMPS run's later 1e9 restores the direct solve:
#  the last value of an option given twice wins. Stop 39 ran an uncommitted full9.sh without it.)
here=$(cd $(dirname $0) && pwd); export ROOT=/tmp/s9 MESH=
full="bash $here/../stop38_long_steps/full.sh"
mkdir -p $ROOT && cd $ROOT
if [ "${ORDER:-bm}" = bm ]; then
  $full blk_$1 -thm_direct_max_unknowns 0 > pair_blk_$1.txt 2>&1 &
  sleep 1; $full mum_$1 -thm_direct_max_unknowns 1000000000 ${MUMPS:--thm_pc_reuse off} > pair_mum_$1.txt 2>&1 &
else
  $full mum_$1 -thm_direct_max_unknowns 1000000000 ${MUMPS:--thm_pc_reuse off} > pair_mum_$1.txt 2>&1 &
  sleep 1; $full blk_$1 -thm_direct_max_unknowns 0 > pair_blk_$1.txt 2>&1 &
fi
wait
cat pair_blk_$1.txt pair_mum_$1.txt
