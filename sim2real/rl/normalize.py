"""Running mean/variance of observations (parallel Welford merge), as a pytree."""
from __future__ import annotations

import jax.numpy as jnp
from flax import struct


@struct.dataclass
class RunningStats:
    """``mean [O]``, ``var [O]`` and the sample ``count []`` they summarise."""

    mean: jnp.ndarray
    var: jnp.ndarray
    count: jnp.ndarray


def init(size: int) -> RunningStats:
    return RunningStats(jnp.zeros(size, jnp.float32), jnp.ones(size, jnp.float32), jnp.asarray(1e-4, jnp.float32))


def update(s: RunningStats, x: jnp.ndarray) -> RunningStats:
    """Merge a batch ``x [..., O]`` into the statistics."""
    x = x.reshape(-1, x.shape[-1])
    return merge(s, x.mean(0), x.var(0), x.shape[0])


def merge(s: RunningStats, mean, var, n) -> RunningStats:
    """Merge the mean ``[O]`` and variance ``[O]`` of ``n`` new samples into the statistics."""
    total = s.count + n
    delta = mean - s.mean
    new_mean = s.mean + delta * n / total
    m2 = s.var * s.count + var * n + delta**2 * s.count * n / total
    return RunningStats(new_mean, m2 / total, total)


def apply(s: RunningStats, x: jnp.ndarray, clip: float = 10.0) -> jnp.ndarray:
    return jnp.clip((x - s.mean) / jnp.sqrt(s.var + 1e-8), -clip, clip)
