"""Cart-pole swing-up and balance with dm_control-style smooth rewards."""
from __future__ import annotations

import jax
import jax.numpy as jnp

from sim2real.envs import classic
from sim2real.envs.base import Env, EnvConfig


class Cartpole(Env):
    """obs ``[x, cos, sin, x_dot, theta_dot]``, action force command in [-1, 1] (x 10 N).

    Reward = upright * centred * small_control * small_velocity, each in (0, 1]
    (upright = (1 + cos theta) / 2). Swing-up starts hanging down; 1000 steps of 10 ms.
    """

    name = "cartpole"
    xml = "cartpole.xml"
    default_config = EnvConfig(episode_length=1000, frame_skip=1)
    metric_names = ("upright",)
    swing_up = True

    def declare_params(self, m):
        return classic.small_env_params(m)

    def joint_damping_dofs(self, m):
        return [1]  # the pole hinge; the rail keeps its own damping

    def init_qpos_qvel(self, key):
        k1, k2 = jax.random.split(key)
        start = jnp.pi if self.swing_up else 0.0
        qpos = jnp.array([0.0, start]) + jax.random.uniform(k1, (2,), minval=-0.05, maxval=0.05)
        return qpos, 0.01 * jax.random.normal(k2, (2,))

    def observe(self, qpos, qvel, goal):
        return jnp.stack([qpos[0], jnp.cos(qpos[1]), jnp.sin(qpos[1]), qvel[0], qvel[1]])

    def task(self, data0, data, action, goal):
        x, th = data.qpos[0], data.qpos[1]
        upright = (1.0 + jnp.cos(th)) / 2.0
        centred = (1.0 + classic.tolerance(x, 2.0)) / 2.0
        small_u = (4.0 + classic.tolerance(jnp.clip(action[0], -1, 1), 1.0)) / 5.0
        small_v = (1.0 + classic.tolerance(data.qvel[1], 5.0)) / 2.0
        reward = upright * centred * small_u * small_v
        return reward, jnp.zeros((), bool), {"upright": (jnp.cos(th) > 0.95).astype(jnp.float32)}


class CartpoleBalance(Cartpole):
    """Same cart-pole, starting near upright."""

    name = "cartpole_balance"
    swing_up = False
