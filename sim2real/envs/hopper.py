"""Hopper: Gymnasium Hopper-v5 observations, reward, termination and reset noise on MJX."""
from __future__ import annotations

import jax.numpy as jnp

from sim2real.envs import locomotion
from sim2real.envs.base import Env, EnvConfig


class Hopper(Env):
    """Planar hopper; obs ``[11]`` (qpos[1:], clipped qvel), action ``[3]`` in [-1, 1].

    Reward = healthy (1 while healthy) + dx/dt - 1e-3 |a|^2; terminated when z <= 0.7,
    |pitch| >= 0.2 or any state entry beyond +-100 (Gymnasium v5 rules).
    """

    name = "hopper"
    xml = "hopper.xml"
    # 8 ms control period as Gymnasium's 0.002 s x 4, reached with 2 Euler steps of 4 ms and a
    # trimmed solver (2 Newton iterations converge here; 1 does not): 2.4x faster than 4 x 2 ms
    # on CPU. Closeness to MuJoCo's default settings is tested in tests/test_accuracy.py.
    default_config = EnvConfig(episode_length=1000, frame_skip=2, timestep=0.004, iterations=2, ls_iterations=4)
    metric_names = ("x_position", "x_velocity")

    def declare_params(self, m):
        return locomotion.locomotion_params(m, "torso_geom")

    def init_qpos_qvel(self, key):
        return locomotion.uniform_reset(key, jnp.asarray(self.mj_model.qpos0), self.mj_model.nv, 5e-3)

    def observe(self, qpos, qvel, goal):
        return locomotion.forward_obs(qpos, qvel)

    def task(self, data0, data, action, goal):
        x_vel = (data.qpos[0] - data0.qpos[0]) / self.dt
        z, angle = data.qpos[1], data.qpos[2]
        state = jnp.concatenate([data.qpos[2:], data.qvel])
        healthy = (jnp.all(jnp.abs(state) < 100.0) & (z > 0.7) & (jnp.abs(angle) < 0.2))
        reward = healthy * 1.0 + x_vel - 1e-3 * jnp.sum(jnp.square(action))
        return reward, ~healthy, {"x_position": data.qpos[0], "x_velocity": x_vel}
