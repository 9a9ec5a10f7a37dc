"""LSDR: learn the domain-randomisation distribution while training (seed 000, Alg. 1-2, Eq. 1-2).

Each outer step, in one jitted function:

1. PPO (or EPOpt-PPO) update of the context-conditioned policy pi(a | s, z) with z ~ p_phi at resets.
2. Every ``dist_every`` steps, ``M`` gradient-ascent steps on
   ``L_DR(phi) - alpha * KL(p(z) || p_phi(z))`` with the score-function estimator
   ``1/K sum_i J~(z_i) grad log p_phi(z_i)``, where J~ is the return of K evaluation episodes
   standardised with exponentially averaged batch statistics, and z_i drawn from the prior p(z)
   (the paper's fix for collapse of discrete distributions) or from p_phi (``sample_from``).

p(z) is the uniform box ``dr.low..dr.high``; p_phi is ``binned`` (100 bins per dimension) or a
full-covariance ``gaussian`` (mean at the box centre, variance 1/10 of the box's, as the paper).

The Gaussian lives in box-normalised coordinates ``x = (z - low) / (high - low)`` (the box is
``[0, 1]^D``): Adam's steps have the same size in every coordinate, so in raw units a torso size
(box 0.3 wide) and a density (box 5,000 wide) would move by the same amount per step -- the
torso mean left its box while the density mean never moved. The KL to the uniform prior is the
same in both coordinates; reported means, covariances and entropies are in raw units.
"""
from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import optax
from flax import struct

from sim2real.common import config as config_lib
from sim2real import dists
from sim2real.algos.base import DRConfig, DRSpace, OuterLoop
from sim2real.algos.registry import register
from sim2real.dists import binned, gaussian
from sim2real.envs.base import Env
from sim2real.rl.episodes import episodes, with_horizon
from sim2real.rl import epopt
from sim2real.rl.ppo import PPO, PPOConfig, PPOState
from sim2real.rl.rollout import Context


@dataclasses.dataclass(frozen=True)
class LSDRConfig:
    """LSDR settings (``algo_options`` of a run).

    Attributes:
      dist: ``binned`` | ``gaussian``.
      num_bins: bins per dimension of the binned distribution.
      init_var_fraction: Gaussian initial variance as a fraction of the prior's (paper: 0.1).
      alpha: weight of the KL(p || p_phi) regulariser.
      lr: Adam step size on phi.
      grad_steps: M, gradient steps per distribution update (on the same K returns).
      num_contexts: K, evaluation episodes per distribution update.
      sample_from: ``prior`` (p(z), biased but avoids collapse) | ``learned`` (p_phi).
      dist_every: PPO updates between distribution updates.
      dist_start: PPO updates before the first distribution update (let the policy learn first:
        the returns of an untrained policy say little about which physics is solvable).
      ema: decay of the exponential return statistics used to standardise J.
      min_std_fraction: the Gaussian is kept inside its box after every step: its mean within
        ``[low, high]`` and each Cholesky diagonal entry (so each marginal standard deviation)
        at least this fraction of the box's width. Without it, a batch whose weights favour
        the samples near the mean can make ``Jt * log p`` grow without bound as the Gaussian
        shrinks and leaves the box (the pendulum's closed loop: entropy -13.8 nats, KL to the
        prior 8e19, all training resets at one corner).
      center: what J is centred by before scaling: ``ema`` (the paper: the exponentially averaged
        mean) or ``batch`` (the K returns' own mean, a REINFORCE baseline). With ``ema`` the
        batch's offset from the running mean, c, adds ``c * mean(log p_phi(z_i))`` to the
        objective: for samples from p_phi, M steps on the same samples then shrink p_phi onto
        them (c > 0) or blow it up (c < 0, e.g. once all K episodes fail); for samples from p(z)
        it adds ``-c * KL(p || p_phi)``, a random change of alpha that can turn it negative.
      max_kl: the most p_phi may move in one distribution update, KL(new || old) in nats; a
        longer step is shrunk towards the old distribution by halving (0: no limit). The M Adam
        steps on one batch of K returns can otherwise carry p_phi across its box in one update:
        on the pendulum's closed loop (4-D Gaussian, lr 0.05, M = 10) one batch moved the mean
        to a corner and tripled every standard deviation, the policy was trained on that corner
        and never recovered (evaluation return -400 -> -1400, LSDR's -1280 in the README).
      eval_horizon: steps of each evaluation episode (0: the env's episode length).
      policy_optimizer: ``ppo`` | ``epopt``.
      epopt: EPOpt settings when ``policy_optimizer == 'epopt'``.
      warm_start: a finished run folder (same env and network) whose policy starts every seed:
        its parameters and observation statistics, with a fresh optimiser, learning-rate schedule
        and distribution (fine-tuning a trained policy on a new box).
      warm_start_seed: which of that run's seeds starts them (-1: one per seed, or its only one).
    """

    dist: str = "binned"
    num_bins: int = 100
    init_var_fraction: float = 0.1
    alpha: float = 1.0
    lr: float = 0.05
    grad_steps: int = 10
    num_contexts: int = 64
    sample_from: str = "prior"
    dist_every: int = 1
    dist_start: int = 0
    ema: float = 0.9
    min_std_fraction: float = 0.01
    center: str = "ema"
    max_kl: float = 0.05
    eval_horizon: int = 0
    policy_optimizer: str = "ppo"
    epopt: epopt.EPOptConfig = epopt.EPOptConfig()
    warm_start: str = ""
    warm_start_seed: int = -1


