#!/bin/bash
# stop 44: item 7's P1 cases again on the landed code, two at a time (counts; times indicative):
# coarse Scene 3 (stop 40's lev3.sh) on one core; Scene 2 P1 layered (stop 39's lev.sh), then the
# 2D crack cases (stop 41's item7.py) on the other. 3D Terzaghi (P2 u) ran in stop 43 on this recipe.
S=$(cd $(dirname $0)/.. && pwd); export SRC=${SRC:-/work/main}; R=${R:-/tmp/s44/item7}
mkdir -p $R
( for l in L1 L2 L3; do bash $S/stop40_scene3_split/lev3.sh $l s44; done > $R/scene3.txt 2>&1 ) &
( for l in L1 L2 L3; do bash $S/stop39_flow_heat_split/lev.sh $l; done > $R/scene2_p1.txt 2>&1
  RUNS=$R/runs $SRC/.venv/bin/python $S/stop41_item7/item7.py run partial_opening_rsls partial_opening_ssls fracture_inflation > $R/crack_run.txt 2>&1
  RUNS=$R/runs $SRC/.venv/bin/python $S/stop41_item7/item7.py table > $R/crack.md 2>&1 ) &
wait
cat $R/scene3.txt $R/scene2_p1.txt $R/crack.md
