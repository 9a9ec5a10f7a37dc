"""Out-of-distribution leaderboard statistics: returns over a physics grid, per method and seed.

A method's result is ``returns [S seeds, N cells]`` (the final policy of each seed on every cell
of a test grid, e.g. the driver's ``test.npz``) and ``in_box [N]`` says which cells lie inside
the training box. ``grid_stats`` gives the in-box / out-of-box / all means with 95% bootstrap
confidence intervals over seeds (the seeds are what is random; the cells are fixed) and the
fraction of cells above a return threshold; ``difference`` says whether two methods differ:
the bootstrap interval of the difference of their means (seeds resampled independently per
method) excludes 0.

Written here rather than taken from ``scipy.stats.bootstrap`` because the statistic of a method
is a mean over a [seeds, cells] array resampled over seeds only, and two methods are resampled
independently for their difference; the resampling is 10 lines and its seed is fixed, so a
table is reproducible.
"""
from __future__ import annotations

import numpy as np

REGIONS = ("in_box", "out_of_box", "all")


def _regions(in_box: np.ndarray) -> dict[str, np.ndarray]:
    in_box = np.asarray(in_box, bool)
    return {"in_box": in_box, "out_of_box": ~in_box, "all": np.ones_like(in_box)}


def _boot_means(returns: np.ndarray, mask: np.ndarray, n_boot: int, rng) -> np.ndarray:
    """``[n_boot]`` means over ``mask``'s cells of seed-resampled ``returns [S, N]``."""
    per_seed = returns[:, mask].mean(1)                                     # [S]
    picks = rng.integers(0, len(per_seed), (n_boot, len(per_seed)))
    return per_seed[picks].mean(1)


def grid_stats(returns, in_box, threshold: float, n_boot: int = 10_000, seed: int = 0) -> dict:
    """``{region: {mean, low, high}, 'above_threshold': fraction, 'seeds': S}`` for ``returns [S, N]``.

    ``low``/``high``: the 2.5% / 97.5% percentiles of the seed bootstrap (with 1 seed: the mean).
    ``above_threshold``: fraction of (seed, cell) pairs whose return is at least ``threshold``.
    """
    r = np.asarray(returns, np.float64)
    if r.ndim != 2 or r.shape[1] != len(in_box):
        raise ValueError(f"returns: expected [seeds, {len(in_box)} cells], got {r.shape}")
    if not np.isfinite(r).all():
        raise ValueError("returns hold NaN/inf")
    rng = np.random.default_rng(seed)
    out = {"seeds": int(r.shape[0]), "above_threshold": float((r >= threshold).mean())}
    for name, mask in _regions(in_box).items():
        if not mask.any():
            out[name] = {"mean": float("nan"), "low": float("nan"), "high": float("nan")}
            continue
        boot = _boot_means(r, mask, n_boot, rng)
        out[name] = {"mean": float(r[:, mask].mean()), "low": float(np.percentile(boot, 2.5)),
                     "high": float(np.percentile(boot, 97.5))}
    return out


def difference(a, b, in_box, region: str = "all", n_boot: int = 10_000, seed: int = 0) -> dict:
    """Mean of ``a`` minus mean of ``b`` on ``region``'s cells (``[S_a, N]``, ``[S_b, N]``), its 95%
    bootstrap interval and ``significant`` (the interval excludes 0)."""
    mask = _regions(in_box)[region]
    rng = np.random.default_rng(seed)
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    boot = _boot_means(a, mask, n_boot, rng) - _boot_means(b, mask, n_boot, rng)
    low, high = float(np.percentile(boot, 2.5)), float(np.percentile(boot, 97.5))
    return {"difference": float(a[:, mask].mean() - b[:, mask].mean()), "low": low, "high": high,
            "significant": bool(low > 0 or high < 0)}


def table(results: dict[str, np.ndarray], in_box, threshold: float, unit: str = "return") -> str:
    """A Markdown table, best mean over all cells first: mean [95% CI] per region, the fraction of
    cells above ``threshold``, and whether each method differs significantly from the best."""
    stats = {m: grid_stats(r, in_box, threshold) for m, r in results.items()}
    order = sorted(stats, key=lambda m: -stats[m]["all"]["mean"])
    best = order[0]
    lines = [f"| method | seeds | in-box {unit} | out-of-box {unit} | all cells {unit} | cells ≥ {threshold:g} | "
             f"vs {best} (all cells) |", "|---|---|---|---|---|---|---|"]
    for m in order:
        s = stats[m]
        cell = lambda k: f"{s[k]['mean']:.1f} [{s[k]['low']:.1f}, {s[k]['high']:.1f}]"  # noqa: E731
        if m == best:
            vs = "—"
        else:
            d = difference(results[m], results[best], in_box)
            vs = f"{d['difference']:+.1f} [{d['low']:+.1f}, {d['high']:+.1f}]" + (
                " significant" if d["significant"] else " not significant")
        lines.append(f"| {m} | {s['seeds']} | {cell('in_box')} | {cell('out_of_box')} | {cell('all')} | "
                     f"{s['above_threshold']:.0%} | {vs} |")
    return "\n".join(lines) + "\n"
