# sat_widen/compare.py LOG...: step 74's runs (logs named <list>[_...].log) against each list's
# answers with steps 69, 70, 72 and 73 applied.
import os, sys
H = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path[:0] = [H + '/timing_restart', H + '/masscap']  # (masscap/ has a compare.py too)
from compare_all import compare, STEP69, STEP70
from compare import STEP72, STEP73, by_list

compare(by_list(sys.argv[1:]), {**STEP69, **STEP70, **STEP72, **STEP73})
