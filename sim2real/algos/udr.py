"""Uniform domain randomisation (and fixed physics when the box is empty) around PPO."""
from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from sim2real.algos.base import DRConfig, DRSpace, OuterLoop
from sim2real.dists import uniform
from sim2real.envs.base import Env
from sim2real.rl.ppo import PPO, PPOConfig, PPOState
from sim2real.rl.rollout import Context


@dataclasses.dataclass(frozen=True)
class UDRConfig:
    """``algo_options`` of ``udr`` / the fixed physics.

    Attributes:
      warm_start: a finished run folder (same env and network) whose policy starts every seed:
        its parameters and observation statistics, with a fresh optimiser and learning-rate
        schedule (fine-tuning a trained policy on new physics; ``sim2real/tools/loop.py``).
      warm_start_seed: which of that run's seeds starts them (-1: one per seed, or its only one).
      warm_std: the action standard deviation (of the network's output, before clipping) the
        warm start's policy restarts from; 0: its own. A policy trained to the end of its
        schedule has narrowed its exploration (the cart-pole swing-up's to about 0.04).
    """

    warm_start: str = ""
    warm_start_seed: int = -1
    warm_std: float = 0.0

    def __post_init__(self):
        if not 0.0 <= self.warm_std < 1e3:
            raise ValueError(f"algo_options.warm_std={self.warm_std}: an action standard deviation >= 0 (0: the warm start's own)")
        if self.warm_std and not self.warm_start:
            raise ValueError(f"algo_options.warm_std={self.warm_std}: restarts a warm start's exploration; "
                             "set algo_options.warm_start=RUN")


class UDR(OuterLoop):
    """PPO on z ~ U(box), resampled at every reset.

    State: :class:`PPOState`. ``update(state) -> (state, metrics)`` is one PPO iteration.
    """

    def __init__(self, env: Env, ppo_cfg: PPOConfig, dr: DRConfig, num_updates: int):
        self.env = env
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

    def init_seeds(self, keys) -> PPOState:
        """``init`` for every seed's key ``[S, 2]``; the policy from the warm start when one is loaded."""
        return self.warm_ppo(jax.vmap(self.init)(keys))

    def update(self, st: PPOState):
        return self.ppo.update(st, self.sampler())

    def policy(self, st: PPOState):
        return st.params, st.obs_stats
