#!/bin/bash
# usage: win.sh NAME [extra...]: 4 long steps from the t=4e8 checkpoint of level 1
name=$1; shift
out=${ROOT:-/tmp/ls}/w-$name; rm -rf $out; cp -r ${ROOT:-/tmp/ls}/base $out
cd ${SRC:-/work/main}
# ROOT: checkpoint folder root (stop 39: /tmp/s9); MESH: mesh options (stop 39: MESH= for the default mesh)
OPENBLAS_NUM_THREADS=1 /usr/bin/time -f '%e %M %U' -o $out/time.txt .venv/bin/python -m petthm penny_impermeable -options_file options/scenes/penny_impermeable.opts ${MESH--thm_mesh_size 150 -thm_scene2_fracture_size 20 -thm_scene2_well_size 10} -thm_direct_max_unknowns 0 -thm_restart $out ${TF:--thm_final_time 4.8e8} -thm_pc_reuse off -log_view :$out/log.txt "$@" > $out/out.txt 2>&1
python3 - $out $name <<'PY'
import json,sys,re
d=json.load(open(sys.argv[1]+'/summary.json'))
t=open(sys.argv[1]+'/time.txt').read().split()
log=open(sys.argv[1]+'/log.txt').read()
ks=re.findall(r'^KSPSolve\s+\d+ \S+ (\S+)', log, re.M)
steps=re.findall(r'newton\s+(\d+)\s+krylov\s+(\d+)', open(sys.argv[1]+'/out.txt').read())
print('%-28s'%sys.argv[2], d['status'], 'steps',d['steps'],'rej',d['rejected_steps'],'newton',d['snes_iterations'],'krylov',d['ksp_iterations'], 'K/N %.1f'%(d['ksp_iterations']/max(1,d['snes_iterations'])), 'per step', [int(k) for n,k in steps], 'kspsolve', ks[:1], 'wall',t[0],'user',t[2], 'p=%.6f T=%.6f'%(d['injection_pressure']/1e6, d['production_temperature']))
PY
