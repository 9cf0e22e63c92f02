import sys
for f in sys.argv[1:]:
    rows=[l.split() for l in open(f) if 'KSP' in l and 'true resid norm' in l]
    s=[];cur=[]
    for r in rows:
        if int(r[0])==0 and cur: s.append(cur); cur=[]
        cur.append((int(r[0]),float(r[5]),float(r[9])))
    s.append(cur)
    a=s[0]
    print(f.split('/')[-2], 'solves', [len(x)-1 for x in s], 'first: ratio true/est at', ' '.join('%d:%.2f'%(it,t/e) for it,e,t in a if it in (60,70,80,90,99)))
