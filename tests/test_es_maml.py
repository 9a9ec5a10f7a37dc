"""ES-MAML: the ES gradient estimate, the PPO adaptation operator, and the jitted, vmapped meta step."""
import csv
import dataclasses
import os
import shutil

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


# small: the driver tests check the meta step's plumbing, not that adaptation helps
DRIVER_BASE = ["env=prismatic", "env_options.episode_length=20", "progress=false", "tensorboard=false",
               "ppo.num_envs=8", "ppo.num_steps=8", "ppo.num_minibatches=2", "ppo.num_epochs=1",
               "ppo.net.hidden=[16,16]", "dr.params=[mass:carriage]", "dr.low=[50.0]", "dr.high=[150.0]"]


def driver_config(out_dir, *extra):
    from sim2real.common import config as config_lib
    from sim2real.training.driver import TrainConfig

    return config_lib.load(TrainConfig, [f"out_dir={out_dir}", *DRIVER_BASE, *extra])


def load_script(name):
    import importlib.util

    path = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "scripts", f"{name}.py")
    spec = importlib.util.spec_from_file_location(f"script_{name}", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def udr_run(tmp_path_factory):
    """A finished 1-seed uniform-DR run: the warm start of the driver tests."""
    from sim2real.training.driver import train

    return train(driver_config(tmp_path_factory.mktemp("udr"), "name=udr", "total_steps=128"))


def _es_overrides(udr_run):
    per_update = 4 * (2 * 64 + 20)  # population x (inner updates x batch + one 20-step scoring episode)
    es = ["algo=es_maml", "num_seeds=2", "updates_per_chunk=1", f"total_steps={2 * per_update}",
          f"algo_options={{population: 4, inner_updates: 2, warm_start: {udr_run['run_dir']}}}"]
    return es, per_update


@pytest.mark.slow  # ~105 s on 2 cores (make test-slow); the fast set keeps ES-MAML's own tests and the PPO driver's resume
def test_meta_step_runs_in_the_training_driver_vmapped_over_seeds_and_resumes(tmp_path, udr_run):
    """algo=es_maml through scripts/train.py's driver: the jitted meta step vmapped over 2 seeds,
    warm-started from a 1-seed uniform-DR run, interrupted and resumed = uninterrupted."""
    from sim2real.training.driver import train

    es, per_update = _es_overrides(udr_run)
    full = train(driver_config(tmp_path, *es, "name=full"))
    train(driver_config(tmp_path, *es, "name=part", "max_chunks=1"))
    resumed = train(driver_config(tmp_path, *es, "name=part", "resume=true"))

    theta = lambda out: np.asarray(jax.vmap(lambda s: jax.flatten_util.ravel_pytree(out["algo"].theta(s))[0])(
        out["state"]))                                                           # [S, n]
    warm = np.asarray(jax.flatten_util.ravel_pytree(udr_run["state"].params)[0])  # 1 seed
    t = theta(full)
    assert t.shape == (2, warm.size) and np.all(np.isfinite(t))
    assert np.abs(t - warm[None]).max(1).min() > 0              # both seeds moved from the warm start
    assert not np.allclose(t[0], t[1])                          # seeds differ
    np.testing.assert_array_equal(theta(resumed), t)            # resume == uninterrupted
    assert np.asarray(full["state"].step).tolist() == [2, 2]
    rows = list(csv.DictReader(open(os.path.join(full["run_dir"], "metrics.csv"))))
    assert [int(r["env_steps"]) for r in rows if r["seed"] == "0"] == [per_update, 2 * per_update]
    assert all(np.isfinite(float(r["fitness_mean"])) for r in rows)


@pytest.mark.slow  # three more compilations of the adapting tester (make test-slow)
def test_the_driver_scores_adapted_policies_with_test_adapt(tmp_path, udr_run):
    """The driver's test section with test.adapt=true scores the policies after adaptation: the
    adapted policies' returns, not those of the meta-policies themselves; an algorithm without an
    adaptation operator is refused."""
    from sim2real.training.driver import make_tester, train

    es, _ = _es_overrides(udr_run)
    test = ["test.every=100", "test.params=[mass:carriage]", "test.points=[[60],[140]]", "test.adapt=true"]
    full = train(driver_config(tmp_path, *es, *test, "name=full"))
    scored = np.load(os.path.join(full["run_dir"], "test.npz"))["returns"][-1]            # [S, 2]
    cfg = driver_config(tmp_path, *es, *test)
    adapted = np.asarray(make_tester(cfg, full["env"], full["algo"])[0](full["state"]))
    plain_cfg = dataclasses.replace(cfg, test=dataclasses.replace(cfg.test, adapt=False))
    plain = np.asarray(make_tester(plain_cfg, full["env"], full["algo"])[0](full["state"]))
    assert scored.shape == (2, 2) and np.all(np.isfinite(scored))
    np.testing.assert_allclose(adapted, scored, rtol=1e-5)
    assert not np.allclose(plain, scored)
    with pytest.raises(Exception, match="test.adapt=true needs an algorithm with an adaptation operator"):
        train(driver_config(tmp_path, "name=udr_adapt", "total_steps=128", *test))


def test_warm_start_must_match_the_network(tmp_path, udr_run):
    from sim2real.training.driver import build_algo  # (the driver reads warm starts; no algorithm reads run folders)

    env = make("prismatic", episode_length=20)
    cfg = driver_config(tmp_path, "algo=es_maml", "ppo.net.hidden=[8,8]",
                        f"algo_options={{population: 4, warm_start: {udr_run['run_dir']}}}")
    with pytest.raises(ValueError, match="network"):
        build_algo(cfg, env)
    cfg = driver_config(tmp_path, "algo=es_maml", f"algo_options.warm_start={tmp_path}/nothing")
    with pytest.raises(FileNotFoundError, match="nothing"):
        build_algo(cfg, env)


@pytest.mark.slow
def test_few_shot_evaluation_of_a_run_and_of_its_exported_policies(tmp_path, udr_run):
    """scripts/evaluate.py adapt=true on an es_maml run: returns before and after adaptation over a
    physics grid; the run folder without checkpoints (and without the run it was warm-started
    from) gives the same numbers from its exported policies; a UDR run cannot be adapted."""
    from sim2real.training.driver import train

    per_update = 4 * (2 * 64 + 20)
    es = ["algo=es_maml", "num_seeds=2", "updates_per_chunk=1", f"total_steps={2 * per_update}",
          f"algo_options={{population: 4, inner_updates: 2, warm_start: {udr_run['run_dir']}}}"]
    full = train(driver_config(tmp_path, *es, "name=full"))
    evaluate = load_script("evaluate")
    evaluate.main([f"run={full['run_dir']}", "adapt=true", "x=mass:carriage=60,140", "episodes=1"])
    for name in ("returns.csv", "returns_before.csv"):  # mass, mean, std, one column per seed
        table = np.loadtxt(os.path.join(full["run_dir"], "eval", "mass-carriage", name), delimiter=",", skiprows=1)
        assert table.shape == (2, 5) and np.all(np.isfinite(table[:, 1]))
        np.testing.assert_allclose(table[:, 1], table[:, 3:].mean(1), rtol=1e-4)
    # a copy of the run folder without checkpoints is evaluated from its exported policies
    part = os.path.join(str(tmp_path), "part")
    shutil.copytree(full["run_dir"], part, ignore=shutil.ignore_patterns("eval"))
    shutil.rmtree(os.path.join(part, "checkpoints"))
    cfg_path = os.path.join(part, "config.yaml")  # ... and needs no longer the run it was warm-started from
    text = open(cfg_path).read()
    assert udr_run["run_dir"] in text
    open(cfg_path, "w").write(text.replace(udr_run["run_dir"], os.path.join(str(tmp_path), "gone")))
    evaluate.main([f"run={part}", "adapt=true", "x=mass:carriage=60,140", "episodes=1"])
    for name in ("returns.csv", "returns_before.csv"):
        assert (open(os.path.join(part, "eval", "mass-carriage", name)).read()
                == open(os.path.join(full["run_dir"], "eval", "mass-carriage", name)).read())
    with pytest.raises(Exception, match="adaptation operator"):  # a UDR run has none
        evaluate.main([f"run={udr_run['run_dir']}", "adapt=true", "x=mass:carriage=60,140"])



def test_bad_config_is_named():
    env = make("pendulum")
    with pytest.raises(ValueError, match="population"):
        ESMAML(env, PPOConfig(), DRConfig(), ESMAMLConfig(population=3))
    with pytest.raises(ValueError, match="MLP"):
        ESMAML(env, PPOConfig(net=NetConfig(kind="lstm")), DRConfig(), ESMAMLConfig())
