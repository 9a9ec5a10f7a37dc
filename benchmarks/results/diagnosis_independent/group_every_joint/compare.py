import json,gzip,glob,sys
rows={}
for f in sorted(glob.glob('benchmarks/results/diagnosis_independent/heldout_segments/device/*.jsonl.gz')+glob.glob('benchmarks/results/diagnosis_independent/heldout_segments/local_2core/*.jsonl.gz')+glob.glob('benchmarks/results/diagnosis_independent/rotor_default/*.jsonl.gz')):
    for l in gzip.open(f,'rt'):
        d=json.loads(l); rows[d['case']]=d
new=[json.loads(l) for l in open(sys.argv[1])]
diff=0; gained=lost=0
for d in new:
    o=rows[d['case']]
    same = sorted(o['named'])==sorted(d['named'])
    g = any('fitted with coulomb_friction on' in json.dumps(d.get('rounds',''))  for _ in [0])
    if not same:
        diff+=1
        gained += (d['correct'] and not o['correct']); lost += (o['correct'] and not d['correct'])
    print(('  ' if same else '**'), d['case'], 'new', d['named'], d['correct'], '| stored', o['named'], o['correct'], '| s', d['seconds'], o.get('seconds'))
print(len(new), 'differ', diff, 'gained', gained, 'lost', lost)
