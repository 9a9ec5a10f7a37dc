# python compare.py LOG...: every answer of the logs that differs from the answers at step 80 (now.py, overlaid by
# step 80's own runs under ../pair_screen/), the net, and FINER where the case's stored diagnosis (under
# $REPORTS/<case>/diagnosis/diagnosis.json, several folders separated by ':') holds a finer-step check with a ratio
# in (0.5, 0.65] that passed: only such a check can move an answer between finer_ratio 0.5 and 0.65.
import glob, json, os, re, sys
H = os.path.dirname(os.path.abspath(__file__))
exec(open(os.path.join(H, '..', 'pair_screen', 'now.py')).read())
for p in sorted(glob.glob(os.path.join(H, '..', 'pair_screen', 'device*', '*.log')) + glob.glob(os.path.join(H, '..', 'pair_screen', 'local', '*.log'))):
    if p.endswith('combos_off.log'):
        continue
    for c, r in fromlogs([p]).items():
        cur[c] = (r['named'], r['correct'] == 'True')


def finer_moves(case):
    for d in os.environ.get('REPORTS', '').split(':'):
        for f in glob.glob(os.path.join(d, case, 'diagnosis', 'diagnosis.json')):
            for r in json.load(open(f))['rounds']:
                for c in r['candidates']:
                    m = re.search(r'at a 4x finer step: ratio ([\d.]+).*: passes', c.get('note') or '')
                    if m and 0.5 < float(m.group(1)) <= 0.65:
                        return True
    return False


net = n = 0
for p in sys.argv[1:]:
    for c, r in fromlogs([p]).items():
        n += 1
        nb, kb = cur[c]
        ok = r['correct'] == 'True'
        if r['named'] != nb:
            d = int(ok) - int(kb)
            net += d
            print(f"{lst[c]:7s} {c:62s} {nb} [{kb}] -> {r['named']} [{ok}] {d:+d} {'FINER' if finer_moves(c) else ''}")
print('cases', n, 'net', net)
