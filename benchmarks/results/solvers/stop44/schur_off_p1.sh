#!/bin/bash
# stop 44: Scene 2 default (P1 u) to 1e9 s on the block path, the recipe against -vi_contact_schur off,
# side by side on the two cores, two pairs with the start order swapped (stop38_long_steps/full.sh)
here=$(cd $(dirname $0) && pwd); export ROOT=${ROOT:-/tmp/s44/so} MESH= SRC=${SRC:-/work/main}
full="bash $here/../stop38_long_steps/full.sh"
mkdir -p $ROOT
$full recipe_1 > $ROOT/r1.txt 2>&1 & sleep 1; $full off_1 -vi_contact_schur off > $ROOT/o1.txt 2>&1 & wait
$full off_2 -vi_contact_schur off > $ROOT/o2.txt 2>&1 & sleep 1; $full recipe_2 > $ROOT/r2.txt 2>&1 & wait
cat $ROOT/r1.txt $ROOT/o1.txt $ROOT/r2.txt $ROOT/o2.txt
