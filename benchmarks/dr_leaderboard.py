"""One out-of-distribution leaderboard: every method trained with the same env-step budget, its
final policy of every seed scored on a physics grid that reaches outside the training box.

    python benchmarks/dr_leaderboard.py task=pendulum            # CPU, minutes: the machinery
    python benchmarks/dr_leaderboard.py task=hopper seeds=5      # GPU: seed 004's grid

Methods (``methods=``, comma-separated): ``fixed`` (nominal physics), ``udr`` (uniform DR, MLP),
``udr_lstm`` (uniform DR, LSTM), ``udr_context`` (uniform DR, the true physics as the policy's
input: an upper bound), ``lsdr`` (learned distribution), ``epopt`` (EPOpt-PPO over the box),
``adr`` (automatic DR) and ``doraemon`` (entropy maximisation under a success constraint), the
last two learning their own box inside a wider limit box (see ``TASKS``), and ``es_maml``
(meta-trained from a uniform-DR policy that used the first 75% of its budget; scored after its
adaptation operator).
Each trains through the driver (``scripts/train.py``'s), seeds vmapped, and the driver's ``test``
section scores the final policies on the grid (one full episode per cell and seed). Statistics:
``sim2real.tools.leaderboard`` (means with 95% seed-bootstrap intervals in / outside the box and
over all cells, the fraction of cells above ``threshold``, each method against the best).
Writes ``<out>/<task>/returns.npz`` (``<method>: [S, N]``, ``z``, ``in_box``), ``summary.md`` and
``leaderboard.png``.
"""
from __future__ import annotations

import dataclasses
import json
import os
import sys
import time

import numpy as np

from sim2real.common.cli import settings

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)

TASKS = {
    "pendulum": {  # swing-up; a light pendulum with little friction is the training box
        "config": "configs/pendulum.yaml", "steps": 1_500_000, "threshold": -300.0,
        "box": {"mass:pole": (0.7, 1.3), "coulomb:hinge": (0.0, 0.1)},
        "grid": {"mass:pole": np.linspace(0.3, 2.1, 7), "coulomb:hinge": np.linspace(0.0, 0.4, 5)},
        "limit": {"mass:pole": (0.1, 4.0), "coulomb:hinge": (0.0, 1.0)}, "num_evals": 16,
        "es_maml": ["ppo.num_envs=16", "ppo.num_steps=64", "ppo.num_minibatches=2", "algo_options.population=8",
                    "algo_options.eval_horizon=200", "updates_per_chunk=1"],
    },
    "hopper": {  # seed 004's grid (12 x 8) and training box
        "config": "configs/hopper.yaml", "steps": 50_000_000, "threshold": 1000.0,
        "box": {"mass:torso": (1.0, 9.0), "friction": (1.5, 2.5)},
        "grid": {"mass:torso": np.linspace(0.5, 11.5, 12), "friction": np.linspace(0.1, 2.9, 8)},
        "limit": {"mass:torso": (0.4, 15.0), "friction": (0.05, 4.0)}, "num_evals": 32,
        # benchmarks/es_maml_hopper.py's settings (seed 004's inner loop: 3 PPO updates x 4096 steps)
        "es_maml": ["ppo.num_envs=256", "ppo.num_steps=16", "ppo.num_minibatches=4", "algo_options.population=32",
                    "algo_options.meta_lr=0.002", "algo_options.eval_horizon=300", "algo_options.eval_episodes=2",
                    "updates_per_chunk=1"],
    },
}
# ADR and DORAEMON learn where to randomise inside a "limit" box (chosen from the nominal physics
# -- mass nominal/10 or /8 to 4x, friction up to what the motor or the floor plausibly sees --
# before any run, not from the grid); both start from the training box of the fixed-box methods.
# Their thresholds derive from the task's solved-cell threshold by one rule, set before any run:
# ADR shrinks a bound at or below it and widens it at or above it + |it| / 2; a DORAEMON episode
# succeeds at or above it, and the success rate must stay >= 0.5.
METHODS = {
    "fixed": ["algo=udr"],
    "udr": ["algo=udr", "BOX"],
    "udr_lstm": ["algo=udr", "BOX", "ppo.net.kind=lstm"],
    "udr_context": ["algo=udr", "BOX", "ppo.net.use_context=true"],
    "lsdr": ["algo=lsdr", "BOX", "ppo.net.use_context=true"],
    "epopt": ["algo=fixed_dr", "BOX", "algo_options.policy_optimizer=epopt"],
    "adr": ["algo=adr", "LIMIT", "START", "ADR"],
    "doraemon": ["algo=doraemon", "LIMIT", "START", "DORAEMON"],
    "es_maml": ["algo=es_maml", "BOX", "ESMAML"],
}
# ES-MAML meta-trained from scratch needs far more than these budgets (one hopper meta-iteration
# is 0.4M env steps): as in seed 004's scaled reproduction it starts from a uniform-DR policy,
# trained here for WARM_FRACTION of the budget, and meta-trains for the rest; both count. It is
# scored after its adaptation operator (3 PPO updates on each grid cell, not counted).
WARM = {"es_maml": ("udr", 0.75)}
ADAPTED = {"es_maml"}


