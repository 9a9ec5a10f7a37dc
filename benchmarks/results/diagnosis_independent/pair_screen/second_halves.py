# python second_halves.py DIR: for the two-effect cases under DIR (<case>/truth.json, <case>/diagnosis/diagnosis.json) with one
# true effect missing, where the missing one stopped in the selection's rounds (its last two rounds shown).
import json, glob, os, re, sys, collections
def key(e, t): return e if e in ('action_delay', 'none') else f'{e}@{t}'
rows = []
for f in sorted(glob.glob(os.path.join(sys.argv[1], '*/diagnosis/diagnosis.json'))):
    case = f.split(os.sep)[-3]
    tr = json.load(open(os.path.join(os.path.dirname(os.path.dirname(f)), 'truth.json')))
    if len(tr['effects']) != 2: continue
    truth = {key(e, t) for e, t, _ in tr['effects']}
    d = json.load(open(f))
    named = [key(s['effect'], s['target']) for s in d['selected'] if s['effect'] != 'none']
    if set(named) == truth: continue
    miss = truth - set(named)
    for m in miss:
        seen = []
        for r in d['rounds']:
            for c in r['candidates']:
                if key(c['effect'], c['target']) == m:
                    seen.append((r['base'], round(c['screen_score'], 4), None if c.get('validation_ratio') is None else round(c['validation_ratio'], 3),
                                 None if c.get('t') is None else round(c['t'], 2), c.get('passed')))
        rows.append((case, named, m, seen))
cat = collections.Counter()
for case, named, m, seen in rows:
    last = seen[-1] if seen else None
    if last is None: k = 'never screened'
    elif last[2] is None: k = 'not fitted (screen %s)' % ('< min_score' if last[1] < 0.01 else 'below the top 4')
    elif last[4]: k = 'passed, then lost (best of round / pruned / held-out)'
    else: k = 'fitted, failed'
    cat[k] += 1
    print(f'{case[:58]:58s} named={"+".join(named) or "none"} missing={m} [{k}] {seen[-2:]}')
print(cat)
