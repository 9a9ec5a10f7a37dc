"""Time of one SimOpt REPS update at the paper's scale: 9,600 parameter samples x 453 timesteps.

One update = sample xi ~ N(mu, Sigma) (full covariance over 5 hopper parameters), simulate the
closed-loop policy (an MLP, 2x64) in MJX hopper for 453 steps from each real rollout's initial
state, smooth and score every trajectory against the real ones (Eq. 4), solve the REPS dual and
refit the Gaussian. The "real" rollouts come from a hopper with hidden parameters. The paper ran
this on a 64-GPU cluster; the target is <= 10 s on one GPU.

    python benchmarks/reps_update.py samples=9600 steps=453 real=1 tag=gpu-h100
    python benchmarks/reps_update.py samples=96 steps=453 tag=cpu-2core   # CPU reference

Appends a row to benchmarks/results/reps_update.csv.
"""
from __future__ import annotations

import csv
import dataclasses
import os
import sys
import time

from sim2real.common.cli import settings


@dataclasses.dataclass
class Settings:
    """samples: REPS samples; steps: rollout steps per sample; real: numbers of real rollouts
    (``[1,3]``); repeats: timed calls; tag: the row's label; out: the CSV appended to."""
    samples: int = 9600
    steps: int = 453
    real: tuple[int, ...] = (1, 3)
    repeats: int = 3
    tag: str = ""
    out: str = os.path.join(os.path.dirname(os.path.abspath(__file__)), "results", "reps_update.csv")


def setup(samples: int, steps: int, real_rollouts: int, spread: bool = False):
    """``(simopt, state, real)``: SimOpt on hopper with 5 hidden parameters at 1.4x their defaults,
    ``real_rollouts`` target rollouts of ``steps`` steps; ``spread``: the samples split over the
    host's devices (``ppo.data_parallel``, ``parallel.spread``)."""
    import jax
    import jax.numpy as jnp

    from sim2real.algos.base import DRConfig
    from sim2real.algos.simopt import SimOpt, SimOptConfig
    from sim2real.envs import make
    from sim2real.rl.networks import NetConfig
    from sim2real.rl.ppo import PPOConfig

    env = make("hopper")
    names = ("mass:torso", "friction", "joint_damping", "gain:thigh", "gain:leg")
    default = env.default_z()
    mu0 = [float(default[env.spec.index(n)]) for n in names]
    dr = DRConfig(params=names, low=tuple(0.2 * m if m > 0 else 0.0 for m in mu0),
                  high=tuple(3.0 * m if m > 0 else 1.0 for m in mu0))
    truth = {n: (1.4 * m if m > 0 else 0.3) for n, m in zip(names, mu0)}
    zt = jnp.asarray(env.z_of(**truth))
    cfg = SimOptConfig(init_std=tuple(0.2 * m if m > 0 else 0.1 for m in mu0), num_samples=samples,
                       horizon=steps, real_rollouts=real_rollouts, eval_episodes=0)
    so = SimOpt(env, PPOConfig(num_envs=8, num_steps=8, num_minibatches=4, net=NetConfig(hidden=(64, 64)),
                               data_parallel=spread), dr, cfg)
    st = jax.jit(so.init)(jax.random.PRNGKey(0))
    real = jax.jit(lambda s: so.target_rollouts(s, zt, jax.random.PRNGKey(1), real_rollouts))(st)
    return so, st, real


def timed(fn, state, repeats: int):
    """``(compile seconds, median seconds of repeats calls, last output)`` of ``fn(state) -> (state,
    ...)`` called with its own output's state: the first call (compilation) apart, then ``repeats``."""
    import jax
    import numpy as np

    t0 = time.perf_counter()
    out = jax.block_until_ready(fn(state))
    compile_s = time.perf_counter() - t0
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = jax.block_until_ready(fn(out[0]))
        times.append(time.perf_counter() - t0)
    return compile_s, float(np.median(times)), out


def main(args: Settings):
    import jax
    import numpy as np

    device = jax.devices()[0].device_kind
    rows = []
    for R in args.real:
        so, st, real = setup(args.samples, args.steps, R)
        step = jax.jit(so.reps_step)
        compile_s, sec, (s2, info) = timed(lambda s: step(s, real), st, args.repeats)
        row = {"tag": args.tag, "device": device, "samples": args.samples, "steps": args.steps, "real_rollouts": R,
               "env_steps": args.samples * args.steps * R, "seconds_per_update": round(sec, 4),
               "env_steps_per_s": round(args.samples * args.steps * R / sec), "compile_s": round(compile_s, 1),
               "kl": float(info["kl"]), "ess": float(info["ess"]), "finite_mean": bool(np.isfinite(s2.mean).all())}
        print(row, flush=True)
        rows.append(row)
    new = not os.path.exists(args.out)
    with open(args.out, "a", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        if new:
            w.writeheader()
        w.writerows(rows)


if __name__ == "__main__":
    main(settings(Settings, sys.argv[1:]))
