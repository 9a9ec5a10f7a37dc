"""Evaluate a trained policy over a set (or grid) of physics vectors, deterministically."""
from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from sim2real.envs.base import Env
from sim2real.rl import networks
from sim2real.rl.ppo import PPO
from sim2real.rl.rollout import to_ctrl


def action(env: Env, ppo: PPO, params, obs_stats, obs, ctx, carry, first, key, deterministic: bool = True):
    """One policy step on one observation ``obs [O]``: ``(ctrl [nu] in actuator units, carry)``;
    the Gaussian mean, or a sample of it when not ``deterministic``."""
    (mean, log_std, _), carry = ppo.net.apply(params, _norm(obs_stats, obs), ctx, carry, first)
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
    truncation. Pure: usable inside jit (LSDR evaluates its contexts this way).
    """
    n = zs.shape[0]

    def one(z, k):
        k_reset, k_run = jax.random.split(k)
        s, ret, length, _ = closed_loop(env, ppo, params, obs_stats, env.reset(k_reset, z), z, k_run,
                                        env.config.episode_length, deterministic)
        out = {"return": ret, "length": length}
        out.update({f"final_{m}": v for m, v in s.metrics.items()})
        return out

    keys = jax.random.split(key, n * num_episodes).reshape(n, num_episodes, -1)
    run = jax.vmap(jax.vmap(one, in_axes=(None, 0)), in_axes=(0, 0))
    return run(jnp.asarray(zs), keys)


def _norm(stats, obs):
    from sim2real.rl import normalize

    return normalize.apply(stats, obs)


def grid(env: Env, axes: dict[str, np.ndarray], base=None) -> tuple[np.ndarray, list[str]]:
    """Physics vectors ``[prod(len), P]`` for the Cartesian grid over named axes (others at ``base``)."""
    names = list(axes)
    mesh = np.meshgrid(*[np.asarray(axes[n], np.float32) for n in names], indexing="ij")
    base = env.default_z() if base is None else np.asarray(base, np.float32)
    zs = np.tile(base, (mesh[0].size, 1))
    for n, m in zip(names, mesh):
        zs[:, env.spec.index(n)] = m.ravel()
    return zs, names


def parse_axis(text: str) -> tuple[str, np.ndarray]:
    """``'mass:pole=0.5:2.0:8'`` -> ``('mass:pole', linspace(0.5, 2.0, 8))``; also ``name=a,b,c``."""
    if "=" not in text:
        raise ValueError(f"grid axis '{text}' must look like name=low:high:count or name=v1,v2,...")
    name, spec = text.rsplit("=", 1)
    try:
        if ":" in spec:
            lo, hi, num = spec.split(":")
            lo, hi, num = float(lo), float(hi), int(num)
            if num < 1:
                raise ValueError(f"grid axis '{text}': the count must be at least 1 (got {num})")
            values = np.linspace(lo, hi, num)
        else:
            values = np.array([float(v) for v in spec.split(",")])
    except ValueError as e:
        if "count must be" in str(e):
            raise
        raise ValueError(f"grid axis '{text}': cannot read '{spec}' as low:high:count or a list") from None
    if not np.all(np.isfinite(values)):
        raise ValueError(f"grid axis '{text}': values must be finite")
    return name, values
