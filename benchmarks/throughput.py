"""Env steps per second: sim2real hopper (physics resampled at every reset) vs Brax MJX vs Gymnasium.

    python benchmarks/throughput.py                                   # CPU, batches 64..4096
    python benchmarks/throughput.py batches=1024,8192,32768,131072 tag=gpu-h100 gym=false

All three run a uniform random policy. sim2real: jit(scan) of vmapped ``step_autoreset`` with the
LSDR context (torso size, density, friction, joint damping) drawn uniformly at every reset, the
env batch split over one CPU device per core with ``sim2real.envs.parallel.batch_map`` (on a one-GPU
host this is the plain single-device run). Brax: ``brax.envs.get_environment('hopper',
backend='mjx')`` wrapped for training (vmap, episode, auto-reset), as its PPO runs it, on one
device as shipped (``brax_mjx``) and with the same batch split as ours (``brax_mjx_split``);
``sim2real_1dev`` is ours on one device. Actions come from per-env keys in every column.
Gymnasium: ``Hopper-v5`` (native MuJoCo) as a sync vector env.
Each figure is the best of 3 timed repeats after two warm-up calls (compilation excluded).
Writes ``benchmarks/results/throughput_<tag>.csv`` and ``throughput_<tag>.png``.
"""
from __future__ import annotations

import csv
import dataclasses
import os
import platform
import sys
import time

import jax
import jax.numpy as jnp
import numpy as np

from sim2real.common.cli import settings
from sim2real.envs import parallel

parallel.use_cpu_cores()  # before anything runs: one CPU device per core

RESULTS = os.path.join(os.path.dirname(__file__), "results")


def time_best(fn, repeats=3):
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        jax.block_until_ready(fn())
        ts.append(time.perf_counter() - t0)
    return min(ts)


def _timed(roll, carry):
    """Two warm-up calls (the second runs on the first's output layout), then best of 3."""
    carry = jax.block_until_ready(roll(*carry))
    carry = jax.block_until_ready(roll(*carry))
    return time_best(lambda: roll(*carry))


def _random_actions(keys, size):
    """Per-env uniform actions ``[B, size]`` and the next keys ``[B, 2]`` from per-env keys ``[B, 2]``.

    Per-env keys (not one key for the batch) keep the draws independent of how the batch is split
    over devices, and let each device draw only its own slice.
    """
    keys, ka = parallel.split_keys(keys)
    a = jax.vmap(lambda k: jax.random.uniform(k, (size,), minval=-1, maxval=1))(ka)
    return a, keys


def _compile(roll, batch, split):
    return parallel.batch_map(roll, batch) if split else jax.jit(roll)


def bench_sim2real(batch: int, steps: int, split: bool = True) -> float:
    from sim2real.envs import make
    from sim2real.envs.autoreset import step_autoreset

    env = make("hopper")
    names = ["torso_size", "density", "friction", "joint_damping"]
    idx = env.spec.indices(names)
    lo = jnp.asarray([0.03, 700.0, 1.5, 0.5])
    hi = jnp.asarray([0.07, 1300.0, 2.5, 1.5])
    base = jnp.asarray(env.default_z())

    def sample(k):
        return base.at[idx].set(jax.random.uniform(k, (len(names),), minval=lo, maxval=hi))

    keys = jax.random.split(jax.random.PRNGKey(0), batch)
    z = jax.vmap(sample)(keys)
    state = jax.vmap(env.reset)(keys, z)
    step = jax.vmap(lambda s, zz, a, k: step_autoreset(env, s, zz, a, k, sample)[:2])

    def roll(state, z, keys):
        def f(c, _):
            s, zz, k = c
            a, k = _random_actions(k, env.action_size)
            k, ks = parallel.split_keys(k)
            return (*step(s, zz, a, ks), k), None

        return jax.lax.scan(f, (state, z, keys), None, length=steps)[0]

    return batch * steps / _timed(_compile(roll, batch, split), (state, z, keys))


