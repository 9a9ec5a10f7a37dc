"""SimOpt ablation in spirit (seed 002, Figs. 6-7 and 9): the target differs from the initial
distribution by a large offset, wide uniform DR fails, SimOpt transfers in <= 5 iterations with
3 target rollouts per iteration.

Task: pendulum swing-up (2 Nm motor). The "real" pendulum has a mis-calibrated angle encoder
(offset ``delta``) and a heavier pole. A policy that balances the *measured* upright holds the real
pole ``delta`` off vertical, where gravity needs more torque than the motor has: it falls. The
offset cannot be seen from one observation, so no single policy trained on a wide box of offsets
can compensate it; SimOpt identifies it from closed-loop rollouts.

    python benchmarks/simopt_ablation.py             # both targets, SimOpt + baselines, plots (CPU, ~40 min)
    python benchmarks/simopt_ablation.py plots=true     # figures from the saved CSV/NPZ
    python benchmarks/simopt_ablation.py scale=0.05 out=/tmp/x   # a quick check of the script
    python benchmarks/simopt_ablation.py task=hopper  # hopper: torso mass and friction (GPU)

Writes benchmarks/results/simopt_ablation/: ``<target>_iterations.csv`` (mean/std/returns per
iteration and seed), ``<target>_distribution.npz``, ``baselines.csv``, ``summary.json`` and the
plots ``mu_sigma.png``, ``covariance.png``, ``target_return.png``.
"""
from __future__ import annotations

import csv
import dataclasses
import json
import os
import sys
import time

import numpy as np

from sim2real.common.cli import settings

HERE = os.path.dirname(os.path.abspath(__file__))
EVAL_EPISODES = 64
# per task: the SimOpt config, the adapted parameters, the targets (like the paper's drawer 15 cm
# and 22 cm away: far outside N(mu0, Sigma0)), the wide uniform DR box covering them, results folder
TASKS = {
    "pendulum": dict(
        config="simopt_pendulum.yaml", env="pendulum", params=["sensor_offset:hinge", "mass:pole"],
        targets={"offset_0.3_mass_1.5": {"sensor_offset:hinge": 0.3, "mass:pole": 1.5},
                 "offset_0.5_mass_1.3": {"sensor_offset:hinge": 0.5, "mass:pole": 1.3}},
        wide=([-0.6, 0.5], [0.6, 2.0]), out="simopt_ablation"),
    # a torso 2.5x as heavy on a slippery floor (GPU scale: 4096 envs x 16 steps per PPO update)
    "hopper": dict(
        config="simopt_hopper.yaml", env="hopper", params=["mass:torso", "friction"],
        targets={"mass_9_friction_0.6": {"mass:torso": 9.0, "friction": 0.6}},
        wide=([1.0, 0.3], [12.0, 3.0]), out="simopt_hopper"),
}


def simopt_config(name, target, args):
    from sim2real.common import config as config_lib
    from sim2real.training.driver import TrainConfig

    tgt = "{" + ", ".join(f"'{k}': {v}" for k, v in target.items()) + "}"
    cfg = config_lib.load(TrainConfig, [
        f"config={os.path.join(HERE, '..', 'configs', args.t['config'])}", f"name=simopt_{name}", f"out_dir={args.work}",
        "overwrite=true", "progress=false", "tensorboard=false", f"num_seeds={args.seeds}", f"algo_options.target={tgt}",
        f"algo_options.init_ppo_updates={max(2, int(300 * args.scale))}",
        f"algo_options.ppo_updates={max(2, int(args.ppo_updates * args.scale))}",
        f"algo_options.num_samples={max(16, int(256 * args.scale))}", f"algo_options.eval_episodes={EVAL_EPISODES}"])
    return cfg


