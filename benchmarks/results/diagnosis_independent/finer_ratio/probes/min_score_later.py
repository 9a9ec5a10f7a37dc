# python min_score_later.py (run in a folder holding d1/ d2/ d4/: the stored step-80 device diagnoses, `<dir>/<case>/diagnosis/diagnosis.json`):
# every later round (an effect named) where fewer than 4 candidates screened at >= min_score 0.01 and some at 0.004-0.01,
# i.e. where a lower min_score after the first round would fit more; whether one of those is a true effect still missing.
import json, glob, os, collections
def key(e, t): return e if e in ('action_delay', 'none') else f'{e}@{t}'
seen = {}
for f in sorted(glob.glob('d*/*/diagnosis/diagnosis.json')):
    case = f.split('/')[1]
    seen[case] = f   # later dirs override (d4 older)
stats = collections.Counter()
for case, f in sorted(seen.items()):
    tr = json.load(open(os.path.join(os.path.dirname(os.path.dirname(f)), 'truth.json')))
    truth = {key(e, t) for e, t, _ in tr['effects']}
    d = json.load(open(f))
    named = {key(s['effect'], s['target']) for s in d['selected'] if s['effect'] != 'none'}
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
print(stats, len(seen))
