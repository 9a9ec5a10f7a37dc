"""A trained policy's episodes under given physics: one action, one closed-loop run, full episodes.

Pure JAX, usable inside jit: the outer loops evaluate their candidate physics with these (LSDR's
contexts, SimOpt's rollouts against a target, ES-MAML's adaptation), and the evaluation grid,
recording and the benchmarks use the same code.
"""
from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp

from sim2real.envs import parallel
from sim2real.envs.base import Env
from sim2real.rl import networks, normalize
from sim2real.rl.ppo import PPO
from sim2real.rl.rollout import to_ctrl


def with_horizon(env: Env, horizon: int) -> Env:
    """``env`` whose episodes last ``horizon`` steps (``env`` itself when ``horizon`` is 0 or its own
    length): the outer loops' evaluation episodes may be shorter than the training ones."""
    if not horizon or horizon == env.config.episode_length:
        return env
    return env.__class__(dataclasses.replace(env.config, episode_length=int(horizon)))


def action(env: Env, ppo: PPO, params, obs_stats, obs, ctx, carry, first, key, deterministic: bool = True):
    """One policy step on one observation ``obs [O]``: ``(ctrl [nu] in actuator units, carry)``;
    the Gaussian mean, or a sample of it when not ``deterministic``."""
    (mean, log_std, _), carry = ppo.net.apply(params, normalize.apply(obs_stats, obs), ctx, carry, first)
    a = mean if deterministic else mean + jnp.exp(log_std) * jax.random.normal(key, mean.shape)
    return to_ctrl(env, a), carry


def closed_loop(env: Env, ppo: PPO, params, obs_stats, s, z, key, horizon: int, deterministic: bool = True,
                stop_on_truncation: bool = True, record=None):
    """Run the policy for ``horizon`` steps from env state ``s`` with physics ``z [P]``.

    The episode's state is frozen after it ends (termination, and truncation unless
    ``stop_on_truncation=False``), so a fixed-length scan gives the episode's own return.
    ``record(state, counted, ctrl, key)``, if given, is called after every step on the (frozen)
    state, with ``counted`` = whether that step was still part of the episode and the ``ctrl``
    sent; its outputs are stacked ``[T, ...]``.

    Returns ``(final state, return, length, records or None)``.
    """
    ctx = ppo.ctx(z)

    def step(c, k):
        s, carry, alive, ret, length, first = c
        ctrl, carry = action(env, ppo, params, obs_stats, s.obs, ctx, carry, first, k, deterministic)
        s2 = env.step(s, ctrl, z)
        ret = ret + jnp.where(alive, s2.reward, 0.0)
        length = length + alive
        done = (s2.terminated | s2.truncated) if stop_on_truncation else s2.terminated
        s = jax.tree_util.tree_map(lambda new, old: jnp.where(alive, new, old), s2, s)
        out = None if record is None else record(s, alive, ctrl, k)
        return (s, carry, alive & ~done, ret, length, jnp.zeros((), bool)), out

    init = (s, jnp.zeros(networks.carry_size(ppo.cfg.net)), jnp.ones((), bool), jnp.zeros(()),
            jnp.zeros((), jnp.int32), jnp.ones((), bool))
    (s, _, _, ret, length, _), recs = jax.lax.scan(step, init, jax.random.split(key, horizon))
    return s, ret, length, recs


def episodes(env: Env, ppo: PPO, params, obs_stats, zs, key, num_episodes: int = 1, deterministic: bool = True):
    """Run full episodes for every ``z`` in ``zs [N, P]``.

    Returns a dict of ``[N, E]`` jax arrays: ``return``, ``length``, and each env metric at the
    last step of the episode (``final_<metric>``). An episode stops at its first termination or
    truncation. Pure: usable inside jit (LSDR evaluates its contexts this way). With
    ``ppo.cfg.spreads`` the ``N`` physics vectors are split over the host's devices.
    """
    n = zs.shape[0]

    def one(policy, z, k):
        k_reset, k_run = jax.random.split(k)
        s, ret, length, _ = closed_loop(env, ppo, *policy, env.reset(k_reset, z), z, k_run,
                                        env.config.episode_length, deterministic)
        out = {"return": ret, "length": length}
        out.update({f"final_{m}": v for m, v in s.metrics.items()})
        return out

    keys = jax.random.split(key, n * num_episodes).reshape(n, num_episodes, -1)
    run = jax.vmap(jax.vmap(one, in_axes=(None, None, 0)), in_axes=(None, 0, 0))
    return parallel.spread(run, n, ppo.cfg.spreads, shared=1)((params, obs_stats), jnp.asarray(zs), keys)
