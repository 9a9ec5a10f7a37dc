"""HalfCheetah: Gymnasium HalfCheetah-v5 observations, reward and reset noise on MJX."""
from __future__ import annotations

import jax
import jax.numpy as jnp

from sim2real.envs import locomotion
from sim2real.envs.base import Env, EnvConfig


class HalfCheetah(Env):
    """Planar cheetah; obs ``[17]`` (qpos[1:], qvel), action ``[6]`` in [-1, 1].

    Reward = dx/dt - 0.1 |a|^2; never terminates (only diverged physics does), truncated at 1000.
    """

    name = "halfcheetah"
    xml = "halfcheetah.xml"
    default_config = EnvConfig(episode_length=1000, frame_skip=5, timestep=0.01, iterations=2, ls_iterations=6)
    metric_names = ("x_position", "x_velocity")

    def declare_params(self, m):
        return locomotion.locomotion_params(m, "torso", damping_scale=True)

    def init_qpos_qvel(self, key):
        k1, k2 = jax.random.split(key)
        m = self.mj_model
        qpos = jnp.asarray(m.qpos0) + jax.random.uniform(k1, (m.nq,), minval=-0.1, maxval=0.1)
        return qpos, 0.1 * jax.random.normal(k2, (m.nv,))

    def observe(self, qpos, qvel, goal):
        return locomotion.forward_obs(qpos, qvel, clip_vel=None)

    def task(self, data0, data, action, goal):
        x_vel = (data.qpos[0] - data0.qpos[0]) / self.dt
        reward = x_vel - 0.1 * jnp.sum(jnp.square(action))
        return reward, jnp.zeros((), bool), {"x_position": data.qpos[0], "x_velocity": x_vel}
