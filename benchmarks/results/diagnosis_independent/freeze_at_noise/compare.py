# python compare.py LOG...: every answer of the logs that differs from its list's latest before step 77, and the net.
import os, re, sys
HERE = os.path.dirname(os.path.abspath(__file__))
exec(open(os.path.join(HERE, 'current.py')).read())
net = n = 0
for p in sys.argv[1:]:
    for line in open(p):
        m = re.match(r'^(OK |-- )(\S+)\s+named (.+?)\s+[0-9.]+s', line)
        if not m:
            continue
        c, named, ok = m.group(2), m.group(3).strip(), m.group(1) == 'OK '
        n += 1
        nb, kb = cur[c]
        if named != nb:
            d = int(ok) - int(kb)
            net += d
            print(f'{lst[c]:7s} {c:64s} {nb} [{kb}] -> {named} [{ok}] {d:+d}')
print('cases', n, 'net', net)
