"""Pure-JAX PPO: one ``update`` = collect a ``[T, B]`` batch, then epochs x minibatches as scans.

Everything is a pure function of ``(PPOState, sample)``, so an outer loop (UDR, LSDR, SimOpt,
ES-MAML) can call it inside its own ``jit``/``scan`` and ``vmap`` it over seeds. ``sample(key) -> z [P]``
is the DR distribution, a closure over *traced* parameters: changing them never recompiles.
"""
from __future__ import annotations

import dataclasses
from typing import Callable

import jax
import jax.numpy as jnp
import optax
from flax import struct

from sim2real.envs.base import Env
from sim2real.envs import parallel
from sim2real.rl import data_parallel
from sim2real.rl import gae as gae_lib
from sim2real.rl import networks, normalize
from sim2real.rl.networks import NetConfig
from sim2real.rl.rollout import Batch, Context, Runner, collect, init_runner


@dataclasses.dataclass(frozen=True)
class PPOConfig:
    """PPO hyper-parameters.

    Attributes:
      num_envs: parallel envs B.
      num_steps: rollout length T per update.
      num_epochs: passes over each batch.
      num_minibatches: minibatches per epoch (over samples; over envs for recurrent nets).
      gamma: discount.
      gae_lambda: GAE lambda.
      clip_eps: surrogate ratio clip.
      clip_value: clip the value update to ``clip_eps`` around the old value.
      vf_coef: value loss weight.
      ent_coef: entropy bonus weight.
      lr: Adam learning rate.
      anneal_lr: decay the learning rate linearly to 0 over the run.
      max_grad_norm: global gradient-norm clip.
      normalize_obs: running mean/std observation normalisation.
      normalize_adv: standardise advantages per minibatch.
      reward_scale: multiply rewards before GAE.
      net: network shape.
      split_envs: step each rollout's envs on all the host's devices that divide ``num_envs`` (the
        CPU cores: the training driver calls ``parallel.use_cpu_cores()``); learning stays whole.
      data_parallel: split the envs over those devices for the whole update, learning included:
        gradients and statistics summed over devices, minibatches stratified by env
        (``rl/data_parallel.py``; feed-forward policies).
    """

    num_envs: int = 64
    num_steps: int = 64
    num_epochs: int = 4
    num_minibatches: int = 4
    gamma: float = 0.99
    gae_lambda: float = 0.95
    clip_eps: float = 0.2
    clip_value: bool = True
    vf_coef: float = 0.5
    ent_coef: float = 0.0
    lr: float = 3e-4
    anneal_lr: bool = True
    max_grad_norm: float = 0.5
    normalize_obs: bool = True
    normalize_adv: bool = True
    reward_scale: float = 1.0
    net: NetConfig = NetConfig()
    split_envs: bool = False
    data_parallel: bool = False

    @property
    def spreads(self) -> bool:
        """Whether work is split over the host's devices (``split_envs`` or ``data_parallel``);
        the outer loops then spread their samples, population and evaluation episodes too."""
        return self.split_envs or self.data_parallel

    @property
    def batch_size(self) -> int:
        return self.num_envs * self.num_steps


def check(cfg: PPOConfig, prefix: str = "ppo.") -> None:
    """Refuse PPO settings that cannot run, naming the key (before anything is compiled or written)."""
    for key in ("num_envs", "num_steps", "num_epochs", "num_minibatches"):
        v = getattr(cfg, key)
        if v < 1:
            raise ValueError(f"{prefix}{key}={v}: must be a positive integer")
    rules = {"lr": (0, None, False), "gamma": (0, 1, True), "gae_lambda": (0, 1, True), "clip_eps": (0, None, False),
             "vf_coef": (0, None, True), "ent_coef": (0, None, True), "max_grad_norm": (0, None, False),
             "reward_scale": (0, None, False)}
    for key, (lo, hi, lo_ok) in rules.items():
        v = float(getattr(cfg, key))
        bad = not (v == v and abs(v) != float("inf")) or (v < lo if lo_ok else v <= lo) or (hi is not None and v > hi)
        if bad:
            rng = f"{'>=' if lo_ok else '>'} {lo}" + (f" and <= {hi}" if hi is not None else "")
            raise ValueError(f"{prefix}{key}={v}: must be a finite number {rng}")
    if cfg.net.kind not in ("mlp", "lstm"):
        raise ValueError(f"{prefix}net.kind={cfg.net.kind!r}: choose mlp or lstm")
    if any(int(h) < 1 for h in cfg.net.hidden) or cfg.net.lstm_size < 1:
        raise ValueError(f"{prefix}net: layer sizes must be positive (hidden={list(cfg.net.hidden)}, "
                         f"lstm_size={cfg.net.lstm_size})")
    if cfg.net.kind == "lstm" and cfg.num_envs % cfg.num_minibatches:
        raise ValueError(f"{prefix}num_envs={cfg.num_envs} must be divisible by {prefix}num_minibatches="
                         f"{cfg.num_minibatches} for recurrent policies")
    if cfg.batch_size % cfg.num_minibatches:
        raise ValueError(f"{prefix}num_envs * {prefix}num_steps = {cfg.batch_size} must be divisible by "
                         f"{prefix}num_minibatches={cfg.num_minibatches}")
    if cfg.data_parallel:
        data_parallel.check(cfg)


