# timing_restart/sets.py: the tuning lists' cases step 73 can move: a delay or lag in the truth or
# in the latest stored answer (steps 69, 70 and 72's runs included). Prints "list:only" words.
import sys, os
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), 'masscap'))
from compare_all import latest, fromlogs, STEP69, STEP70, R
M = R + 'masscap/'

logs = {'tuning': ['device/tuning.log', 'local/tuning.log'], 'combos': ['device/combos.log', 'local/combos.log'],
        'extra': ['device/extra.log', 'local/extra_cut.log'], 'focus': ['device/focus.log'], 'beside': ['device/beside.log'],
        'pairs': ['local/pairs.log'], 'timing': ['local/timing.log'], 'servo': ['local/servo.log']}
def main():
    base = latest()
    out = []
    for s, paths in logs.items():
      ans = {c: r['named'] for c, r in base[s].items()}
      ans.update({c: v[0] for c, v in {**STEP69, **STEP70}.items() if c in ans})
      ans.update({c: r['named'] for c, r in fromlogs([M + p for p in paths]).items()})
      pick = sorted(c for c, named in ans.items()
                    if any(k in c.split('_', 1)[1] + ' ' + named for k in ('action_delay', 'motor_lag')))
      print(s, len(pick), 'of', len(ans), file=sys.stderr)
      out.append(f"{s}:" + ','.join(c.split('_')[0] + '_' for c in pick))
    print(' '.join(out))


if __name__ == '__main__':
    main()
