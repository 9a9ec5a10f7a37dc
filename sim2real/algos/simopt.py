"""SimOpt (seed 002): adapt a Gaussian simulation distribution from a few real rollouts.

One SimOpt iteration (Alg. 1 of the paper), a pure function of :class:`SimOptState`:

1. retrain the policy with PPO on ``xi ~ N(mu, Sigma)`` (warm-started from the previous iteration),
2. run it on the real system: ``real_rollouts`` closed-loop rollouts (at most 3 in the ablation),
3. ``reps_updates`` times: sample ``num_samples`` parameter vectors, roll the same policy out in
   simulation from the real rollouts' initial states, score each with the smoothed trajectory
   discrepancy (Eq. 4, :mod:`sim2real.sysid.discrepancy`) and move ``N(mu, Sigma)`` by REPS under a
   KL bound (:mod:`sim2real.algos.reps`).

The real side is pluggable (:class:`RealData` is all the update sees): :func:`target_rollouts`
runs a target env with hidden parameters (sim-to-sim, as the paper's ablation, jittable, so a
whole run is one ``jit`` and ``vmap``s over seeds), and :func:`real_from_recordings` reads
recordings on disk in the diagnosis tool's format (a hardware loop: record the current policy,
run :meth:`SimOpt.adapt`, retrain, repeat).

It is an outer loop like the others (``algo: simopt`` in a training config, run by ``train.py``):
one ``update`` is one SimOpt iteration, one chunk of ``updates_per_chunk = 1`` update, so every
iteration is checkpointed. With ``real: target`` a run is ``iterations + 1`` updates (the last one
trains and evaluates on the final distribution); with ``real: recordings`` each call runs one
iteration on the recordings it is given (``resume=true algo_options.recordings=[...]`` for the next,
with recordings of the policy the last call wrote).

Compared signals are the *measured* joint positions (with the sensor offsets of the parameters
under test) followed by the joint velocities, ``[nq + nv]``; a simulation starts from the real
rollout's measured initial state, corrected for the hypothesised sensor offsets.
"""
from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
from flax import struct

from sim2real.common import config as config_lib
from sim2real.algos import reps
from sim2real.algos.base import DRConfig, DRSpace, OuterLoop
from sim2real.algos.registry import register
from sim2real.dists import gaussian
from sim2real.envs import parallel
from sim2real.envs.base import Env
from sim2real.rl.episodes import closed_loop
from sim2real.rl.ppo import PPO, PPOConfig, PPOState
from sim2real.sysid import discrepancy


@dataclasses.dataclass(frozen=True)
class SimOptConfig:
    """SimOpt settings (``algo_options`` of a run; defaults: the paper's Tables III-IV where they apply).

    Attributes:
      real: where the real rollouts come from: ``target`` (a target env with hidden physics,
        sim-to-sim) or ``recordings`` (files of the current policy on the real system).
      target: hidden physics of the target env, ``{param: value}`` (``real: target``).
      recordings: recording files of the current policy (``real: recordings``; the diagnosis'
        formats, sampled at the env's control step).
      init_mean: initial mean per ``dr.params`` (empty: the env's defaults).
      init_std: initial standard deviation per ``dr.params`` (empty: 1/20 of the ``dr`` box width).
      iterations: SimOpt iterations (distribution updates from new real rollouts).
      real_rollouts: real rollouts per iteration.
      reps_updates: REPS updates per iteration on the same real rollouts (paper: 3).
      num_samples: parameter samples per REPS update (paper: 9600).
      epsilon: KL bound of a REPS update (paper: 1.0).
      eta_min: minimum REPS temperature, in units of the cost spread (paper: 0.001).
      horizon: compared steps per rollout (0: the env's episode length).
      signal_weights: importance weight per compared signal ``[nq + nv]`` (empty: all 1).
      w_l1, w_l2: weights of the L1 and squared-L2 terms of Eq. 4 (paper: 0.5, 1.0).
      smooth_std, smooth_truncate: Gaussian smoothing (paper: 5 timesteps, 4).
      ppo_updates: PPO updates per iteration (warm-started).
      init_ppo_updates: PPO updates before the first real rollouts (0: ``ppo_updates``).
      eval_episodes: extra target episodes per iteration for the reported return: whole episodes
        (the env's episode length, whatever ``horizon`` is), not used by SimOpt itself; 0 disables.
    """

    real: str = "target"
    target: dict[str, float] = dataclasses.field(default_factory=dict)
    recordings: tuple[str, ...] = ()
    init_mean: tuple[float, ...] = ()
    init_std: tuple[float, ...] = ()
    iterations: int = 5
    real_rollouts: int = 3
    reps_updates: int = 3
    num_samples: int = 256
    epsilon: float = 1.0
    eta_min: float = 1e-3
    horizon: int = 0
    signal_weights: tuple[float, ...] = ()
    w_l1: float = 0.5
    w_l2: float = 1.0
    smooth_std: float = 5.0
    smooth_truncate: float = 4.0
    ppo_updates: int = 100
    init_ppo_updates: int = 0
    eval_episodes: int = 16