@struct.dataclass
class PPOState:
    params: dict
    opt_state: optax.OptState
    obs_stats: normalize.RunningStats
    runner: Runner
    key: jax.Array
    update_step: jax.Array


class PPO:
    """Static pieces (env, network, optimiser); all methods are pure."""

    def __init__(self, env: Env, cfg: PPOConfig, num_updates: int, context: Context | None = None):
        self.env, self.cfg = env, cfg
        self.ctx = context if context is not None else Context.empty()
        if cfg.net.use_context and len(self.ctx) == 0:
            raise ValueError("net.use_context=true needs the context parameters (the DR parameters)")
        if not cfg.net.use_context:
            self.ctx = Context.empty()
        self.num_updates = max(1, int(num_updates))
        steps_per_update = cfg.num_epochs * cfg.num_minibatches
        lr = (optax.linear_schedule(cfg.lr, 0.0, self.num_updates * steps_per_update) if cfg.anneal_lr else cfg.lr)
        self.tx = optax.chain(optax.clip_by_global_norm(cfg.max_grad_norm), optax.adam(lr, eps=1e-5))
        self.net, _ = networks.init_params(jax.random.PRNGKey(0), cfg.net, env.obs_size, len(self.ctx),
                                           env.action_size)
        check(cfg)
        if cfg.spreads:  # before any trace: the partitioner is in jit's cache key
            parallel.batch_devices(cfg.num_envs)
        if cfg.num_envs % cfg.num_minibatches and cfg.net.kind == "lstm":
            raise ValueError("num_envs must be divisible by num_minibatches for recurrent policies")
        if cfg.batch_size % cfg.num_minibatches:
            raise ValueError("num_envs * num_steps must be divisible by num_minibatches")

    # ------------------------------------------------------------------------------
    def init(self, key, sample: Callable) -> PPOState:
        k_net, k_run, k_next = jax.random.split(key, 3)
        _, params = networks.init_params(k_net, self.cfg.net, self.env.obs_size, len(self.ctx), self.env.action_size)
        runner = init_runner(self.env, k_run, self.cfg.num_envs, sample, networks.carry_size(self.cfg.net))
        st = PPOState(params, self.tx.init(params), normalize.init(self.env.obs_size), runner, k_next,
                      jnp.zeros((), jnp.int32))
        return data_parallel.place(self, st) if self.cfg.data_parallel else st

    def update(self, st: PPOState, sample: Callable):
        """One PPO iteration: collect with ``sample`` for resets, then learn. Returns ``(state, metrics)``."""
        if self.cfg.data_parallel:
            st, metrics, ep = data_parallel.update(self, st, sample)
            return st, self._episode_metrics(metrics, ep)
        key, k_col, k_learn = jax.random.split(st.key, 3)
        runner, batch, ep = collect(self.env, self.net, st.params, st.obs_stats, self.ctx, st.runner, k_col,
                                    sample, self.cfg.num_steps, split=self.cfg.split_envs)
        st = st.replace(runner=runner, key=key)
        st, metrics = self.learn(st, batch, k_learn)
        return st, self._episode_metrics(metrics, ep)

    @staticmethod
    def _episode_metrics(metrics, ep):
        # no episode ended in this batch: there is no episode statistic (NaN, not a return of 0)
        ended = ep["episodes"] > 0
        metrics.update(
            episode_return=jnp.where(ended, ep["return_sum"] / jnp.maximum(ep["episodes"], 1), jnp.nan),
            episode_length=jnp.where(ended, ep["length_sum"] / jnp.maximum(ep["episodes"], 1), jnp.nan),
            episodes=ep["episodes"], diverged=ep["diverged"],
        )
        return metrics

    def advantages(self, batch: Batch):
        """GAE advantages and returns ``[T, B]`` of a collected batch (rewards scaled first)."""
        cfg = self.cfg
        return gae_lib.gae(batch.reward * cfg.reward_scale, batch.value, batch.next_value,
                           batch.terminated, batch.truncated, cfg.gamma, cfg.gae_lambda)

    def learn(self, st: PPOState, batch: Batch, key):
        """Epochs x minibatches of clipped-surrogate updates on a collected ``[T, B]`` batch."""
        cfg = self.cfg
        adv, ret = self.advantages(batch)
        recurrent = cfg.net.kind == "lstm"
        T, B = batch.first.shape
        total = T * B

        def epoch(carry, k):
            params, opt_state = carry
            n = cfg.num_minibatches
            if recurrent:  # minibatches of whole env sequences: [n, T, b, ...], carry0 [n, b, H]
                idx = jax.random.permutation(k, B)[: (B // n) * n].reshape(n, B // n)
                seq = lambda x: jnp.moveaxis(x[:, idx], 1, 0)
                mbs = jax.tree_util.tree_map(seq, (batch.replace(carry0=None), adv, ret))
                mbs = (mbs[0].replace(carry0=batch.carry0[idx]),) + mbs[1:]
            else:          # minibatches of samples: [n, m, ...]
                m = total // n
                perm = jax.random.permutation(k, total)[: n * m]
                flat = lambda x: x.reshape((total,) + x.shape[2:])[perm].reshape((n, m) + x.shape[2:])
                mbs = jax.tree_util.tree_map(flat, (batch.replace(carry0=None), adv, ret))

            def minibatch(carry, mb):
                params, opt_state = carry
                grads, info = jax.grad(self._loss, has_aux=True)(params, *mb)
                updates, opt_state = self.tx.update(grads, opt_state, params)
                return (optax.apply_updates(params, updates), opt_state), info

            (params, opt_state), info = jax.lax.scan(minibatch, (params, opt_state), mbs)
            return (params, opt_state), info

        (params, opt_state), info = jax.lax.scan(epoch, (st.params, st.opt_state),
                                                 jax.random.split(key, cfg.num_epochs))
        obs_stats = normalize.update(st.obs_stats, batch.raw_obs) if cfg.normalize_obs else st.obs_stats
        metrics = jax.tree_util.tree_map(jnp.mean, info)
        metrics["mean_reward"] = batch.reward.mean()
        st = st.replace(params=params, opt_state=opt_state, obs_stats=obs_stats, update_step=st.update_step + 1)
        return st, metrics

    def _forward(self, params, mb: Batch):
        """(mean, log_std, value) for a minibatch: ``[n]`` samples, or ``[T, b]`` sequences for LSTMs."""
        if self.cfg.net.kind != "lstm":
            return jax.vmap(lambda o, c: self.net.apply(params, o, c, jnp.zeros(0), jnp.zeros((), bool))[0])(
                mb.obs, mb.ctx)
        policy = jax.vmap(self.net.apply, in_axes=(None, 0, 0, 0, 0))

        def step(carry, x):
            obs, ctx, first = x
            out, carry = policy(params, obs, ctx, carry, first)
            return carry, out

        return jax.lax.scan(step, mb.carry0, (mb.obs, mb.ctx, mb.first))[1]

    def _loss(self, params, mb: Batch, adv, ret, weight_sum=None):
        """Clipped-surrogate loss of a minibatch. ``weight_sum`` given (data-parallel PPO): the
        minibatch is one device's part, ``adv`` already standardised over the whole minibatch,
        and the averages divide by the whole minibatch's weight (summed over devices later)."""
        cfg = self.cfg
        mean, log_std, value = self._forward(params, mb)
        log_prob = networks.gaussian_log_prob(mean, log_std, mb.action)
        ratio = jnp.exp(log_prob - mb.log_prob)
        w = mb.valid / (jnp.maximum(mb.valid.sum(), 1.0) if weight_sum is None else weight_sum)
        avg = lambda x: jnp.sum(w * x)
        if cfg.normalize_adv and weight_sum is None:
            mu = avg(adv)
            adv = (adv - mu) / (jnp.sqrt(avg(jnp.square(adv - mu))) + 1e-8)
        pg = -avg(jnp.minimum(ratio * adv, jnp.clip(ratio, 1 - cfg.clip_eps, 1 + cfg.clip_eps) * adv))
        v_loss = jnp.square(value - ret)
        if cfg.clip_value:
            v_clip = mb.value + jnp.clip(value - mb.value, -cfg.clip_eps, cfg.clip_eps)
            v_loss = jnp.maximum(v_loss, jnp.square(v_clip - ret))
        v_loss = 0.5 * avg(v_loss)
        entropy = avg(networks.gaussian_entropy(log_std))
        loss = pg + cfg.vf_coef * v_loss - cfg.ent_coef * entropy
        info = dict(loss=loss, policy_loss=pg, value_loss=v_loss, entropy=entropy,
                    approx_kl=avg((ratio - 1) - jnp.log(ratio)),
                    clip_frac=avg((jnp.abs(ratio - 1) > cfg.clip_eps).astype(jnp.float32)))
        return loss, info

    # ------------------------------------------------------------------------------
    def act(self, params, obs_stats, obs, ctx, carry, first):
        """Deterministic action (the Gaussian mean) for evaluation; batched over a leading axis."""
        policy = jax.vmap(self.net.apply, in_axes=(None, 0, 0, 0, 0))
        (mean, _, _), carry = policy(params, normalize.apply(obs_stats, obs), ctx, carry, first)
        return mean, carry

