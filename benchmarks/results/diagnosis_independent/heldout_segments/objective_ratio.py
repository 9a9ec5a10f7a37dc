"""Offline, on the stored rows here: do the training objectives of fitted candidates that failed their
round separate the true ones from the false (a likelihood-ratio or BIC-like criterion in place of
the validation test)? Prints the objective ratios (candidate / its base) by truth and outcome, and
how many true and false failed candidates lie under each threshold. Run from this folder."""
import json,gzip,glob,math,collections
rows=[]
for f in glob.glob('device/*.jsonl.gz')+glob.glob('local_2core/*.jsonl.gz'):
    for l in gzip.open(f,'rt'):
        rows.append(json.loads(l))
print(len(rows))
def key(c): return c['effect'] if c['effect'] in('action_delay','none') else f"{c['effect']}@{c['target']}"
pts=[]
for d in rows:
    truth=set(d['truth']); steps=d['steps']
    for k,r in enumerate(d['rounds']):
        if k>=len(steps): break
        base=steps[k]['objective']; basemodel=steps[k]['model']
        for c in r:
            if c.get('objective') is None: continue
            kk=key(c)
            if kk in basemodel: continue
            pts.append((kk in truth, c['passed'], c['objective']/base, c['validation_ratio'], c['t'], d['case'], kk, len(c.get('params',{}))))
print(len(pts))
import numpy as np
for lab in (True,False):
  for pas in (True,False):
    s=[p for p in pts if p[0]==lab and p[1]==pas]
    o=np.array([p[2] for p in s]); v=np.array([p[3] for p in s])
    print('true' if lab else 'false','passed' if pas else 'failed',len(s),'obj ratio pct',np.percentile(o,[10,25,50,75,90]).round(3),'val',np.percentile(v,[10,50,90]).round(3))
# among failed: can objective ratio separate?
s=[p for p in pts if p[1]==False]
for th in (0.3,0.5,0.7,0.8,0.9):
    t=sum(1 for p in s if p[0] and p[2]<th); f=sum(1 for p in s if not p[0] and p[2]<th)
    t2=sum(1 for p in s if p[0] and p[2]<th and p[3]<0.9); f2=sum(1 for p in s if not p[0] and p[2]<th and p[3]<0.9)
    print(th,'failed with obj ratio<th: true',t,'false',f,' and val<0.9: true',t2,'false',f2)
