"""Uniform domain randomisation (and fixed physics when the box is empty) around PPO."""
from __future__ import annotations

import jax.numpy as jnp

from sim2real.algos.base import DRConfig, DRSpace, OuterLoop
from sim2real.dists import uniform
from sim2real.envs.base import Env
from sim2real.rl.ppo import PPO, PPOConfig, PPOState
from sim2real.rl.rollout import Context


class UDR(OuterLoop):
    """PPO on z ~ U(box), resampled at every reset.

    State: :class:`PPOState`. ``update(state) -> (state, metrics)`` is one PPO iteration.
    """

    def __init__(self, env: Env, ppo_cfg: PPOConfig, dr: DRConfig, num_updates: int):
        self.space = DRSpace(env, dr)
        ctx = Context.make(env, self.space.names, self.space.low, self.space.high) if len(self.space) else None
        self.ppo = PPO(env, ppo_cfg, num_updates, ctx)
        self.dist = uniform.make(self.space.low, self.space.high) if len(self.space) else None

    def sampler(self, dist=None):
        base = jnp.asarray(self.space.base)
        if self.dist is None:
            return lambda key: base
        d = self.dist if dist is None else dist
        return lambda key: self.space.expand(uniform.sample(key, d))

    def init(self, key) -> PPOState:
        return self.ppo.init(key, self.sampler())

    def update(self, st: PPOState):
        return self.ppo.update(st, self.sampler())

    def policy(self, st: PPOState):
        return st.params, st.obs_stats
