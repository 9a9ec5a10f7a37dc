"""The README's closed-loop figure: every chain's return on the "real" plant, per method, for the
four rows of the README's table (pendulum and cart-pole, ten chains each on the 2-core CPU; the
hopper's nine chains and the held-out hopper plant's six, one NVIDIA H200). Reads only committed
``results.csv`` files (``compare.rows_by_set``, ``boxes.chains``); writes ``docs/closed_loop.png``.

    python benchmarks/results/closed_loop_figure.py
"""
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

RES = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(RES))
HOPPER = os.path.join(RES, "closed_loop_warm_std_hopper")
sys.path[:0] = [os.path.dirname(RES), os.path.join(RES, "closed_loop_warm_std_centred"), HOPPER]

import boxes  # noqa: E402
import compare  # noqa: E402

# (column label, method name per row's naming); the CPU tasks' wide box is the blind one, the
# hopper's the wide box of closed_loop.py (centred on the first plant's truth, off the held-out one's)
COLUMNS = [("nominal", "nominal", "nominal"), ("oracle", "oracle_ft", "oracle_ft"),
           ("wide DR", "udr_blind_ft", "udr_wide_ft"), ("SimOpt", "simopt", "simopt"),
           ("LSDR", None, "lsdr"), ("one loop", "diag_dr_1", "loop_centred"),
           ("two loops", "diag_dr_2", "loop_centred_2")]


def hopper_rows(folders):
    """``boxes.chains`` of these folders of ``closed_loop_warm_std_hopper/``."""
    return boxes.chains([os.path.join(HOPPER, f) for f in folders])


def main():
    by_set = compare.rows_by_set()
    panels = [("pendulum (10 chains, 2-core CPU)", compare.ten_chains(by_set, "pendulum", common=False), 1),
              ("cart-pole (10 chains, 2-core CPU)", compare.ten_chains(by_set, "cartpole", common=False), 1),
              ("hopper (9 chains, one H200)", hopper_rows(["two_loops", "seed1", "seed2"]), 2),
              ("hopper, held-out plant (6 chains, one H200)", hopper_rows(["hopper_b", "hopper_b_seed1"]), 2)]
    fig, axes = plt.subplots(1, 4, figsize=(17, 4.2))
    for ax, (title, rows, col) in zip(axes, panels):
        labels = []
        for column in COLUMNS:
            v = np.array([r["return"] for r in rows if r["method"] == column[col]], float)
            if not len(v):  # (no LSDR on the CPU tasks' chains)
                continue
            x = len(labels)
            loop = "loop" in column[0]
            ax.plot([x - 0.32, x + 0.32], [v.mean()] * 2, color="tab:green" if loop else "0.35", lw=3)
            ax.plot(x + (np.linspace(-0.2, 0.2, len(v)) if len(v) > 1 else 0), v, ".",
                    color="tab:green" if loop else "k", ms=5)
            labels.append(f"{column[0]}\n{v.mean():.0f} ({len(v)})")
        ax.set_xticks(range(len(labels)), labels, fontsize=7)
        ax.set_title(title, fontsize=9)
        ax.grid(axis="y", lw=0.3)
    axes[0].set_ylabel("return on the native-MuJoCo plant\n(mean of 64 episodes per chain)")
    fig.suptitle("record -> diagnose -> retrain against the baselines, 3 real episodes each; the oracle and wide "
                 "DR fine-tuned from the nominal policy as the loop is\n(dots: chains; lines and labels: the mean "
                 "over chains, in brackets how many)", fontsize=10)
    fig.tight_layout()
    out = os.path.join(ROOT, "docs", "closed_loop.png")
    fig.savefig(out, dpi=110)
    print(out)


if __name__ == "__main__":
    main()