@struct.dataclass
class LSDRState:
    ppo: PPOState
    phi: object          # the distribution pytree (Binned or Gaussian)
    phi_opt: optax.OptState
    ret_mean: jax.Array  # exponential return statistics
    ret_var: jax.Array
    stats_init: jax.Array
    key: jax.Array
    step: jax.Array


class LSDR(OuterLoop):
    """LSDR (and EPOpt-LSDR) around PPO; also runs fixed uniform DR with ``learn_dist=False``."""

    def __init__(self, env: Env, ppo_cfg: PPOConfig, dr: DRConfig, cfg: LSDRConfig, num_updates: int,
                 learn_dist: bool = True):
        if not dr.params:
            raise ValueError("LSDR needs dr.params / dr.low / dr.high: the prior box p(z)")
        if cfg.dist not in ("binned", "gaussian"):
            raise ValueError(f"lsdr dist '{cfg.dist}' unknown: binned, gaussian")
        if cfg.sample_from not in ("prior", "learned"):
            raise ValueError(f"lsdr sample_from '{cfg.sample_from}' unknown: prior, learned")
        if cfg.center not in ("ema", "batch"):
            raise ValueError(f"lsdr center '{cfg.center}' unknown: ema, batch")
        if cfg.policy_optimizer not in ("ppo", "epopt"):
            raise ValueError(f"lsdr policy_optimizer '{cfg.policy_optimizer}' unknown: ppo, epopt")
        if not cfg.max_kl >= 0.0:
            raise ValueError(f"lsdr max_kl={cfg.max_kl}: must be >= 0 (0: no limit)")
        if not 0.0 < cfg.min_std_fraction < 1.0:
            raise ValueError(f"lsdr min_std_fraction={cfg.min_std_fraction}: must be in (0, 1)")
        self.env, self.cfg, self.learn_dist = env, cfg, learn_dist
        self.space = DRSpace(env, dr)
        # the prior box: p_phi's coordinates are scaled by it (Gaussian) and samples clipped to it
        self._low, self._high = np.asarray(self.space.low), np.asarray(self.space.high)
        self._width = self._high - self._low
        ctx = Context.make(env, self.space.names, self.space.low, self.space.high)
        self.ppo = PPO(env, ppo_cfg, num_updates, ctx)
        self.tx = optax.adam(cfg.lr)
        self.horizon = cfg.eval_horizon or env.config.episode_length
        self.eval_env = with_horizon(env, self.horizon)

    # ---------------------------------------------------------------------- distributions ----
    def init_dist(self):
        lo, hi = self.space.low, self.space.high
        if self.cfg.dist == "binned":
            return binned.make(lo, hi, self.cfg.num_bins)
        d = len(lo)  # normalised box [0, 1]^D
        return gaussian.make(np.full(d, 0.5), np.full(d, np.sqrt(self.cfg.init_var_fraction / 12.0)))

    @property
    def _normalised(self) -> bool:
        return self.cfg.dist == "gaussian"

    def to_z(self, x):
        """Distribution coordinates ``[..., D]`` -> physics units (identity for ``binned``)."""
        return self._low + x * self._width if self._normalised else x

    def to_x(self, z):
        """Physics units ``[..., D]`` -> distribution coordinates (inverse of :meth:`to_z`)."""
        return (z - self._low) / self._width if self._normalised else z

    def sample(self, key, phi, n=None):
        """``[D]`` (or ``[n, D]``) draws of the sub-vector from p_phi, in physics units, clipped to
        the prior box: the box is the support the user allowed (a Gaussian's tails would otherwise
        train on delays or masses nobody asked for)."""
        return jnp.clip(self.to_z(dists.sample(key, phi, n)), self._low, self._high)

    def sampler(self, phi):
        return lambda key: self.space.expand(self.sample(key, phi))

    def prior_sample(self, key, n):
        return jax.random.uniform(key, (n, len(self.space)), minval=self.space.low, maxval=self.space.high)

    # ------------------------------------------------------------------------------------------
    def init(self, key) -> LSDRState:
        k_ppo, k_next = jax.random.split(key)
        phi = self.init_dist()
        return LSDRState(self.ppo.init(k_ppo, self.sampler(phi)), phi, self.tx.init(phi), jnp.zeros(()),
                         jnp.ones(()), jnp.zeros((), bool), k_next, jnp.zeros((), jnp.int32))

    def init_seeds(self, keys) -> LSDRState:
        """``init`` for every seed's key ``[S, 2]``; the policy from the warm start when one is loaded."""
        st = jax.vmap(self.init)(keys)
        return st.replace(ppo=self.warm_ppo(st.ppo))

    takes_update_index = True  # the training driver passes the (unbatched) update index

    def update(self, st: LSDRState, index=None):
        """One PPO (or EPOpt) update, then the distribution update when it is due.

        ``index`` is the run's update counter as an unbatched scalar (the driver's scan); with
        it, the due-check stays a real ``lax.cond`` even when seeds are vmapped, so the K
        evaluation episodes run only on the updates that use them. Without it (plain calls),
        the check uses the state's counter, which vmap batches: the cond becomes a select.
        """
        cfg = self.cfg
        sample = self.sampler(st.phi)
        if cfg.policy_optimizer == "epopt":
            ppo_st, metrics = epopt.update(self.ppo, cfg.epopt, st.ppo, sample)
        else:
            ppo_st, metrics = self.ppo.update(st.ppo, sample)
        st = st.replace(ppo=ppo_st, step=st.step + 1)
        if self.learn_dist:
            n = st.step if index is None else index + 1  # both: updates done so far
            do = ((n % cfg.dist_every) == 0) & (n > cfg.dist_start)
            st, dm = jax.lax.cond(do, self._update_dist,
                                  lambda s: (s, {"dist_eval_return": jnp.full((), jnp.nan)}), st)
            metrics.update(dm)
        metrics.update(self.describe(st.phi))
        return st, metrics

    def _update_dist(self, st: LSDRState):
        cfg = self.cfg
        key, k_z, k_ep = jax.random.split(st.key, 3)
        if cfg.sample_from == "prior":
            z_sub = self.prior_sample(k_z, cfg.num_contexts)
        else:
            z_sub = self.sample(k_z, st.phi, cfg.num_contexts)
        zs = jax.vmap(self.space.expand)(z_sub)
        res = episodes(self.eval_env, self.ppo, st.ppo.params, st.ppo.obs_stats, zs, k_ep, 1)
        J = res["return"][:, 0]
        Jt, mean, var = self.standardise(J, st.ret_mean, st.ret_var, st.stats_init)
        phi, opt = self.ascend(st.phi, st.phi_opt, z_sub, Jt)
        st = st.replace(phi=phi, phi_opt=opt, ret_mean=mean, ret_var=var, stats_init=jnp.ones((), bool), key=key)
        return st, {"dist_eval_return": J.mean()}

    def standardise(self, J, ret_mean, ret_var, stats_init):
        """``J [K]`` -> ``(Jt [K], new running mean, new running variance)``.

        Exponentially averaged batch statistics scale J so both terms of Eq. 1 have similar
        size; J is centred by the running mean or by its own mean (``center``).
        """
        cfg = self.cfg
        b_mean, b_var = J.mean(), J.var()
        mean = jnp.where(stats_init, cfg.ema * ret_mean + (1 - cfg.ema) * b_mean, b_mean)
        var = jnp.where(stats_init, cfg.ema * ret_var + (1 - cfg.ema) * b_var, b_var)
        Jt = (J - (mean if cfg.center == "ema" else b_mean)) / jnp.sqrt(var + 1e-8)
        return Jt, mean, var

    def ascend(self, phi, opt, z_sub, Jt):
        """M Adam steps on ``mean(Jt * log p_phi(z)) - alpha * KL(p || p_phi)`` (Eq. 2).

        Args:
          phi, opt: distribution and its optimiser state.
          z_sub: ``[K, D]`` evaluated contexts; Jt: ``[K]`` their standardised returns.
        """
        cfg = self.cfg
        # ``sample`` draws inside the box already; a caller's own contexts may not be
        z_in = jnp.clip(z_sub, self._low, self._high - 1e-6 * self._width)
        x_in, (x_lo, x_hi) = self.to_x(z_in), self._box()

        def objective(phi):
            score = jnp.mean(Jt * dists.log_prob(phi, x_in))
            return score - cfg.alpha * dists.kl_from_uniform(x_lo, x_hi, phi)

        def step(carry, _):
            phi, opt = carry
            g = jax.grad(objective)(phi)
            # optax minimises; a non-finite entry is no step (nan_to_num would turn inf into
            # 3e38, and Adam's second moment into inf for good)
            g = jax.tree_util.tree_map(lambda x: -jnp.where(jnp.isfinite(x), x, 0.0), g)
            if isinstance(g, binned.Binned):  # the bins are fixed: only the logits learn
                g = g.replace(low=jnp.zeros_like(g.low), high=jnp.zeros_like(g.high))
            upd, opt = self.tx.update(g, opt, phi)
            return (self.project(optax.apply_updates(phi, upd)), opt), None

        new, opt = jax.lax.scan(step, (phi, opt), None, length=cfg.grad_steps)[0]
        return self.limit(phi, new), opt

    def limit(self, old, new):
        """``new`` shrunk towards ``old`` (``old + b (new - old)``, b = 1, 1/2, ... 1/2048, else 0)
        until KL(new || old) <= ``max_kl``. Both ends are inside the box (:meth:`project`), and
        so is every point between them: the box and the std floor are convex in these parameters."""
        if self.cfg.max_kl <= 0:
            return new
        betas = 0.5 ** jnp.arange(12.0)
        mix = lambda b: jax.tree_util.tree_map(lambda o, n: o + b * (n - o), old, new)  # noqa: E731
        kls = jax.vmap(lambda b: dists.kl(mix(b), old))(betas)
        ok = kls <= self.cfg.max_kl
        return mix(jnp.where(ok.any(), betas[jnp.argmax(ok)], 0.0))

    def project(self, phi):
        """A Gaussian back inside its box (``min_std_fraction``); binned ones are bounded already."""
        if not isinstance(phi, gaussian.Gaussian):
            return phi
        lo, hi = self._box()
        raw = phi.chol_raw
        floor = jnp.log(self.cfg.min_std_fraction * (hi - lo))
        raw = raw - jnp.diag(jnp.diagonal(raw)) + jnp.diag(jnp.maximum(jnp.diagonal(raw), floor))
        return phi.replace(mean=jnp.clip(phi.mean, lo, hi), chol_raw=raw)

    def _box(self):
        """The prior box in distribution coordinates: ``(low [D], high [D])``."""
        if self._normalised:
            return jnp.zeros(len(self.space)), jnp.ones(len(self.space))
        return jnp.asarray(self._low), jnp.asarray(self._high)

    def entropy(self, phi):
        """Differential entropy of p_phi in physics units (nats)."""
        h = dists.entropy(phi)
        if self._normalised:  # z = low + x * width: + sum log width
            h = h + jnp.sum(jnp.log(self._width))
        return h

    def describe(self, phi) -> dict:
        """Scalar summaries plus the distribution itself (arrays, for evolution plots), in physics units."""
        out = {"dist_entropy": self.entropy(phi), "dist_kl_prior": dists.kl_from_uniform(*self._box(), phi)}
        if isinstance(phi, binned.Binned):
            out["dist_probs"] = binned.probs(phi)           # [K, bins]
        else:
            out["dist_mean"] = self.to_z(phi.mean)           # [K]
            out["dist_cov"] = gaussian.cov(phi) * jnp.outer(self._width, self._width)  # [K, K]
        return out

    def policy(self, st: LSDRState):
        return st.ppo.params, st.ppo.obs_stats


def _build(env, cfg, learn_dist=True):
    opts = config_lib.from_dict(LSDRConfig, cfg.algo_options, "algo_options.")
    algo = LSDR(env, cfg.ppo, cfg.dr, opts, cfg.num_updates, learn_dist=learn_dist)
    algo.warm_start_from, algo.warm_start_seed = opts.warm_start, opts.warm_start_seed
    return algo


register("lsdr", _build)
# the fixed-DR baseline in the same harness (same context-conditioned policy, same PPO/EPOpt)
register("fixed_dr", lambda env, cfg: _build(env, cfg, learn_dist=False))
