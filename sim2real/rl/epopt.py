"""EPOpt-PPO (Rajeswaran et al. 2016), as used in the LSDR paper (seed 000, Fig. 9).

Each iteration draws ``num_contexts`` physics vectors from the training distribution, runs one
episode on each, keeps the worst ``worst_fraction`` by return and fills the PPO batch with those
trajectories only (the rest are discarded). Steps after a kept episode ended are masked out.
"""
from __future__ import annotations

import dataclasses
from typing import Callable

import jax
import jax.numpy as jnp

from sim2real.rl.ppo import PPO, PPOState
from sim2real.rl.rollout import collect, init_runner
from sim2real.rl import networks


@dataclasses.dataclass(frozen=True)
class EPOptConfig:
    """Attributes:
      num_contexts: episodes (one per sampled physics vector) per iteration.
      worst_fraction: fraction of them, lowest return first, that train the policy.
    """

    num_contexts: int = 100
    worst_fraction: float = 0.1


def update(ppo: PPO, cfg: EPOptConfig, st: PPOState, sample: Callable):
    """One EPOpt iteration; ``st.runner`` is not used (every episode starts fresh)."""
    env = ppo.env
    T = env.config.episode_length
    keep = max(1, int(round(cfg.num_contexts * cfg.worst_fraction)))
    key, k_init, k_col, k_learn = jax.random.split(st.key, 4)
    runner = init_runner(env, k_init, cfg.num_contexts, sample, networks.carry_size(ppo.cfg.net))
    _, batch, _ = collect(env, ppo.net, st.params, st.obs_stats, ppo.ctx, runner, k_col, sample, T,
                          split=ppo.cfg.spreads)
    done = batch.terminated | batch.truncated                         # [T, N]
    # valid until (and including) the first episode end of each env
    ended_before = jnp.cumsum(done, axis=0) - done > 0
    valid = (~ended_before).astype(jnp.float32)
    returns = jnp.sum(batch.reward * valid, axis=0)                   # [N]
    worst = jnp.argsort(returns)[:keep]
    sub = jax.tree_util.tree_map(lambda x: x[:, worst], batch.replace(carry0=None))
    sub = sub.replace(valid=valid[:, worst], carry0=batch.carry0[worst])
    st = st.replace(key=key)
    st, metrics = ppo.learn(st, sub, k_learn)
    metrics.update(episode_return=returns.mean(), episode_return_worst=returns[worst].mean(),
                   episode_length=valid.sum(0).mean(), episodes=jnp.asarray(cfg.num_contexts, jnp.float32),
                   diverged=jnp.zeros(()))
    return st, metrics
