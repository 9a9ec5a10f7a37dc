"""Distributions: sample / log_prob / kl / entropy against closed forms and scipy."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import stats

from sim2real import dists
from sim2real.dists import binned, gaussian, uniform

KEY = jax.random.PRNGKey(0)


def test_uniform():
    d = uniform.make([0.0, -1.0], [2.0, 3.0])
    z = np.asarray(dists.sample(KEY, d, 20000))
    assert z[:, 0].min() >= 0 and z[:, 1].max() <= 3 and abs(z[:, 1].mean() - 1.0) < 0.05
    want = stats.uniform(0, 2).logpdf(0.5) + stats.uniform(-1, 4).logpdf(1.0)
    assert float(dists.log_prob(d, jnp.array([0.5, 1.0]))) == pytest.approx(want, rel=1e-6)
    assert float(dists.log_prob(d, jnp.array([2.5, 1.0]))) == -np.inf
    assert float(dists.entropy(d)) == pytest.approx(np.log(2) + np.log(4), rel=1e-6)
    assert float(dists.kl(uniform.make([0.5, 0], [1.5, 1]), d)) == pytest.approx(np.log(2) + np.log(4), rel=1e-6)


def test_binned_sampling_follows_bin_probabilities():
    logits = jnp.log(jnp.array([[0.7, 0.2, 0.1, 1e-9]]))
    d = binned.Binned(logits, jnp.array([0.0]), jnp.array([4.0]))
    z = np.asarray(dists.sample(KEY, d, 50000))[:, 0]
    hist = np.histogram(z, bins=4, range=(0, 4))[0] / len(z)
    np.testing.assert_allclose(hist, [0.7, 0.2, 0.1, 0.0], atol=0.01)
    # inside a bin the density is uniform: log p = log(prob / width)
    assert float(dists.log_prob(d, jnp.array([0.3]))) == pytest.approx(np.log(0.7 / 1.0), rel=1e-5)
    p = np.array([0.7, 0.2, 0.1, 1e-9])
    assert float(dists.entropy(d)) == pytest.approx(stats.entropy(p) + np.log(1.0), rel=1e-4)


def test_binned_kl_closed_form():
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(2, 1, 10))
    p = binned.Binned(jnp.asarray(a), jnp.array([0.0]), jnp.array([1.0]))
    q = binned.Binned(jnp.asarray(b), jnp.array([0.0]), jnp.array([1.0]))
    pa, pb = np.exp(a) / np.exp(a).sum(), np.exp(b) / np.exp(b).sum()
    assert float(dists.kl(p, q)) == pytest.approx(stats.entropy(pa[0], pb[0]), rel=1e-5)
    u = binned.make([0.0], [1.0], 10)
    assert float(dists.kl_from_uniform([0.0], [1.0], q)) == pytest.approx(stats.entropy(np.full(10, 0.1), pb[0]), rel=1e-5)
    assert float(dists.kl_from_uniform([0.0], [1.0], u)) == pytest.approx(0.0, abs=1e-6)


def test_gaussian_against_scipy():
    cov = np.array([[1.0, 0.6, 0.1], [0.6, 2.0, -0.3], [0.1, -0.3, 0.5]])
    mean = np.array([0.5, -1.0, 2.0])
    d = gaussian.make(mean, cov_matrix=cov)
    np.testing.assert_allclose(np.asarray(gaussian.cov(d)), cov, rtol=1e-5, atol=1e-6)
    ref = stats.multivariate_normal(mean, cov)
    z = np.array([[0.0, 0.0, 0.0], [1.0, -2.0, 2.5]])
    np.testing.assert_allclose(np.asarray(dists.log_prob(d, jnp.asarray(z))), ref.logpdf(z), rtol=1e-5)
    assert float(dists.entropy(d)) == pytest.approx(ref.entropy(), rel=1e-5)
    s = np.asarray(dists.sample(KEY, d, 100000))
    np.testing.assert_allclose(np.cov(s.T), cov, atol=0.05)
    # KL between Gaussians: closed form vs Monte Carlo
    q = gaussian.make(mean + 0.3, std=[1.2, 1.0, 0.9])
    mc = np.mean(ref.logpdf(s[:20000]) - stats.multivariate_normal(mean + 0.3, np.diag([1.44, 1.0, 0.81])).logpdf(s[:20000]))
    assert float(dists.kl(d, q)) == pytest.approx(mc, rel=0.05)


def test_gaussian_kl_from_uniform_matches_monte_carlo():
    lo, hi = np.array([0.0, -2.0]), np.array([1.0, 2.0])
    d = gaussian.make([0.4, 0.3], cov_matrix=[[0.2, 0.05], [0.05, 1.5]])
    z = np.random.default_rng(1).uniform(lo, hi, size=(200000, 2))
    mc = np.mean(-np.log(np.prod(hi - lo)) - stats.multivariate_normal([0.4, 0.3], [[0.2, 0.05], [0.05, 1.5]]).logpdf(z))
    assert float(dists.kl_from_uniform(lo, hi, d)) == pytest.approx(mc, rel=0.01)


def test_distributions_are_differentiable_pytrees():
    d = gaussian.make([0.0, 0.0], std=[1.0, 2.0])
    g = jax.grad(lambda d: dists.log_prob(d, jnp.array([1.0, 1.0])))(d)
    assert np.isfinite(np.asarray(g.mean)).all() and np.abs(np.asarray(g.mean)).sum() > 0
    batched = jax.vmap(lambda m: dists.entropy(gaussian.make(m, std=[1.0, 2.0])))(jnp.zeros((3, 2)))
    assert batched.shape == (3,)


def test_beta_matches_scipy_and_its_own_samples():
    import scipy.stats as st

    from sim2real.dists import beta

    p, q = beta.make([2.0, 0.7], [3.0, 1.5]), beta.make([1.0, 1.2], [1.0, 4.0])
    ref = [st.beta(2, 3), st.beta(0.7, 1.5)]
    np.testing.assert_allclose(float(dists.entropy(p)), sum(r.entropy() for r in ref), rtol=1e-5)
    np.testing.assert_allclose(float(dists.log_prob(p, np.array([0.3, 0.6]))),
                               ref[0].logpdf(0.3) + ref[1].logpdf(0.6), rtol=1e-5)
    xs = np.asarray(dists.sample(jax.random.PRNGKey(0), p, 200_000))
    mc = np.mean(np.asarray(beta.log_prob(p, xs) - beta.log_prob(q, xs)))
    np.testing.assert_allclose(float(dists.kl(p, q)), mc, atol=0.01)
    u = np.random.default_rng(0).uniform([0.1, 0.2], [0.5, 0.9], (200_000, 2))
    np.testing.assert_allclose(float(dists.kl_from_uniform([0.1, 0.2], [0.5, 0.9], p)),
                               np.mean(-np.log(0.4 * 0.7) - np.asarray(beta.log_prob(p, u))), atol=0.01)
    m = beta.from_moments([0.3, 0.5], [0.01, 0.02])
    np.testing.assert_allclose(beta.mean(m), [0.3, 0.5], rtol=1e-5)
    np.testing.assert_allclose(beta.var(m), [0.01, 0.02], rtol=1e-4)
