# The tuning lists' answers before step 80 (cur: {case: (named, right)}, lst: {case: list}): freeze_at_noise/current.py
# (before step 77), overlaid by the step 77-79 runs of the thirty-third session in the order run.
import glob, os
R = os.path.dirname(os.path.dirname(os.path.abspath(__file__))) + '/'
__file__ = R + 'freeze_at_noise/compare.py'
exec(open(R + 'freeze_at_noise/current.py').read())
for pat in ['finer_share/device1/*.log', 'finer_share/device2/*.log', 'finer_share/device3/*.log',
            'finer_share/device4_step77/*.log', 'finer_share/local_step77/extra.log',
            'finer_share/local_step77/recheck_step77.log', 'finer_share/local_step77/beside_3833_step77.log',
            'rigid_band_2core/step79.log']:
    for p in sorted(glob.glob(R + pat)):
        for c, r in fromlogs([p]).items():
            cur[c] = (r['named'], r['correct'] == 'True')
