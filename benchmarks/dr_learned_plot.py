"""How ADR's bounds and DORAEMON's Betas moved during training: one panel per parameter, one line
per seed (ADR: the band between its bounds; DORAEMON: mean +- one standard deviation), the
fixed-box methods' training box dashed.

    python benchmarks/dr_learned_plot.py adr=RUN_DIR doraemon=RUN_DIR out=learned.png

RUN_DIR: a run folder (``arrays.npz``, ``config.yaml``) of ``algo=adr`` / ``algo=doraemon``.
"""
from __future__ import annotations

import dataclasses
import os
import sys

import numpy as np

from sim2real.common.cli import settings


@dataclasses.dataclass
class Settings:
    """adr, doraemon: run folders (either may be empty); out: the PNG written."""
    adr: str = ""
    doraemon: str = ""
    out: str = "learned.png"


def _run(path: str):
    from sim2real.training.runs import TrainConfig
    from sim2real.common import config as config_lib

    cfg = config_lib.load(TrainConfig, [f"config={os.path.join(path, 'config.yaml')}"])
    with np.load(os.path.join(path, "arrays.npz")) as f:
        arrays = dict(f)
    return cfg, arrays


def main(args: Settings) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    runs = [(name, _run(p)) for name, p in (("ADR", args.adr), ("DORAEMON", args.doraemon)) if p]
    if not runs:
        raise SystemExit("give adr= and/or doraemon= (run folders)")
    params = runs[0][1][0].dr.params
    fig, axes = plt.subplots(len(runs), len(params), figsize=(4.2 * len(params), 2.8 * len(runs)), squeeze=False)
    for r, (name, (cfg, a)) in enumerate(runs):
        for c, p in enumerate(params):
            ax = axes[r, c]
            if name == "ADR":
                lo, hi = a["adr_low"][..., c], a["adr_high"][..., c]
            else:
                lo = a["dist_mean"][..., c] - a["dist_std"][..., c]
                hi = a["dist_mean"][..., c] + a["dist_std"][..., c]
            u = np.arange(lo.shape[1]) + 1
            for s in range(lo.shape[0]):
                ax.fill_between(u, lo[s], hi[s], alpha=0.25, color=f"C{s}", lw=0)
                ax.plot(u, lo[s], color=f"C{s}", lw=0.8)
                ax.plot(u, hi[s], color=f"C{s}", lw=0.8)
            init_lo, init_hi = cfg.algo_options.get("init_low"), cfg.algo_options.get("init_high")
            if init_lo and init_hi:
                ax.axhline(init_lo[c], ls="--", color="k", lw=0.8)
                ax.axhline(init_hi[c], ls="--", color="k", lw=0.8)
            ax.set_ylim(cfg.dr.low[c], cfg.dr.high[c])
            ax.set_title(f"{name}: {p} ({'bounds' if name == 'ADR' else 'mean +- std'})", fontsize=9)
            ax.set_xlabel("update")
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    plt.close(fig)
    return args.out


if __name__ == "__main__":
    print(main(settings(Settings, sys.argv[1:])))
