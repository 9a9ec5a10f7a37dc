"""A MuJoCo Playground task trained with sim2real's LSDR (and uniform DR beside it), GPU scale.

    python benchmarks/playground_lsdr.py                    # seeds=3, out=benchmarks/results/playground_lsdr
    python benchmarks/playground_lsdr.py total_steps=1e6    # a smaller run

The task is dm_control suite's CheetahRun from the ``playground`` package, brought into sim2real by
``sim2real/envs/playground.py`` (its MjModel read into a ParamSpec; its reward and observation
its own). Both methods train ``configs/playground_cheetah_lsdr.yaml``'s budget over its prior box of
torso mass x floor friction x joint-damping multiplier: ``lsdr`` learns a Gaussian inside it,
``udr`` samples it uniformly. Each run is then evaluated over torso mass x friction (damping at
the box centre) with ``sim2real.tools.evaluate``. Writes ``<out>/summary.md``, ``results.csv``
(method, seed, mean return over the grid), the training curves ``curves.png`` and each
run's ``eval`` heat map and ``metrics.csv``.
"""
from __future__ import annotations

import csv
import dataclasses
import os
import shutil
import time

import numpy as np

from sim2real.common.cli import settings

HERE = os.path.dirname(os.path.abspath(__file__))


@dataclasses.dataclass
class Settings:
    """seeds: training seeds (vmapped in one run); total_steps: env steps per seed; methods:
    comma-separated of lsdr, udr; episodes: evaluation episodes per grid cell and seed; grid: cells
    per axis; train: more training overrides, space-separated ``key=value``; out: results folder;
    work: run folders (not kept)."""
    seeds: int = 3
    total_steps: float = 20e6
    methods: str = "lsdr,udr"
    episodes: int = 4
    grid: int = 5
    train: str = ""
    out: str = os.path.join(HERE, "results", "playground_lsdr")
    work: str = "/tmp/playground_lsdr_runs"


def main(args: Settings):
    import jax

    from sim2real.common import config as config_lib
    from sim2real.tools.evaluate import EvaluateConfig, evaluate_run
    from sim2real.training.driver import TrainConfig, train

    shutil.rmtree(args.work, ignore_errors=True)
    os.makedirs(args.out, exist_ok=True)
    device = jax.devices()[0].device_kind
    rows, curves, lines = [], {}, []
    for method in [m for m in args.methods.split(",") if m]:
        over = ["config=playground_cheetah_lsdr", f"num_seeds={args.seeds}", f"total_steps={int(args.total_steps)}",
                f"out_dir={args.work}", f"name={method}", "tensorboard=false"] + args.train.split()
        cfg = config_lib.load(TrainConfig, over)
        if method == "udr":  # the same box, sampled uniformly (LSDR's options dropped)
            cfg = dataclasses.replace(cfg, algo="udr", algo_options={})
        t = time.time()
        run = train(cfg)["run_dir"]
        seconds = time.time() - t
        lo, hi = cfg.dr.low, cfg.dr.high
        ev = evaluate_run(config_lib.load(EvaluateConfig, [
            f"run={run}", f"x=mass:torso={lo[0]}:{hi[0]}:{args.grid}", f"y=friction={lo[1]}:{hi[1]}:{args.grid}",
            f"episodes={args.episodes}", "progress=false"]))
        grid_means = np.asarray(ev["per_seed"]).mean(1)                # [S]
        for seed, g in enumerate(grid_means):
            rows.append({"method": method, "seed": seed, "grid_return": round(float(g), 1)})
        with open(os.path.join(run, "metrics.csv")) as f:
            m = list(csv.DictReader(f))
        curves[method] = m
        dest = os.path.join(args.out, method)
        shutil.rmtree(dest, ignore_errors=True)
        shutil.copytree(os.path.join(run, "eval"), os.path.join(dest, "eval"))
        shutil.copy(os.path.join(run, "metrics.csv"), dest)
        shutil.copy(os.path.join(run, "config.yaml"), dest)
        lines.append(f"| {method} | " + ", ".join(f"{float(g):.1f}" for g in grid_means)
                     + f" | {np.mean(grid_means):.1f} | {seconds:.0f} |")
        print(lines[-1], flush=True)
    with open(os.path.join(args.out, "results.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["method", "seed", "grid_return"])
        w.writeheader()
        w.writerows(rows)
    head = [f"# Playground CheetahRun through sim2real ({device}, {args.seeds} seeds, "
            f"{args.total_steps:.3g} env steps per seed)", "",
            f"Return of {cfg.env_options.get('episode_length', 1000)}-step episodes (the task's reward, at most 1 per step), {args.episodes} episodes "
            f"per cell; grid: torso mass x friction over the prior box, {args.grid} x {args.grid}, damping "
            "multiplier at the box centre. GPU runs are not bit-reproducible.", "",
            "| method | grid mean per seed | mean | train seconds |", "|---|---|---|---|"]
    with open(os.path.join(args.out, "summary.md"), "w") as f:
        f.write("\n".join(head + lines) + "\n")
    _plot(curves, os.path.join(args.out, "curves.png"))


def _plot(curves, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 3.5))
    for (method, rows), c in zip(curves.items(), ("C0", "C1")):
        seeds = sorted({r["seed"] for r in rows})
        for s in seeds:
            pts = [(float(r["env_steps"]), float(r["episode_return"])) for r in rows
                   if r["seed"] == s and r["episode_return"] not in ("", "nan")]
            if pts:
                x, y = zip(*pts)
                ax.plot(np.array(x) / 1e6, y, color=c, alpha=0.8, label=method if s == seeds[0] else None)
    ax.set_xlabel("env steps per seed (millions)")
    ax.set_ylabel("training episode return")
    ax.set_title("Playground CheetahRun: sim2real LSDR vs uniform DR")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)


if __name__ == "__main__":
    import sys

    main(settings(Settings, sys.argv[1:]))
