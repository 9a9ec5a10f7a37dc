# timing_restart/compare.py LOG...: step 73's runs (logs named <list>.log) against each list's
# answers with steps 69, 70 and 72 (the mass limit's runs, masscap/) applied.
import os, sys
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), 'masscap'))
from compare_all import compare, fromlogs, STEP69, STEP70, R
from sets import logs as MASSCAP

step72 = {c: (r['named'], r['correct'])
          for paths in MASSCAP.values() for c, r in fromlogs([R + 'masscap/' + p for p in paths]).items()}
runs = {}
for log in sys.argv[1:]:
    runs.setdefault(os.path.basename(log)[:-4], []).append(log)
compare(runs, {**STEP69, **STEP70, **step72})