@struct.dataclass
class RealData:
    """What SimOpt sees of the real system (``R`` rollouts of ``T`` steps).

    Attributes:
      signals: ``[R, T, S]`` measured joint positions then velocities, after each control step.
      mask: ``[R, T]`` 1 while the rollout is running (0 after it ended).
      qpos0: ``[R, nq]`` measured initial joint positions; qvel0: ``[R, nv]``.
      goal: ``[R, G]`` task goal of each rollout (empty G for goal-less envs).
      ret: ``[R]`` task return (NaN when unknown, as for recordings).
      ctrl: ``[R, T, nu]`` commands sent at each step (kept for recordings; SimOpt replays the policy).
    """

    signals: jax.Array
    mask: jax.Array
    qpos0: jax.Array
    qvel0: jax.Array
    goal: jax.Array
    ret: jax.Array
    ctrl: jax.Array


@struct.dataclass
class SimOptState:
    ppo: PPOState
    mean: jax.Array  # [D]
    cov: jax.Array   # [D, D]
    key: jax.Array


class SimOpt(OuterLoop):
    """Static pieces; all methods are pure (jittable, vmappable over seeds).

    ``update(state, i)`` is SimOpt iteration ``i`` against the configured real side
    (``cfg.real``); ``iteration``/``adapt``/``train`` are its parts, for other drivers.
    """

    takes_update_index = True  # the first iteration trains longer (init_ppo_updates)

    def __init__(self, env: Env, ppo_cfg: PPOConfig, dr: DRConfig, cfg: SimOptConfig):
        if not dr.params:
            raise ValueError("SimOpt needs dr.params (the simulator parameters to adapt) and dr.low/dr.high "
                             "(the range samples are clipped to)")
        self.env, self.cfg = env, cfg
        self.space = DRSpace(env, dr)
        d = len(self.space)
        default = np.asarray([env.default_z()[env.spec.index(n)] for n in self.space.names], np.float32)
        self.init_mean = np.asarray(cfg.init_mean or default, np.float32)
        self.init_std = np.asarray(cfg.init_std or (self.space.high - self.space.low) / 20, np.float32)
        for what, v in (("init_mean", self.init_mean), ("init_std", self.init_std)):
            if v.shape != (d,):
                raise ValueError(f"simopt.{what} has {v.size} values; dr.params has {d} ({', '.join(self.space.names)})")
        if (self.init_std <= 0).any():
            raise ValueError(f"simopt.init_std must be positive (got {list(self.init_std)})")
        self.horizon = cfg.horizon or env.config.episode_length
        n_sig = env.mj_model.nq + env.mj_model.nv
        self.weights = np.asarray(cfg.signal_weights or np.ones(n_sig), np.float32)
        if self.weights.shape != (n_sig,):
            raise ValueError(f"simopt.signal_weights needs {n_sig} values (nq + nv of '{env.name}'), "
                             f"got {self.weights.size}")
        if cfg.real_rollouts < 1 or cfg.num_samples < 2 or cfg.iterations < 1:
            raise ValueError("simopt needs real_rollouts >= 1, num_samples >= 2, iterations >= 1")
        m = env.mj_model
        if m.nq != m.njnt or m.nv != m.njnt:
            raise ValueError(f"SimOpt compares one position and one velocity per joint; '{env.name}' has "
                             f"free or ball joints (nq={m.nq}, nv={m.nv}, joints={m.njnt})")
        if ppo_cfg.net.kind != "mlp" or ppo_cfg.net.use_context:
            raise ValueError("SimOpt trains a plain MLP policy (ppo.net.kind=mlp, ppo.net.use_context=false), "
                             "as the paper")
        # the policy is retrained every iteration from a warm start: a constant step size
        self.ppo = PPO(env, dataclasses.replace(ppo_cfg, anneal_lr=False), 1)
        self.z_target, self.real = None, None
        if cfg.real == "target":
            if cfg.recordings:
                raise config_lib.ConfigError("algo_options.recordings is read with real=recordings, not real=target")
            if cfg.target:  # (without one only iteration()/adapt() can be used, with a target given to them)
                self.z_target = env.z_of(**{k: float(v) for k, v in cfg.target.items()})
                env.check_z(self.z_target)
        elif cfg.real == "recordings":
            if not cfg.recordings:
                raise config_lib.ConfigError("algo_options.real=recordings needs algo_options.recordings=[a.csv, ...]: "
                                             "recordings of the current policy on the real system")
            # read now, before a run folder is made: a bad file is refused with nothing written
            self.real = real_from_recordings(self, list(cfg.recordings))
        else:
            raise config_lib.ConfigError(f"algo_options.real={cfg.real!r} unknown: target, recordings")

    # ------------------------------------------------------------- outer-loop contract ----
    def update(self, st: SimOptState, i):
        """SimOpt iteration ``i``: ``(state, metrics)``. Metrics: the distribution the policy was
        trained on (``dist_mean [D]``, ``dist_cov [D, D]``, ``mean:<param>``, ``std:<param>``),
        ``target_return``/``eval_return`` (NaN with recordings), ``train_return``, and the last
        REPS update's ``reps_kl``, ``reps_ess``, ``reps_cost_min``, ``reps_cost_mean``."""
        first = i == 0
        if self.real is None:
            # a traced count: the first iteration and the later ones share one compiled function
            n = jnp.where(first, self.updates_for(True), self.updates_for(False))
            st, m = self.iteration(st, jnp.asarray(self.target()), num_updates=n)
        else:
            st, m = self.hardware_iteration(st, self.real, first)
        out = dict(dist_mean=m["mean"], dist_cov=m["cov"], target_return=m["target_return"],
                   eval_return=m["eval_return"], train_return=m["train_return"])
        for j, name in enumerate(self.space.names):
            out[f"mean:{name}"] = m["mean"][j]
            out[f"std:{name}"] = jnp.sqrt(m["cov"][j, j])
        out.update({f"reps_{k}": m[f"reps_{k}"][-1] for k in ("kl", "ess", "cost_min", "cost_mean")})
        return st, out

    def target(self) -> np.ndarray:
        """``z [P]`` of the target env (``algo_options.target``); refused, named, when none was given."""
        if self.z_target is None:
            raise config_lib.ConfigError("algo_options.real=target needs algo_options.target={param: value, ...}: "
                                         "the hidden physics of the target env")
        return self.z_target

    def env_steps_per_update(self) -> int:
        """PPO env steps per seed in a later iteration (the first trains ``init_ppo_updates``; the
        REPS rollouts in simulation are not counted)."""
        return int(self.cfg.ppo_updates * self.ppo.cfg.batch_size)

    def total_updates(self, total_steps: int, done: int) -> int:
        """``iterations + 1`` against a target env; with recordings, one more than ``done`` (each
        call adapts on the recordings it is given). ``total_steps`` is not used."""
        return self.cfg.iterations + 1 if self.real is None else done + 1

    # ------------------------------------------------------------------ distribution ----
    def clip(self, xi):
        return jnp.clip(xi, self.space.low, self.space.high)

    def sampler(self, mean, cov):
        dist = gaussian.make(mean, cov_matrix=cov)
        return lambda key: self.space.expand(self.clip(gaussian.sample(key, dist)))

    # ------------------------------------------------------------------------ state ----
    def init(self, key) -> SimOptState:
        k_ppo, k_next = jax.random.split(key)
        mean = jnp.asarray(self.init_mean)
        cov = jnp.diag(jnp.asarray(self.init_std) ** 2)
        return SimOptState(self.ppo.init(k_ppo, self.sampler(mean, cov)), mean, cov, k_next)

    def train(self, st: SimOptState, num_updates) -> tuple[SimOptState, dict]:
        """``num_updates`` PPO updates on the current distribution (warm start).

        ``num_updates`` may be a Python int or a traced int32 scalar: a traced count lets the
        first SimOpt iteration (more updates) and the later ones share one compiled function.
        ``train_return`` is the last update's mean episode return (NaN after 0 updates).
        """
        sample = self.sampler(st.mean, st.cov)

        def body(_, c):
            s, _ret = c
            s, m = self.ppo.update(s, sample)
            return s, m["episode_return"].astype(jnp.float32)

        ppo_st, ret = jax.lax.fori_loop(0, num_updates, body, (st.ppo, jnp.full((), jnp.nan, jnp.float32)))
        return st.replace(ppo=ppo_st), {"train_return": ret}

    # ---------------------------------------------------------------------- rollouts ----
    def rollout(self, params, obs_stats, z, key, qpos0, qvel0, goal, horizon: int | None = None):
        """Deterministic closed-loop rollout from a measured state.

        Args:
          z: ``[P]`` physics; qpos0 ``[nq]`` (measured), qvel0 ``[nv]``; goal ``[G]`` or ``None``.
          horizon: steps (default: the compared horizon, ``cfg.horizon`` or the episode length).
        Returns:
          ``(signals [T, S], alive [T], return, ctrl [T, nu])``; after a termination the state is frozen.
        """
        env = self.env
        k_reset, k_run = jax.random.split(key)
        s = env.reset(k_reset, z)
        if goal is not None:
            s = s.replace(goal=goal)
        data = s.data.replace(qpos=env.effects.unsense(z, qpos0), qvel=qvel0)
        s = s.replace(data=data, obs=env._observe(z, data, s.goal, k_reset))

        def record(s, counted, ctrl, k):
            sig = jnp.concatenate([env.effects.sense(z, s.data.qpos, k), s.data.qvel])
            return sig, counted.astype(jnp.float32), ctrl

        # truncation at the episode length is not a reason to stop comparing
        _, ret, _, (sig, alive, ctrl) = closed_loop(env, self.ppo, params, obs_stats, s, z, k_run,
                                                    horizon or self.horizon, stop_on_truncation=False, record=record)
        return sig, alive, ret, ctrl

    def target_rollouts(self, st: SimOptState, z_target, key, n: int, horizon: int | None = None) -> RealData:
        """``n`` rollouts of the current policy on a target env with hidden physics ``z_target [P]``
        (``horizon`` steps; default: the compared horizon)."""
        env = self.env

        def one(k):
            k_init, k_run = jax.random.split(k)
            s = env.reset(k_init, z_target)
            qpos0 = env.effects.sense(z_target, s.data.qpos, k_init)
            sig, alive, ret, ctrl = self.rollout(st.ppo.params, st.ppo.obs_stats, z_target, k_run, qpos0,
                                                 s.data.qvel, s.goal, horizon)
            return RealData(sig, alive, qpos0, s.data.qvel, s.goal, ret, ctrl)

        return jax.vmap(one)(jax.random.split(key, n))

    # ------------------------------------------------------------------- REPS update ----
    def costs(self, st: SimOptState, xi, real: RealData, key):
        """Discrepancy per parameter sample: ``xi [N, D]`` -> ``[N]`` (mean over real rollouts)."""
        cfg = self.cfg
        R = real.signals.shape[0]

        def per_sample(shared, x, k):
            params, obs_stats, real = shared
            z = self.space.expand(x)

            def per_real(sig_r, mask_r, q0, v0, g, kk):
                sig, _, _, _ = self.rollout(params, obs_stats, z, kk, q0, v0, g)
                return discrepancy.discrepancy(sig, sig_r, self.weights, cfg.w_l1, cfg.w_l2, cfg.smooth_std,
                                               cfg.smooth_truncate, mask_r)

            return jnp.mean(jax.vmap(per_real)(real.signals, real.mask, real.qpos0, real.qvel0, real.goal,
                                               jax.random.split(k, R)))

        n = xi.shape[0]  # the samples split over the host's devices with ppo.split_envs / data_parallel
        costs = parallel.spread(jax.vmap(per_sample, in_axes=(None, 0, 0)), n, self.ppo.cfg.spreads, shared=1)
        return costs((st.ppo.params, st.ppo.obs_stats, real), xi, jax.random.split(key, n))

    def reps_step(self, st: SimOptState, real: RealData):
        """One REPS update of ``N(mu, Sigma)`` against ``real``; returns ``(state, info)``."""
        cfg = self.cfg
        key, k_xi, k_sim = jax.random.split(st.key, 3)
        xi = self.clip(gaussian.sample(k_xi, gaussian.make(st.mean, cov_matrix=st.cov), cfg.num_samples))
        c = self.costs(st, xi, real, k_sim)
        mean, cov, info = reps.update(xi, c, cfg.epsilon, cfg.eta_min)
        info.update(cost_mean=jnp.nanmean(jnp.where(jnp.isfinite(c), c, jnp.nan)), cost_min=jnp.min(c))
        return st.replace(mean=mean, cov=cov, key=key), info

    def adapt(self, st: SimOptState, real: RealData):
        """``reps_updates`` REPS updates on the same real rollouts; info has a leading update axis."""
        return jax.lax.scan(lambda s, _: self.reps_step(s, real), st, None, length=self.cfg.reps_updates)

    # --------------------------------------------------------------------- iteration ----
    def iteration(self, st: SimOptState, z_target, first: bool = False, num_updates=None):
        """Train, roll out on the target, adapt. Returns ``(state, metrics)``.

        ``num_updates`` (int or traced int32 scalar) overrides the PPO update count that
        ``first`` selects (``init_ppo_updates`` for the first iteration, else ``ppo_updates``).

        ``metrics``: ``mean [D]``, ``cov [D, D]`` (the distribution the policy was trained on),
        ``target_return`` (mean over the real rollouts, ``horizon`` steps), ``eval_return``
        (``eval_episodes`` extra whole target episodes, NaN when 0), REPS ``eta``/``kl``/``ess``/costs per update.
        """
        cfg = self.cfg
        n = self.updates_for(first) if num_updates is None else num_updates
        mean, cov = st.mean, st.cov
        st, tm = self.train(st, n)
        key, k_real, k_eval = jax.random.split(st.key, 3)
        st = st.replace(key=key)
        real = self.target_rollouts(st, z_target, k_real, cfg.real_rollouts)
        if cfg.eval_episodes:
            # whole episodes, whatever horizon the discrepancy compares (the task's return)
            ev = self.target_rollouts(st, z_target, k_eval, cfg.eval_episodes,
                                      self.env.config.episode_length).ret.mean()
        else:
            ev = jnp.full((), jnp.nan)
        st, info = self.adapt(st, real)
        metrics = dict(mean=mean, cov=cov, target_return=real.ret.mean(), eval_return=ev, **tm,
                       **{f"reps_{k}": v for k, v in info.items()})
        return st, metrics

    def hardware_iteration(self, st: SimOptState, real: RealData, first) -> tuple[SimOptState, dict]:
        """Adapt on recorded rollouts of the current policy, then retrain (``first``: the policy
        that made the recordings is trained first, ``init_ppo_updates``). Metrics as
        :meth:`iteration` (``target_return``/``eval_return`` NaN: no target to score on)."""
        st, _ = self.train(st, jnp.where(first, self.updates_for(True), 0))
        mean, cov = st.mean, st.cov
        st, info = self.adapt(st, real)
        st, tm = self.train(st, self.cfg.ppo_updates)
        return st, dict(mean=mean, cov=cov, target_return=jnp.nan, eval_return=jnp.nan, **tm,
                        **{f"reps_{k}": v for k, v in info.items()})

    def updates_for(self, first: bool) -> int:
        """PPO updates in an iteration: ``init_ppo_updates`` (or ``ppo_updates``) for the first."""
        return (self.cfg.init_ppo_updates or self.cfg.ppo_updates) if first else self.cfg.ppo_updates

    def policy(self, st: SimOptState):
        return st.ppo.params, st.ppo.obs_stats


