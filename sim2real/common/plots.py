"""Plots shared by scripts and benchmarks (matplotlib, headless)."""
from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def heatmap(axes: dict, values: np.ndarray, path: str, title: str = "", box: dict | None = None,
            cbar: str = "return"):
    """1-D line or 2-D heat map of ``values`` over named grid ``axes``; ``box`` outlines a training range."""
    names = list(axes)
    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    box = box or {}
    if len(names) == 1:
        x = axes[names[0]]
        ax.plot(x, values, "o-")
        ax.set_xlabel(names[0])
        ax.set_ylabel(cbar)
        if names[0] in box:
            ax.axvspan(*box[names[0]], color="C1", alpha=0.15, label="training range")
            ax.legend()
    else:
        x, y = axes[names[0]], axes[names[1]]
        dx = (x[-1] - x[0]) / max(len(x) - 1, 1) / 2 or 0.5
        dy = (y[-1] - y[0]) / max(len(y) - 1, 1) / 2 or 0.5
        im = ax.imshow(values.T, origin="lower", aspect="auto", cmap="viridis",
                       extent=[x[0] - dx, x[-1] + dx, y[0] - dy, y[-1] + dy])
        fig.colorbar(im, ax=ax, label=cbar)
        ax.set_xlabel(names[0])
        ax.set_ylabel(names[1])
        if names[0] in box and names[1] in box:
            (x0, x1), (y0, y1) = box[names[0]], box[names[1]]
            ax.add_patch(plt.Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, ec="red", lw=2,
                                       label="training range"))
            ax.legend(loc="upper right")
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
