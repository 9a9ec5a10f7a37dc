"""Batched data collection: ``vmap`` over envs, ``scan`` over time, physics resampled at resets."""
from __future__ import annotations

import dataclasses
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from sim2real.envs import parallel
from sim2real.envs.autoreset import step_autoreset
from sim2real.envs.base import Env, State
from sim2real.rl import networks, normalize


@dataclasses.dataclass(frozen=True)
class Context:
    """Which physics parameters a context-conditioned policy sees, and how they are scaled.

    ``ctx = (z[idx] - center) / half`` maps the DR box to [-1, 1]. Empty for plain policies.
    """

    idx: np.ndarray
    center: np.ndarray
    half: np.ndarray

    @staticmethod
    def make(env: Env, names, low, high) -> "Context":
        low, high = np.asarray(low, np.float32), np.asarray(high, np.float32)
        return Context(env.spec.indices(list(names)), (low + high) / 2, np.maximum((high - low) / 2, 1e-6))

    @staticmethod
    def empty() -> "Context":
        z = np.zeros(0, np.float32)
        return Context(np.zeros(0, np.int32), z, z + 1)

    def __call__(self, z):
        return (z[..., self.idx] - self.center) / self.half

    def __len__(self):
        return len(self.idx)


@struct.dataclass
class Runner:
    """Env-side state carried between PPO updates (leading axis ``[B]``).

    Attributes:
      env_state: batched env ``State``.
      z: ``[B, P]`` physics of each env's current episode.
      carry: ``[B, H]`` recurrent policy state (H = 0 for feed-forward policies).
      first: ``[B]`` bool, the next step starts an episode (resets ``carry``).
      ep_return, ep_length: ``[B]`` running return and length of the current episode.
    """

    env_state: State
    z: jax.Array
    carry: jax.Array
    first: jax.Array
    ep_return: jax.Array
    ep_length: jax.Array


@struct.dataclass
class Batch:
    """A ``[T, B]`` batch; ``carry0 [B, H]`` is the recurrent state before its first step.

    ``valid [T, B]`` weights samples in the loss (1 everywhere for ordinary PPO; EPOpt masks the
    steps after a kept trajectory ended).
    """

    obs: jax.Array
    ctx: jax.Array
    first: jax.Array
    action: jax.Array
    log_prob: jax.Array
    value: jax.Array
    next_value: jax.Array
    reward: jax.Array
    terminated: jax.Array
    truncated: jax.Array
    z: jax.Array
    raw_obs: jax.Array
    carry0: jax.Array
    valid: jax.Array


def to_ctrl(env: Env, action):
    """Policy units ([-1, 1] after clipping) to the actuators' ctrl range."""
    a = jnp.clip(action, -1.0, 1.0)
    lo, hi = env.ctrl_low, env.ctrl_high
    bounded = np.isfinite(lo) & np.isfinite(hi)
    lo_, hi_ = np.where(bounded, lo, -1.0), np.where(bounded, hi, 1.0)
    return jnp.where(bounded, lo_ + (a + 1.0) / 2.0 * (hi_ - lo_), action)


def init_runner(env: Env, key, num_envs: int, sample: Callable, carry_size: int) -> Runner:
    k_z, k_reset = jax.random.split(key)
    z = jax.vmap(sample)(jax.random.split(k_z, num_envs))
    state = jax.vmap(env.reset)(jax.random.split(k_reset, num_envs), z)
    return Runner(state, z, jnp.zeros((num_envs, carry_size)), jnp.ones(num_envs, bool),
                  jnp.zeros(num_envs), jnp.zeros(num_envs, jnp.int32))


