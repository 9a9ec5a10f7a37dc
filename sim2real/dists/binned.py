"""Per-dimension discrete distribution over equal bins of a box (LSDR's 100-bin distribution).

Sampling picks a bin by its probability, then a value uniformly inside it, so the density is
piecewise constant: ``p(z) = prod_k softmax(logits_k)[bin_k(z)] / width_k``.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import struct


@struct.dataclass
class Binned:
    """``logits [K, N]`` over N bins spanning ``[low [K], high [K]]`` per dimension."""

    logits: jax.Array
    low: jax.Array
    high: jax.Array

    @property
    def num_bins(self) -> int:
        return self.logits.shape[-1]

    @property
    def width(self):
        return (self.high - self.low) / self.num_bins


def make(low, high, num_bins: int = 100) -> Binned:
    """Uniform over the box (all logits 0)."""
    low = jnp.asarray(low, jnp.float32)
    return Binned(jnp.zeros(low.shape + (num_bins,)), low, jnp.asarray(high, jnp.float32))


def probs(d: Binned):
    return jax.nn.softmax(d.logits, axis=-1)


def bin_index(d: Binned, z):
    """``[..., K]`` values -> ``[..., K]`` int bin indices (clipped to the box)."""
    i = jnp.floor((z - d.low) / d.width).astype(jnp.int32)
    return jnp.clip(i, 0, d.num_bins - 1)


def bin_centers(d: Binned):
    return d.low[:, None] + (jnp.arange(d.num_bins) + 0.5) * d.width[:, None]


def sample(key, d: Binned, n: int | None = None):
    k1, k2 = jax.random.split(key)
    shape = () if n is None else (n,)
    K = d.logits.shape[0]
    bins = jax.random.categorical(k1, d.logits, axis=-1, shape=shape + (K,))
    u = jax.random.uniform(k2, shape + (K,))
    return d.low + (bins + u) * d.width


def log_prob(d: Binned, z):
    """``[..., K] -> [...]``; -inf outside the box."""
    logp = jax.nn.log_softmax(d.logits, axis=-1)
    idx = bin_index(d, z)
    per = jnp.take_along_axis(jnp.broadcast_to(logp, z.shape + (d.num_bins,)), idx[..., None], -1)[..., 0]
    inside = jnp.all((z >= d.low) & (z <= d.high), axis=-1)
    return jnp.where(inside, jnp.sum(per - jnp.log(d.width), -1), -jnp.inf)


def entropy(d: Binned):
    p = probs(d)
    return jnp.sum(-jnp.sum(p * jnp.log(p + 1e-30), -1) + jnp.log(d.width))


def kl(p: Binned, q: Binned):
    """KL(p || q) for two binned distributions on the same bins."""
    lp, lq = jax.nn.log_softmax(p.logits, -1), jax.nn.log_softmax(q.logits, -1)
    return jnp.sum(jnp.exp(lp) * (lp - lq))


def kl_from_uniform(low, high, d: Binned):
    """KL(U(low, high) || d) when the uniform spans d's box (LSDR's regulariser)."""
    lq = jax.nn.log_softmax(d.logits, -1)
    n = d.num_bins
    return jnp.sum(jnp.sum((1.0 / n) * (-jnp.log(n) - lq), -1))
