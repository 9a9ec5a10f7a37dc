# replays/bot.py ROOT...: passing backlash fits with a width at (or near) the bottom of its range (tuning.md step 69)
import json, glob, os, sys
for root in sys.argv[1:]:
    hits = []
    for f in sorted(glob.glob(os.path.join(root, '[0-9]*_*/diagnosis/diagnosis.json'))):
        case = f.split('/')[-3]
        if case[:2] in ('40','41'): continue
        d = json.load(open(f))
        for i, r in enumerate(d['rounds']):
            for c in r['candidates']:
                if c['effect']=='backlash' and c.get('passed'):
                    w = c['params'][f"backlash:{c['target']}"]
                    if w <= 1.05e-3 or (w < 1.1e-5):
                        hits.append((case, i, round(w,6)))
    print(root, len(hits)); [print('  ', h) for h in hits]
