# replays/dl.py ROOT...: rounds of stored diagnoses where an action delay and a motor lag both passed, with the truth and the answer (tuning.md, twenty-fifth round)
import json, glob, os, sys
import numpy as np
for root in sys.argv[1:]:
    for f in sorted(glob.glob(os.path.join(root, '[0-9]*_*/diagnosis/diagnosis.json'))):
        case = f.split('/')[-3]
        if case[:2] in ('40','41'): continue
        tr = json.load(open(os.path.join(os.path.dirname(os.path.dirname(f)), 'truth.json')))
        true = {e[0] if e[0]=='action_delay' else f'{e[0]}@{e[1]}' for e in tr['effects']}
        d = json.load(open(f))
        named = [s['effect'] if s['effect']=='action_delay' else f"{s['effect']}@{s['target']}" for s in d['selected']]
        for i, r in enumerate(d['rounds']):
            p = [(c['effect'] if c['effect']=='action_delay' else f"{c['effect']}@{c['target']}", round(c['validation_ratio'],4), round(c['t'],2)) for c in r['candidates'] if c.get('passed')]
            kinds = {k.split('@')[0] for k,_,_ in p}
            if 'action_delay' in kinds and 'motor_lag' in kinds:
                print(case, i, 'true', sorted(true), 'named', named, p)
