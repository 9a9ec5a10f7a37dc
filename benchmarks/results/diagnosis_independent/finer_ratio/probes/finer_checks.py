# python finer_checks.py DIR...: every finer-step check in the stored diagnoses: the candidate, true or not, its ratio and t
# at the finer step, passes/fails; then the failures with t >= 2 binned by that ratio (what finer_ratio 0.5 -> x would admit).
import collections, sys, re
from stored import cases, key
rows = []
for case, truth, named, d in cases(sys.argv[1:]):
    for r in d['rounds']:
        for c in r['candidates']:
            n = c.get('note') or ''
            m = re.search(r'at a 4x finer step: ratio ([\d.]+), t = ([-\d.inf]+), misfit ([\d.e-]+).*: (passes|fails)', n)
            if not m: continue
            k = key(c['effect'], c['target'])
            rows.append((case[:50], r['base'][:30], k, k in truth, c.get('passed'), round(c['validation_ratio'], 3), round(c['t'], 1), float(m.group(1)), m.group(2), m.group(4)))
for x in sorted(rows, key=lambda x: x[7]): print(*x)
fails = [x for x in rows if x[9] == 'fails']
for lo, hi in ((0, 0.5), (0.5, 0.6), (0.6, 0.7), (0.7, 0.8), (0.8, 9)):
    s = [x for x in fails if lo < x[7] <= hi and float(x[8]) >= 2]
    print(lo, hi, 'fails with t>=2:', collections.Counter(x[3] for x in s))
