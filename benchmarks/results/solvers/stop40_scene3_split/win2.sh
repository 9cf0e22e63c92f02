#!/bin/bash
# usage: win2.sh NAME [options]: Scene 2 default P2 u, two long steps from the t=8.13e7 s checkpoint
name=$1; shift
out=/tmp/s10/w-$name; rm -rf $out; cp -r /tmp/s10/base $out
cd ${SRC:-/work/main}
OPENBLAS_NUM_THREADS=1 /usr/bin/time -f '%e %M %U' -o $out/time.txt .venv/bin/python -m petthm penny_impermeable -options_file options/scenes/penny_impermeable.opts -thm_fe_degree 2 -thm_restart $out ${TF:--thm_final_time 1e8} -thm_pc_reuse off -vi_fieldsplit_mech_contact_pc_mg_log -log_view :$out/log.txt "$@" > $out/out.txt 2>&1
python3 - $out $name <<'PY'
import json,sys,re
d=json.load(open(sys.argv[1]+'/summary.json'))
t=open(sys.argv[1]+'/time.txt').read().split()
log=open(sys.argv[1]+'/log.txt').read()
def ev(n):
    m=re.search(r'^'+n+r'\s+(\d+) \S+ (\S+)', log, re.M); return (int(m.group(1)), float(m.group(2))) if m else (0,0)
st=re.findall(r'newton\s+(\d+)\s+krylov\s+(\d+)', open(sys.argv[1]+'/out.txt').read().split('restart from')[-1])
N=sum(int(a) for a,b in st); K=sum(int(b) for a,b in st)
pa=ev('PCApply'); ks=ev('KSPSolve')
print('%-20s'%sys.argv[2], d['status'], 'N',N,'K',K,'K/N %.1f'%(K/max(1,N)), 'per step', [(int(a),int(b)) for a,b in st], 'KSPSolve %.1f'%ks[1], 'PCApply %.2f s'%(pa[1]/max(pa[0],1)), 'wall',t[0], 'rssMB', int(t[1])//1024, 'p=%.6f T=%.8f'%(d['injection_pressure']/1e6, d['production_temperature']))
PY
