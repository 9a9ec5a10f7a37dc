"""SimOpt driver: ``jit(vmap_seeds(iteration))`` per SimOpt iteration, with checkpoints between.

Two ways to get the "real" rollouts (``SimOptRunConfig.real``):

* ``target`` (sim-to-sim): a target env whose hidden physics is ``target``; the whole iteration
  (train, real rollouts, REPS) is one jitted function vmapped over seeds.
* ``recordings``: recordings of the current policy on hardware (the diagnosis tool's format). One
  call does one SimOpt iteration: REPS on the recordings, then retraining; run it again with new
  recordings of the new policy (``policy.msgpack`` in the run folder) for the next one.

Writes ``iterations.csv`` (one row per iteration and seed), ``distribution.npz`` (mean/cov per
iteration), ``policy.msgpack`` and orbax checkpoints; ``resume=true`` continues after the last
completed iteration.
"""
from __future__ import annotations

import csv
import dataclasses
import os
import time
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from sim2real import checkpoint
from sim2real.algos.base import DRConfig
from sim2real.algos.simopt import SimOpt, SimOptConfig, real_from_recordings
from sim2real.envs import make
from sim2real.progress import Bar
from sim2real.rl.ppo import PPOConfig


@dataclasses.dataclass(frozen=True)
class SimOptRunConfig:
    """One SimOpt run.

    Attributes:
      name, out_dir, seed, num_seeds, resume, overwrite, progress: as ``TrainConfig``.
      max_iterations: stop after this many SimOpt iterations in this invocation (0: run to the
        end); ``resume=true`` continues (``real=target``).
      env, env_options: the simulator (and, sim-to-sim, the target) env.
      real: ``target`` | ``recordings``.
      target: hidden physics of the target env, ``{param: value}`` (``real=target``).
      recordings: recording files of the current policy on the real system (``real=recordings``).
      ppo: PPO settings of the policy (plain MLP).
      dr: ``params`` adapted by SimOpt; ``low``/``high`` bound the samples; ``fixed`` as usual.
      simopt: SimOpt settings.
    """

    name: str = "simopt"
    out_dir: str = "runs"
    env: str = "pendulum"
    env_options: dict[str, Any] = dataclasses.field(default_factory=dict)
    seed: int = 0
    num_seeds: int = 1
    real: str = "target"
    target: dict[str, float] = dataclasses.field(default_factory=dict)
    recordings: tuple[str, ...] = ()
    resume: bool = False
    overwrite: bool = False
    progress: bool = True
    max_iterations: int = 0
    ppo: PPOConfig = PPOConfig()
    dr: DRConfig = DRConfig()
    simopt: SimOptConfig = SimOptConfig()


def build(cfg: SimOptRunConfig):
    env = make(cfg.env, **cfg.env_options)
    if cfg.real not in ("target", "recordings"):
        raise ValueError(f"real='{cfg.real}' unknown: target, recordings")
    so = SimOpt(env, cfg.ppo, cfg.dr, cfg.simopt)
    z_target = None
    if cfg.real == "target":
        if not cfg.target:
            raise ValueError("real=target needs target={param: value, ...}: the hidden physics of the target env")
        z_target = env.z_of(**{k: float(v) for k, v in cfg.target.items()})
        env.check_z(z_target)
    elif not cfg.recordings:
        raise ValueError("real=recordings needs recordings=[a.csv, ...]")
    return env, so, z_target


