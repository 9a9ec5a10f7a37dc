"""Independent Beta distributions on ``[0, 1]^K``: ``Beta(a [K], b [K])``, stored as logs so any
parameter value is a valid density (DORAEMON's distribution; scale to a box outside).

Densities, entropies and KLs are per dimension in closed form (``betaln``, ``digamma``) and summed.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import struct
from jax.scipy.special import betaln, digamma

# samples and densities stay this far inside (0, 1): a Beta with a < 1 or b < 1 has an infinite
# density at the edge, and float32 draws land exactly on it
EDGE = 1e-6


@struct.dataclass
class Beta:
    log_a: jax.Array
    log_b: jax.Array

    @property
    def a(self):
        return jnp.exp(self.log_a)

    @property
    def b(self):
        return jnp.exp(self.log_b)


def make(a, b) -> Beta:
    return Beta(jnp.log(jnp.asarray(a, jnp.float32)), jnp.log(jnp.asarray(b, jnp.float32)))


def from_moments(mean, var) -> Beta:
    """The Beta with per-dimension ``mean [K]`` in (0, 1) and variance ``var [K]`` (< mean (1 - mean))."""
    mean, var = jnp.asarray(mean, jnp.float32), jnp.asarray(var, jnp.float32)
    c = mean * (1 - mean) / var - 1
    return make(mean * c, (1 - mean) * c)


def mean(d: Beta):
    return d.a / (d.a + d.b)


def var(d: Beta):
    s = d.a + d.b
    return d.a * d.b / (s**2 * (s + 1))


def sample(key, d: Beta, n: int | None = None):
    """``[K]`` (n None) or ``[n, K]`` samples in ``[EDGE, 1 - EDGE]``."""
    shape = d.log_a.shape if n is None else (n,) + d.log_a.shape
    return jnp.clip(jax.random.beta(key, d.a, d.b, shape), EDGE, 1 - EDGE)


def log_prob(d: Beta, x):
    """``[..., K] -> [...]``."""
    x = jnp.clip(x, EDGE, 1 - EDGE)
    return jnp.sum((d.a - 1) * jnp.log(x) + (d.b - 1) * jnp.log1p(-x) - betaln(d.a, d.b), axis=-1)


def entropy(d: Beta):
    a, b = d.a, d.b
    return jnp.sum(betaln(a, b) - (a - 1) * digamma(a) - (b - 1) * digamma(b) + (a + b - 2) * digamma(a + b))


def kl(p: Beta, q: Beta):
    """KL(p || q)."""
    ap, bp, aq, bq = p.a, p.b, q.a, q.b
    return jnp.sum(betaln(aq, bq) - betaln(ap, bp) + (ap - aq) * digamma(ap) + (bp - bq) * digamma(bp)
                   + (aq - ap + bq - bp) * digamma(ap + bp))


def kl_from_uniform(low, high, d: Beta):
    """KL(U(low, high) || d) for a box inside ``[0, 1]^K``: E_U[log U] - E_U[log d], the second in
    closed form (the mean of ``log x`` over [l, h] is ``(h log h - h - l log l + l) / (h - l)``)."""
    low, high = jnp.asarray(low, jnp.float32), jnp.asarray(high, jnp.float32)

    def mean_log(lo, hi):  # E[log x], x ~ U(lo, hi), 0 <= lo < hi
        xlogx = lambda x: jnp.where(x > 0, x * jnp.log(jnp.maximum(x, 1e-30)), 0.0)  # noqa: E731
        return (xlogx(hi) - hi - xlogx(lo) + lo) / (hi - lo)

    e_log_x, e_log_1mx = mean_log(low, high), mean_log(1 - high, 1 - low)
    e_log_d = jnp.sum((d.a - 1) * e_log_x + (d.b - 1) * e_log_1mx - betaln(d.a, d.b))
    return -jnp.sum(jnp.log(high - low)) - e_log_d
