"""Where one PPO update spends its time: env alone vs rollout vs GAE vs epochs, and the training chunk.

    python benchmarks/ppo_profile.py                       # configs/hopper.yaml, 1 and 5 seeds
    python benchmarks/ppo_profile.py seeds=1,5 ppo.num_envs=8192 ppo.num_steps=16 out=results.csv

Every part is its own jitted function of the same ``[S seeds, B envs, T steps]`` shapes the
training driver uses (seeds vmapped), timed as the best of 3 calls after one warm-up (compiling) call:

- ``env``: ``T`` auto-reset steps of all ``S*B`` envs under uniform random actions (no network)
  -- the simulator's own rate at this batch;
- ``collect``: the PPO rollout (policy forward, action sampling, env step, V of the pre-reset
  next observation);
- ``gae``: advantages and returns of the collected batch;
- ``learn``: GAE + ``num_epochs x num_minibatches`` gradient steps (what ``PPO.learn`` does);
- ``chunk``: ``updates_per_chunk`` whole updates in one jitted scan, exactly as ``train.py`` runs
  them -- the training throughput.

Rates are env steps per second over all seeds. ``chunk / env`` is the share of the simulator's
rate that training keeps. Prints a table and appends it to ``out=`` (CSV) when given.
"""
from __future__ import annotations

import csv
import dataclasses
import os
import sys
import time

import jax
import jax.numpy as jnp

from sim2real.envs import make
from sim2real.envs.autoreset import step_autoreset
from sim2real.rl.rollout import collect, to_ctrl
from sim2real.training.driver import TrainConfig, build_algo, make_chunk

from hopper_ppo import load_args  # (the same key=value + config= handling)


def best_of(fn, arg, repeats=3):
    """One warm-up call (compiles), then the best of ``repeats`` timed calls (seconds)."""
    jax.block_until_ready(fn(arg))
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(fn(arg))
        ts.append(time.perf_counter() - t0)
    return min(ts)


def profile(cfg: TrainConfig, seeds: int) -> dict:
    env = make(cfg.env)
    algo = build_algo(cfg, env)
    ppo, sample = algo.ppo, algo.sampler()
    T, B = cfg.ppo.num_steps, cfg.ppo.num_envs
    # the initial state: timings do not depend on the weights, and an extra update would cost a
    # compilation (~20 s for an MJX env on a GPU)
    state = jax.jit(jax.vmap(algo.init))(jax.random.split(jax.random.PRNGKey(cfg.seed), seeds))

    def env_only(st):
        def step(c, k):
            s, z = c
            keys = jax.random.split(k, B)
            a = jax.vmap(lambda kk: jax.random.uniform(kk, (env.action_size,), minval=-1, maxval=1))(keys)
            s, z = jax.vmap(lambda s_, z_, a_, k_: step_autoreset(env, s_, z_, to_ctrl(env, a_), k_, sample)[:2])(
                s, z, a, jax.random.split(jax.random.fold_in(k, 1), B))
            return (s, z), None

        return jax.lax.scan(step, (st.runner.env_state, st.runner.z), jax.random.split(st.key, T))[0]

    def col(st):
        return collect(env, ppo.net, st.params, st.obs_stats, ppo.ctx, st.runner, st.key, sample, T)

    collect_fn = jax.jit(jax.vmap(col))
    batch = collect_fn(state)[1]
    gae_fn = jax.jit(jax.vmap(ppo.advantages))
    learn_fn = jax.jit(jax.vmap(lambda sb: ppo.learn(sb[0], sb[1], sb[0].key)))
    k = cfg.updates_per_chunk
    chunk = make_chunk(algo, k)
    steps = seeds * B * T
    t = {
        "env": best_of(jax.jit(jax.vmap(env_only)), state),
        "collect": best_of(collect_fn, state),
        "gae": best_of(gae_fn, batch),
        "learn": best_of(learn_fn, (state, batch)),
        "chunk": best_of(lambda s: chunk(s, 0), state) / k,
    }
    row = {"device": jax.devices()[0].device_kind, "seeds": seeds, "num_envs": B, "num_steps": T,
           "epochs_x_minibatches": f"{cfg.ppo.num_epochs}x{cfg.ppo.num_minibatches}",
           "hidden": "x".join(map(str, cfg.ppo.net.hidden))}
    for name, sec in t.items():
        row[f"{name}_ms"] = round(sec * 1e3, 2)
    for name in ("env", "collect", "chunk"):
        row[f"{name}_steps_per_s"] = round(steps / t[name])
    row["chunk_share_of_env_rate"] = round(t["env"] / t["chunk"], 3)
    row["learn_share_of_update"] = round(t["learn"] / t["chunk"], 3)
    return row


@dataclasses.dataclass
class Settings:
    """seeds: comma-separated seed counts, one row each; out: a CSV to append the rows to."""
    seeds: str = "1,5"
    out: str = ""


def main(argv):
    own, cfg = load_args(argv, Settings)
    rows = []
    for s in own.seeds.split(","):  # each row printed and saved as soon as it is measured
        r = profile(cfg, int(s))
        rows.append(r)
        print(" ".join(f"{k}={v}" for k, v in r.items()), flush=True)
        if own.out:
            new = not os.path.exists(own.out)
            with open(own.out, "a", newline="") as f:
                w = csv.DictWriter(f, fieldnames=list(r))
                if new:
                    w.writeheader()
                w.writerow(r)
    return rows


if __name__ == "__main__":
    main(sys.argv[1:])