def run_simopt(name, target, args):
    """One SimOpt run (``train.py``, ``algo: simopt``); its metrics.csv / arrays.npz are copied out as
    ``<name>_iterations.csv`` (one row per iteration and seed) and ``<name>_distribution.npz``
    (``mean [I, S, D]``, ``cov [I, S, D, D]``: the distribution each iteration trained on; ``final_*``:
    after the last update)."""
    from sim2real.training.driver import train

    cfg = simopt_config(name, target, args)
    t0 = time.time()
    out = train(cfg)
    print(f"[simopt {name}] {time.time() - t0:.0f} s", flush=True)
    rd = out["run_dir"]
    with open(os.path.join(rd, "metrics.csv")) as f:
        rows = list(csv.DictReader(f))
    with open(os.path.join(args.out, f"{name}_iterations.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["iteration"] + [k for k in rows[0] if k != "update"])
        w.writeheader()
        w.writerows({"iteration": r["update"], **{k: v for k, v in r.items() if k != "update"}} for r in rows)
    arrays = np.load(os.path.join(rd, "arrays.npz"))
    np.savez(os.path.join(args.out, f"{name}_distribution.npz"), mean=np.swapaxes(arrays["dist_mean"], 0, 1),
             cov=np.swapaxes(arrays["dist_cov"], 0, 1), final_mean=np.asarray(out["state"].mean),
             final_cov=np.asarray(out["state"].cov), names=np.array(out["algo"].space.names))
    return cfg


def train_baseline(label, dr_args, args, so_cfg):
    """PPO with the same network and the same number of updates as a whole SimOpt run."""
    from sim2real.algos.simopt import SimOptConfig
    from sim2real.common import config as config_lib
    from sim2real.training.driver import TrainConfig, train

    s = config_lib.from_dict(SimOptConfig, so_cfg.algo_options)
    updates = (s.init_ppo_updates or s.ppo_updates) + s.iterations * s.ppo_updates
    p = so_cfg.ppo
    cfg = config_lib.load(TrainConfig, [
        f"env={args.t['env']}", f"name=baseline_{label}", f"out_dir={args.work}", "overwrite=true", "progress=false",
        "tensorboard=false", f"num_seeds={args.seeds}", f"total_steps={updates * p.batch_size}",
        f"updates_per_chunk={max(1, updates // 4)}", f"ppo.num_envs={p.num_envs}", f"ppo.num_steps={p.num_steps}",
        f"ppo.num_epochs={p.num_epochs}", f"ppo.num_minibatches={p.num_minibatches}", f"ppo.gamma={p.gamma}",
        f"ppo.lr={p.lr}", "ppo.anneal_lr=false", f"ppo.reward_scale={p.reward_scale}",
        f"ppo.net.hidden={list(p.net.hidden)}", *dr_args])
    t0 = time.time()
    out = train(cfg)
    print(f"[baseline {label}] {time.time() - t0:.0f} s", flush=True)
    return out


def evaluate_on(out, target, seeds):
    import jax

    from sim2real.rl.episodes import episodes

    env, algo, state = out["env"], out["algo"], out["state"]
    z = np.tile(env.z_of(**target), (EVAL_EPISODES, 1))
    params, stats = algo.policy(state)
    f = jax.jit(jax.vmap(lambda p, s, k: episodes(env, algo.ppo, p, s, z, k, 1)["return"].mean()))
    return np.asarray(f(params, stats, jax.random.split(jax.random.PRNGKey(7), seeds)))


@dataclasses.dataclass
class Settings:
    """seeds; scale: multiplies every budget; task: a key of TASKS; out: results folder (default:
    benchmarks/results/<the task's folder>); work: run folders; plots: figures from the saved CSV/NPZ
    only; ppo_updates: PPO updates per SimOpt iteration; targets: comma-separated target names
    (default: all of the task's); skip_simopt: train baselines only (the targets' SimOpt CSVs must
    already be in out); baselines: which baselines to (re)train, comma-separated."""
    seeds: int = 2
    scale: float = 1.0
    task: str = "pendulum"
    out: str = ""
    work: str = "/tmp/simopt_ablation_runs"
    plots: bool = False
    ppo_updates: int = 100
    targets: str = ""
    skip_simopt: bool = False
    baselines: str = "nominal,wide_udr,oracle"


def main(args: Settings):
    if args.task not in TASKS:
        raise SystemExit(f"task={args.task}: one of {', '.join(sorted(TASKS))}")
    args.t = TASKS[args.task]
    args.out = args.out or os.path.join(HERE, "results", args.t["out"])
    targets, params, wide_box = args.t["targets"], args.t["params"], args.t["wide"]
    os.makedirs(args.out, exist_ok=True)
    if args.plots:
        return plots(args.out, args.t)
    import jax

    rows, summary = [], {"device": str(jax.devices()[0].device_kind), "seeds": args.seeds, "scale": args.scale,
                         "task": args.task}
    names = [n for n in args.targets.split(",") if n] or list(targets)
    so_cfg = None
    for name in names:
        if args.skip_simopt:  # baselines only (another device call): the SimOpt CSVs are in out
            so_cfg = simopt_config(name, targets[name], args)
        else:
            so_cfg = run_simopt(name, targets[name], args)
    # baselines: trained once, evaluated on every target
    wide = [f"dr.params={params}", f"dr.low={wide_box[0]}", f"dr.high={wide_box[1]}"]
    baselines = {"nominal": [], "wide_udr": wide}
    baselines.update({f"oracle_{n}": ["dr.fixed={" + ", ".join(f"'{k}': {v}" for k, v in targets[n].items()) + "}"]
                      for n in names})
    wanted = set(args.baselines.split(","))
    method = lambda label: "oracle" if label.startswith("oracle_") else label  # noqa: E731
    todo = {label: a for label, a in baselines.items() if method(label) in wanted}
    path = os.path.join(args.out, "baselines.csv")
    if os.path.exists(path):  # keep the rows of baselines an earlier call trained and this one does not
        redo = {method(label) for label in todo}
        rows = [r for r in _read(path) if r["method"] not in redo or r["target"] not in names]
    for label, dr_args in todo.items():
        out = train_baseline(label, dr_args, args, so_cfg)
        for name in names:
            if label.startswith("oracle_") and label != f"oracle_{name}":
                continue
            r = evaluate_on(out, targets[name], args.seeds)
            rows.append({"target": name, "method": method(label),
                         **{f"seed{s}": float(v) for s, v in enumerate(r)}, "mean": float(r.mean())})
            print(rows[-1], flush=True)
        with open(path, "w", newline="") as f:  # after every baseline: a timed-out call keeps the rest
            w = csv.DictWriter(f, fieldnames=list(dict.fromkeys(k for r in rows for k in r)))
            w.writeheader()
            w.writerows(rows)
    for name in names:
        it = _read(os.path.join(args.out, f"{name}_iterations.csv"))
        last = int(max(r["iteration"] for r in it))
        fin = [r for r in it if r["iteration"] == last]
        summary[name] = {
            "truth": targets[name],
            "final_mean": {p: float(np.mean([r[f"mean:{p}"] for r in fin])) for p in params},
            "final_std": {p: float(np.mean([r[f"std:{p}"] for r in fin])) for p in params},
            "eval_return_per_iteration": [float(np.mean([r["eval_return"] for r in it if r["iteration"] == i]))
                                          for i in range(last + 1)],
            "baselines": {r["method"]: r["mean"] for r in rows if r["target"] == name},
        }
    with open(os.path.join(args.out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=2)
    plots(args.out, args.t)


def _read(path):
    with open(path) as f:
        return [{k: (float(v) if k not in ("target", "method") else v) for k, v in r.items()} for r in csv.DictReader(f)]


def plots(out, task):
    targets, params = task["targets"], task["params"]
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = [n for n in targets if os.path.exists(os.path.join(out, f"{n}_iterations.csv"))]
    base = _read(os.path.join(out, "baselines.csv")) if os.path.exists(os.path.join(out, "baselines.csv")) else []
    # Fig. 6 / 9 (left): mean and std per iteration against the truth
    fig, axes = plt.subplots(len(names), len(params), figsize=(5 * len(params), 3.2 * len(names)), squeeze=False)
    for i, n in enumerate(names):
        it = _read(os.path.join(out, f"{n}_iterations.csv"))
        seeds = sorted({int(r["seed"]) for r in it})
        for j, p in enumerate(params):
            ax = axes[i, j]
            for s in seeds:
                rs = [r for r in it if int(r["seed"]) == s]
                x = [r["iteration"] for r in rs]
                mu = np.array([r[f"mean:{p}"] for r in rs])
                sd = np.array([r[f"std:{p}"] for r in rs])
                ax.plot(x, mu, marker="o", label=f"seed {s}")
                ax.fill_between(x, mu - sd, mu + sd, alpha=0.2)
            ax.axhline(targets[n][p], color="k", ls="--", label="truth")
            ax.set_title(f"{n}: {p}")
            ax.set_xlabel("SimOpt iteration (distribution the policy trained on)")
            ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "mu_sigma.png"), dpi=110)
    # covariance heat maps (seed 0): initial, after 1, 2 iterations, final
    fig, axes = plt.subplots(len(names), 4, figsize=(14, 3.4 * len(names)), squeeze=False)
    for i, n in enumerate(names):
        d = np.load(os.path.join(out, f"{n}_distribution.npz"))
        covs = list(d["cov"][:, 0]) + [d["final_cov"][0]]
        picks = [0, 1, 2, len(covs) - 1]
        for j, k in enumerate(picks):
            c = covs[k]
            sd = np.sqrt(np.diag(c))
            corr = c / np.outer(sd, sd)
            ax = axes[i, j]
            im = ax.imshow(corr, vmin=-1, vmax=1, cmap="RdBu_r")
            for a in range(len(params)):
                for b in range(len(params)):
                    ax.text(b, a, f"{c[a, b]:.2g}", ha="center", va="center", fontsize=8)
            short = [q.split(":")[0] for q in params]
            ax.set_xticks(range(len(params)), short, fontsize=7)
            ax.set_yticks(range(len(params)), short if j == 0 else [], fontsize=7)
            ax.set_title(f"{n}\n{'final' if k == len(covs) - 1 else f'iteration {k}'} (colour: correlation)", fontsize=8)
        fig.colorbar(im, ax=axes[i].tolist(), shrink=0.8)
    fig.savefig(os.path.join(out, "covariance.png"), dpi=110)
    # Fig. 7: target return per iteration, with the baselines
    fig, axes = plt.subplots(1, len(names), figsize=(6 * len(names), 4), squeeze=False)
    for i, n in enumerate(names):
        ax = axes[0, i]
        it = _read(os.path.join(out, f"{n}_iterations.csv"))
        its = sorted({int(r["iteration"]) for r in it})
        ev = np.array([[r["eval_return"] for r in it if int(r["iteration"]) == k] for k in its])
        ax.errorbar(its, ev.mean(1), yerr=ev.std(1), marker="o", label="SimOpt (policy of iteration i)")
        for r, c in zip([r for r in base if r["target"] == n], ["C1", "C2", "C3"]):
            ax.axhline(r["mean"], color=c, ls="--", label=f"{r['method']} (same PPO updates)")
        ax.set_xlabel("SimOpt iteration")
        ax.set_ylabel(f"return on the target ({EVAL_EPISODES} episodes)")
        ax.set_title(n)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "target_return.png"), dpi=110)
    print(f"plots in {out}")


if __name__ == "__main__":
    main(settings(Settings, sys.argv[1:]))
