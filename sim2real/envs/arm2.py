"""Planar 2-link arm with torque motors, reaching a goal point in its vertical plane."""
from __future__ import annotations

import jax
import jax.numpy as jnp

from sim2real.envs import classic
from sim2real.envs.base import Env, EnvConfig

L1, L2 = 0.5, 0.4


def tip(q):
    """End-effector (x, z) of joint angles ``q [2]`` (0 = hanging down)."""
    a, b = q[0], q[0] + q[1]
    return jnp.stack([-L1 * jnp.sin(a) - L2 * jnp.sin(b), -L1 * jnp.cos(a) - L2 * jnp.cos(b)])


class Arm2(Env):
    """obs ``[cos q, sin q, q_dot, goal]`` (8); reward = -|tip - goal| - 0.01 |a|^2; 200 steps of 20 ms."""

    name = "arm2"
    xml = "arm2.xml"
    default_config = EnvConfig(episode_length=200, frame_skip=4)
    metric_names = ("distance",)

    def declare_params(self, m):
        return classic.small_env_params(m)

    def init_qpos_qvel(self, key):
        return jax.random.uniform(key, (2,), minval=-0.1, maxval=0.1), jnp.zeros(2)

    def init_goal(self, key):
        k1, k2 = jax.random.split(key)
        r = jax.random.uniform(k1, (), minval=0.3, maxval=0.85)
        ang = jax.random.uniform(k2, (), minval=-jnp.pi, maxval=jnp.pi)
        return jnp.stack([r * jnp.sin(ang), -r * jnp.cos(ang)])

    def observe(self, qpos, qvel, goal):
        return jnp.concatenate([jnp.cos(qpos), jnp.sin(qpos), qvel, goal])

    def task(self, data0, data, action, goal):
        dist = jnp.linalg.norm(tip(data.qpos) - goal)
        reward = -dist - 0.01 * jnp.sum(jnp.square(action))
        return reward, jnp.zeros((), bool), {"distance": dist}
