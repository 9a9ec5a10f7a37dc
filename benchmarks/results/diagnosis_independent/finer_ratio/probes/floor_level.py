# python floor_level.py DIR...: fitted candidates that failed only by floor_level (ratio, t passed, base misfit <= 0.003 per
# residual, the step's floor lower): true or false.
import json, glob, os, collections, sys
def key(e, t): return e if e in ('action_delay', 'none') else f'{e}@{t}'
seen = {}
for pat in sys.argv[1:]:
    for f in sorted(glob.glob(pat + '/*/diagnosis/diagnosis.json')):
        seen[f.split('/')[-3]] = f
rows = []
for case, f in sorted(seen.items()):
    tr = json.load(open(os.path.join(os.path.dirname(os.path.dirname(f)), 'truth.json')))
    truth = {key(e, t) for e, t, _ in tr['effects']}
    d = json.load(open(f))
    named = {key(s['effect'], s['target']) for s in d['selected'] if s['effect'] != 'none'}
    sl = d['step_level']
    for r in d['rounds']:
        first = r['base'] == 'none'
        for c in r['candidates']:
            if c.get('validation_ratio') is None or c.get('passed'): continue
            ratio, t, lv = c['validation_ratio'], c['t'], c.get('base_level')
            if lv is None: continue
            gain = 0.02 if first else 0.05
            if ratio <= 1 - gain and t >= 2.0 and lv <= 0.003 and 2 * sl < 0.003:
                k = key(c['effect'], c['target'])
                rows.append((case, r['base'], k, k in truth, k in named, round(ratio, 3), round(t, 2), round(lv, 5), round(sl, 6)))
for x in rows: print(*x)
print(collections.Counter((x[3]) for x in rows), len(seen))
