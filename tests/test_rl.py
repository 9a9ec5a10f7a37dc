"""PPO pieces: GAE against a Python loop, normalisation, and learning on a small task."""
import jax.numpy as jnp
import numpy as np
import pytest

from sim2real.rl import normalize
from sim2real.rl.gae import gae


def gae_reference(r, v, nv, term, trunc, gamma, lam):
    T, B = r.shape
    adv = np.zeros((T, B))
    for b in range(B):
        running = 0.0
        for t in reversed(range(T)):
            target = r[t, b] + (0.0 if term[t, b] else gamma * nv[t, b])
            delta = target - v[t, b]
            if term[t, b] or trunc[t, b]:
                running = 0.0
            running = delta + gamma * lam * running
            adv[t, b] = running
    return adv


def test_gae_matches_python_loop_and_bootstraps_truncation():
    rng = np.random.default_rng(0)
    T, B = 12, 5
    r, v, nv = rng.normal(size=(T, B)), rng.normal(size=(T, B)), rng.normal(size=(T, B))
    term = rng.random((T, B)) < 0.15
    trunc = (rng.random((T, B)) < 0.15) & ~term
    adv, ret = gae(jnp.asarray(r), jnp.asarray(v), jnp.asarray(nv), jnp.asarray(term), jnp.asarray(trunc), 0.97, 0.9)
    want = gae_reference(r, v, nv, term, trunc, 0.97, 0.9)
    np.testing.assert_allclose(np.asarray(adv), want, rtol=1e-5, atol=1e-5)
    np.testing.assert_allclose(np.asarray(ret), want + v, rtol=1e-5, atol=1e-5)
    # a truncated last step keeps gamma * V(next) in its target; a terminated one does not
    t1 = np.zeros((1, 1), bool)
    a_trunc, _ = gae(jnp.ones((1, 1)), jnp.zeros((1, 1)), jnp.full((1, 1), 10.0), jnp.asarray(t1), jnp.asarray(~t1), 0.9, 0.9)
    a_term, _ = gae(jnp.ones((1, 1)), jnp.zeros((1, 1)), jnp.full((1, 1), 10.0), jnp.asarray(~t1), jnp.asarray(t1), 0.9, 0.9)
    assert float(a_trunc[0, 0]) == pytest.approx(10.0) and float(a_term[0, 0]) == pytest.approx(1.0)


def test_running_stats_match_numpy():
    rng = np.random.default_rng(1)
    x = rng.normal(3.0, 2.0, size=(7, 50, 4)).astype(np.float32)
    s = normalize.init(4)
    for chunk in x:
        s = normalize.update(s, jnp.asarray(chunk))
    np.testing.assert_allclose(np.asarray(s.mean), x.reshape(-1, 4).mean(0), rtol=1e-4)
    np.testing.assert_allclose(np.asarray(s.var), x.reshape(-1, 4).var(0), rtol=1e-3)
