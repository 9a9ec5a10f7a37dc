"""PPO through the training driver: wall time to a target return, training throughput, final return.

    python benchmarks/hopper_ppo.py [key=value overrides of configs/hopper.yaml]          # GPU, target 2500
    python benchmarks/hopper_ppo.py config=configs/pendulum.yaml target=-200 out_dir=...  # CPU pendulum

Trains with ``configs/hopper.yaml`` (or ``config=``) through the normal driver (so the run folder
has config, metrics.csv and policy.msgpack), then evaluates the deterministic policy of *every*
seed (``num_seeds=5`` for the headline) on ``eval_episodes=`` episodes (default 128) of the nominal
env. Prints one summary line -- per-seed returns, their mean, worst and spread -- and writes
``<out_dir>/<name>/summary.json`` and ``curve.png`` (training return against wall time).
Training throughput = env steps / wall time of the jitted chunks (learning included, compilation
excluded; the time to compile is reported separately).
"""
from __future__ import annotations

import csv
import dataclasses
import json
import os
import sys
import time

import jax
import numpy as np

from sim2real.common import config as config_lib
from sim2real.rl.episodes import episodes
from sim2real.training.driver import TrainConfig, train

HERE = os.path.dirname(os.path.abspath(__file__))


@dataclasses.dataclass
class Settings:
    """target: the return whose first crossing is timed; eval_episodes: nominal episodes per seed."""
    target: float = 2500.0
    eval_episodes: int = 128


def load_args(argv, settings):
    """``key=value`` arguments -> ``(own, cfg)``: the script's own ``settings`` (a dataclass, its
    fields' keys) and the ``TrainConfig`` from the rest (``config=`` default: ``configs/hopper.yaml``)."""
    mine, rest = config_lib.split(argv, settings)
    config = next((a for a in rest if a.startswith("config=")), f"config={os.path.join(HERE, '..', 'configs', 'hopper.yaml')}")
    return (config_lib.load(settings, mine),
            config_lib.load(TrainConfig, [config, *(a for a in rest if not a.startswith("config="))]))


def main(argv):
    own, cfg = load_args(argv, Settings)
    target, n_eval = own.target, own.eval_episodes
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
    hit = [float(r["wall_seconds"]) for r, e, x in zip(rows, eps, ret) if e > 0 and x >= target]
    env, algo = out["env"], out["algo"]
    per_seed = []
    zs = np.tile(env.default_z(), (n_eval, 1))
    # one compiled evaluation for every seed (same shapes), not a trace per seed
    evaluate = jax.jit(lambda p, st: episodes(env, algo.ppo, p, st, zs, jax.random.PRNGKey(1)))
    for s in range(cfg.num_seeds):
        params, stats = algo.policy(jax.tree_util.tree_map(lambda x: x[s], out["state"]))
        res = evaluate(params, stats)
        per_seed.append({"seed": s, "return_mean": float(np.mean(res["return"])),
                         "return_std": float(np.std(res["return"])), "length_mean": float(np.mean(res["length"]))})
    means = np.array([p["return_mean"] for p in per_seed])
    last = {}
    for r in rows:  # the last training-episode return each seed logged
        if float(r["episodes"]) > 0:
            last[r["seed"]] = float(r["episode_return"])
    summary = {
        "device": f"{jax.devices()[0].device_kind}", "env_steps": int(steps.max()), "wall_seconds": round(wall, 1),
        "compile_and_first_chunk_seconds": round(first_chunk_end, 1),
        "train_steps_per_second": round(sps), f"seconds_to_train_return_{target:g}": hit[0] if hit else None,
        "num_seeds": cfg.num_seeds, "eval_episodes_per_seed": n_eval,
        "eval_return_mean": float(means.mean()), "eval_return_worst": float(means.min()),
        "eval_return_best": float(means.max()), "eval_return_seed_std": float(means.std(ddof=1)) if len(means) > 1 else 0.0,
        "eval_per_seed": per_seed, "final_training_return_per_seed": last,
    }
    with open(os.path.join(out["run_dir"], "summary.json"), "w") as f:
        json.dump(summary, f, indent=2)
    print("SUMMARY", json.dumps(summary))
    curve(rows, target, summary, f"{cfg.env} PPO on {summary['device']}", os.path.join(out["run_dir"], "curve.png"))


def curve(rows, target, summary, title, path, extra=None):
    """Training return of every seed against wall time (``rows``: the run's metrics.csv), the
    final deterministic evaluation and the target; ``extra(ax)`` draws more (Brax's curve)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for seed in sorted({r["seed"] for r in rows}):
        mine = [r for r in rows if r["seed"] == seed and float(r["episodes"]) > 0]
        ax.plot([float(r["wall_seconds"]) for r in mine], [float(r["episode_return"]) for r in mine],
                label=f"sim2real PPO, seed {seed}, training episodes")
    if extra is not None:
        extra(ax)
    ax.axhline(summary["eval_return_mean"], color="C0", ls=":",
               label=f"sim2real final, deterministic eval (mean of {summary.get('num_seeds', 1)} seeds)")
    ax.axhline(target, color="gray", lw=0.8, label=f"target {target:g}")
    ax.set_xlabel("wall time incl. compilation [s]")
    ax.set_ylabel("episode return")
    ax.set_title(title)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


if __name__ == "__main__":
    main(sys.argv[1:])
