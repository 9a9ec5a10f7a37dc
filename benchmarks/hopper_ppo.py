"""Hopper PPO on one GPU: wall time to a return of 2500, training throughput, final return.

    python benchmarks/hopper_ppo.py [key=value overrides of configs/hopper.yaml]

Trains with ``configs/hopper.yaml`` through the normal driver (so the run folder has config,
metrics.csv and policy.msgpack), then evaluates the deterministic policy on 128 episodes of the
nominal hopper. Prints one summary line and writes ``<out_dir>/<name>/summary.json``.
Training throughput = env steps / wall time of the jitted chunks (learning included, compilation
excluded; the time to compile is reported separately).
"""
from __future__ import annotations

import csv
import json
import os
import sys
import time

import jax
import numpy as np

from sim2real import config as config_lib
from sim2real.evaluate import episodes
from sim2real.train import TrainConfig, train

HERE = os.path.dirname(os.path.abspath(__file__))


def main(argv):
    cfg = config_lib.load(TrainConfig, [f"config={os.path.join(HERE, '..', 'configs', 'hopper.yaml')}", *argv])
    t0 = time.time()
    out = train(cfg)
    wall = time.time() - t0
    rows = list(csv.DictReader(open(os.path.join(out["run_dir"], "metrics.csv"))))
    # first chunk includes compilation: throughput from chunk wall-clock stamps after it
    stamps = sorted({float(r["wall_seconds"]) for r in rows})
    steps = np.array([int(r["env_steps"]) for r in rows])
    first_chunk_end = stamps[0]
    k = cfg.updates_per_chunk
    sps = (steps.max() - k * cfg.ppo.batch_size) * cfg.num_seeds / max(stamps[-1] - first_chunk_end, 1e-9)
    ret = np.array([float(r["episode_return"]) for r in rows])
    eps = np.array([float(r["episodes"]) for r in rows])
    hit = [float(r["wall_seconds"]) for r, e, x in zip(rows, eps, ret) if e > 0 and x >= 2500]
    env, algo = out["env"], out["algo"]
    params, stats = algo.policy(jax.tree_util.tree_map(lambda x: x[0], out["state"]))
    res = episodes(env, algo.ppo, params, stats, np.tile(env.default_z(), (128, 1)), jax.random.PRNGKey(1))
    summary = {
        "device": f"{jax.devices()[0].device_kind}", "env_steps": int(steps.max()), "wall_seconds": round(wall, 1),
        "compile_and_first_chunk_seconds": round(first_chunk_end, 1),
        "train_steps_per_second": round(sps), "seconds_to_train_return_2500": hit[0] if hit else None,
        "eval_return_mean": float(np.mean(res["return"])), "eval_return_std": float(np.std(res["return"])),
        "eval_length_mean": float(np.mean(res["length"])),
    }
    with open(os.path.join(out["run_dir"], "summary.json"), "w") as f:
        json.dump(summary, f, indent=2)
    print("SUMMARY", json.dumps(summary))


if __name__ == "__main__":
    main(sys.argv[1:])
