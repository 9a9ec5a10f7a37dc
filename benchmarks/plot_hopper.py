"""Learning curves of the GPU hopper runs: sim2real PPO vs Brax PPO, return against wall time.

    python benchmarks/plot_hopper.py results=DIR   # default benchmarks/results/hopper_ppo_gpu
"""
from __future__ import annotations

import csv
import dataclasses
import json
import os
import sys

from sim2real.common.cli import settings

HERE = os.path.dirname(os.path.abspath(__file__))


@dataclasses.dataclass
class Settings:
    """results: the folder holding the runs' files (the figure is written there)."""
    results: str = os.path.join(HERE, "results", "hopper_ppo_gpu")


def main(args: Settings):
    from hopper_ppo import curve

    d = args.results
    rows = list(csv.DictReader(open(os.path.join(d, "metrics.csv"))))
    brax = [json.loads(line) for line in open(os.path.join(d, "brax_ppo.log")) if line.startswith("{")]
    summary = json.load(open(os.path.join(d, "summary.json")))

    def brax_curve(ax):
        ax.plot([b["wall_seconds"] for b in brax], [b["eval_return"] for b in brax], "s--", label="Brax PPO (its evals)")

    path = os.path.join(d, "curves.png")
    curve(rows, 2500, summary, f"Hopper PPO on {summary['device']}", path, extra=brax_curve)
    print(f"wrote {path}")


if __name__ == "__main__":
    main(settings(Settings, sys.argv[1:]))
