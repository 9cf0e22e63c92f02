#!/bin/bash
# usage: [SCENE=fracture_inflation] [SRC=checkout] po.sh LEVEL(1..5) SNES extra...: a 2D crack scene with
# block.opts (+ extra options); one line: wall, KSPSolve, PCSetUp, unknowns, steps, rejected, Newton, Krylov, per Newton
L=$1; S=$2; shift 2
case $L in 1) lv="-thm_partial_crack_size 0.05 -thm_mesh_size 100";; 2) lv="-thm_partial_crack_size 0.025 -thm_mesh_size 50";; 3) lv="-thm_partial_crack_size 0.0125 -thm_mesh_size 25";; 4) lv="-thm_partial_crack_size 0.00625 -thm_mesh_size 12.5";; 5) lv="-thm_partial_crack_size 0.003125 -thm_mesh_size 6.25";; esac
out=$(mktemp -d /tmp/s41/po.XXXX)
cd ${SRC:-/tmp/s41/src} && OMP_NUM_THREADS=1 .venv/bin/python -m petthm ${SCENE:-partial_opening} -options_file options/scenes/${SCENE:-partial_opening}.opts -thm_fe_degree 1 -snes_type $S $lv -options_file options/solvers/block.opts -thm_output_dir $out "$@" > $out/log 2>&1
/work/main/.venv/bin/python $(dirname $(readlink -f $0))/summ.py $out "L$L $S" "$@"
