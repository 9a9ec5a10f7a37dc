"""The same policies on the native plant and on the env with the plant's physics (MJX)."""
import sys, numpy as np
from sim2real.tools.record import from_run
DET = sys.argv[1] == "det"; runs = sys.argv[2:]
plant = "benchmarks/plants/cartpole_real.xml"
for run in runs:
    import os
    from sim2real.training.runs import load_run
    for s in range(5):
        try:
            a = np.mean(from_run(run, plant, 64, seed=12345, run_seed=s, noise=1e-3, deterministic=DET)[0].ret)
        except ValueError:
            break
        b = np.mean(from_run(run, "coulomb:slider=3.0,action_delay=2.0", 64, seed=12345, run_seed=s, deterministic=DET)[0].ret)
        c = np.mean(from_run(run, "coulomb:slider=0.0,action_delay=0.0", 64, seed=12345, run_seed=s)[0].ret)
        print(os.path.basename(run), s, "plant", round(a,1), "env@truth", round(b,1), "env@nominal", round(c,1), flush=True)