def real_from_recordings(sim: SimOpt, paths) -> RealData:
    """Real rollouts from recordings (CSV/NPZ, the diagnosis format) sampled at the env's control step.

    Each recording needs ``qpos:<joint>`` for every joint of the env's model; rollouts shorter than
    the horizon are masked, longer ones cut. Each is read as the diagnosis reads it (a
    ``sysid.trajectory.Trajectory``): a ``qvel:<joint>`` column is compared as measured (the
    simulator's states are compared with what the sensor gave, step by step); without one, the
    velocities are the positions' Savitzky-Golay derivative over the window the data's noise allows.
    """
    from sim2real.sysid import recordings as rec_lib
    from sim2real.sysid.trajectory import ModelColumns, from_recording

    env = sim.env
    recs = rec_lib.load_all(paths, env.mj_model, "SimOpt real recordings")
    rec_lib.check_sample_rate(recs, env.dt, f"the env's control step ({env.dt:g} s)")
    columns = ModelColumns(env.mj_model, f"the {env.name} env's model")
    T = sim.horizon
    out = []
    for r in recs:
        tr = from_recording(r, columns)
        q, v = tr.q, (tr.qvel if tr.qvel is not None else tr.v)
        # row 0 is the initial state; rows 1.. are the states after each control step
        sig = np.concatenate([q[1:], v[1:]], -1)[:T]
        mask = np.ones(len(sig), np.float32)
        if len(sig) < T:
            sig = np.concatenate([sig, np.repeat(sig[-1:], T - len(sig), 0)])
            mask = np.concatenate([mask, np.zeros(T - len(mask), np.float32)])
        u = tr.ctrl[:-1][:T]
        if len(u) < T:
            u = np.concatenate([u, np.repeat(u[-1:], T - len(u), 0)])
        out.append((sig, mask, q[0], v[0], u))
    sig, mask, q0, v0, u = (jnp.asarray(np.stack(x), jnp.float32) for x in zip(*out))
    n = len(out)
    return RealData(sig, mask, q0, v0, jnp.zeros((n, 0)), jnp.full((n,), jnp.nan), u)


