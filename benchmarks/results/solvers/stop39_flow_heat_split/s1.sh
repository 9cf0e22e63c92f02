#!/bin/bash
# usage: s1.sh NAME [options]: default Scene 2 step 1 (block path), count + cost
name=$1; shift
out=/tmp/s9/s1-$name; rm -rf $out; mkdir -p $out
cd ${SRC:-/work/main}
OPENBLAS_NUM_THREADS=1 .venv/bin/python -m petthm penny_impermeable -options_file options/scenes/penny_impermeable.opts -thm_direct_max_unknowns 0 -thm_output_dir $out -thm_final_time ${TF:-1000} -vi_fieldsplit_mech_contact_pc_hypre_boomeramg_print_statistics 1 -log_view :$out/log.txt "$@" > $out/out.txt 2>&1
python3 - $out $name <<'PY'
import sys,re
o=open(sys.argv[1]+'/out.txt').read(); log=open(sys.argv[1]+'/log.txt').read()
def ev(n):
    m=re.search(r'^'+n+r'\s+(\d+) \S+ (\S+)', log, re.M); return (int(m.group(1)), float(m.group(2))) if m else (0,0)
oc=re.findall(r'operator = (\S+)', o)
st=re.findall(r'newton\s+(\d+)\s+krylov\s+(\d+)', o)
N=sum(int(a) for a,b in st); K=sum(int(b) for a,b in st)
pa=ev('PCApply'); ks=ev('KSPSolve'); su=ev('PCSetUp')
print('%-24s N %d K %d K/N %.1f KSPSolve %.2f PCApply/app %.1f ms PCSetUp %.2f opcx %s' % (sys.argv[2], N, K, K/max(N,1), ks[1], 1e3*pa[1]/max(pa[0],1), su[1], oc[:1]))
PY
