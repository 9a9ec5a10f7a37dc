"""sim2real envs in Brax: the physics is redrawn at every reset inside Brax's training wrapper,
and Brax's own PPO trains through it."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest

pytest.importorskip("brax")

from sim2real.interop.brax import BraxEnv, wrap_for_training  # noqa: E402


def test_every_reset_draws_new_physics_and_an_episode_keeps_its_own():
    env = BraxEnv("pendulum", physics={"mass:pole": (0.5, 2.0)})
    w = wrap_for_training(env, episode_length=5)
    st = jax.jit(w.reset)(jax.random.split(jax.random.PRNGKey(0), 4))
    step = jax.jit(w.step)
    i = env.env.spec.index("mass:pole")
    masses, dones = [np.asarray(st.pipeline_state.z[:, i])], []
    for t in range(15):
        st = step(st, jnp.ones((4, 1)))
        if t == 0:  # full positive action: the top of the motor's ctrlrange
            np.testing.assert_allclose(np.asarray(st.pipeline_state.state.data.ctrl), 2.0)
        masses.append(np.asarray(st.pipeline_state.z[:, i]))
        dones.append(np.asarray(st.done))
    masses, dones = np.array(masses), np.array(dones)
    assert dones[:, 0].tolist() == [0, 0, 0, 0, 1] * 3          # Brax's EpisodeWrapper's time limit
    episodes = masses[[0, 5, 10, 15]]                             # one per episode, per env
    for k in range(1, 5):                                         # constant within an episode ...
        np.testing.assert_array_equal(masses[k], masses[0])
    assert np.all(episodes[1:] != episodes[:-1])                  # ... new at every reset
    assert np.all((episodes >= 0.5) & (episodes <= 2.0))
    assert len(np.unique(episodes)) == episodes.size              # every env its own draws


def test_wrapping_is_refused_with_brax_randomization_or_another_env():
    env = BraxEnv("pendulum")
    with pytest.raises(ValueError, match="draws its physics at every reset"):
        wrap_for_training(env, randomization_fn=lambda sys, rng: (sys, None))
    with pytest.raises(TypeError, match="sim2real BraxEnv"):
        wrap_for_training(object())
    with pytest.raises(Exception, match="mass:nothing"):
        BraxEnv("pendulum", physics={"mass:nothing": (0.5, 2.0)})


# Brax's own trainers, tiny budgets: the adapter's step fills PPO's rollouts and SAC's replay
# buffer, physics redrawn at every reset
BRAX_AGENTS = {
    "ppo": dict(num_timesteps=2048, episode_length=50, num_envs=16, batch_size=16, unroll_length=8,
                num_minibatches=2, num_updates_per_batch=2, num_evals=2),
    "sac": dict(num_timesteps=1024, episode_length=50, num_envs=8, batch_size=32, min_replay_size=128,
                max_replay_size=2048, grad_updates_per_step=1, num_evals=2),
}


@pytest.mark.slow  # ~30-60 s each on 2 cores, mostly Brax's compilation (make test-slow)
@pytest.mark.parametrize("agent", sorted(BRAX_AGENTS))
def test_brax_agents_train_on_a_sim2real_env_unchanged(agent):
    import importlib

    trainer = importlib.import_module(f"brax.training.agents.{agent}.train")
    env = BraxEnv("pendulum", physics={"mass:pole": (0.5, 2.0)})
    make_policy, params, metrics = trainer.train(env, wrap_env_fn=wrap_for_training, seed=0, **BRAX_AGENTS[agent])
    assert np.isfinite(float(metrics["eval/episode_reward"]))
    act = make_policy(params, deterministic=True)
    a, _ = act(jnp.zeros((1, env.observation_size)), jax.random.PRNGKey(0))
    assert a.shape == (1, env.action_size) and np.all(np.abs(np.asarray(a)) <= 1.0)
