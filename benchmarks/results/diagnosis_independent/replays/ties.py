# replays/ties.py ROOT...: cases of stored diagnoses with a validation segment within 0.2 KAPPA per residual in some round, the only ones step 70 can change (tuning.md step 70)
import json, glob, os, sys
import numpy as np
KAPPA=0.1; drop=0.2
for root in sys.argv[1:]:
    hits=[]; n=0
    for f in sorted(glob.glob(os.path.join(root, '[0-9]*_*/diagnosis/diagnosis.json'))):
        case = f.split('/')[-3]
        if case[:2] in ('40','41'): continue
        n+=1
        d = json.load(open(f))
        found=False
        for r in d['rounds']:
            npt=r.get('residuals_per_segment'); base=r.get('base_validation_segments')
            if base is None: continue
            thr=drop*KAPPA*npt
            segs=[np.array(base)]+[np.array(c['validation_segments']) for c in r['candidates'] if 'validation_segments' in c]
            for s in segs:
                if (s < thr).sum() >= 1: found=True
        if found: hits.append(case.split('_')[0])
    print(root, n, len(hits), ' '.join(hits))
