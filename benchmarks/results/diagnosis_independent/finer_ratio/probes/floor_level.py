# python floor_level.py DIR...: fitted candidates that failed only by floor_level (ratio, t passed, base misfit <= 0.003 per
# residual, the step's floor lower): true or false.
import collections, sys
from stored import cases, key
rows, n = [], 0
for case, truth, named, d in cases(sys.argv[1:]):
    n += 1
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
print(collections.Counter((x[3]) for x in rows), n)
