"""Seed 004 on hopper: ES-MAML (PPO inner loop) vs fixed physics, uniform DR (MLP) and uniform DR
(LSTM), trained on torso mass U[1, 9] x friction U[1.5, 2.5], tested on mass [0.5, 11.5] x
friction [0.1, 2.9].

    python benchmarks/es_maml_hopper.py part=train     # GPU: baselines, ES-MAML, test grid
    (part=baselines, then part=esmaml: the same in two calls; the second starts from the
     uniform-DR policy the first kept in the results folder)
    python benchmarks/es_maml_hopper.py part=speed     # meta-iterations/s on this machine
    python benchmarks/es_maml_hopper.py part=plots     # heat maps + table from the saved grid
    python benchmarks/es_maml_hopper.py part=merge merge_from=DIR   # add DIR's seeds (run with
                                                         # seed=/seeds= out=DIR), then table + plots
    ... scale=0.01 out=/tmp/x                        # tiny budgets, to check the script on CPU

Scaled down from seed 004 (device budget): the baselines train ``steps`` env steps; ES-MAML is
warm-started from each seed's uniform-DR MLP policy (meta-training from scratch with ES needs far
more than the budget) and runs ``meta_iters`` meta-iterations with population ``population``,
each member adapting with 3 PPO updates x 4096 env steps (seed 004's inner loop) and scored on
``eval_horizon``-step episodes. Test episodes are full length (1000 steps). ES-MAML and the
"udr_mlp+adapt" row are evaluated after the same 3-update adaptation on each test cell.

Writes benchmarks/results/es_maml_hopper/: grid.npz (returns [method, seed, mass, friction]),
table.csv (in/out-of-distribution means), meta.csv (per meta-iteration), speed.csv, heatmaps.png.
"""
from __future__ import annotations

import csv
import dataclasses
import json
import os
import sys
import time
from typing import Literal

import numpy as np

from sim2real.common.cli import settings

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "results", "es_maml_hopper")
TRAIN_BOX = {"mass:torso": (1.0, 9.0), "friction": (1.5, 2.5)}
FIXED = {"mass:torso": 6.0, "friction": 2.0}  # seed 004's defaults
MASSES = np.linspace(0.5, 11.5, 12)
FRICTIONS = np.linspace(0.1, 2.9, 8)
BASE = ["env=hopper", "ppo.num_envs=4096", "ppo.num_steps=16", "ppo.num_epochs=4", "ppo.num_minibatches=8",
        "ppo.gamma=0.99", "ppo.lr=3e-4", "ppo.reward_scale=0.1", "ppo.net.hidden=[128,128]",
        "tensorboard=false", "progress=false"]
INNER = dict(num_envs=256, num_steps=16, num_epochs=4, num_minibatches=4)  # 4096 steps per inner update


def dr_args(box):
    names = list(box)
    return [f"dr.params={names}", f"dr.low={[box[n][0] for n in names]}", f"dr.high={[box[n][1] for n in names]}"]


def train_baseline(label, extra, args):
    from sim2real.common import config as config_lib
    from sim2real.training.driver import TrainConfig, train

    cfg = config_lib.load(TrainConfig, BASE + [f"name={label}", f"out_dir={args.work}", "overwrite=true",
                                               f"seed={args.seed}", f"num_seeds={args.seeds}", f"total_steps={int(args.steps * args.scale)}",
                                               "updates_per_chunk=20"] + extra)
    t0 = time.time()
    out = train(cfg)
    print(f"[{label}] trained in {time.time() - t0:.0f} s", flush=True)
    return out, cfg


def make_esmaml(env, ppo_cfg, args):
    import dataclasses

    from sim2real.algos.base import DRConfig
    from sim2real.algos.es_maml import ESMAML, ESMAMLConfig

    inner = dataclasses.replace(ppo_cfg, **INNER)
    if args.scale < 1:
        inner = dataclasses.replace(inner, num_envs=32)
    dr = DRConfig(params=tuple(TRAIN_BOX), low=tuple(v[0] for v in TRAIN_BOX.values()),
                  high=tuple(v[1] for v in TRAIN_BOX.values()))
    return ESMAML(env, inner, dr, ESMAMLConfig(population=args.population, sigma=args.sigma, meta_lr=args.meta_lr,
                                               inner_updates=3, eval_episodes=2, eval_horizon=args.eval_horizon))


def grid_z(env):
    from sim2real.tools.evaluate import grid

    zs, _ = grid(env, {"mass:torso": MASSES, "friction": FRICTIONS})
    return zs  # [12 * 8, P], mass-major