def bench_brax(batch: int, steps: int, split: bool = False) -> float:
    from brax import envs
    from brax.envs.wrappers import training

    env = training.wrap(envs.get_environment("hopper", backend="mjx"), episode_length=1000)
    state = jax.jit(env.reset)(jax.random.split(jax.random.PRNGKey(0), batch))
    keys = jax.random.split(jax.random.PRNGKey(1), batch)

    def roll(state, keys):
        def f(c, _):
            s, k = c
            a, k = _random_actions(k, env.action_size)
            return (env.step(s, a), k), None

        return jax.lax.scan(f, (state, keys), None, length=steps)[0]

    return batch * steps / _timed(_compile(roll, batch, split), (state, keys))


def bench_gym(batch: int, total_steps: int) -> float:
    import gymnasium as gym

    envs = gym.make_vec("Hopper-v5", num_envs=batch, vectorization_mode="sync")
    envs.reset(seed=0)
    rng = np.random.default_rng(0)
    n = max(1, total_steps // batch)
    acts = rng.uniform(-1, 1, (n, batch, 3)).astype(np.float32)

    def run():
        for a in acts:
            envs.step(a)
        return jnp.zeros(())

    t = time_best(run)
    envs.close()
    return batch * n / t


@dataclasses.dataclass
class Settings:
    """batches: comma-separated env batch sizes; steps: scan length per timed call; gym_steps: env
    steps per timed Gymnasium call; tag: the rows' label; brax, gym: also time Brax's MJX hopper and
    Gymnasium's MuJoCo hopper; out: results folder."""
    batches: str = "64,256,1024,4096"
    steps: int = 100
    gym_steps: int = 20000
    tag: str = "cpu"
    brax: bool = True
    gym: bool = True
    out: str = RESULTS


def main(args: Settings):
    batches = [int(b) for b in args.batches.split(",")]
    device = (f"{jax.devices()[0].device_kind} ({jax.default_backend()}) x {len(jax.devices())}, "
              f"{os.cpu_count()} CPU cores, {platform.node()}")
    rows = []
    for b in batches:
        split = len(parallel.batch_devices(b)) > 1
        row = {"batch": b, "sim2real": bench_sim2real(b, args.steps, split=split)}
        if split:
            row["sim2real_1dev"] = bench_sim2real(b, args.steps, split=False)
        if args.brax:
            row["brax_mjx"] = bench_brax(b, args.steps)
            if split:
                row["brax_mjx_split"] = bench_brax(b, args.steps, split=True)
        if args.gym:
            row["gymnasium"] = bench_gym(b, args.gym_steps)
        rows.append(row)
        print({k: (round(v) if isinstance(v, float) else v) for k, v in row.items()}, flush=True)
    if args.gym:
        rows.append({"batch": 1, "gymnasium": bench_gym(1, args.gym_steps)})
        print(rows[-1], flush=True)
    write(rows, args, device)


def write(rows, args, device):
    os.makedirs(args.out, exist_ok=True)
    cols = ["batch", "sim2real", "sim2real_1dev", "brax_mjx", "brax_mjx_split", "gymnasium"]
    path = os.path.join(args.out, f"throughput_{args.tag}.csv")
    with open(path, "w", newline="") as f:
        f.write(f"# env-steps/s, hopper, random policy; device: {device}; jax {jax.__version__}\n")
        w = csv.DictWriter(f, fieldnames=cols)
        w.writeheader()
        for r in rows:
            w.writerow({c: (f"{r[c]:.0f}" if isinstance(r.get(c), float) else r.get(c, "")) for c in cols})
    print(f"wrote {path}")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for c, style in [("sim2real", "o-"), ("sim2real_1dev", "o:"), ("brax_mjx", "s--"),
                     ("brax_mjx_split", "s:"), ("gymnasium", "^:")]:
        pts = [(r["batch"], r[c]) for r in rows if c in r]
        if pts:
            ax.loglog(*zip(*sorted(pts)), style, label=c)
    ax.set_xlabel("parallel envs")
    ax.set_ylabel("env steps / s")
    ax.set_title(f"Hopper throughput ({args.tag})")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, f"throughput_{args.tag}.png"), dpi=120)


if __name__ == "__main__":
    main(settings(Settings, sys.argv[1:]))
