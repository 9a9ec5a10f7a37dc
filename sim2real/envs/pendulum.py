"""Pendulum swing-up (Gym Pendulum's reward): obs ``[cos, sin, theta_dot]``, action torque in [-2, 2]."""
from __future__ import annotations

import jax
import jax.numpy as jnp

from sim2real.envs import classic
from sim2real.envs.base import Env, EnvConfig


class Pendulum(Env):
    """Gym Pendulum dynamics (uniform 1 kg, 1 m rod; 2 Nm): too weak to lift it directly, it must pump.

    Reward = -(theta^2 + 0.1 min(theta_dot^2, 64) + 0.001 u^2), theta = 0 upright; 200 steps of 50 ms.
    """

    name = "pendulum"
    xml = "pendulum.xml"
    default_config = EnvConfig(episode_length=200, frame_skip=5)
    metric_names = ("upright",)

    def declare_params(self, m):
        return classic.small_env_params(m)

    def init_qpos_qvel(self, key):
        k1, k2 = jax.random.split(key)
        return (jax.random.uniform(k1, (1,), minval=-jnp.pi, maxval=jnp.pi),
                jax.random.uniform(k2, (1,), minval=-1.0, maxval=1.0))

    def observe(self, qpos, qvel, goal):
        return jnp.stack([jnp.cos(qpos[0]), jnp.sin(qpos[0]), qvel[0]])

    def task(self, data0, data, action, goal):
        th = classic.wrap_angle(data.qpos[0])
        u = jnp.clip(action[0], -2.0, 2.0)
        # Gym caps the speed at 8 rad/s; we cap its cost term, so a light pole spun by the motor
        # cannot produce unbounded penalties (the physics itself is not limited)
        reward = -(th**2 + 0.1 * jnp.minimum(data.qvel[0] ** 2, 64.0) + 0.001 * u**2)
        upright = (jnp.abs(th) < 0.2) & (jnp.abs(data.qvel[0]) < 1.0)
        return reward, jnp.zeros((), bool), {"upright": upright.astype(jnp.float32)}


class PendulumBalance(Pendulum):
    """Same pendulum starting near upright (|theta| < 0.3): held by 2 Nm only while m < ~1.3 kg.

    The LSDR toy: over a wide mass range part of the contexts is unsolvable.
    """

    name = "pendulum_balance"

    def init_qpos_qvel(self, key):
        k1, k2 = jax.random.split(key)
        return (jax.random.uniform(k1, (1,), minval=-0.3, maxval=0.3),
                jax.random.uniform(k2, (1,), minval=-0.3, maxval=0.3))
