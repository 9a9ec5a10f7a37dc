"""A MuJoCo Playground task as a sim2real env: its MjModel read into a ParamSpec, the physics an
argument of reset/step (one trace for every physics), and sim2real's outer loops training on it."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

pytest.importorskip("mujoco_playground")

from sim2real.envs.registry import make  # noqa: E402
from sim2real.physics.params import UnknownNameError  # noqa: E402

NAME = "playground:CheetahRun"


@pytest.fixture(scope="module")
def env():
    return make(NAME, episode_length=6, reset_pool=8)


def test_the_tasks_model_becomes_the_parameter_spec(env):
    m = env.inner.mj_model
    moving = [m.body(b).name for b in range(1, m.nbody) if m.body_mass[b] > 0]
    assert [n for n in env.spec.names if n.startswith("mass:")] == [f"mass:{b}" for b in moving]
    for b in moving:  # nominal values are the task's own
        assert env.spec.params[env.spec.index(f"mass:{b}")].default == pytest.approx(m.body(b).mass[0], rel=1e-5)
    robot_geom = next(g for g in range(m.ngeom) if m.geom_bodyid[g] > 0)   # (geom 0 is the floor)
    assert env.spec.params[env.spec.index("friction")].default == pytest.approx(m.geom_friction[robot_geom, 0])
    assert {f"gain:{m.actuator(a).name}" for a in range(m.nu)} <= set(env.spec.names)
    assert env.obs_size == 17 and env.action_size == 6 and env.dt == pytest.approx(0.01)


TRACES = []


@pytest.fixture(scope="module")
def rollout(env):
    """``run(key, z, actions [6, A]) -> (qpos [6, nq], reward, truncated, terminated [6])``, jitted once."""

    def run(key, z, actions):
        TRACES.append(1)

        def body(s, a):
            s = env.step(s, a, z)
            return s, (s.data.qpos, s.reward, s.truncated, s.terminated)

        return jax.lax.scan(body, env.reset(key, z), actions)[1]

    return jax.jit(run)


def test_physics_is_an_argument_one_trace_for_every_physics(env, rollout):
    key, acts = jax.random.PRNGKey(0), 0.5 * jnp.ones((6, env.action_size))
    nominal = rollout(key, jnp.asarray(env.default_z()), acts)
    heavy = rollout(key, jnp.asarray(env.z_of(**{"mass:torso": 4 * env.spec.params[env.spec.index("mass:torso")].default})), acts)
    slippery = rollout(key, jnp.asarray(env.z_of(friction=0.0, damping_scale=5.0)), acts)
    assert len(TRACES) == 1
    x = [np.asarray(r[0]) for r in (nominal, heavy, slippery)]
    assert not np.allclose(x[0], x[1]) and not np.allclose(x[0], x[2])   # the physics reached the task
    assert np.asarray(nominal[2]).tolist() == [False] * 5 + [True]         # sim2real's time limit
    assert not np.asarray(nominal[3]).any() and np.isfinite(np.asarray(nominal[1])).all()


def test_the_command_path_sits_in_front_of_the_task(env, rollout):
    """A 1-step action delay shifts the response; a gain of 0 silences its joint."""
    key = jax.random.PRNGKey(1)
    acts = jnp.zeros((6, env.action_size)).at[0].set(1.0)
    z0 = jnp.asarray(env.default_z())
    now = np.asarray(rollout(key, z0, acts)[0])
    late = np.asarray(rollout(key, jnp.asarray(env.z_of(action_delay=1.0)), acts)[0])
    silent = np.asarray(rollout(key, z0.at[env.spec.index("gain:bthigh")].set(0.0), acts)[0])
    assert not np.allclose(now[0], late[0])
    assert not np.allclose(now[:, 3], silent[:, 3])   # bthigh is qpos 3


def test_unknown_tasks_and_the_tasks_own_timing_are_refused():
    with pytest.raises(UnknownNameError, match="CheetahRun"):
        make("playground:CheetahRnu")
    with pytest.raises(ValueError, match="frame_skip"):
        make(NAME, frame_skip=2)
    with pytest.raises(ValueError, match="reset_pool"):
        make(NAME, reset_pool=0)


@pytest.mark.slow
def test_lsdr_trains_on_a_playground_task(tmp_path):
    from sim2real.common import config as config_lib
    from sim2real.training.driver import TrainConfig, train

    cfg = config_lib.load(TrainConfig, [
        "config=playground_cheetah_lsdr", "total_steps=2048", "ppo.num_envs=8", "ppo.num_steps=16",
        "ppo.num_minibatches=2", "algo_options.num_contexts=4", "algo_options.dist_start=1",
        "algo_options.dist_every=1", "algo_options.eval_horizon=8", "updates_per_chunk=4", "num_seeds=1",
        f"out_dir={tmp_path}", "progress=false", "tensorboard=false"])
    res = train(cfg)
    import csv
    import os

    rows = list(csv.DictReader(open(os.path.join(res["run_dir"], "metrics.csv"))))
    assert len(rows) == 16 and np.isfinite(float(rows[-1]["dist_eval_return"]))


@pytest.mark.slow  # compiles the task's settling reset once more (~40 s on 2 cores)
def test_an_auto_reset_starts_from_the_tasks_own_settled_states(env):
    """Auto-resets draw from the pool of the task's resets (computed once, nominal physics) with
    fresh keys, so an episode boundary costs no settling; the new physics acts from the first step."""
    z = jnp.asarray(env.z_of(obs_noise=0.0))
    a, b = env.auto_reset(jax.random.PRNGKey(3), z), env.auto_reset(jax.random.PRNGKey(4), z)
    pool = np.asarray(env.pool().data.qpos)
    assert pool.shape[0] == 8 and len(np.unique(pool[:, 3])) == 8
    for s in (a, b):
        assert np.any(np.all(np.isclose(pool, np.asarray(s.data.qpos)), axis=1))
        np.testing.assert_allclose(np.asarray(s.obs), np.asarray(s.inner_obs))
    assert not np.array_equal(np.asarray(a.key), np.asarray(b.key))
