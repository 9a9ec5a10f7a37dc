"""Probe: oracle_ft from an existing nominal run, with algo_options overrides; scores on the plant."""
import sys, time, dataclasses, numpy as np
sys.path.insert(0, "benchmarks")
import closed_loop as cl
from sim2real.common import config as config_lib
from sim2real.training.driver import TrainConfig
from sim2real.algos.base import DRConfig
nominal, name = sys.argv[1], sys.argv[2]
opts = dict(kv.split("=") for kv in sys.argv[3:])
opts = {k: float(v) for k, v in opts.items()}
setup = cl.SETUPS["cartpole"]
base = config_lib.load(TrainConfig, [f"config={cl.ROOT}/{setup['config']}", "num_seeds=1", "total_steps=4000000"])
t = time.time()
r = cl._train(base, name, "/tmp/cl_probe", num_seeds=5, dr=DRConfig(fixed=dict(setup["truth"])),
              algo_options={**base.algo_options, "warm_start": nominal, **opts})
rets = cl._scores(r, f"{cl.ROOT}/{setup['plant']}", 64, 5)
print(name, opts, [round(x, 1) for x in rets], "mean", round(float(np.mean(rets)), 1), "s", round(time.time() - t), flush=True)
