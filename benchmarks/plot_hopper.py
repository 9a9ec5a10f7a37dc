"""Learning curves of the GPU hopper runs: sim2real PPO vs Brax PPO, return against wall time.

    python benchmarks/plot_hopper.py [results_dir]   # default benchmarks/results/hopper_ppo_gpu
"""
from __future__ import annotations

import csv
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))


def main(argv):
    d = argv[0] if argv else os.path.join(HERE, "results", "hopper_ppo_gpu")
    rows = list(csv.DictReader(open(os.path.join(d, "metrics.csv"))))
    t = np.array([float(r["wall_seconds"]) for r in rows])
    ret = np.array([float(r["episode_return"]) for r in rows])
    eps = np.array([float(r["episodes"]) for r in rows])
    ok = eps > 0
    brax = [json.loads(line) for line in open(os.path.join(d, "brax_ppo.log")) if line.startswith("{")]
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(t[ok], ret[ok], label="sim2real PPO (training episodes)")
    ax.plot([b["wall_seconds"] for b in brax], [b["eval_return"] for b in brax], "s--", label="Brax PPO (its evals)")
    summary = json.load(open(os.path.join(d, "summary.json")))
    ax.axhline(summary["eval_return_mean"], color="C0", ls=":", label="sim2real final, deterministic eval")
    ax.axhline(2500, color="gray", lw=0.8)
    ax.set_xlabel("wall time incl. compilation [s]")
    ax.set_ylabel("episode return")
    ax.set_title(f"Hopper PPO on {summary['device']}")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(d, "curves.png"), dpi=120)
    print(f"wrote {os.path.join(d, 'curves.png')}")


if __name__ == "__main__":
    main(sys.argv[1:])
