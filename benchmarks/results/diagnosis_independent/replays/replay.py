# replays/replay.py ROOT...: every round's candidates of stored diagnoses (diagnosis.json per case folder), the paired t with and without segments both models predict within drop*KAPPA per residual (tuning.md, twenty-fifth round)
import json, glob, os, sys
import numpy as np
KAPPA = 0.1
def pt(d):
    d = np.asarray(d, float)
    if len(d) < 2: return 0.0
    s = np.std(d, ddof=1)
    if s == 0: return np.inf if np.mean(d) > 0 else 0.0
    return np.mean(d) / (s / np.sqrt(len(d)))
def tj(a, b, floor, drop):
    a, b = np.asarray(a), np.asarray(b)
    if drop:
        keep = np.maximum(a, b) > drop * floor
        if keep.sum() >= 3: a, b = a[keep], b[keep]
    return max(pt(a - b), pt(np.log((a + floor) / (b + floor))))
roots = sys.argv[1:]
drop = 0.2
rows = []
for root in roots:
    for f in sorted(glob.glob(os.path.join(root, '[0-9]*_*/diagnosis/diagnosis.json'))):
        case = f.split('/')[-3]
        try:
            tr = json.load(open(os.path.join(os.path.dirname(os.path.dirname(f)), 'truth.json')))
        except Exception: continue
        true = {e[0] if e[0]=='action_delay' else f'{e[0]}@{e[1]}' for e in tr['effects']}
        d = json.load(open(f))
        for i, r in enumerate(d['rounds']):
            base = r.get('base_validation_segments'); npt = r.get('residuals_per_segment')
            if base is None: continue
            floor = KAPPA * max(npt, 1)
            for c in r['candidates']:
                if 'validation_segments' not in c: continue
                key = c['effect'] if c['effect']=='action_delay' else f"{c['effect']}@{c['target']}"
                t_old = tj(base, c['validation_segments'], floor, 0)
                t_new = tj(base, c['validation_segments'], floor, drop)
                ratio = c['validation_ratio']
                if (t_old >= 2) != (t_new >= 2) and ratio < 0.98:
                    rows.append((case, i, key, key in true, round(ratio,4), round(c['t'],2), round(t_old,2), round(t_new,2), c['passed']))
for r in rows: print(*r)
print(len(rows))