def eval_grid(env, ppo, params, stats, key, episodes_per_cell):
    """Returns ``[S, 12, 8]`` mean full-episode returns (no adaptation)."""
    import jax

    from sim2real.rl.episodes import episodes

    zs = grid_z(env)
    f = jax.jit(jax.vmap(lambda p, s, k: episodes(env, ppo, p, s, zs, k, episodes_per_cell)["return"].mean(-1)))
    S = jax.tree_util.tree_leaves(params)[0].shape[0]
    return np.asarray(f(params, stats, jax.random.split(key, S))).reshape(S, len(MASSES), len(FRICTIONS))


def eval_grid_adapted(es, params, stats, key, episodes_per_cell):
    """Few-shot: 3 PPO updates on each test cell, then full-length episodes; ``[S, 12, 8]``."""
    import jax

    from sim2real.rl.episodes import episodes

    env = es.env
    zs = grid_z(env)

    def cell(p, s, z, k):
        k_a, k_e = jax.random.split(k)
        p2, s2, _ = es.adapt(p, s, z, k_a)
        return episodes(env, es.ppo, p2, s2, z[None], k_e, episodes_per_cell)["return"].mean()

    per_seed = jax.vmap(lambda p, s, k: jax.vmap(lambda z, kk: cell(p, s, z, kk))(zs, jax.random.split(k, len(zs))))
    S = jax.tree_util.tree_leaves(params)[0].shape[0]
    out = jax.jit(per_seed)(params, stats, jax.random.split(key, S))
    return np.asarray(out).reshape(S, len(MASSES), len(FRICTIONS))


def part_train(args):
    import jax

    from sim2real.training import checkpoint

    os.makedirs(args.out, exist_ok=True)
    results = {}
    device = str(jax.devices()[0].device_kind)
    key = jax.random.PRNGKey(123)
    E = args.episodes
    grid_path = os.path.join(args.out, "grid.npz")
    if os.path.exists(grid_path) and (args.resume or args.part == "esmaml"):  # esmaml adds to the baselines' grid
        # returns only: the axes are written again by save()
        results = {k: v for k, v in np.load(grid_path).items() if k not in ("masses", "frictions")}

    def save():
        np.savez(grid_path + ".tmp.npz", **results, masses=MASSES, frictions=FRICTIONS)
        os.replace(grid_path + ".tmp.npz", grid_path)

    if args.part in ("train", "baselines"):
        fixed = [f"dr.fixed={json.dumps(FIXED)}"]
        runs = {"fixed": fixed, "udr_mlp": dr_args(TRAIN_BOX), "udr_lstm": dr_args(TRAIN_BOX) + [
            "ppo.net.kind=lstm", "ppo.net.lstm_size=128", "ppo.num_minibatches=4"]}
        for label, extra in runs.items():
            out, cfg = train_baseline(label, extra, args)
            if label == "udr_mlp":  # kept with the results: ES-MAML starts from it (maybe in another session)
                import shutil

                keep = os.path.join(args.out, "udr_mlp_run")
                os.makedirs(keep, exist_ok=True)
                for fn in ("config.yaml", "policy.msgpack"):
                    shutil.copy(os.path.join(out["run_dir"], fn), os.path.join(keep, fn))
            t0 = time.time()
            params, stats = out["algo"].policy(out["state"])
            results[label] = eval_grid(out["env"], out["algo"].ppo, params, stats, key, E)
            print(f"[{label}] grid evaluated in {time.time() - t0:.0f} s", flush=True)
            save()
        if args.part == "baselines":
            table(args.out)
            return

    # ES-MAML, warm-started from the uniform-DR MLP of each seed
    from sim2real.training.runs import load_policy

    cfg, env, _, params, stats = load_policy(os.path.join(args.out, "udr_mlp_run"))
    es = make_esmaml(env, cfg.ppo, args)
    n = jax.tree_util.tree_leaves(params)[0].shape[0]
    if n != args.seeds:
        raise ValueError(f"the saved uniform-DR policy has {n} seeds; pass seeds={n}")
    if not (args.resume and "udr_mlp+adapt" in results):  # a resumed run keeps what it evaluated
        t0 = time.time()
        results["udr_mlp+adapt"] = eval_grid_adapted(es, params, stats, key, E)
        print(f"[udr_mlp+adapt] grid evaluated in {time.time() - t0:.0f} s", flush=True)
        save()
    st = jax.jit(jax.vmap(es.init))(jax.random.split(jax.random.PRNGKey(args.seed), args.seeds), params, stats)
    chunk = max(1, min(args.chunk, args.meta_iters))

    def many(s):
        return jax.lax.scan(lambda c, _: jax.vmap(es.update)(c), s, None, length=chunk)

    many = jax.jit(many)
    mngr = checkpoint.manager(os.path.join(args.work, "es_maml", "checkpoints"), 2)
    start = 0
    if args.resume and mngr.latest_step() is not None:
        start = mngr.latest_step()
        st = checkpoint.restore(mngr, start, st)
    meta_rows = []
    times = []
    for it in range(start, args.meta_iters, chunk):
        t0 = time.time()
        st, m = many(st)
        m = jax.tree_util.tree_map(np.asarray, m)  # [chunk, S]
        dt = time.time() - t0
        times.append(dt / chunk)
        for j in range(chunk):
            meta_rows.append({"meta_iteration": it + j, "seconds_per_iteration": dt / chunk,
                              **{k: float(np.mean(v[j])) for k, v in m.items()}})
        checkpoint.save(mngr, it + chunk, st)
        print(f"[es_maml] meta-iter {it + chunk}/{args.meta_iters}: fitness {np.mean(m['fitness_mean'][-1]):.1f} "
              f"({dt / chunk:.2f} s/iter)", flush=True)
    mngr.wait_until_finished()
    if meta_rows:  # a run resumed at its last checkpoint has none; keep the earlier meta.csv
        with open(os.path.join(args.out, "meta.csv" if start == 0 else f"meta_from_{start}.csv"), "w",
                  newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(meta_rows[0]))
            w.writeheader()
            w.writerows(meta_rows)
    theta, stats = jax.vmap(es.policy)(st)  # [S, ...]
    t0 = time.time()
    results["es_maml"] = eval_grid_adapted(es, theta, stats, key, E)
    results["es_maml_noadapt"] = eval_grid(env, es.ppo, theta, stats, key, E)
    print(f"[es_maml] grid evaluated in {time.time() - t0:.0f} s", flush=True)
    save()
    steady = times[1:] or times
    if steady:  # none when resumed at the last checkpoint: keep the earlier speed_train.json
        speed = {"device": device, "population": args.population, "seeds": args.seeds,
                 "meta_iterations_per_s": 1.0 / float(np.median(steady)),
                 "env_steps_per_meta_iteration_per_seed": es.env_steps_per_update()}
        with open(os.path.join(args.out, "speed_train.json"), "w") as f:
            json.dump(speed, f, indent=2)
    table(args.out)
    plots(args.out)