def collect(env: Env, net, params, obs_stats, ctx_fn: Context, runner: Runner, key, sample: Callable,
            num_steps: int, deterministic: bool = False, split: bool = False, step_keys=None):
    """Run ``num_steps`` steps of all envs.

    Every env draws from its own key (``[T, B]`` keys from ``key``), so the draws do not depend on
    how the batch is split. With ``split``, each of the host's devices that divide ``B`` (the CPU
    cores after ``parallel.use_cpu_cores()``) steps its own slice of the envs
    (``parallel.env_slices``); the returned batch is gathered whole for learning and the runner
    stays split for the next call.

    ``step_keys [T, B, 2]``, if given, replaces the keys drawn from ``key`` (a device's slice of
    the whole batch's keys in data-parallel PPO, ``rl/data_parallel.py``).

    Returns ``(runner, batch [T, B], stats)`` with ``stats`` holding the sums over episodes that
    ended in this batch (``return_sum``, ``length_sum``, ``episodes``) and ``diverged`` steps.
    """
    num_envs = runner.z.shape[0]
    if split and not any(isinstance(x, jax.core.Tracer) for x in jax.tree_util.tree_leaves((runner, key))):
        # an eager call: arrays built eagerly are committed to one device, which the per-device
        # slices cannot read; place the runner split and run the whole collection under jit
        whole = lambda r, k: collect(env, net, params, obs_stats, ctx_fn, r, k, sample, num_steps,
                                     deterministic, split)
        return jax.jit(whole)(parallel.shard_batch(runner), key)
    policy = jax.vmap(net.apply, in_axes=(None, 0, 0, 0, 0))

    def step(r: Runner, k):
        n = r.z.shape[0]  # this device's slice of the envs
        k_act, k_env = parallel.split_keys(k)
        obs = normalize.apply(obs_stats, r.env_state.obs)
        ctx = ctx_fn(r.z)
        (mean, log_std, value), carry = policy(params, obs, ctx, r.carry, r.first)
        action = mean if deterministic else jax.vmap(networks.sample_action)(k_act, mean, log_std)
        log_prob = networks.gaussian_log_prob(mean, log_std, action)
        env_step = lambda s, z, a, kk: step_autoreset(env, s, z, to_ctrl(env, a), kk, sample)
        state, z, tr, done = jax.vmap(env_step)(r.env_state, r.z, action, k_env)
        # value of the pre-reset next observation, with the pre-reset recurrent state
        nobs = normalize.apply(obs_stats, tr.next_obs)
        (_, _, next_value), _ = policy(params, nobs, ctx, carry, jnp.zeros(n, bool))
        ep_return = r.ep_return + tr.reward
        ep_length = r.ep_length + 1
        out = Batch(obs=obs, ctx=ctx, first=r.first, action=action, log_prob=log_prob, value=value,
                    next_value=next_value, reward=tr.reward, terminated=tr.terminated,
                    truncated=tr.truncated, z=r.z, raw_obs=r.env_state.obs, carry0=jnp.zeros((n, 0)),
                    valid=jnp.ones(n))
        # per env ([B]); summed over the batch outside, where the whole batch is
        ended = dict(return_sum=jnp.where(done, ep_return, 0.0), length_sum=jnp.where(done, ep_length, 0),
                     episodes=done.astype(jnp.int32), diverged=tr.diverged.astype(jnp.int32))
        r = Runner(state, z, carry, done, jnp.where(done, 0.0, ep_return), jnp.where(done, 0, ep_length))
        return r, (out, ended)

    def roll(runner, keys):
        return jax.lax.scan(step, runner, keys)

    if split:
        roll = parallel.env_slices(roll, num_envs, in_specs=(parallel.ENVS, parallel.ENVS_OVER_TIME),
                                   out_specs=(parallel.ENVS, parallel.ENVS_OVER_TIME))
    carry0 = runner.carry
    keys = jax.random.split(key, (num_steps, num_envs)) if step_keys is None else step_keys
    runner, (batch, ended) = roll(runner, keys)
    if split:
        # learning runs on the whole batch on every device (no cross-device reductions in the
        # loss, so the update is the one-device update)
        batch, ended = parallel.gather_whole((batch, ended), num_envs)
    stats = jax.tree_util.tree_map(jnp.sum, ended)
    return runner, batch.replace(carry0=carry0), stats
