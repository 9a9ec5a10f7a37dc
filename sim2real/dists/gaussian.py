"""Full-covariance Gaussian, Cholesky-parametrised so any parameter value is a valid density.

``Sigma = L L^T`` with ``L = tril(raw, -1) + diag(exp(diag(raw)))``.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
from flax import struct


@struct.dataclass
class Gaussian:
    """``mean [K]``, ``chol_raw [K, K]`` (see module docstring)."""

    mean: jax.Array
    chol_raw: jax.Array


def chol(d: Gaussian):
    raw = d.chol_raw
    return jnp.tril(raw, -1) + jnp.diag(jnp.exp(jnp.diagonal(raw)))


def cov(d: Gaussian):
    L = chol(d)
    return L @ L.T


def make(mean, std=None, cov_matrix=None) -> Gaussian:
    """From a mean and either per-dimension ``std [K]`` or a covariance ``[K, K]``."""
    mean = jnp.asarray(mean, jnp.float32)
    if cov_matrix is None:
        L = jnp.diag(jnp.asarray(std, jnp.float32))
    else:
        L = jnp.linalg.cholesky(jnp.asarray(cov_matrix, jnp.float32))
    raw = jnp.tril(L, -1) + jnp.diag(jnp.log(jnp.diagonal(L)))
    return Gaussian(mean, raw)


def sample(key, d: Gaussian, n: int | None = None):
    shape = d.mean.shape if n is None else (n,) + d.mean.shape
    eps = jax.random.normal(key, shape)
    return d.mean + eps @ chol(d).T


def log_prob(d: Gaussian, z):
    L = chol(d)
    diff = z - d.mean
    sol = jax.scipy.linalg.solve_triangular(L, diff.reshape(-1, diff.shape[-1]).T, lower=True).T
    maha = jnp.sum(sol**2, -1).reshape(diff.shape[:-1])
    K = d.mean.shape[-1]
    return -0.5 * maha - jnp.sum(jnp.log(jnp.diagonal(L))) - 0.5 * K * jnp.log(2 * jnp.pi)


def entropy(d: Gaussian):
    K = d.mean.shape[-1]
    return 0.5 * K * (1 + jnp.log(2 * jnp.pi)) + jnp.sum(jnp.log(jnp.diagonal(chol(d))))


def kl(p: Gaussian, q: Gaussian):
    """KL(p || q)."""
    Lq = chol(q)
    K = p.mean.shape[-1]
    a = jax.scipy.linalg.solve_triangular(Lq, chol(p), lower=True)
    b = jax.scipy.linalg.solve_triangular(Lq, q.mean - p.mean, lower=True)
    logdet = 2 * (jnp.sum(jnp.log(jnp.diagonal(Lq))) - jnp.sum(jnp.log(jnp.diagonal(chol(p)))))
    return 0.5 * (jnp.sum(a**2) + jnp.sum(b**2) - K + logdet)


def kl_from_uniform(low, high, d: Gaussian):
    """KL(U(low, high) || d), in closed form (LSDR's regulariser for Gaussian p_phi)."""
    low, high = jnp.asarray(low), jnp.asarray(high)
    m_u, var_u = (low + high) / 2, (high - low) ** 2 / 12
    L = chol(d)
    Linv = jax.scipy.linalg.solve_triangular(L, jnp.eye(L.shape[0]), lower=True)
    prec = Linv.T @ Linv
    diff = m_u - d.mean
    expected_maha = jnp.sum(jnp.diagonal(prec) * var_u) + diff @ prec @ diff
    K = L.shape[0]
    cross = 0.5 * expected_maha + jnp.sum(jnp.log(jnp.diagonal(L))) + 0.5 * K * jnp.log(2 * jnp.pi)
    return cross - jnp.sum(jnp.log(high - low))
