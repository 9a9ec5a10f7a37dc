"""Brax's own PPO on a hopper, with our hopper run's budget and hyper-parameters: Brax's MJX hopper
(``env=brax``) or sim2real's hopper through ``sim2real.interop.brax`` (``env=sim2real``; with
``dr=true`` its physics redrawn at every reset from the leaderboard's training box, torso mass
[1, 9] kg x friction [1.5, 2.5]).

    python benchmarks/brax_ppo_hopper.py num_timesteps=100000000 num_envs=4096 unroll_length=32 ...
    python benchmarks/brax_ppo_hopper.py env=sim2real dr=true num_timesteps=20000000 discounting=0.995

Prints evaluation returns against wall time (Brax evaluates ``num_evals`` times with 128 envs,
deterministic policy; through the adapter each evaluation episode draws its own physics) and
writes ``<out>/brax_ppo_hopper.csv`` (``brax_ppo_<env>[_dr]_seed<seed>.csv`` for env=sim2real).
Brax 0.14.2 calls ``jax.device_put_replicated``, which JAX 0.11 removed; a one-device shim is
installed when it is missing.
"""
from __future__ import annotations

import csv
import dataclasses
import functools
import json
import os
import sys
import time

import jax
import jax.numpy as jnp

if not hasattr(jax, "device_put_replicated"):  # removed in JAX 0.11; brax 0.14.2 still calls it
    def _device_put_replicated(x, devices):
        return jax.tree_util.tree_map(lambda a: jax.device_put(jnp.stack([jnp.asarray(a)] * len(devices)), devices[0]), x)

    jax.device_put_replicated = _device_put_replicated



@dataclasses.dataclass
class Settings:
    """Brax PPO's own arguments (same names), the hidden layer width, the output folder, the hopper
    (``brax``: Brax's; ``sim2real``: ours through the adapter) and, for ours, ``dr`` (the box)."""
    num_timesteps: int = 100_000_000
    num_envs: int = 4096
    unroll_length: int = 32
    num_minibatches: int = 16
    num_updates_per_batch: int = 4
    learning_rate: float = 3e-4
    discounting: float = 0.99
    gae_lambda: float = 0.95
    reward_scaling: float = 0.1
    entropy_cost: float = 0.0
    clipping_epsilon: float = 0.2
    max_grad_norm: float = 0.5
    num_evals: int = 11
    hidden: int = 128
    seed: int = 0
    out: str = "."
    env: str = "brax"
    dr: bool = False


def main(argv):
    from brax import envs
    from brax.training.agents.ppo import networks as ppo_networks
    from brax.training.agents.ppo import train as ppo

    from sim2real.common import config as config_lib

    args = config_lib.load(Settings, argv)
    extra = {}
    if args.env == "brax":
        if args.dr:
            raise SystemExit("dr=true: only with env=sim2real (Brax's hopper has no physics box here)")
        env = envs.get_environment("hopper", backend="mjx")
    elif args.env == "sim2real":
        from sim2real.interop.brax import BraxEnv, wrap_for_training

        env = BraxEnv("hopper", physics={"mass:torso": (1.0, 9.0), "friction": (1.5, 2.5)} if args.dr else None)
        extra["wrap_env_fn"] = wrap_for_training
    else:
        raise SystemExit(f"env={args.env}: brax or sim2real")
    # env steps per update = batch_size * num_minibatches * unroll_length = num_envs * unroll_length
    batch_size = args.num_envs // args.num_minibatches
    net = functools.partial(ppo_networks.make_ppo_networks, policy_hidden_layer_sizes=(args.hidden,) * 2,
                            value_hidden_layer_sizes=(args.hidden,) * 2)
    rows, t0 = [], time.time()

    def progress(step, metrics):
        rows.append({"env_steps": int(step), "wall_seconds": round(time.time() - t0, 1),
                     "eval_return": float(metrics.get("eval/episode_reward", float("nan")))})
        print(json.dumps(rows[-1]), flush=True)

    ppo.train(environment=env, num_timesteps=args.num_timesteps, episode_length=1000, num_envs=args.num_envs,
              unroll_length=args.unroll_length, batch_size=batch_size, num_minibatches=args.num_minibatches,
              num_updates_per_batch=args.num_updates_per_batch, learning_rate=args.learning_rate,
              discounting=args.discounting, gae_lambda=args.gae_lambda, reward_scaling=args.reward_scaling,
              entropy_cost=args.entropy_cost, clipping_epsilon=args.clipping_epsilon,
              max_grad_norm=args.max_grad_norm, normalize_observations=True,
              num_evals=args.num_evals, network_factory=net, seed=args.seed, progress_fn=progress, **extra)
    total = time.time() - t0
    os.makedirs(args.out, exist_ok=True)
    name = "brax_ppo_hopper.csv" if args.env == "brax" else f"brax_ppo_{args.env}{'_dr' if args.dr else ''}_seed{args.seed}.csv"
    with open(os.path.join(args.out, name), "w", newline="") as f:
        f.write(f"# brax {__import__('brax').__version__} PPO, hopper ({args.env}), device {jax.devices()[0].device_kind}, "
                f"args {json.dumps(dataclasses.asdict(args))}\n")
        w = csv.DictWriter(f, fieldnames=["env_steps", "wall_seconds", "eval_return"])
        w.writeheader()
        w.writerows(rows)
    print("SUMMARY", json.dumps({"brax_total_seconds": round(total, 1), "final_eval_return": rows[-1]["eval_return"],
                                 "steps_per_second_incl_evals": round(rows[-1]["env_steps"] / max(total, 1e-9))}))


if __name__ == "__main__":
    main(sys.argv[1:])
