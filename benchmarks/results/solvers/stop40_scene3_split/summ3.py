import json,sys,re
out,name=sys.argv[1:3]
d=json.load(open(out+'/summary.json'))
t=open(out+'/time.txt').read().split()
o=open(out+'/out.txt').read().split('restart from')[-1]
st=[(int(a),int(b),float(dt)) for dt,a,b in re.findall(r'dt = (\S+) s\s+newton\s+(\d+)\s+krylov\s+(\d+)', o)]
N=sum(a for a,b,c in st); K=sum(b for a,b,c in st)
lng=[(a,b) for a,b,c in st if c>2e6]; NL=sum(a for a,b in lng); KL=sum(b for a,b in lng)
mx=max((b/max(a,1) for a,b,c in st), default=0)
log=open(out+'/log.txt').read()
m=re.search(r'^KSPSolve\s+\d+ \S+ (\S+)', log, re.M)
print('%-18s'%name, d['status'], 'dofs', sum(d['dofs'].values()) if isinstance(d['dofs'],dict) else d['dofs'], 'steps', d['steps'], 'rej', d['rejected_steps'], 'N', N, 'K', K, 'K/N %.1f'%(K/max(N,1)), 'long K/N %.1f'%(KL/max(NL,1)), 'max %.1f'%mx, 'kspsolve', m.group(1) if m else '-', 'wall', t[0], 'rssMB', int(t[1])//1024, 'p=%.6f T=%.6f'%(d['injection_pressure']/1e6, d['production_temperature']))
