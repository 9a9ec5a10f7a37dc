"""Generalised advantage estimation that bootstraps on time-limit truncation.

A truncated step is not a terminal one: its TD target still includes ``gamma * V(next_obs)``
(``next_obs`` is the observation *before* the auto-reset). Only the advantage recursion stops
at every episode end, terminated or truncated. PureJaxRL's ``(1 - done)`` in the TD target
treats truncation as death; this does not.
"""
from __future__ import annotations

import jax
import jax.numpy as jnp


def gae(reward, value, next_value, terminated, truncated, gamma: float, lam: float):
    """Advantages and returns for a ``[T, B]`` batch.

    Args:
      reward, value, next_value: ``[T, B]``; ``next_value`` is V of the pre-reset next observation.
      terminated, truncated: ``[T, B]`` bool.
    Returns:
      ``(advantages [T, B], returns [T, B])`` with ``returns = advantages + value``.
    """
    not_term = 1.0 - terminated.astype(reward.dtype)
    not_done = 1.0 - (terminated | truncated).astype(reward.dtype)
    delta = reward + gamma * not_term * next_value - value

    def step(adv_next, x):
        d, nd = x
        adv = d + gamma * lam * nd * adv_next
        return adv, adv

    _, adv = jax.lax.scan(step, jnp.zeros_like(reward[0]), (delta, not_done), reverse=True)
    return adv, adv + value
