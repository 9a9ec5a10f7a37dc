"""Episodic REPS (relative entropy policy search) over a full-covariance Gaussian search distribution.

Given samples ``xi_i ~ p(xi) = N(mu, Sigma)`` and their costs ``c_i``, REPS finds the reweighting
``w_i ∝ exp(-c_i / eta)`` that minimises the expected cost subject to ``KL(q || p) <= epsilon``,
where ``q`` is the reweighted sample distribution; ``eta`` comes from the dual

    g(eta) = eta * epsilon + eta * log(1/N sum_i exp(-c_i / eta)),

which is convex in ``eta`` with ``g'(eta) = epsilon - KL(w || uniform)``. We solve it by bisection
on ``log eta`` (60 halvings, a fixed-length ``lax.fori_loop``, so it is jittable and vmappable):
the derivative is monotone in eta, bisection cannot diverge or need a step size, and it returns the
eta on the feasible side, so the KL bound holds to machine precision instead of to a solver
tolerance. ``eta`` is kept at or above a minimum temperature (the paper's Table III: 0.001) for
numerical safety; costs are divided by their spread first so that minimum is scale-free.

The new Gaussian is the weighted maximum-likelihood fit of the samples (plus a small ridge).
No maintained JAX library offers REPS with a KL dual (evosax has CMA-ES/OpenES etc., not
REPS), hence this module. Non-finite costs (a diverged simulation) get zero weight.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp


def _weights_at(log_eta, c):
    """Normalised weights ``[N]`` and ``KL(w || uniform)`` at temperature ``exp(log_eta)``."""
    logits = -c / jnp.exp(log_eta)
    logw = logits - jax.scipy.special.logsumexp(logits)
    w = jnp.exp(logw)
    kl = jnp.sum(w * (logw + jnp.log(c.shape[0])))
    return w, kl


def dual(eta, costs, epsilon):
    """The REPS dual ``g(eta)`` (for tests and diagnostics); ``costs [N]``."""
    c0 = jnp.min(costs)
    lme = jax.scipy.special.logsumexp(-(costs - c0) / eta) - jnp.log(costs.shape[0])
    return eta * epsilon + eta * lme - c0


def weights(costs, epsilon: float, eta_min: float = 1e-3, iters: int = 60):
    """REPS sample weights for ``costs [N]`` (lower is better).

    Returns ``(w [N], eta, kl)``: weights summing to 1, the temperature in units of the cost spread
    times that spread (i.e. in cost units), and the achieved ``KL(w || uniform) <= epsilon``.
    """
    costs = jnp.asarray(costs, jnp.float32)
    ok = jnp.isfinite(costs)
    worst = jnp.where(jnp.any(ok), jnp.max(jnp.where(ok, costs, -jnp.inf)), 0.0)
    c = jnp.where(ok, costs, worst)
    c = c - jnp.min(c)
    scale = jnp.maximum(jnp.std(c), 1e-12)
    c = c / scale
    # unusable samples get a cost far above every usable one: weight exp(-1e6) = 0
    c = jnp.where(ok, c, 1e6)

    lo, hi = jnp.log(eta_min), jnp.log(1e6)

    def body(_, bounds):
        lo, hi = bounds
        mid = 0.5 * (lo + hi)
        _, kl = _weights_at(mid, c)
        feasible = kl <= epsilon  # KL falls as eta grows: feasible -> try smaller eta
        return jnp.where(feasible, lo, mid), jnp.where(feasible, mid, hi)

    _, kl_min = _weights_at(lo, c)
    lo2, hi2 = jax.lax.fori_loop(0, iters, body, (lo, hi))
    log_eta = jnp.where(kl_min <= epsilon, lo, hi2)
    w, kl = _weights_at(log_eta, c)
    return w, jnp.exp(log_eta) * scale, kl


def fit_gaussian(xi, w, ridge: float = 1e-6):
    """Weighted ML Gaussian: ``xi [N, D]``, ``w [N]`` (sums to 1) -> ``(mean [D], cov [D, D])``.

    ``ridge`` times the mean diagonal variance is added so the covariance stays invertible even
    when the weights collapse onto a few samples.
    """
    mean = w @ xi
    d = xi - mean
    cov = (d * w[:, None]).T @ d
    # the unbiased weighted estimate: divide by 1 - sum w^2 (effective sample size correction)
    cov = cov / jnp.maximum(1.0 - jnp.sum(w**2), 1e-6)
    cov = 0.5 * (cov + cov.T)
    return mean, cov + ridge * (jnp.trace(cov) / xi.shape[1] + 1e-12) * jnp.eye(xi.shape[1])


def update(xi, costs, epsilon: float, eta_min: float = 1e-3):
    """One REPS step: ``xi [N, D]``, ``costs [N]`` -> ``(mean [D], cov [D, D], info)``."""
    w, eta, kl = weights(costs, epsilon, eta_min)
    mean, cov = fit_gaussian(xi, w)
    ess = 1.0 / jnp.sum(w**2)
    return mean, cov, {"eta": eta, "kl": kl, "ess": ess}
