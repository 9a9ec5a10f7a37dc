"""sim2real's PPO and Brax's PPO on hopper, 5 seeds each, one figure: return against env steps and
against wall time, and a table of both at the budget every run reached.

    python benchmarks/plot_ppo_vs_brax.py results=DIR   # default benchmarks/results/ppo_seeds

Reads ``hopper_g0995_100M_5seeds_seed1_metrics.csv`` (sim2real: the 5 seeds of one vmapped run;
per update its training episode return, stochastic policy) and ``brax_5seeds/seed*_g0995.jsonl``
(Brax 0.14.2, ``benchmarks/brax_ppo_hopper.py``, one process per seed, run one after another;
its deterministic evaluations on 128 envs). Writes ``ppo_vs_brax.png`` and ``ppo_vs_brax.md``.
"""
from __future__ import annotations

import csv
import dataclasses
import glob
import json
import os
import sys

import numpy as np

from sim2real.common.cli import settings

HERE = os.path.dirname(os.path.abspath(__file__))


@dataclasses.dataclass
class Settings:
    """results: the folder holding the runs' files (the figure is written there)."""
    results: str = os.path.join(HERE, "results", "ppo_seeds")


def load(d: str):
    ours = {}
    for r in csv.DictReader(open(os.path.join(d, "hopper_g0995_100M_5seeds_seed1_metrics.csv"))):
        ours.setdefault(int(r["seed"]), []).append(
            (float(r["env_steps"]), float(r["wall_seconds"]), float(r["episode_return"])))
    brax = {}
    for p in sorted(glob.glob(os.path.join(d, "brax_5seeds", "seed*_g0995.jsonl"))):
        seed = int(os.path.basename(p)[4])
        rows = [json.loads(x) for x in open(p) if x.startswith("{")]
        brax[seed] = [(r["env_steps"], r["wall_seconds"], r["eval_return"]) for r in rows]
    return ({k: np.array(v) for k, v in ours.items()}, {k: np.array(v) for k, v in brax.items()})


def at(curve: np.ndarray, steps: float) -> float:
    """The curve's return at its first point at or past ``steps`` env steps (NaN if it ended before)."""
    i = np.searchsorted(curve[:, 0], steps)
    return float(curve[i, 2]) if i < len(curve) else float("nan")


def main(args: Settings):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    d = args.results
    ours, brax = load(d)
    budget = min(c[-1, 0] for c in brax.values())  # the budget every Brax run reached
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for curves, colour, style, name in ((ours, "C0", "-", "sim2real PPO (training return)"),
                                        (brax, "C3", "o--", "Brax PPO (deterministic evals)")):
        for i, (seed, c) in enumerate(sorted(curves.items())):
            axes[0].plot(c[:, 0] / 1e6, c[:, 2], style, color=colour, alpha=0.7, ms=3, label=name if i == 0 else None)
            axes[1].plot(c[:, 1], c[:, 2], style, color=colour, alpha=0.7, ms=3, label=name if i == 0 else None)
    axes[0].axvline(budget / 1e6, color="grey", lw=0.8, ls=":")
    axes[0].set_xlabel("env steps (millions, per seed)")
    axes[1].set_xlabel("wall time (s; sim2real: 5 seeds in one run; Brax: each seed alone)")
    for ax in axes:
        ax.set_ylabel("episode return")
        ax.grid(alpha=0.3)
        ax.legend(loc="lower right", fontsize=8)
    fig.suptitle("Hopper, 5 seeds each, gamma 0.995, 4096 envs x 32 steps, one NVIDIA H100")
    fig.tight_layout()
    png = os.path.join(d, "ppo_vs_brax.png")
    fig.savefig(png, dpi=120)
    o = [at(c, budget) for _, c in sorted(ours.items())]
    b = [at(c, budget) for _, c in sorted(brax.items())]
    def wall(c):  # wall time at the first point at or past the budget
        return float(c[np.searchsorted(c[:, 0], budget), 1])

    t_o = wall(ours[min(ours)])  # the five seeds share one run's clock
    t_b = [wall(c) for _, c in sorted(brax.items())]
    lines = [f"At {budget / 1e6:.1f}M env steps per seed (the budget every Brax run reached):", "",
             "| | per seed | mean | worst | wall time to get there |", "|---|---|---|---|---|",
             f"| sim2real PPO (training return) | {', '.join(f'{x:.0f}' for x in o)} | {np.mean(o):.0f} | {np.min(o):.0f} "
             f"| {t_o:.0f} s for all 5 seeds together |",
             f"| Brax PPO (deterministic eval) | {', '.join(f'{x:.0f}' for x in b)} | {np.mean(b):.0f} | {np.min(b):.0f} "
             f"| {np.mean(t_b):.0f} s per seed ({np.sum(t_b):.0f} s for 5) |", ""]
    with open(os.path.join(d, "ppo_vs_brax.md"), "w") as f:
        f.write("\n".join(lines))
    print("\n".join(lines))
    print(f"wrote {png}")


if __name__ == "__main__":
    main(settings(Settings, sys.argv[1:]))
