"""DORAEMON: domain randomisation via entropy maximisation (Tiboni et al. 2023, arXiv 2311.01885).

The training distribution nu_phi is a product of Betas, one per parameter, on the limit box
``dr.low..dr.high``. Every update, inside one jitted function:

1. PPO trains on ``z ~ nu_phi_i``.
2. ``num_evals`` evaluation episodes on fresh draws ``z_k ~ nu_phi_i``; episode k succeeds when its
   return reaches ``success_return``.
3. The distribution moves (the paper's Eq. 4-5):

       max_phi  H(nu_phi)   s.t.  KL(nu_phi || nu_phi_i) <= kl_bound,   G(phi) >= alpha

   with G the success rate under nu_phi, estimated from the K episodes by importance weights
   ``nu_phi(z_k) / nu_phi_i(z_k)``, self-normalised (the paper divides by K: unbiased, but the
   estimate can exceed 1 and swings with a few large weights; self-normalised stays in [0, 1]).
   When G(phi_i) < alpha already, the paper's fallback runs instead: ``max G s.t. KL <= kl_bound``.

The authors solve step 3 with SciPy's trust-region solver on the host. Here it is a feasible-
direction line search inside jit: ``solver_steps`` times, step along the objective's normalised
gradient in (log a, log b) by the largest of ``radius * 2^-j`` (j < 12) that keeps both
constraints and improves the objective; stay if none does. It returns a feasible improvement, not
necessarily the constrained optimum (no step along the constraint boundary). a and b stay in
[1, 1e4]: unimodal Betas, whose entropy is largest at a = b = 1 (uniform over the limit box).
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
from sim2real.dists import beta
from sim2real.envs.base import Env
from sim2real.rl.episodes import episodes, with_horizon
from sim2real.rl.ppo import PPO, PPOConfig, PPOState
from sim2real.rl.rollout import Context

LOG_AB_MAX = float(np.log(1e4))
LINE_SEARCH = 0.5 ** np.arange(12)


@dataclasses.dataclass(frozen=True)
class DORAEMONConfig:
    """DORAEMON settings (``algo_options`` of a run).

    Attributes:
      init_low, init_high: the start distribution is the Beta with the mean and variance of the
        uniform over this box, one value per ``dr.params`` (empty: the nominal value, with a
        standard deviation of ``init_std`` of the limit box's width).
      init_std: see above.
      success_return: an evaluation episode with at least this return counts as a success (the
        env's return units; the authors use 1600 for their hopper).
      alpha: the success rate the distribution must keep.
      kl_bound: epsilon, the largest KL(nu_new || nu_old) of one update (nats).
      num_evals: evaluation episodes per update (the importance-sampling batch).
      eval_horizon: steps of each evaluation episode (0: the env's episode length).
      solver_steps: line-search steps of the distribution update.
      radius: the longest step, in (log a, log b).
    """

    init_low: tuple[float, ...] = ()
    init_high: tuple[float, ...] = ()
    init_std: float = 0.02
    success_return: float = 0.0
    alpha: float = 0.5
    kl_bound: float = 0.1
    num_evals: int = 64
    eval_horizon: int = 0
    solver_steps: int = 20
    radius: float = 1.0


@struct.dataclass
class DORAEMONState:
    ppo: PPOState
    dist: beta.Beta   # on the limit box scaled to [0, 1]^D
    key: jax.Array


class DORAEMON(OuterLoop):
    """DORAEMON around PPO (see the module docstring). State: :class:`DORAEMONState`."""

    def __init__(self, env: Env, ppo_cfg: PPOConfig, dr: DRConfig, cfg: DORAEMONConfig, num_updates: int):
        if not dr.params:
            raise ValueError("DORAEMON needs dr.params / dr.low / dr.high: the box its Betas live on")
        if not 0 < cfg.alpha < 1:
            raise ValueError(f"algo_options.alpha={cfg.alpha}: a success rate in (0, 1)")
        if not cfg.kl_bound > 0:
            raise ValueError(f"algo_options.kl_bound={cfg.kl_bound}: must be > 0")
        if not 0 < cfg.init_std < 0.5:
            raise ValueError(f"algo_options.init_std={cfg.init_std}: a fraction of the box in (0, 0.5)")
        if cfg.num_evals < 2 or cfg.solver_steps < 1 or not cfg.radius > 0:
            raise ValueError("algo_options.num_evals >= 2, solver_steps >= 1 and radius > 0 are needed")
        self.env, self.cfg = env, cfg
        self.space = DRSpace(env, dr)
        self._low, self._width = np.asarray(self.space.low), np.asarray(self.space.high - self.space.low)
        lo, hi = self.space.start_box(cfg.init_low, cfg.init_high)
        m = np.clip(((lo + hi) / 2 - self._low) / self._width, 0.01, 0.99)
        w = np.maximum((hi - lo) / self._width, cfg.init_std * np.sqrt(12.0))
        d = beta.from_moments(m, np.minimum(w**2 / 12, 0.9 * m * (1 - m)))
        self.init_dist = beta.Beta(jnp.clip(d.log_a, 0.0, LOG_AB_MAX), jnp.clip(d.log_b, 0.0, LOG_AB_MAX))
        ctx = Context.make(env, self.space.names, self.space.low, self.space.high)
        self.ppo = PPO(env, ppo_cfg, num_updates, ctx)
        self.horizon = cfg.eval_horizon or env.config.episode_length
        self.eval_env = with_horizon(env, self.horizon)

    def to_z(self, x):
        """``[..., D]`` in [0, 1] -> physics units."""
        return self._low + x * self._width

    def sampler(self, dist):
        return lambda key: self.space.expand(self.to_z(beta.sample(key, dist)))

    def init(self, key) -> DORAEMONState:
        k_ppo, k_next = jax.random.split(key)
        return DORAEMONState(self.ppo.init(k_ppo, self.sampler(self.init_dist)), self.init_dist, k_next)

    def update(self, st: DORAEMONState):
        cfg = self.cfg
        ppo_st, metrics = self.ppo.update(st.ppo, self.sampler(st.dist))
        key, k_x, k_ep = jax.random.split(st.key, 3)
        x = beta.sample(k_x, st.dist, cfg.num_evals)                       # [K, D]
        res = episodes(self.eval_env, self.ppo, ppo_st.params, ppo_st.obs_stats,
                       jax.vmap(self.space.expand)(self.to_z(x)), k_ep, 1)
        J = res["return"][:, 0]
        success = (J >= cfg.success_return).astype(jnp.float32)
        dist, info = self.solve(st.dist, x, success)
        st = st.replace(ppo=ppo_st, dist=dist, key=key)
        metrics.update(self.describe(dist), doraemon_eval_return=J.mean(), **info)
        return st, metrics

    # ------------------------------------------------------------------------------------------
    def solve(self, old: beta.Beta, x, success):
        """Step 3 of the module docstring from samples ``x [K, D]`` of ``old`` and their
        ``success [K]`` (0/1). Returns ``(new distribution, info)``."""
        cfg = self.cfg
        log_old = beta.log_prob(old, x)
        as_dist = lambda th: beta.Beta(th[0], th[1])  # noqa: E731

        def success_rate(th):
            logw = beta.log_prob(as_dist(th), x) - log_old
            w = jax.nn.softmax(logw)                   # self-normalised weights, summing to 1
            return jnp.sum(w * success)

        kl = lambda th: beta.kl(as_dist(th), old)  # noqa: E731
        rate_now = jnp.mean(success)
        keep = rate_now >= cfg.alpha  # otherwise the fallback: regain success within the KL bound

        def objective(th):
            return jnp.where(keep, beta.entropy(as_dist(th)), success_rate(th))

        def feasible(th):
            return (kl(th) <= cfg.kl_bound) & (~keep | (success_rate(th) >= cfg.alpha))

        def step(th, _):
            g = jax.grad(objective)(th)
            g = jax.tree_util.tree_map(jnp.nan_to_num, g)
            norm = jnp.sqrt(sum(jnp.sum(v**2) for v in g)) + 1e-12
            cands = [jax.tree_util.tree_map(lambda p, d: jnp.clip(p + r * cfg.radius * d / norm, 0.0, LOG_AB_MAX),
                                            th, g) for r in LINE_SEARCH]
            stacked = jax.tree_util.tree_map(lambda *v: jnp.stack(v), *cands)
            f0 = objective(th)
            ok = jax.vmap(lambda c: feasible(c) & (objective(c) > f0))(stacked)
            j = jnp.argmax(ok)
            chosen = jax.tree_util.tree_map(lambda v: v[j], stacked)
            return jax.tree_util.tree_map(lambda c, p: jnp.where(ok.any(), c, p), chosen, th), None

        th0 = (old.log_a, old.log_b)
        th, _ = jax.lax.scan(step, th0, None, length=cfg.solver_steps)
        new = as_dist(th)
        return new, {"doraemon_success": rate_now, "doraemon_success_new": success_rate(th),
                     "doraemon_kl_step": kl(th), "doraemon_fallback": (~keep).astype(jnp.float32)}

    def describe(self, dist: beta.Beta) -> dict:
        """Entropy in physics units (nats), mean and standard deviation ``[D]`` in physics units."""
        return {"dist_entropy": beta.entropy(dist) + float(np.sum(np.log(self._width))),
                "dist_mean": self.to_z(beta.mean(dist)), "dist_std": jnp.sqrt(beta.var(dist)) * self._width}

    def env_steps_per_update(self) -> int:
        return int(self.ppo.cfg.batch_size + self.cfg.num_evals * self.horizon)

    def policy(self, st: DORAEMONState):
        return st.ppo.params, st.ppo.obs_stats


def _build(env, cfg):
    opts = config_lib.from_dict(DORAEMONConfig, cfg.algo_options, "algo_options.")
    return DORAEMON(env, cfg.ppo, cfg.dr, opts, cfg.num_updates)


register("doraemon", _build)
