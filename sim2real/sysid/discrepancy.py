"""Trajectory discrepancy between simulated and real signals, shared by the diagnosis and SimOpt.

* :func:`nrmse` — normalised RMS error (the diagnosis tool's before/after figure).
* :func:`smooth` / :func:`discrepancy` — SimOpt's Eq. 4 (seed 002):
  ``D = w_l1 sum_t |W (o_sim - o_real)| + w_l2 sum_t ||W (o_sim - o_real)||^2`` on Gaussian-smoothed
  observations, with per-dimension importance weights ``W``. Smoothing tolerates small time
  misalignments between the trajectories (the paper's reason for it).

The smoothing follows ``scipy.ndimage.gaussian_filter1d(mode='nearest')``: a kernel of standard
deviation ``std`` timesteps cut at ``truncate`` standard deviations (radius ``int(truncate*std+0.5)``),
edges padded with the end values. The paper's Tables III-IV use std 5 and truncation 4.
"""
from __future__ import annotations

import jax.numpy as jnp
import numpy as np


def nrmse(pred: np.ndarray, meas: np.ndarray, scale: float) -> float:
    """RMS of ``pred - meas`` over ``scale`` (NumPy, any shapes that broadcast)."""
    return float(np.sqrt(np.mean((pred - meas) ** 2)) / max(scale, 1e-12))


def gaussian_kernel(std: float, truncate: float = 4.0) -> np.ndarray:
    """Normalised kernel ``[2r + 1]``, ``r = int(truncate * std + 0.5)``; ``[1]`` when std is 0."""
    if std <= 0:
        return np.ones(1, np.float32)
    r = int(truncate * std + 0.5)
    x = np.arange(-r, r + 1, dtype=np.float64)
    k = np.exp(-0.5 * (x / std) ** 2)
    return (k / k.sum()).astype(np.float32)


def smooth(x, std: float, truncate: float = 4.0):
    """Gaussian filter along the time axis: ``x [..., T, D] -> [..., T, D]`` (edges: nearest)."""
    k = gaussian_kernel(std, truncate)
    r = len(k) // 2
    if r == 0:
        return x
    x = jnp.asarray(x)
    pad = [(0, 0)] * (x.ndim - 2) + [(r, r), (0, 0)]
    xp = jnp.pad(x, pad, mode="edge")
    T = x.shape[-2]
    # a sum of shifted copies: for the short kernels used here (<= ~41 taps) this is as fast as a
    # convolution and keeps the arithmetic identical on CPU and GPU
    out = jnp.zeros_like(x)
    for i, ki in enumerate(k):
        out = out + ki * xp[..., i:i + T, :]
    return out


def discrepancy(o_sim, o_real, weights, w_l1: float = 0.5, w_l2: float = 1.0, std: float = 5.0,
                truncate: float = 4.0, mask=None):
    """Eq. 4 of SimOpt: ``o_sim, o_real [..., T, D]``, ``weights [D]``, ``mask [..., T]`` -> ``[...]``.

    ``mask`` (1 = compare, 0 = skip) drops steps after a real rollout ended.
    """
    diff = (smooth(o_sim, std, truncate) - smooth(o_real, std, truncate)) * jnp.asarray(weights)
    per_t = w_l1 * jnp.sum(jnp.abs(diff), -1) + w_l2 * jnp.sum(diff**2, -1)
    if mask is not None:
        per_t = per_t * mask
    return jnp.sum(per_t, -1)