def method_args(method: str, task: dict, threshold: float) -> list[str]:
    """``key=value`` settings of ``method`` on ``task`` (the placeholders of METHODS filled in)."""
    def box(b):
        return [f"dr.params=[{','.join(b)}]", f"dr.low={[v[0] for v in b.values()]}",
                f"dr.high={[v[1] for v in b.values()]}"]

    fill = {
        "BOX": box(task["box"]), "LIMIT": box(task.get("limit", {})),
        "START": [f"algo_options.init_low={[v[0] for v in task['box'].values()]}",
                  f"algo_options.init_high={[v[1] for v in task['box'].values()]}"],
        "ADR": [f"algo_options.t_low={threshold}", f"algo_options.t_high={threshold + abs(threshold) / 2}",
                f"algo_options.num_evals={task.get('num_evals', 32)}"],
        "DORAEMON": [f"algo_options.success_return={threshold}", f"algo_options.num_evals={task.get('num_evals', 32)}"],
        "ESMAML": task.get("es_maml", []),
    }
    return [x for m in METHODS[method] for x in fill.get(m, [m])]


@dataclasses.dataclass
class Settings:
    """task: a key of TASKS; methods: comma-separated keys of METHODS; seeds: per method (5 where a
    ranking is claimed); scale: multiplies the task's env-step budget; threshold: return a cell
    counts as solved at (default: the task's); out: results root; work: run folders (replaced);
    merge_from: ``returns.npz`` files of earlier calls (same task, seeds and budget) whose methods
    join this table (a leaderboard trained over several device calls; ``methods=`` may then be
    empty)."""
    task: str = "pendulum"
    methods: str = "fixed,udr,udr_context,lsdr,epopt"
    seeds: int = 5
    scale: float = 1.0
    threshold: float | None = None
    out: str = os.path.join(HERE, "results", "dr_leaderboard")
    work: str = "/tmp/dr_leaderboard_runs"
    merge_from: tuple[str, ...] = ()


def grid_points(task: dict) -> tuple[list[str], np.ndarray, np.ndarray]:
    """``(names, points [N, 2], in_box [N])`` of the task's grid (first axis major)."""
    names = list(task["grid"])
    mesh = np.meshgrid(*[task["grid"][n] for n in names], indexing="ij")
    points = np.stack([m.ravel() for m in mesh], 1)
    in_box = np.all([(points[:, i] >= task["box"][n][0]) & (points[:, i] <= task["box"][n][1])
                     for i, n in enumerate(names)], 0)
    return names, points, in_box


def train_method(method: str, task: dict, args: Settings, names, points, threshold: float) -> np.ndarray:
    """The method's final policies on the grid: ``[S, N]`` returns."""
    from sim2real.common import config as config_lib
    from sim2real.training.driver import train
    from sim2real.training.runs import TestConfig, TrainConfig

    def config(name, settings, steps):
        return config_lib.load(TrainConfig, [f"config={os.path.join(ROOT, task['config'])}", f"name={name}",
                                             f"out_dir={args.work}", "overwrite=true", "progress=false",
                                             "tensorboard=false", f"num_seeds={args.seeds}",
                                             f"total_steps={steps}"] + settings)

    budget = int(task["steps"] * args.scale)
    extra = method_args(method, task, threshold)
    if method in WARM:  # the warm start's steps count in the method's budget
        first, fraction = WARM[method]
        warm = train(config(f"{method}_warm", method_args(first, task, threshold), int(budget * fraction)))
        extra = extra + [f"algo_options.warm_start={warm['run_dir']}"]
        budget -= int(budget * fraction)
    cfg = config(method, extra, budget)
    test = TestConfig(every=10**9, params=tuple(names), points=tuple(tuple(map(float, p)) for p in points),
                      adapt=method in ADAPTED)
    out = train(dataclasses.replace(cfg, test=test))  # tested before the first chunk and after the last
    with np.load(os.path.join(out["run_dir"], "test.npz")) as f:
        return f["returns"][-1]


