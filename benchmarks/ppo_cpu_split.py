"""PPO training throughput on the CPU with and without ``ppo.split_envs`` (hopper).

    python benchmarks/ppo_cpu_split.py            # envs=[256,1024]; ~5 min on 2 cores

Env steps per second *including learning* (4 PPO updates per jitted chunk, 16 steps per env per
update, 4 epochs x 4 minibatches, 64x64 MLP), best of 3 chunks after a compiling one. Each
setting runs in its own process: the CPU device count is fixed when JAX starts. With
``split_envs`` each core steps its slice of the envs (``sim2real.envs.parallel``); learning runs on
the whole batch. Writes ``out=`` (default ``benchmarks/results/ppo_cpu_split.csv``).
"""
from __future__ import annotations

import csv
import dataclasses
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)

CHILD = """
import sys, time
split, n = sys.argv[1] == "1", int(sys.argv[2])
if split:
    from sim2real.envs import parallel
    parallel.use_cpu_cores()
import jax
from sim2real.common import config as config_lib
from sim2real.envs import make
from sim2real.training.driver import TrainConfig, build_algo, make_chunk
cfg = config_lib.load(TrainConfig, ["env=hopper", f"ppo.num_envs={n}", "ppo.num_steps=16", "ppo.num_minibatches=4",
                                    "ppo.num_epochs=4", f"ppo.split_envs={str(split).lower()}", "ppo.net.hidden=[64,64]"])
algo = build_algo(cfg, make("hopper"))
st = jax.jit(jax.vmap(algo.init))(jax.random.split(jax.random.PRNGKey(0), 1))
chunk = make_chunk(algo, 4)
st, _ = chunk(st, 0)
jax.block_until_ready(st)
ts = []
for i in range(3):
    t = time.perf_counter()
    st, _ = chunk(st, 4 * (i + 1))
    jax.block_until_ready(st)
    ts.append(time.perf_counter() - t)
print("RESULT", len(jax.devices()), 4 * n * 16 / min(ts))
"""


def measure(split: bool, n: int) -> tuple[int, float]:
    env = dict(os.environ, PYTHONPATH=ROOT + os.pathsep + os.environ.get("PYTHONPATH", ""))
    r = subprocess.run([sys.executable, "-c", CHILD, str(int(split)), str(n)], capture_output=True, text=True,
                       env=env, check=False)
    line = [x for x in r.stdout.splitlines() if x.startswith("RESULT")]
    if r.returncode or not line:
        raise RuntimeError(f"split={split} n={n} failed:\n{r.stderr[-2000:]}")
    _, devices, sps = line[0].split()
    return int(devices), float(sps)


@dataclasses.dataclass
class Settings:
    """envs: env batch sizes to time; out: the CSV written."""
    envs: tuple[int, ...] = (256, 1024)
    out: str = os.path.join(HERE, "results", "ppo_cpu_split.csv")


def main(args: Settings):
    rows = []
    for n in args.envs:
        for split in (False, True):
            devices, sps = measure(split, n)
            rows.append({"env": "hopper", "num_envs": n, "split_envs": split, "devices": devices,
                         "cores": os.cpu_count(), "env_steps_per_s_incl_learning": round(sps)})
            print(rows[-1], flush=True)
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    with open(args.out, "w", newline="") as f:
        w = csv.DictWriter(f, list(rows[0]))
        w.writeheader()
        w.writerows(rows)


if __name__ == "__main__":
    from sim2real.common.cli import settings

    main(settings(Settings, sys.argv[1:]))