def part_speed(args):
    """meta-iterations/s of one jitted meta step (1 seed) at the given population."""
    import jax

    from sim2real.common import config as config_lib
    from sim2real.envs import make
    from sim2real.training.driver import TrainConfig

    cfg = config_lib.load(TrainConfig, BASE)
    env = make("hopper")
    es = make_esmaml(env, cfg.ppo, args)
    st = jax.jit(es.init)(jax.random.PRNGKey(0))
    step = jax.jit(es.update)
    t0 = time.time()
    st, _ = step(st)
    jax.block_until_ready(st)
    compile_s = time.time() - t0
    ts = []
    for _ in range(args.repeats):
        t0 = time.time()
        st, _ = step(st)
        jax.block_until_ready(st)
        ts.append(time.time() - t0)
    row = {"tag": args.tag, "device": str(jax.devices()[0].device_kind), "population": args.population,
           "inner_envs": es.ppo.cfg.num_envs, "inner_steps_per_update": es.ppo.cfg.batch_size,
           "eval_horizon": es.horizon, "seconds_per_meta_iteration": round(float(np.median(ts)), 3),
           "meta_iterations_per_s": round(1.0 / float(np.median(ts)), 4),
           "env_steps_per_meta_iteration": es.env_steps_per_update(), "compile_s": round(compile_s, 1)}
    print(row, flush=True)
    path = os.path.join(args.out, "speed.csv")
    os.makedirs(args.out, exist_ok=True)
    new = not os.path.exists(path)
    with open(path, "a", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(row))
        if new:
            w.writeheader()
        w.writerow(row)


def merge(out, others):
    """Stack the seeds of ``others``' grid.npz onto ``out``'s (kept first as grid_own_seeds.npz)."""
    path = os.path.join(out, "grid.npz")
    own = os.path.join(out, "grid_own_seeds.npz")
    grids = [dict(np.load(own if os.path.exists(own) else path))]
    grids += [dict(np.load(os.path.join(o, "grid.npz"))) for o in others]
    methods = [k for k in grids[0] if k not in ("masses", "frictions")]
    for o, g in zip(others, grids[1:]):
        missing = set(methods) - set(g)
        if missing or g["masses"].shape != MASSES.shape or g["frictions"].shape != FRICTIONS.shape:
            raise ValueError(f"{o}/grid.npz: methods {sorted(missing)} missing or a different test grid")
    if not os.path.exists(own):  # only once the inputs are known good: nothing half-moved on error
        os.replace(path, own)
    merged = {k: np.concatenate([g[k] for g in grids]) for k in methods}
    np.savez(path + ".tmp.npz", **merged, masses=MASSES, frictions=FRICTIONS)
    os.replace(path + ".tmp.npz", path)
    table(out)
    plots(out)


