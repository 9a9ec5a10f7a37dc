"""Plots and the Markdown report of a diagnosis."""
from __future__ import annotations

import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def overlay(path, time, signals: dict, title: str, zoom: tuple[float, float] | None = None):
    """Measured vs nominal vs fitted, one panel per signal (+ a zoom column)."""
    n = len(signals)
    cols = 2 if zoom else 1
    fig, axes = plt.subplots(n, cols, figsize=(5.5 * cols, 2.4 * n), squeeze=False)
    for r, (name, s) in enumerate(signals.items()):
        for c in range(cols):
            ax = axes[r, c]
            sel = slice(None) if c == 0 else (time >= zoom[0]) & (time <= zoom[1])
            ax.plot(time[sel], s["measured"][sel], "k", lw=1.2, label="measured")
            ax.plot(time[sel], s["nominal"][sel], "C3", lw=0.9, alpha=0.8, label="nominal model")
            ax.plot(time[sel], s["fitted"][sel], "C0", lw=0.9, alpha=0.8, label="fitted model")
            ax.set_ylabel(name, fontsize=8)
            ax.tick_params(labelsize=7)
            if r == 0:
                ax.set_title(title if c == 0 else f"zoom {zoom[0]:.2f}-{zoom[1]:.2f} s", fontsize=9)
            if r == n - 1:
                ax.set_xlabel("time [s]", fontsize=8)
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def regimes_plot(path, tables: dict, title: str):
    """Bar chart of residual excess per regime (before and after the fit), per joint."""
    fig, ax = plt.subplots(figsize=(6.5, 3.2))
    names = sorted({k for t in tables.values() for k in t})
    width = 0.8 / max(len(tables), 1)
    for i, (label, t) in enumerate(tables.items()):
        vals = [t.get(n, {}).get("excess") or 0.0 for n in names]
        ax.bar(np.arange(len(names)) + i * width, vals, width, label=label)
    ax.axhline(1.0, color="gray", lw=0.8)
    ax.set_xticks(np.arange(len(names)) + width * (len(tables) - 1) / 2)
    ax.set_xticklabels(names, rotation=20, fontsize=7, ha="right")
    ax.set_ylabel("residual RMS in regime / overall")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def ranking_plot(path, rows: list[dict], top: int = 12):
    rows = rows[:top]
    fig, ax = plt.subplots(figsize=(6.5, 0.35 * len(rows) + 1.2))
    labels = [f"{r['effect']}@{r['target']}" if r["target"] else r["effect"] for r in rows]
    vals = [r["heldout_ratio"] for r in rows]
    ax.barh(range(len(rows)), vals, color=["C0" if i == 0 else "C7" for i in range(len(rows))])
    ax.set_yticks(range(len(rows)))
    ax.set_yticklabels(labels, fontsize=7)
    ax.invert_yaxis()
    ax.axvline(1.0, color="C3", lw=0.8)
    ax.set_xlabel("held-out residual RMSE / nominal re-fit ('none')")
    ax.set_title("candidates, best BIC first", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def residual_vs_velocity(path, v: np.ndarray, before: np.ndarray, after: np.ndarray, joint: str):
    fig, ax = plt.subplots(figsize=(5, 3.5))
    k = max(1, len(v) // 4000)
    ax.plot(v[::k], before[::k], ".", ms=2, alpha=0.4, color="C3", label="nominal")
    ax.plot(v[::k], after[::k], ".", ms=2, alpha=0.4, color="C0", label="fitted")
    ax.axhline(0, color="k", lw=0.6)
    ax.set_xlabel(f"velocity of {joint}")
    ax.set_ylabel("inverse-dynamics residual")
    ax.set_title("residual vs velocity (a step at 0 = Coulomb friction)", fontsize=9)
    ax.legend(fontsize=7, markerscale=4)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def markdown(path: str, d: dict, images: dict[str, str]) -> None:
    sel = d["effects"][0]
    fit = d["fit"]
    L = [f"# Diagnosis of `{os.path.basename(d['model'])}`", ""]
    L += [f"**Selected: `{sel['effect']}`" + (f" at `{sel['target']}`" if sel["target"] else "") +
          f"** (confidence {d['confidence']:.2f}).", ""]
    if sel["params"]:
        L += ["| parameter | value | std |", "|---|---|---|"]
        for k, v in sel["params"].items():
            L.append(f"| `{k}` | {v:.6g} | {sel['std'].get(k, float('nan')):.3g} |")
        L.append("")
    for note in d.get("notes", []):
        L.append(f"- {note}")
    L += ["", "## Fit on held-out data", "",
          f"Normalised RMSE of {fit['metric']}, mean over signals: **{fit['before']:.4g} -> {fit['after']:.4g}** "
          f"({100 * (1 - fit['after'] / max(fit['before'], 1e-300)):.1f}% lower), on {', '.join(fit['recordings'])}.", "",
          "| signal | before | after |", "|---|---|---|"]
    for s, v in fit["per_signal"].items():
        L.append(f"| {s} | {v['before']:.4g} | {v['after']:.4g} |")
    L += ["", f"Fitted MJCF: `{d['fitted_mjcf']}`", ""]
    L += ["## Where the nominal model is wrong", "", "| signal | NRMSE | offset ratio |", "|---|---|---|"]
    for s, v in d["mismatch"]["signals"].items():
        L.append(f"| {s} | {v['nrmse']:.4g} | {v['offset_ratio']:.2f} |")
    L += ["", "Worst time windows:", ""]
    for w in d["mismatch"]["worst_windows"][:5]:
        L.append(f"- {w['recording']} {w['t_start']:.2f}-{w['t_end']:.2f} s, {w['signal']}: NRMSE {w['nrmse']:.3g}")
    L += ["", "Regimes (inverse-dynamics residual RMS in regime / overall):", ""]
    for j, t in d["mismatch"]["regimes"].items():
        parts = [f"{k} {v['excess']}" for k, v in t.items() if v.get("excess") is not None]
        L.append(f"- {j}: " + ", ".join(parts))
    L += ["", "## Candidates", "",
          "Screened by BIC on the inverse-dynamics equation error (dBIC < 0: better than `none`; held-out "
          "ratio: equation-error RMSE on the held-back tail relative to `none`); the front-runners verified "
          "by simulated predictions on that tail (NRMSE).", "",
          "| effect | target | dBIC vs none | held-out ratio | BIC weight | verified NRMSE |", "|---|---|---|---|---|---|"]
    for r in d["effects"]:
        v = r.get("verified_nrmse")
        L.append(f"| {r['effect']} | {r['target']} | {r['score']:.1f} | {r['heldout_ratio']:.3f} | {r['weight']:.3f} | "
                 f"{'' if v is None else f'{v:.4g}'} |")
    L.append("")
    for title, img in images.items():
        L += [f"## {title}", "", f"![{title}]({img})", ""]
    with open(path, "w") as f:
        f.write("\n".join(L))
