"""1-DOF prismatic drive under a PD position loop (the EMPS hardware's structure and numbers).

The action is the position reference ``qg`` [m] fed to the servo; the task is to bring the
carriage to a goal drawn at reset. The diagnosis tool uses the same MJCF with recorded references.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp

from sim2real.envs import classic
from sim2real.envs.base import Env, EnvConfig


class PrismaticDrive(Env):
    """obs ``[q, q_dot, goal]``; reward = -|q - goal| / 0.1 - 1e-3 |action - goal|; 1 kHz physics."""

    name = "prismatic"
    xml = "prismatic.xml"
    default_config = EnvConfig(episode_length=200, frame_skip=10)
    metric_names = ("error",)

    def declare_params(self, m):
        return classic.small_env_params(m, damping_unit="N s/m")

    def init_qpos_qvel(self, key):
        return jax.random.uniform(key, (1,), minval=0.0, maxval=0.05), jnp.zeros(1)

    def init_goal(self, key):
        return jax.random.uniform(key, (1,), minval=0.0, maxval=0.2)

    def observe(self, qpos, qvel, goal):
        return jnp.stack([qpos[0], qvel[0], goal[0]])

    def task(self, data0, data, action, goal):
        err = jnp.abs(data.qpos[0] - goal[0])
        reward = -err / 0.1 - 1e-3 * jnp.abs(action[0] - goal[0])
        return reward, jnp.zeros((), bool), {"error": err}
