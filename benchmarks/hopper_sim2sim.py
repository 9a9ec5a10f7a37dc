"""Run the GPU-trained hopper policy in Gymnasium's Hopper-v5 (native MuJoCo, RK4, 2 ms x 4, default
solver, every geom colliding) and in our MJX hopper, on the CPU: does the tuned simulator transfer?

    python benchmarks/hopper_sim2sim.py run=RUN_DIR episodes=20

Writes ``<run_dir>/sim2sim.json``.
"""
from __future__ import annotations

import dataclasses
import json
import os
import sys

import jax
import numpy as np

from sim2real.common.cli import settings
from sim2real.rl import normalize
from sim2real.rl.episodes import episodes
from sim2real.training.runs import load_policy

HERE = os.path.dirname(os.path.abspath(__file__))


def gym_returns(algo, params, stats, n, seed=0):
    import gymnasium as gym

    env = gym.make("Hopper-v5")
    act = jax.jit(lambda o: algo.ppo.net.apply(params, normalize.apply(stats, o), np.zeros(0, np.float32),
                                               np.zeros(0, np.float32), np.zeros((), bool))[0][0])
    rets, lens = [], []
    for i in range(n):
        obs, _ = env.reset(seed=seed + i)
        total, t, done = 0.0, 0, False
        while not done:
            a = np.clip(np.asarray(act(obs.astype(np.float32))), -1, 1)
            obs, r, term, trunc, _ = env.step(a)
            total, t, done = total + r, t + 1, term or trunc
        rets.append(total)
        lens.append(t)
    return np.array(rets), np.array(lens)


@dataclasses.dataclass
class Settings:
    """run: the trained hopper run folder; episodes: episodes in each simulator."""
    run: str = os.path.join(HERE, "results", "hopper_ppo_gpu")
    episodes: int = 20


def main(args: Settings):
    run, n = args.run, args.episodes
    cfg, env, algo, params, stats = load_policy(run)
    params, stats = jax.tree_util.tree_map(lambda x: x[0], (params, stats))
    g_ret, g_len = gym_returns(algo, params, stats, n)
    res = episodes(env, algo.ppo, params, stats, np.tile(env.default_z(), (n, 1)), jax.random.PRNGKey(0))
    out = {"gymnasium_hopper_v5": {"return_mean": float(g_ret.mean()), "return_std": float(g_ret.std()),
                                   "length_mean": float(g_len.mean()), "episodes": n},
           "sim2real_mjx_cpu": {"return_mean": float(np.mean(res["return"])), "return_std": float(np.std(res["return"])),
                                "length_mean": float(np.mean(res["length"])), "episodes": n}}
    with open(os.path.join(run, "sim2sim.json"), "w") as f:
        json.dump(out, f, indent=2)
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main(settings(Settings, sys.argv[1:]))
