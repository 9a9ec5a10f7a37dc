"""ADR: automatic domain randomisation (OpenAI et al. 2019, "Solving Rubik's Cube with a Robot
Hand", Sec. 5 and Alg. 1; the survey in ``shared/seeds`` summarises it).

The training distribution is uniform over per-parameter bounds ``[low_i, high_i]`` that move:

1. PPO trains on ``z ~ U(low, high)``; with probability ``p_boundary`` one parameter of a reset's
   draw, chosen uniformly, is pinned to its lower or upper bound (boundary sampling).
2. Every update, ``num_evals`` evaluation episodes run with one parameter pinned to a bound, the
   ``2 D`` (parameter, side) cells taking turns. Their returns accumulate per cell
   (``buf_sum``, ``buf_n``: arrays ``[D, 2]``, so the buffers live inside the jitted update).
3. A cell with at least ``buffer_size`` returns compares their mean with the thresholds: at or
   above ``t_high`` the bound moves outwards by ``step`` (a fraction of the limit box's width), at
   or below ``t_low`` inwards (never past the other bound); its buffer empties either way.

Bounds stay inside the limit box ``dr.low..dr.high`` (which the bounds rule checks like any DR
box). They start at ``algo_options.init_low/init_high`` (default: the env's nominal value, a
point). Where the paper's evaluation workers run apart from the rollout workers, here the
evaluation episodes run inside the same update, after the PPO step; their env steps count towards
the run's budget (``env_steps_per_update``).
"""
from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from sim2real.algos.base import DRConfig, DRSpace, OuterLoop
from sim2real.algos.registry import register
from sim2real.common import config as config_lib
from sim2real.envs.base import Env
from sim2real.rl.episodes import episodes, with_horizon
from sim2real.rl.ppo import PPO, PPOConfig, PPOState
from sim2real.rl.rollout import Context


@dataclasses.dataclass(frozen=True)
class ADRConfig:
    """ADR settings (``algo_options`` of a run).

    Attributes:
      init_low, init_high: starting bounds, one per ``dr.params`` (empty: the nominal value).
      t_low, t_high: return thresholds (the env's return units): a bound's mean evaluation return
        at or below ``t_low`` shrinks it, at or above ``t_high`` widens it.
      step: how far a bound moves, as a fraction of the limit box's width.
      buffer_size: m, evaluation returns a bound collects before it may move.
      p_boundary: probability that a training reset pins one parameter to a bound.
      num_evals: evaluation episodes per update (spread evenly over the 2 D bounds).
      eval_horizon: steps of each evaluation episode (0: the env's episode length).
    """

    init_low: tuple[float, ...] = ()
    init_high: tuple[float, ...] = ()
    t_low: float = 0.0
    t_high: float = 1.0
    step: float = 0.02
    buffer_size: int = 16
    p_boundary: float = 0.5
    num_evals: int = 32
    eval_horizon: int = 0


@struct.dataclass
class ADRState:
    ppo: PPOState
    low: jax.Array      # [D] current bounds, physics units
    high: jax.Array     # [D]
    buf_sum: jax.Array  # [D, 2] summed evaluation returns at (parameter, lower/upper bound)
    buf_n: jax.Array    # [D, 2] how many
    key: jax.Array