def in_box_mask():
    m = (MASSES[:, None] >= TRAIN_BOX["mass:torso"][0]) & (MASSES[:, None] <= TRAIN_BOX["mass:torso"][1])
    f = (FRICTIONS[None, :] >= TRAIN_BOX["friction"][0]) & (FRICTIONS[None, :] <= TRAIN_BOX["friction"][1])
    return m & f


def table(out):
    d = np.load(os.path.join(out, "grid.npz"))
    inside = in_box_mask()
    rows = []
    for k in ("fixed", "udr_mlp", "udr_lstm", "udr_mlp+adapt", "es_maml_noadapt", "es_maml"):
        if k not in d:
            continue
        g = d[k]  # [S, 12, 8]
        rows.append({"method": k, "in_distribution": float(g[:, inside].mean()),
                     "out_of_distribution": float(g[:, ~inside].mean()), "all": float(g.mean()),
                     "seed_std_all": float(g.mean((1, 2)).std()), "seeds": g.shape[0]})
    with open(os.path.join(out, "table.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    for r in rows:
        print(r)


def plots(out):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    d = np.load(os.path.join(out, "grid.npz"))
    keys = [k for k in ("fixed", "udr_mlp", "udr_lstm", "udr_mlp+adapt", "es_maml") if k in d]
    vmax = max(float(d[k].mean(0).max()) for k in keys)
    fig, axes = plt.subplots(1, len(keys), figsize=(4.2 * len(keys), 4), squeeze=False)
    dm, df = MASSES[1] - MASSES[0], FRICTIONS[1] - FRICTIONS[0]
    for ax, k in zip(axes[0], keys):
        g = d[k].mean(0)
        im = ax.imshow(g.T, origin="lower", aspect="auto", vmin=0, vmax=vmax, cmap="viridis",
                       extent=[MASSES[0] - dm / 2, MASSES[-1] + dm / 2, FRICTIONS[0] - df / 2, FRICTIONS[-1] + df / 2])
        (m0, m1), (f0, f1) = TRAIN_BOX["mass:torso"], TRAIN_BOX["friction"]
        ax.add_patch(Rectangle((m0, f0), m1 - m0, f1 - f0, fill=False, ec="red", lw=2))
        title = k + (" (after 3 PPO updates)" if k in ("es_maml", "udr_mlp+adapt") else "")
        ax.set_title(f"{title}\nmean {g.mean():.0f}", fontsize=9)
        ax.set_xlabel("torso mass [kg]")
        ax.set_ylabel("friction")
    fig.colorbar(im, ax=axes[0].tolist(), shrink=0.8, label="return (1000-step episodes)")
    fig.savefig(os.path.join(out, "heatmaps.png"), dpi=110)
    print(f"plots in {out}")


@dataclasses.dataclass
class Settings:
    """part: what to run; merge_from: (part=merge) results folders of other seeds (same methods) to
    stack onto out; seeds; seed: base seed (seeds are split from it: baselines and ES init); steps:
    env steps per baseline seed; scale: multiplies every budget; meta_iters, chunk, population,
    sigma, meta_lr: ES-MAML's; eval_horizon, episodes, repeats: the evaluation's; tag; resume;
    out: results folder; work: run folders."""
    part: Literal["train", "baselines", "esmaml", "speed", "plots", "merge"] = "train"
    merge_from: tuple[str, ...] = ()
    seeds: int = 3
    seed: int = 0
    steps: float = 20e6
    scale: float = 1.0
    meta_iters: int = 100
    chunk: int = 10
    population: int = 32
    sigma: float = 0.02
    meta_lr: float = 0.002
    eval_horizon: int = 300
    episodes: int = 2
    repeats: int = 3
    tag: str = ""
    resume: bool = False
    out: str = OUT
    work: str = "/tmp/es_maml_hopper_runs"


def main(args: Settings):
    if args.part in ("train", "baselines", "esmaml"):
        part_train(args)
    elif args.part == "speed":
        part_speed(args)
    elif args.part == "merge":
        merge(args.out, args.merge_from)
    else:
        table(args.out)
        plots(args.out)


if __name__ == "__main__":
    main(settings(Settings, sys.argv[1:]))
