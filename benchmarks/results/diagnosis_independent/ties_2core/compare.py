# step 70's replay (tuning.md): the runs of run_ties.sh (/tmp/tie_out_<list>.log) against each
# list's stored answers with step 69's moves (masscap/compare_all.py's ``compare``; the
# changes.txt beside this file was printed by its first form, without the net per line)
import glob, os, sys
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), 'masscap'))
from compare_all import STEP69, compare  # noqa: E402

logs = {}
for log in sorted(glob.glob('/tmp/tie_out_*.log')):
    logs.setdefault(log.split('_')[-1][:-4], []).append(log)
compare(logs, STEP69)
