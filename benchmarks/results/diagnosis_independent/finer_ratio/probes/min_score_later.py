# python min_score_later.py (run in a folder holding d4/ d2/ d1/, later ones replacing earlier: the stored device diagnoses, d4/ before step 80, d2/ and d1/ after it, `<dir>/<case>/diagnosis/diagnosis.json`):
# every later round (an effect named) where fewer than 4 candidates screened at >= min_score 0.01 and some at 0.004-0.01,
# i.e. where a lower min_score after the first round would fit more; whether one of those is a true effect still missing.
import collections
from stored import cases, key
stats = collections.Counter()
n = 0
for case, truth, named, d in cases(['d4', 'd2', 'd1']):   # (d4: older runs; d2, d1 replace them)
    n += 1
    for r in d['rounds']:
        if r['base'] == 'none': continue
        sc = [c['screen_score'] for c in r['candidates']]
        above = sum(s >= 0.01 for s in sc)
        low = [(key(c['effect'], c['target']), round(c['screen_score'], 4)) for c in r['candidates'] if 0.004 <= c['screen_score'] < 0.01]
        if above < 4 and low:
            nt = [x for x in low if x[0] in truth and x[0] not in named]
            stats['rounds affected'] += 1
            stats['with missing true'] += bool(nt)
            print(case[:60], 'named', sorted(named), 'truth', sorted(truth), 'base', r['base'], 'above', above, 'low', low[:4 - above])
print(stats, n)
