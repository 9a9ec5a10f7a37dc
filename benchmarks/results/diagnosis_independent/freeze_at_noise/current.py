# Each tuning list's latest answers before step 77 (cur: {case: (named, right)}, lst: {case: list}): the stored
# answers of masscap/compare_all.latest() with steps 69-70, overlaid by every later run's log in the order run.
import sys, os, glob
R=__import__('os').path.dirname(__import__('os').path.dirname(__import__('os').path.abspath(__file__)))+'/'
sys.path.insert(0, R+'masscap')
from compare_all import latest, fromlogs, STEP69, STEP70
base = latest()
cur = {}
lst = {}
for s, d in base.items():
    for c, r in d.items():
        cur[c] = (r['named'], r['correct'] == 'True'); lst[c] = s
for c,(n,k) in list(STEP69.items())+list(STEP70.items()):
    cur[c] = (n, k == 'True')
order = ['masscap/local/*.log','masscap/device/*.log',
         'timing_restart/device/timing.log','timing_restart/device/tuning.log','timing_restart/device/focus.log','timing_restart/device/beside.log','timing_restart/device/extra.log','timing_restart/device/extra_rest.log','timing_restart/device/combos_margin.log',
         'sat_widen/*.log','pair_train/*.log','pair_train/recheck_device/*.log']
for pat in order:
    for p in sorted(glob.glob(R+pat)):
        for c, r in fromlogs([p]).items():
            cur[c] = (r['named'], r['correct'] == 'True')
            if c not in lst: lst[c] = os.path.basename(p).split('.')[0].split('_')[0]
