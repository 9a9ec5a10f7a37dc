"""The physics an adapter draws at every reset: one sampler, shared by the Gymnasium and Brax adapters."""
from __future__ import annotations

import jax.numpy as jnp

from sim2real.algos.base import DRConfig, DRSpace
from sim2real.dists import uniform
from sim2real.envs import Env, make


def env_of(env: Env | str, **env_options) -> Env:
    """``env`` itself, or the registered env of that name built with ``env_options``."""
    return make(env, **env_options) if isinstance(env, str) else env


def sampler(env: Env, physics: dict | None):
    """``sample(key) -> z [P]``: ``physics={name: (low, high)}`` uniform, the rest at the defaults;
    the box is checked by the rule every DR box follows (``algos.base.DRSpace``)."""
    space = DRSpace(env, DRConfig(params=tuple(physics or ()), low=tuple(float(v[0]) for v in (physics or {}).values()),
                                  high=tuple(float(v[1]) for v in (physics or {}).values())))
    if not len(space):
        base = jnp.asarray(space.base)
        return lambda key: base
    box = uniform.make(space.low, space.high)
    return lambda key: space.expand(uniform.sample(key, box))