def plot(results: dict, in_box, stats: dict, path: str, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    methods = list(results)
    fig, ax = plt.subplots(figsize=(1.6 + 1.3 * len(methods), 3.6))
    width = 0.27
    for k, (region, label) in enumerate((("in_box", "in the box"), ("out_of_box", "outside"), ("all", "all cells"))):
        x = np.arange(len(methods)) + (k - 1) * width
        m = np.array([stats[n][region]["mean"] for n in methods])
        err = np.array([[m[i] - stats[n][region]["low"], stats[n][region]["high"] - m[i]] for i, n in enumerate(methods)]).T
        ax.bar(x, m, width, yerr=err, capsize=3, label=label)
    ax.set_xticks(np.arange(len(methods)), methods)
    ax.set_ylabel("mean episode return (95% CI over seeds)")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(args: Settings) -> dict:
    import jax

    from sim2real.tools import leaderboard

    if args.task not in TASKS:
        raise SystemExit(f"task={args.task}: one of {', '.join(TASKS)}")
    methods = [m for m in args.methods.split(",") if m]
    unknown = [m for m in methods if m not in METHODS]
    if unknown:
        raise SystemExit(f"methods: unknown {unknown}; known: {', '.join(METHODS)}")
    task = TASKS[args.task]
    threshold = task["threshold"] if args.threshold is None else args.threshold
    names, points, in_box = grid_points(task)
    out = os.path.join(args.out, args.task)
    os.makedirs(out, exist_ok=True)
    results, seconds, devices = {}, {}, set()
    for path in args.merge_from:
        with np.load(path) as f:
            if not np.array_equal(f["points"], points):
                raise SystemExit(f"merge_from {path}: another grid than task={args.task}'s")
            seconds.update(json.loads(str(f["seconds"])))
            devices.add(str(f["device"]))
            results.update({m: f[m] for m in json.loads(str(f["methods"]))})
    for method in methods:
        t0 = time.time()
        results[method] = train_method(method, task, args, names, points, threshold)
        seconds[method] = round(time.time() - t0, 1)
        print(f"{method}: mean return {results[method].mean():.1f} over {len(points)} cells x {args.seeds} seeds "
              f"({seconds[method]:.0f} s)", flush=True)
    stats = {m: leaderboard.grid_stats(r, in_box, threshold) for m, r in results.items()}
    if methods or not devices:
        devices.add(f"{jax.devices()[0].device_kind} ({jax.default_backend()})")
    device = " and ".join(sorted(devices))
    np.savez(os.path.join(out, "returns.npz"), points=points, names=np.array(names), in_box=in_box,
             methods=json.dumps(list(results)), seconds=json.dumps(seconds), device=device, **results)
    budget = int(task["steps"] * args.scale)
    grid = " x ".join(f"{n} {len(task['grid'][n])} values [{task['grid'][n][0]:g}, {task['grid'][n][-1]:g}]"
                      for n in names)
    box = ", ".join(f"{n} [{lo:g}, {hi:g}]" for n, (lo, hi) in task["box"].items())
    head = (f"# DR leaderboard: {args.task}\n\n{args.seeds} seeds per method, {budget:,} env steps per seed, "
            f"device {device}; grid {grid}; training box {box} ({int(in_box.sum())} of {len(points)} cells "
            f"inside). Seconds per method: {json.dumps(seconds)}. GPU runs are not bit-reproducible.\n\n")
    text = head + leaderboard.table(results, in_box, threshold)
    with open(os.path.join(out, "summary.md"), "w") as f:
        f.write(text)
    plot(results, in_box, stats, os.path.join(out, "leaderboard.png"), f"{args.task}: {args.seeds} seeds, {budget:,} steps")
    print(text)
    return {"results": results, "stats": stats, "in_box": in_box, "out": out}


if __name__ == "__main__":
    main(settings(Settings, sys.argv[1:]))