def run(cfg: SimOptRunConfig) -> dict:
    """Run (or resume) SimOpt; returns ``{'state', 'rows', 'run_dir', 'simopt'}``."""
    from sim2real.train import Run, export_policy

    env, so, z_target = build(cfg)
    real_rec = real_from_recordings(so, list(cfg.recordings)) if cfg.real == "recordings" else None
    rd = Run(cfg)
    rd.prepare()
    seeds = jax.random.split(jax.random.PRNGKey(cfg.seed), cfg.num_seeds)
    state = jax.jit(jax.vmap(so.init))(seeds)
    mngr = checkpoint.manager(rd.ckpt_dir, 2)
    start = 0
    if cfg.resume:
        step = mngr.latest_step()
        if step is None:
            raise FileNotFoundError(f"resume=true but '{rd.ckpt_dir}' holds no checkpoint")
        state, start = checkpoint.restore(mngr, step, state), step
    dist_path = os.path.join(rd.dir, "distribution.npz")
    hist = dict(np.load(dist_path)) if start and os.path.exists(dist_path) else {}
    # per-iteration history only (the file also holds final_mean/final_cov/names, rewritten below)
    hist = {k: hist[k][:start] for k in ("mean", "cov") if k in hist}

    if cfg.real == "target":
        zt = jnp.asarray(z_target)
        # one compiled function for every iteration: the update count is an argument, not a shape
        it_fn = jax.jit(jax.vmap(lambda s, n: so.iteration(s, zt, num_updates=n), in_axes=(0, None)))
        n_updates = so.updates_for
        total = cfg.simopt.iterations + 1  # the last one trains and evaluates on the final distribution
    else:
        def hw(s, n):
            # n > 0 only on the very first call: the policy that produced the recordings is trained first
            s, _ = so.train(s, n)
            mean, cov = s.mean, s.cov
            s, info = so.adapt(s, real_rec)
            s, tm = so.train(s, cfg.simopt.ppo_updates)
            return s, dict(mean=mean, cov=cov, target_return=jnp.nan, eval_return=jnp.nan, **tm,
                           **{f"reps_{k}": v for k, v in info.items()})

        it_fn = jax.jit(jax.vmap(hw, in_axes=(0, None)))
        n_updates = lambda first: so.updates_for(True) if first else 0
        total = start + 1
    rows = []
    names = so.space.names
    bar = Bar(cfg.progress, total, "SimOpt", done=start)
    end = total if not cfg.max_iterations else min(total, start + cfg.max_iterations)
    try:
        for i in range(start, end):
            t0 = time.perf_counter()
            state, m = it_fn(state, jnp.int32(n_updates(i == 0)))
            m = jax.tree_util.tree_map(np.asarray, m)
            for k in ("mean", "cov"):
                hist[k] = np.concatenate([hist.get(k, np.zeros((0,) + m[k].shape)), m[k][None]])
            for s in range(cfg.num_seeds):
                row = {"iteration": i, "seed": s, "seconds": time.perf_counter() - t0,
                       "target_return": float(m["target_return"][s]), "eval_return": float(m["eval_return"][s]),
                       "train_return": float(m["train_return"][s])}
                row.update({f"mean:{n}": float(m["mean"][s, j]) for j, n in enumerate(names)})
                row.update({f"std:{n}": float(np.sqrt(m["cov"][s, j, j])) for j, n in enumerate(names)})
                row.update({f"reps_{k}": float(m[f"reps_{k}"][s, -1]) for k in ("kl", "ess", "cost_min", "cost_mean")})
                rows.append(row)
            _write_rows(os.path.join(rd.dir, "iterations.csv"), rows, append=i > 0 or start > 0)
            # the distribution after the last update too (what the next iteration trains on)
            np.savez(dist_path + ".tmp.npz", **hist, final_mean=np.asarray(state.mean),
                     final_cov=np.asarray(state.cov), names=np.array(names))
            os.replace(dist_path + ".tmp.npz", dist_path)
            checkpoint.save(mngr, i + 1, state)
            bar.step(text=f"iter {i}: target return {np.nanmean(m['eval_return']):.1f}")
    finally:
        mngr.wait_until_finished()
        bar.close()
    export_policy(so, state, os.path.join(rd.dir, "policy.msgpack"))
    return {"state": state, "rows": rows, "run_dir": rd.dir, "simopt": so, "env": env}


def _write_rows(path, rows, append):
    if not rows:
        return
    tmp = path + ".tmp"
    with open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    if append and os.path.exists(path):
        # keep rows of earlier invocations (resume) that this one did not rewrite
        with open(path) as f:
            old = [r for r in csv.DictReader(f) if int(r["iteration"]) < int(rows[0]["iteration"])]
        with open(tmp, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(old + rows)
    os.replace(tmp, path)
