# timing_restart/compare.py LOG...: step 73's runs (logs named <list>.log) against each list's
# answers with steps 69, 70 and 72 (the mass limit's runs, masscap/) applied.
import os, sys
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), 'masscap'))
from compare_all import compare, fromlogs, STEP69, STEP70, R
from sets import logs as MASSCAP

STEP72 = {c: (r['named'], r['correct'])
          for paths in MASSCAP.values() for c, r in fromlogs([R + 'masscap/' + p for p in paths]).items()}
STEP73 = {'6098_linear_axis_action_delay+actuator_saturation@drive': ('action_delay + actuator_saturation@drive', 'True')}


def by_list(paths):
    """{list: [log paths]} from logs named <list>[_anything].log"""
    runs = {}
    for log in paths:
        runs.setdefault(os.path.basename(log)[:-4].split('_')[0], []).append(log)
    return runs


if __name__ == '__main__':
    compare(by_list(sys.argv[1:]), {**STEP69, **STEP70, **STEP72})
