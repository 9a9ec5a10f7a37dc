"""Gymnasium adapters: Gymnasium's own env checker, vector auto-reset, physics redrawn per reset."""
import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")


def test_single_env_passes_gymnasiums_env_checker():
    from gymnasium.utils.env_checker import check_env

    from sim2real.interop.gymnasium import GymnasiumEnv

    env = GymnasiumEnv("pendulum", physics={"mass:pole": (0.5, 2.0)}, episode_length=20)
    check_env(env, skip_render_check=True)
    obs, info = env.reset(seed=3)
    again, info2 = env.reset(seed=3)
    np.testing.assert_array_equal(obs, again)
    np.testing.assert_array_equal(info["z"], info2["z"])


def test_vector_env_resets_finished_envs_with_new_physics_in_the_same_step():
    from sim2real.interop.gymnasium import GymnasiumVectorEnv

    venv = GymnasiumVectorEnv("pendulum", num_envs=6, physics={"mass:pole": (0.5, 2.0)}, episode_length=5)
    i = venv.physics_names.index("mass:pole")
    obs, info = venv.reset(seed=0)
    assert obs.shape == (6, venv.single_observation_space.shape[0]) and obs.dtype == np.float32
    z0 = info["z"][:, i]
    assert len(np.unique(z0)) == 6 and ((z0 >= 0.5) & (z0 <= 2.0)).all()  # one draw per env
    act = np.zeros((6, venv.single_action_space.shape[0]), np.float32)
    for t in range(5):
        obs, rew, term, trunc, info = venv.step(act)
        assert rew.shape == (6,) and np.isfinite(rew).all()
    assert trunc.all() and info["_final_obs"].all()  # the time limit: every env ended at step 5
    assert not np.allclose(info["final_obs"], obs)  # obs is the next episode's first one
    obs, rew, term, trunc, info = venv.step(act)
    assert not np.allclose(info["z"][:, i], z0)  # ... under new physics
    with pytest.raises(ValueError, match="actions"):
        venv.step(np.full((6, 1), np.nan, np.float32))


def test_physics_box_outside_the_bounds_or_unknown_is_refused():
    from sim2real.interop.gymnasium import GymnasiumVectorEnv

    with pytest.raises(ValueError, match="mass:pole"):
        GymnasiumVectorEnv("pendulum", 2, physics={"mass:pole": (-1.0, 2.0)})
    with pytest.raises(KeyError, match="mass:pole"):
        GymnasiumVectorEnv("pendulum", 2, physics={"mass:pol": (0.5, 2.0)})
