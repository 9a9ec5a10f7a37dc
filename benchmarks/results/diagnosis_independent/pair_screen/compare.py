# python compare.py LOG...: every answer of the logs that differs from now.py's (before step 80), the net, and
# SCREENED where the case's report (under $REPORTS/<case>/diagnosis/report.md, if given) holds a pair whose
# second half was screened on top of the first (step 80's own pairs).
import glob, os, sys
exec(open(os.path.join(os.path.dirname(os.path.abspath(__file__)), 'now.py')).read())
net = n = 0
for p in sys.argv[1:]:
    for c, r in fromlogs([p]).items():
        n += 1
        nb, kb = cur[c]
        ok = r['correct'] == 'True'
        if r['named'] != nb:
            d = int(ok) - int(kb)
            net += d
            reps = glob.glob(os.path.join(os.environ.get('REPORTS', '/nonexistent'), c, 'diagnosis', 'report.md'))
            scr = any('screened on top of its fit' in open(x).read() for x in reps)
            print(f"{lst[c]:7s} {c:62s} {nb} [{kb}] -> {r['named']} [{ok}] {d:+d} {'SCREENED' if scr else ''}")
print('cases', n, 'net', net)
