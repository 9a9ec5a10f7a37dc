"""Auto-reset that draws new physics at every reset, inside jit.

Brax/Playground sample domain randomisation once, when the wrapper is built (brax issue #446),
so changing the distribution recompiles. Here the sampler is an argument: ``sample(key) -> z [P]``
closes over traced distribution parameters, and a finished env gets a fresh ``z`` and a fresh
initial state in the same step.
"""
from __future__ import annotations

from typing import Callable

import jax
import jax.numpy as jnp
from flax import struct

from sim2real.envs.base import Env, State


@struct.dataclass
class Transition:
    """One step of one env (``[T, B, ...]`` once a rollout stacks them).

    Attributes:
      obs: ``[O]`` observation the action was taken from.
      action: ``[A]`` action taken (policy units).
      reward: ``[]``.
      next_obs: ``[O]`` observation after the step, *before* any reset (for bootstrapping).
      terminated, truncated: ``[]`` bool.
      z: ``[P]`` physics the step ran under.
      diverged: ``[]`` 1.0 where the physics diverged in this step (the env was terminated).
    """

    obs: jax.Array
    action: jax.Array
    reward: jax.Array
    next_obs: jax.Array
    terminated: jax.Array
    truncated: jax.Array
    z: jax.Array
    diverged: jax.Array


def select(pred, a, b):
    """``a`` where ``pred`` else ``b``, leaf by leaf (``pred`` a scalar bool)."""
    return jax.tree_util.tree_map(lambda x, y: jnp.where(pred, x, y), a, b)


def step_autoreset(env: Env, state: State, z: jax.Array, action: jax.Array, key: jax.Array,
                   sample: Callable[[jax.Array], jax.Array]):
    """Step one env; on termination/truncation resample ``z`` and reset.

    Returns ``(state, z, transition, done)`` where ``state``/``z`` are post-reset.
    """
    nxt = env.step(state, action, z)
    done = nxt.terminated | nxt.truncated
    k_z, k_reset = jax.random.split(key)
    z_new = sample(k_z)
    fresh = env.auto_reset(k_reset, z_new)
    tr = Transition(obs=state.obs, action=action, reward=nxt.reward, next_obs=nxt.obs,
                    terminated=nxt.terminated, truncated=nxt.truncated, z=z,
                    diverged=nxt.metrics["diverged"])
    return select(done, fresh, nxt), jnp.where(done, z_new, z), tr, done
