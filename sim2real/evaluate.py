"""Evaluate a trained policy over a set (or grid) of physics vectors, deterministically."""
from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from sim2real.envs.base import Env
from sim2real.rl import networks
from sim2real.rl.ppo import PPO
from sim2real.rl.rollout import to_ctrl


def episodes(env: Env, ppo: PPO, params, obs_stats, zs, key, num_episodes: int = 1, deterministic: bool = True):
    """Run full episodes for every ``z`` in ``zs [N, P]``.

    Returns a dict of ``[N, E]`` jax arrays: ``return``, ``length``, and each env metric at the
    last step of the episode (``final_<metric>``). An episode stops at its first termination or
    truncation. Pure: usable inside jit (LSDR evaluates its contexts this way).
    """
    n = zs.shape[0]
    horizon = env.config.episode_length
    carry_size = networks.carry_size(ppo.cfg.net)

    def one(z, k):
        k_reset, k_run = jax.random.split(k)
        s = env.reset(k_reset, z)
        ctx = ppo.ctx(z)

        def step(c, kk):
            s, carry, alive, ret, length, first = c
            (mean, log_std, _), carry = ppo.net.apply(params, _norm(obs_stats, s.obs), ctx, carry, first)
            a = mean if deterministic else mean + jnp.exp(log_std) * jax.random.normal(kk, mean.shape)
            s2 = env.step(s, to_ctrl(env, a), z)
            ret = ret + jnp.where(alive, s2.reward, 0.0)
            length = length + alive
            done = s2.terminated | s2.truncated
            s = jax.tree_util.tree_map(lambda new, old: jnp.where(alive, new, old), s2, s)
            return (s, carry, alive & ~done, ret, length, jnp.zeros((), bool)), None

        init = (s, jnp.zeros(carry_size), jnp.ones((), bool), jnp.zeros(()), jnp.zeros((), jnp.int32),
                jnp.ones((), bool))
        (s, _, _, ret, length, _), _ = jax.lax.scan(step, init, jax.random.split(k_run, horizon))
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
            return name, np.linspace(float(lo), float(hi), int(num))
        return name, np.array([float(v) for v in spec.split(",")])
    except ValueError:
        raise ValueError(f"grid axis '{text}': cannot read '{spec}' as low:high:count or a list") from None
