#!/bin/bash
# usage: run.sh NAME LEVEL [extra options...]; runs Scene 2 P1 layered, step 1 (t=1000 s), block.opts
name=$1; lev=$2; shift 2
case $lev in
 L2) sz="-thm_scene2_fracture_size 10 -thm_scene2_well_size 5 -thm_mesh_size 75";;
 L3) sz="-thm_scene2_fracture_size 5 -thm_scene2_well_size 2.5 -thm_mesh_size 37.5";;
 L4) sz="-thm_scene2_fracture_size 2.5 -thm_scene2_well_size 1.25 -thm_mesh_size 18.75";;
esac
out=/tmp/nb/$name-$lev; mkdir -p $out
cd ${SRC:-/work/main}
OPENBLAS_NUM_THREADS=1 /usr/bin/time -f '%e %M' -o $out/time.txt .venv/bin/python -m petthm penny_impermeable -options_file options/scenes/penny_impermeable.opts -thm_fe_degree 1 -thm_scene2_layer 2 -thm_scene2_layer_growth 2.5 ${TEND:--thm_final_time 1000} $sz -options_file options/solvers/block.opts -thm_output_dir $out -thm_quiet -log_view :$out/log.txt "$@" > $out/out.txt 2>&1
python3 - $out <<'PY'
import json,sys,re
d=json.load(open(sys.argv[1]+'/summary.json'))
t=open(sys.argv[1]+'/time.txt').read().split()
ks=re.findall(r'^KSPSolve\s+\d+ \S+ (\S+)', open(sys.argv[1]+'/log.txt').read(), re.M)
print(sys.argv[1], d['status'], 'steps',d['steps'],'newton',d['snes_iterations'],'krylov',d['ksp_iterations'], 'K/N %.1f'%(d['ksp_iterations']/max(1,d['snes_iterations'])), 'kspsolve', ks[:1], 'wall',t[0],'rssMB',int(t[1])//1024)
PY
