# compare.py LOG BASELINE_CASES_CSV: a run log's OK/-- lines against a stored list run (GAIN, LOSS, moved)
# compare a run log's OK/-- lines with a baseline cases.csv
import csv,sys,re
base={r['case']:r for r in csv.DictReader(open(sys.argv[2]))}
n=gain=loss=same=0
for line in open(sys.argv[1]):
    m=re.match(r'^(OK |-- )(\S+)\s+named (.*?)\s+[0-9.]+s ',line)
    if not m: continue
    ok=m.group(1)=='OK '; case=m.group(2); named=m.group(3).strip()
    b=base.get(case)
    if b is None: print('no base',case); continue
    bok=b['correct']=='True'; n+=1
    if ok and not bok: gain+=1; print('GAIN',case,b['named'],'->',named)
    elif bok and not ok: loss+=1; print('LOSS',case,b['named'],'->',named)
    elif b['named']!=named: print('moved',case,b['named'],'->',named)
print(f'{n} cases: +{gain} -{loss}')
