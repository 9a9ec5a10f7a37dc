"""Uniform box over K dimensions: ``Uniform(low [K], high [K])``."""
from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import struct


@struct.dataclass
class Uniform:
    low: jax.Array
    high: jax.Array


def make(low, high) -> Uniform:
    return Uniform(jnp.asarray(low, jnp.float32), jnp.asarray(high, jnp.float32))


def sample(key, d: Uniform, n: int | None = None):
    """``[K]`` (n None) or ``[n, K]`` samples."""
    shape = d.low.shape if n is None else (n,) + d.low.shape
    return jax.random.uniform(key, shape, minval=d.low, maxval=d.high)


def log_prob(d: Uniform, z):
    """``[..., K] -> [...]``; -inf outside the box."""
    inside = jnp.all((z >= d.low) & (z <= d.high), axis=-1)
    return jnp.where(inside, -jnp.sum(jnp.log(d.high - d.low)), -jnp.inf)


def entropy(d: Uniform):
    return jnp.sum(jnp.log(d.high - d.low))


def kl(p: Uniform, q: Uniform):
    """KL(p || q): finite only when p's box lies inside q's."""
    inside = jnp.all((p.low >= q.low) & (p.high <= q.high))
    return jnp.where(inside, jnp.sum(jnp.log(q.high - q.low) - jnp.log(p.high - p.low)), jnp.inf)
