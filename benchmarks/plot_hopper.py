"""Learning curves of the GPU hopper runs: sim2real PPO vs Brax PPO, return against wall time.

    python benchmarks/plot_hopper.py [results_dir]   # default benchmarks/results/hopper_ppo_gpu
"""
from __future__ import annotations

import csv
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def main(argv):
    from hopper_ppo import curve

    d = argv[0] if argv else os.path.join(HERE, "results", "hopper_ppo_gpu")
    rows = list(csv.DictReader(open(os.path.join(d, "metrics.csv"))))
    brax = [json.loads(line) for line in open(os.path.join(d, "brax_ppo.log")) if line.startswith("{")]
    summary = json.load(open(os.path.join(d, "summary.json")))

    def brax_curve(ax):
        ax.plot([b["wall_seconds"] for b in brax], [b["eval_return"] for b in brax], "s--", label="Brax PPO (its evals)")

    path = os.path.join(d, "curves.png")
    curve(rows, 2500, summary, f"Hopper PPO on {summary['device']}", path, extra=brax_curve)
    print(f"wrote {path}")


if __name__ == "__main__":
    main(sys.argv[1:])
