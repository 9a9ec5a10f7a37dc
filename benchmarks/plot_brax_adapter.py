"""Brax's PPO through ``sim2real.interop.brax`` and sim2real's PPO on the same hopper, the same
physics box (torso mass [1, 9] kg x friction [1.5, 2.5], redrawn at every reset) and budget: one
figure of deterministic evaluation return against env steps, and a table at the last common budget.

    python benchmarks/plot_brax_adapter.py results=benchmarks/results/brax_adapter

Reads ``brax_ppo_sim2real_dr_seed*.csv`` (``benchmarks/brax_ppo_hopper.py env=sim2real dr=true``:
Brax's evaluations, 128 envs, each episode's physics drawn from the box) and ``sim2real_test.npz``
(the driver's ``test`` section of ``scripts/train.py``: a 4 x 4 grid over the same box, one
episode per point and seed). Writes ``brax_adapter.png`` and ``brax_adapter.md``.
"""
from __future__ import annotations

import csv
import dataclasses
import glob
import os
import sys

import numpy as np

from sim2real.common.cli import settings

HERE = os.path.dirname(os.path.abspath(__file__))


@dataclasses.dataclass
class Settings:
    """results: the folder holding both sides' files (the figure is written there)."""
    results: str = os.path.join(HERE, "results", "brax_adapter")


def read_brax(folder: str) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per seed ``(env_steps [E], eval_return [E])``."""
    runs = []
    for path in sorted(glob.glob(os.path.join(folder, "brax_ppo_sim2real_dr_seed*.csv"))):
        with open(path) as f:
            rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
        runs.append((np.array([int(r["env_steps"]) for r in rows]), np.array([float(r["eval_return"]) for r in rows])))
    if not runs:
        raise SystemExit(f"no brax_ppo_sim2real_dr_seed*.csv in {folder}")
    return runs


def main(args: Settings) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    brax = read_brax(args.results)
    with np.load(os.path.join(args.results, "sim2real_test.npz")) as f:
        steps, ours = f["env_steps"], f["returns"].mean(-1)          # [E], [E, S]
    fig, ax = plt.subplots(figsize=(6.4, 3.8))
    for k, (x, y) in enumerate(brax):
        ax.plot(x / 1e6, y, color="tab:orange", alpha=0.8, label="Brax PPO through the adapter" if k == 0 else None)
    for s in range(ours.shape[1]):
        ax.plot(steps / 1e6, ours[:, s], color="tab:blue", alpha=0.8, label="sim2real PPO" if s == 0 else None)
    ax.set_xlabel("env steps per seed (millions)")
    ax.set_ylabel("deterministic return (mean over the box)")
    ax.set_title("hopper, physics redrawn at every reset (one line per seed)", fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    png = os.path.join(args.results, "brax_adapter.png")
    fig.savefig(png, dpi=120)
    plt.close(fig)
    budget = min(min(int(x[-1]) for x, _ in brax), int(steps[-1]))

    def at(x, y):  # the last evaluation at or below the common budget
        return float(y[np.searchsorted(x, budget, side="right") - 1])

    b = [at(x, y) for x, y in brax]
    o = [at(steps, ours[:, s]) for s in range(ours.shape[1])]
    text = (f"At {budget:,} env steps per seed (the last evaluation at or below the budget every run reached):\n\n"
            "| | seeds | per seed | mean |\n|---|---|---|---|\n"
            f"| Brax PPO through sim2real.interop.brax | {len(b)} | {', '.join(f'{v:.0f}' for v in b)} | {np.mean(b):.0f} |\n"
            f"| sim2real PPO | {len(o)} | {', '.join(f'{v:.0f}' for v in o)} | {np.mean(o):.0f} |\n")
    with open(os.path.join(args.results, "brax_adapter.md"), "w") as f:
        f.write(text)
    print(text)
    return png


if __name__ == "__main__":
    main(settings(Settings, sys.argv[1:]))
