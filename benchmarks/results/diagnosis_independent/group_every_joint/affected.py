import json,gzip,glob,collections
rows={}
for f in sorted(glob.glob('heldout_segments/device/*.jsonl.gz')+glob.glob('heldout_segments/local_2core/*.jsonl.gz')+glob.glob('rotor_default/*.jsonl.gz')):
    for l in gzip.open(f,'rt'):
        d=json.loads(l); rows[d['case']]=(d,f)
print(len(rows))
aff=[]
for c,(d,f) in rows.items():
    r0=d['rounds'][0] if d['rounds'] else []
    cf=[x for x in r0 if x['effect']=='coulomb_friction']
    passed=any(x.get('passed') for x in r0)
    pair = len(d['rounds'])>1 and len(d['rounds'][1])==1
    if len(cf)>=2 and not passed:
        aff.append((c, d['split'], d['correct'], d['named'], pair))
print(len(aff))
cnt=collections.Counter((a[1],a[2]) for a in aff); print(cnt)
for a in aff: print(a)
