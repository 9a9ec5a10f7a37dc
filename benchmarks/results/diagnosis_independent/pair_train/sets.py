# pair_train/sets.py (tuning.md step 76): every tuning-list case whose latest stored diagnosis (the /tmp runs
# of steps 72-74 and of spread_floor_not_kept, not committed) had nothing pass on the nominal model or a pair
# joined together, or that has no stored diagnosis; prints the "list:only" words of sets.txt
import json, glob, os, sys
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', '..'))  # benchmarks/
import sysid_cases as C
seen={}
for root in ['/tmp/cap_work','/tmp/dev4','/tmp/dev1','/tmp/sat_work','/tmp/sf/d1']:
    for f in sorted(glob.glob(os.path.join(root,'[0-9]*_*/diagnosis/diagnosis.json'))):
        case=f.split('/')[-3]
        if case.startswith('4'): continue
        seen[case]=f
out=[]; tot=0; ns=0
for s in ['tuning','extra','focus','pairs','servo','beside','timing','combos']:
    pick=[]
    for x in C.split_cases(s):
        lab=x.label
        f=seen.get(lab)
        if f is None:
            pick.append(x); ns+=1; continue
        d=json.load(open(f))
        r0=d['rounds'][0] if d['rounds'] else None
        if r0 is None or not any(c.get('passed') for c in r0['candidates']) or any('fitted together' in (c.get('note') or '') for r in d['rounds'] for c in r['candidates']):
            pick.append(x)
    tot+=len(pick)
    out.append(s+':'+','.join((str(x.seed) if x.seed>=1000 else '%03d'%x.seed)+'_' for x in pick))
print(' '.join(out))
print(tot, 'cases;', ns, 'without a stored diagnosis', file=sys.stderr)