def save_recordings(sim: SimOpt, real: RealData, folder: str, prefix: str = "real") -> list[str]:
    """Write real rollouts as recordings (measured qpos, qvel per joint) for :func:`real_from_recordings`."""
    import os

    import mujoco

    from sim2real.sysid import recordings as rec_lib

    m, env = sim.env.mj_model, sim.env
    os.makedirs(folder, exist_ok=True)
    names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, j) for j in range(m.njnt)]
    acts = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, a) for a in range(m.nu)]
    paths = []
    for i in range(real.signals.shape[0]):
        T = int(np.asarray(real.mask[i]).sum())
        q = np.concatenate([np.asarray(real.qpos0[i])[None], np.asarray(real.signals[i, :T, :m.nq])])
        v = np.concatenate([np.asarray(real.qvel0[i])[None], np.asarray(real.signals[i, :T, m.nq:])])
        cols = {f"qpos:{n}": q[:, j] for j, n in enumerate(names)}
        cols.update({f"qvel:{n}": v[:, j] for j, n in enumerate(names)})
        u = np.asarray(real.ctrl[i, :T])
        u = np.concatenate([u, u[-1:]])  # the command row t is applied from t to t+1; last row repeats
        cols.update({f"ctrl:{a}": u[:, j] for j, a in enumerate(acts)})
        path = os.path.join(folder, f"{prefix}_{i}.csv")
        rec_lib.save_csv(path, np.arange(T + 1) * env.dt, cols)
        paths.append(path)
    return paths


def _build(env, cfg):
    opts = config_lib.from_dict(SimOptConfig, cfg.algo_options, "algo_options.")
    if cfg.updates_per_chunk != 1:
        raise config_lib.ConfigError(f"updates_per_chunk={cfg.updates_per_chunk}: algo=simopt runs one SimOpt "
                                     "iteration per chunk (each one checkpointed); set updates_per_chunk=1")
    so = SimOpt(env, cfg.ppo, cfg.dr, opts)
    if so.real is None:
        so.target()  # (refused here, before the driver makes a run folder)
    return so


register("simopt", _build, resumable_options=("recordings",))
