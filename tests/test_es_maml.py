"""ES-MAML: the ES gradient estimate, the PPO adaptation operator, and the jitted, vmapped meta step."""
import jax
import jax.flatten_util
import jax.numpy as jnp
import numpy as np
import optax
import pytest
from evosax.algorithms import Open_ES

from sim2real.algos.base import DRConfig
from sim2real.algos.es_maml import ESMAML, ESMAMLConfig, grad_estimate
from sim2real.envs import make
from sim2real.rl.networks import NetConfig
from sim2real.rl.ppo import PPOConfig


def test_es_gradient_points_along_true_gradient_on_quadratic():
    target = {"w": jnp.linspace(-1.0, 1.0, 20), "b": jnp.array([0.5, -0.5])}
    theta = {"w": jnp.zeros(20), "b": jnp.zeros(2)}
    f = lambda p: -sum(jnp.sum((p[k] - target[k]) ** 2) for k in p)
    es = Open_ES(population_size=400, solution=theta, optimizer=optax.sgd(0.05),
                 std_schedule=optax.constant_schedule(0.05))
    params = es.default_params
    state = es.init(jax.random.PRNGKey(0), theta, params)
    true = jax.flatten_util.ravel_pytree(jax.grad(f)(theta))[0]
    est = grad_estimate(es, params, state, f, jax.random.PRNGKey(1))
    cos = float(est @ true / (jnp.linalg.norm(est) * jnp.linalg.norm(true)))
    assert cos > 0.8
    # and OpenES's (rank-shaped, minimising) step on -f moves theta towards the optimum
    for i in range(60):
        pop, state = es.ask(jax.random.PRNGKey(10 + i), state, params)
        state, _ = es.tell(jax.random.PRNGKey(100 + i), pop, -jax.vmap(f)(pop), state, params)
    assert float(f(es.get_mean(state))) > 0.2 * float(f(theta))


@pytest.fixture(scope="module")
def esmaml():
    env = make("prismatic", episode_length=50)
    dr = DRConfig(params=("mass:carriage",), low=(50.0,), high=(150.0,))
    return ESMAML(env, PPOConfig(num_envs=16, num_steps=32, num_minibatches=4, lr=3e-3), dr,
                  ESMAMLConfig(population=4, inner_updates=10))


def test_inner_loop_adaptation_improves_return(esmaml):
    """The PPO adaptation operator U: a few updates on one physics raise the deterministic return."""
    st = esmaml.init(jax.random.PRNGKey(0))
    theta, stats = esmaml.policy(st)
    z = jnp.asarray(esmaml.env.z_of(**{"mass:carriage": 95.0}))
    after, before = jax.jit(jax.vmap(lambda k: esmaml.adapt_and_evaluate(theta, stats, z, k)))(
        jax.random.split(jax.random.PRNGKey(1), 4))
    assert float(jnp.mean(after)) > float(jnp.mean(before)) + 5.0


def test_meta_step_jits_and_vmaps_over_seeds():
    # smaller than the fixture: this checks the meta step's plumbing, not that adaptation helps
    env = make("prismatic", episode_length=20)
    dr = DRConfig(params=("mass:carriage",), low=(50.0,), high=(150.0,))
    esmaml = ESMAML(env, PPOConfig(num_envs=8, num_steps=8, num_minibatches=2, num_epochs=1), dr,
                    ESMAMLConfig(population=4, inner_updates=2))
    st = jax.jit(jax.vmap(esmaml.init))(jax.random.split(jax.random.PRNGKey(0), 2))
    st2, m = jax.jit(jax.vmap(esmaml.update))(st)
    assert m["fitness_mean"].shape == (2,) and np.all(np.isfinite(np.asarray(m["fitness_mean"])))
    flat = lambda st, i: jax.flatten_util.ravel_pytree(
        jax.tree_util.tree_map(lambda x: x[i], jax.vmap(esmaml.theta)(st)))[0]
    assert float(jnp.abs(flat(st2, 0) - flat(st, 0)).max()) > 0  # theta moved
    a, b = flat(st2, 0), flat(st2, 1)
    assert not np.allclose(np.asarray(a), np.asarray(b))  # seeds differ
    assert int(st2.step[0]) == 1


def test_bad_config_is_named():
    env = make("pendulum")
    with pytest.raises(ValueError, match="population"):
        ESMAML(env, PPOConfig(), DRConfig(), ESMAMLConfig(population=3))
    with pytest.raises(ValueError, match="MLP"):
        ESMAML(env, PPOConfig(net=NetConfig(kind="lstm")), DRConfig(), ESMAMLConfig())
