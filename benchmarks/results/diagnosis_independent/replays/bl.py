# replays/bl.py ROOT...: cases of stored diagnoses where a backlash passed in some round (tuning.md step 69)
import json, glob, os, sys
out = {}
for root in sys.argv[1:]:
    for f in sorted(glob.glob(os.path.join(root, '[0-9]*_*/diagnosis/diagnosis.json'))):
        case = f.split('/')[-3]
        if case[:2] in ('40','41'): continue
        d = json.load(open(f))
        hit = any(c['effect']=='backlash' and c.get('passed')
                  for r in d['rounds'] for c in r['candidates'])
        hit = hit or any(s['effect']=='backlash' for s in d['selected'])
        if hit: out.setdefault(root, []).append(case)
for k, v in out.items(): print(k, len(v), ' '.join(x.split('_')[0] for x in v))
