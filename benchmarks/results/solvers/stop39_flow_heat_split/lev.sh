#!/bin/bash
# usage: [DEG=2] lev.sh L1|L2|L3 [extra]: Scene 2 layered (stop 29's levels; P1 u unless DEG=2) to 1e9 s, the scene's block recipe
lev=$1; shift
case $lev in
 L1) sz="-thm_scene2_fracture_size 20 -thm_scene2_well_size 10 -thm_mesh_size 150";;
 L2) sz="-thm_scene2_fracture_size 10 -thm_scene2_well_size 5 -thm_mesh_size 75";;
 L3) sz="-thm_scene2_fracture_size 5 -thm_scene2_well_size 2.5 -thm_mesh_size 37.5";;
esac
out=/tmp/s9/lev-$lev${TAG:-}; rm -rf $out; mkdir -p $out
cd ${SRC:-/work/main}
OPENBLAS_NUM_THREADS=1 /usr/bin/time -f '%e %M' -o $out/time.txt .venv/bin/python -m petthm penny_impermeable -options_file options/scenes/penny_impermeable.opts -thm_fe_degree ${DEG:-1} -thm_scene2_layer 2 -thm_scene2_layer_growth 2.5 -thm_direct_max_unknowns 0 $sz -thm_output_dir $out -log_view :$out/log.txt "$@" > $out/out.txt 2>&1
python3 - $out <<'PY'
import json,sys,re
d=json.load(open(sys.argv[1]+'/summary.json'))
t=open(sys.argv[1]+'/time.txt').read().split()
o=open(sys.argv[1]+'/out.txt').read()
st=[(float(dt), int(n), int(k)) for dt, n, k in re.findall(r'dt = (\S+) s\s+newton\s+(\d+)\s+krylov\s+(\d+)', o)]
late=[k/n for dt,n,k in st if dt>=1e7]
worst=max(k/n for dt,n,k in st)
print(sys.argv[1], d['status'], 'unknowns', sum(d['dofs'].values()), 'steps',d['steps'],'rej',d['rejected_steps'],'newton',d['snes_iterations'],'krylov',d['ksp_iterations'], 'K/N %.1f'%(d['ksp_iterations']/max(1,d['snes_iterations'])), 'K/N dt>=1e7 %.1f'%(sum(late)/max(1,len(late))), 'worst step K/N %.1f'%worst, 'wall',t[0],'rssMB',int(t[1])//1024)
PY