class ADR(OuterLoop):
    """ADR around PPO (see the module docstring). State: :class:`ADRState`."""

    def __init__(self, env: Env, ppo_cfg: PPOConfig, dr: DRConfig, cfg: ADRConfig, num_updates: int):
        if not dr.params:
            raise ValueError("ADR needs dr.params / dr.low / dr.high: the limit box its bounds stay in")
        if not cfg.t_low < cfg.t_high:
            raise ValueError(f"algo_options.t_low={cfg.t_low} must be below algo_options.t_high={cfg.t_high}")
        if not 0 < cfg.step <= 1:
            raise ValueError(f"algo_options.step={cfg.step}: a fraction of the limit box in (0, 1]")
        if not 0 <= cfg.p_boundary <= 1:
            raise ValueError(f"algo_options.p_boundary={cfg.p_boundary}: a probability in [0, 1]")
        if cfg.buffer_size < 1:
            raise ValueError(f"algo_options.buffer_size={cfg.buffer_size}: must be >= 1")
        self.env, self.cfg = env, cfg
        self.space = DRSpace(env, dr)
        D = len(self.space)
        if cfg.num_evals < 2 * D:
            raise ValueError(f"algo_options.num_evals={cfg.num_evals}: at least 2 x {D} (one per bound)")
        self.init_low, self.init_high = self.space.start_box(cfg.init_low, cfg.init_high)
        self.delta = jnp.asarray(cfg.step * (self.space.high - self.space.low))
        ctx = Context.make(env, self.space.names, self.space.low, self.space.high)
        self.ppo = PPO(env, ppo_cfg, num_updates, ctx)
        self.horizon = cfg.eval_horizon or env.config.episode_length
        self.eval_env = with_horizon(env, self.horizon)
        # evaluation episode k pins parameter cells[k] // 2 to its lower (even) or upper (odd) bound;
        # cell_of[k] is its one-hot row, so the per-cell sums are one matrix product
        self.cells = np.arange(cfg.num_evals) % (2 * D)
        self.cell_of = np.eye(2 * D, dtype=np.float32)[self.cells]                 # [K, 2D]

    # ------------------------------------------------------------------------------------------
    @staticmethod
    def draw(key, low, high):
        """``z_sub [D]`` ~ U(low, high)."""
        return low + jax.random.uniform(key, low.shape) * (high - low)

    @staticmethod
    def pin(z_sub, low, high, cell):
        """``z_sub [D]`` with parameter ``cell // 2`` on its lower (``cell`` even) or upper (odd) bound."""
        i = cell // 2
        return z_sub.at[i].set(jnp.where(cell % 2 == 1, high[i], low[i]))

    def sampler(self, low, high):
        D, p_b = len(self.space), self.cfg.p_boundary

        def sample(key):
            k_z, k_b, k_cell = jax.random.split(key, 3)
            z = self.draw(k_z, low, high)
            pinned = self.pin(z, low, high, jax.random.randint(k_cell, (), 0, 2 * D))
            return self.space.expand(jnp.where(jax.random.uniform(k_b) < p_b, pinned, z))

        return sample

    def init(self, key) -> ADRState:
        k_ppo, k_next = jax.random.split(key)
        low, high = jnp.asarray(self.init_low), jnp.asarray(self.init_high)
        D = len(self.space)
        return ADRState(self.ppo.init(k_ppo, self.sampler(low, high)), low, high, jnp.zeros((D, 2)),
                        jnp.zeros((D, 2)), k_next)

    def update(self, st: ADRState):
        ppo_st, metrics = self.ppo.update(st.ppo, self.sampler(st.low, st.high))
        key, k_z, k_ep = jax.random.split(st.key, 3)
        z_sub = jax.vmap(lambda k, c: self.pin(self.draw(k, st.low, st.high), st.low, st.high, c))(
            jax.random.split(k_z, len(self.cells)), jnp.asarray(self.cells))
        res = episodes(self.eval_env, self.ppo, ppo_st.params, ppo_st.obs_stats,
                       jax.vmap(self.space.expand)(z_sub), k_ep, 1)
        J = res["return"][:, 0]
        D = len(self.space)
        buf_sum = st.buf_sum + (J @ self.cell_of).reshape(D, 2)
        buf_n = st.buf_n + self.cell_of.sum(0).reshape(D, 2)
        low, high, buf_sum, buf_n = self.move_bounds(st.low, st.high, buf_sum, buf_n)
        st = st.replace(ppo=ppo_st, low=low, high=high, buf_sum=buf_sum, buf_n=buf_n, key=key)
        metrics.update(self.describe(st), adr_eval_return=J.mean())
        return st, metrics

    def move_bounds(self, low, high, buf_sum, buf_n):
        """Step 3 of the module docstring on every full buffer; returns the new
        ``(low [D], high [D], buf_sum [D, 2], buf_n [D, 2])``."""
        cfg = self.cfg
        full = buf_n >= cfg.buffer_size
        mean = buf_sum / jnp.maximum(buf_n, 1)
        grow = full & (mean >= cfg.t_high)
        shrink = full & (mean <= cfg.t_low)
        move = jnp.where(grow, 1.0, 0.0) - jnp.where(shrink, 1.0, 0.0)      # [D, 2]: +1 outwards
        lim_lo, lim_hi = jnp.asarray(self.space.low), jnp.asarray(self.space.high)
        new_low = jnp.clip(low - move[:, 0] * self.delta, lim_lo, lim_hi)
        new_high = jnp.clip(high + move[:, 1] * self.delta, lim_lo, lim_hi)
        # a shrinking bound stops at the other one; two that would cross meet half-way
        new_low, new_high = jnp.minimum(new_low, high), jnp.maximum(new_high, low)
        mid = 0.5 * (new_low + new_high)
        crossed = new_low > new_high
        new_low, new_high = jnp.where(crossed, mid, new_low), jnp.where(crossed, mid, new_high)
        return new_low, new_high, jnp.where(full, 0.0, buf_sum), jnp.where(full, 0.0, buf_n)

    def describe(self, st: ADRState) -> dict:
        """The bounds ``[D]`` and the entropy of U(low, high) in physics units (nats; a zero-width
        bound counts as 1e-6 of its unit)."""
        return {"adr_low": st.low, "adr_high": st.high,
                "dist_entropy": jnp.sum(jnp.log(jnp.maximum(st.high - st.low, 1e-6)))}

    def env_steps_per_update(self) -> int:
        return int(self.ppo.cfg.batch_size + self.cfg.num_evals * self.horizon)

    def policy(self, st: ADRState):
        return st.ppo.params, st.ppo.obs_stats


def _build(env, cfg):
    opts = config_lib.from_dict(ADRConfig, cfg.algo_options, "algo_options.")
    return ADR(env, cfg.ppo, cfg.dr, opts, cfg.num_updates)


register("adr", _build)
