"""Plots shared by scripts and benchmarks (matplotlib, headless)."""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def heatmap(axes: dict, values: np.ndarray, path: str, title: str = "", box: dict | None = None,
            cbar: str = "return", spread: np.ndarray | None = None, subtitle: str = ""):
    """1-D line or 2-D heat map of ``values`` over named grid ``axes``; ``box`` outlines a training
    range; ``spread`` (same shape: the seeds' standard deviation) is a band (1-D) or a second panel
    (2-D); ``subtitle`` a smaller line under the title (what was held fixed, seeds, episodes)."""
    names = list(axes)
    box = box or {}
    two = len(names) == 2 and spread is not None
    fig, axs = plt.subplots(1, 2 if two else 1, figsize=(10.5 if two else 5.5, 4.4))
    ax = axs[0] if two else axs
    if len(names) == 1:
        x = axes[names[0]]
        ax.plot(x, values, "o-", label="mean over seeds")
        if spread is not None:
            ax.fill_between(x, values - spread, values + spread, alpha=0.25, label="± 1 std over seeds")
        ax.set_xlabel(names[0])
        ax.set_ylabel(cbar)
        if names[0] in box:
            ax.axvspan(*box[names[0]], color="C1", alpha=0.15, label="training range")
        ax.legend(fontsize=8)
    else:
        x, y = axes[names[0]], axes[names[1]]
        dx = (x[-1] - x[0]) / max(len(x) - 1, 1) / 2 or 0.5
        dy = (y[-1] - y[0]) / max(len(y) - 1, 1) / 2 or 0.5
        panels = [(ax, values, cbar)] + ([(axs[1], spread, f"{cbar}: std over seeds")] if two else [])
        for a, v, label in panels:
            im = a.imshow(v.T, origin="lower", aspect="auto", cmap="viridis",
                          extent=[x[0] - dx, x[-1] + dx, y[0] - dy, y[-1] + dy])
            fig.colorbar(im, ax=a, label=label)
            a.set_xlabel(names[0])
            a.set_ylabel(names[1])
            if names[0] in box and names[1] in box:
                (x0, x1), (y0, y1) = box[names[0]], box[names[1]]
                a.add_patch(plt.Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, ec="red", lw=2,
                                          label="training range"))
                a.legend(loc="upper right", fontsize=8)
    ax.set_title(title)
    if subtitle:
        fig.text(0.5, 0.01, subtitle, ha="center", va="bottom", fontsize=7, wrap=True)
    fig.tight_layout(rect=(0, 0.05 if subtitle else 0, 1, 1))
    fig.savefig(path, dpi=120)
    plt.close(fig)
