"""The PPO curves behind issue 26's "same return at the same per-GPU batch" (committed JSON of
``multi_gpu.py`` runs, hopper, 16,384 envs per GPU, 100M env steps per seed), on one plot:
1 GPU with the config's clip 0.2, 2 GPUs with clip 0.2, 2 GPUs with clip 1.0.

    python benchmarks/plot_multi_gpu_clip.py                # the clip search: h200_clip_ppo.png
    python benchmarks/plot_multi_gpu_clip.py runs=moments   # one nvidia-h200-x2 machine, the code
                                                            # with one moments all-reduce per update
"""
from __future__ import annotations

import dataclasses
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from sim2real.common.cli import settings  # noqa: E402

R = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results", "multi_gpu")
# (label, colour, [(file, key in it)]): seeds 0-2, 3-5, 6-8 in that order
GROUPS = [
    ("1 GPU, clip 0.2 (the config)", "C0", [("h200x2_100M_ppo_curves.json", "ppo_1"),
                                             ("h200x4_g1_clip_0p2_seed1_mbtotal0_ppo_curves.json", "ppo_1"),
                                             ("h200x4_g1_clip_0p2_seed2_mbtotal0_ppo_curves.json", "ppo_1")]),
    ("2 GPUs, clip 0.2", "C3", [("h200x2_100M_ppo_curves.json", "ppo_2")]),
    ("2 GPUs, clip 1.0", "C2", [("h200x4_clip_eps_1p0_seed0_ppo_curves.json", "ppo_2"),
                                ("h200x4_clip_eps_1p0_seed1_ppo_curves.json", "ppo_2"),
                                ("h200x4_g2_clip_1p0_seed2_mbtotal0_ppo_curves.json", "ppo_2")]),
]

# One warm nvidia-h200-x2 machine (2026-11-26, eighth session), seeds 0-2 and 3-5.
MOMENTS = [
    ("1 GPU, clip 0.2 (the config)", "C0", [("h200x2_moments_g1_clip0p2_seed0_ppo_curves.json", "ppo_1"),
                                             ("h200x2_moments_g1_clip0p2_seed1_ppo_curves.json", "ppo_1")]),
    ("2 GPUs, clip 1.0", "C2", [("h200x2_moments_g2_clip1p0_seed0_ppo_curves.json", "ppo_2"),
                                ("h200x2_moments_g2_clip1p0_seed1_ppo_curves.json", "ppo_2")]),
]
RUNS = {"clip": (GROUPS, "h200_clip_ppo.png"), "moments": (MOMENTS, "h200x2_moments_ppo.png")}


@dataclasses.dataclass
class Settings:
    """runs: clip (the clip search, 2 machines) or moments (one 2-GPU machine); out: the figure's
    path (default: the runs' own name in results/multi_gpu)."""
    runs: str = "clip"
    out: str = ""


def main(args: Settings):
    if args.runs not in RUNS:
        raise SystemExit(f"runs={args.runs!r}: expected one of {sorted(RUNS)}")
    groups, name = RUNS[args.runs]
    out = args.out or os.path.join(R, name)
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for label, color, runs in groups:
        first = True
        for name, key in runs:
            curve = json.load(open(os.path.join(R, name)))[key]
            for s in sorted({c[0] for c in curve}):
                pts = sorted((x, y) for seed, x, y in curve if seed == s)
                ax.plot(*zip(*pts), color=color, alpha=0.7, lw=1, label=label if first else None)
                first = False
    ax.set_xlabel("env steps per seed")
    ax.set_ylabel("training episode return")
    ax.set_title("PPO hopper, 16,384 envs per GPU, NVIDIA H200 (one line per seed)", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print("wrote", out)


if __name__ == "__main__":
    main(settings(Settings, sys.argv[1:]))
