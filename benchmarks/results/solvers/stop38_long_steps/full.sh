#!/bin/bash
# usage: full.sh NAME [extra...]: Scene 2 level 1 to 1e9 s, the size rule's block path
name=$1; shift
out=${ROOT:-/tmp/ls}/f-$name; rm -rf $out; mkdir -p $out
cd ${SRC:-/work/main}
# ROOT: checkpoint folder root (stop 39: /tmp/s9); MESH: mesh options (stop 39: MESH= for the default mesh)
OPENBLAS_NUM_THREADS=1 /usr/bin/time -f '%e %M %U' -o $out/time.txt .venv/bin/python -m petthm penny_impermeable -options_file options/scenes/penny_impermeable.opts ${MESH--thm_mesh_size 150 -thm_scene2_fracture_size 20 -thm_scene2_well_size 10} -thm_direct_max_unknowns 0 -thm_output_dir $out -log_view :$out/log.txt "$@" > $out/out.txt 2>&1
python3 - $out $name <<'PY'
import json,sys,re
d=json.load(open(sys.argv[1]+'/summary.json'))
t=open(sys.argv[1]+'/time.txt').read().split()
log=open(sys.argv[1]+'/log.txt').read()
ks=re.findall(r'^KSPSolve\s+\d+ \S+ (\S+)', log, re.M)
print('%-16s'%sys.argv[2], d['status'], 'steps',d['steps'],'rej',d['rejected_steps'],'newton',d['snes_iterations'],'krylov',d['ksp_iterations'], 'K/N %.1f'%(d['ksp_iterations']/max(1,d['snes_iterations'])), 'kspsolve', ks[:1], 'wall',t[0],'user',t[2], 'rssMB', int(t[1])//1024, 'p=%.6f T=%.8f lam=%.6f'%(d['injection_pressure']/1e6, d['production_temperature'], d['lam_injector']/1e6))
PY
