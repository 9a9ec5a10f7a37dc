# python check_real.py: for each of real/<name>/diagnosis.json (run_real.sh), its answer, named effects, held-out NRMSE
# before -> after, and every finer-step check (ratio, passes/fails), beside the last stored run's (masscap/real/, and
# sat_widen/real/ for the KUKA).
import glob, json, os, re
H = os.path.dirname(os.path.abspath(__file__))


def show(f):
    d = json.load(open(f))
    fin = [(c['effect'], c['target'], m.group(1), m.group(2)) for r in d['rounds'] for c in r['candidates']
           if (m := re.search(r'at a 4x finer step: ratio ([\d.]+).*: (passes|fails)', c.get('note') or ''))]
    sel = [f"{s['effect']}@{s['target']}" for s in d['selected'] if s['effect'] != 'none']
    fit = d.get('fit') or {}
    return d['answer'], sel, fit.get('before'), fit.get('after'), fin


for f in sorted(glob.glob(os.path.join(H, 'real', '*', 'diagnosis.json'))):
    name = f.split(os.sep)[-2]
    old = os.path.join(H, '..', 'sat_widen' if name.startswith('kuka') else 'masscap', 'real', name, 'diagnosis.json')
    print(name, '\n  now   ', show(f), '\n  before', show(old) if os.path.exists(old) else None)
