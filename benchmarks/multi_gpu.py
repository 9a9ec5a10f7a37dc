"""1 GPU against N GPUs of one host at the same per-GPU work (issue 26): env stepping, PPO on
hopper, a SimOpt REPS update at the paper's 9,600 x 453, and ES-MAML meta-iterations.

    python benchmarks/multi_gpu.py gpus=1,2 tag=h100x2           # on a host with 2 GPUs
    python benchmarks/multi_gpu.py stages=ppo,ppo_total gpus=1,2 ppo_envs=16384 ppo_steps=30e6

Every (stage, GPU count) runs in its own process with ``CUDA_VISIBLE_DEVICES`` set to the first
``n`` GPUs, so the 1-GPU figure is a plain one-GPU program on the same host. Both counts run the
same algorithm: PPO with ``devices=all`` (``ppo.data_parallel=true``; on one GPU a mesh of one),
SimOpt and ES-MAML with their samples / population split over the devices (``parallel.spread``).
Per GPU: ``env_batch`` envs stepping; ``ppo_envs`` PPO envs with ``ppo_minibatches`` minibatches
each (at 16, a minibatch has the same size and an env step buys the same number of gradient steps at
any count); REPS ``9600`` samples and the ES-MAML ``population`` in total (strong scaling: the
paper's sizes). Stage ``ppo_total`` runs, on each count below the largest, the largest count's PPO
configuration (all its envs and minibatches): the same algorithm as that count's ``ppo`` row, so
their returns should agree (data-parallel PPO is the one-device update to float rounding).
A stage that crashes is recorded with its exit code (a segmentation fault is -11), not retried.

Writes ``<out>/<tag>.csv`` (one row per stage and count, the device named) and
``<out>/<tag>_ppo.png`` (training return against env steps, every seed, per count).
"""
from __future__ import annotations

import csv
import dataclasses
import json
import os
import subprocess
import sys
import time

from sim2real.common.cli import settings

HERE = os.path.dirname(os.path.abspath(__file__))


def _sibling(name: str):
    """Another benchmark script of this folder, as a module (the stages reuse their set-ups)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(f"_bench_{name}", os.path.join(HERE, f"{name}.py"))
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # (its dataclasses look their module up there)
    spec.loader.exec_module(mod)
    return mod


@dataclasses.dataclass
class Settings:
    """stages: comma-separated of env, ppo, ppo_total, reps, esmaml; gpus: GPU counts; env_batch,
    env_steps: envs per GPU and scan length of the stepping benchmark; ppo_envs: PPO envs per GPU;
    ppo_minibatches: PPO minibatches per GPU; ppo_minibatches_total: above 0, that many minibatches
    at every count instead (each GPU's share of a minibatch then holds as many samples as on one
    GPU: the same work per GPU, fewer gradient steps per env step); ppo_num_steps: rollout length per
    env and update (with twice the envs and half the rollout, an update has the same samples);
    ppo_chunk: updates per timed chunk; ppo_steps: env steps per seed; ppo_lr: PPO learning rate (0:
    the config's); ppo_set: more PPO settings, comma-separated ``key:value`` (e.g. ``clip_eps:0.3``);
    seeds: PPO seeds (vmapped); seed: their base seed; eval_episodes: final deterministic episodes per
    seed; reps_samples, reps_horizon; population: ES-MAML population
    (total); es_scale: below 1, es_maml_hopper's small inner loop (a CPU check of the script);
    repeats: timed calls; timeout: seconds per stage process; tag; out. stage, n: internal (one
    stage in this process)."""
    stages: str = "env,ppo,ppo_total,reps,esmaml"
    gpus: str = "1,2"
    env_batch: int = 131072
    env_steps: int = 100
    ppo_envs: int = 8192
    ppo_minibatches: int = 16
    ppo_minibatches_total: int = 0
    ppo_num_steps: int = 32
    ppo_lr: float = 0.0
    ppo_set: str = ""
    ppo_chunk: int = 5
    ppo_steps: float = 40e6
    seeds: int = 3
    seed: int = 0
    eval_episodes: int = 64
    reps_samples: int = 9600
    reps_horizon: int = 453
    population: int = 64
    es_scale: float = 1.0
    repeats: int = 3
    timeout: int = 600
    tag: str = "multi_gpu"
    out: str = os.path.join(HERE, "results", "multi_gpu")
    stage: str = ""
    n: int = 0


def _counts(a: Settings) -> list[int]:
    return [int(g) for g in a.gpus.split(",")]


def stage_env(a: Settings) -> dict:
    b = a.env_batch * a.n
    return {"batch": b, "env_steps_per_s": _sibling("throughput").bench_sim2real(b, a.env_steps, split=a.n > 1)}


def stage_ppo(a: Settings, per_gpu: int | None = None) -> dict:
    """PPO on hopper with ``per_gpu`` GPUs' worth of envs and minibatches (default: this process's)."""
    import jax
    import numpy as np

    from sim2real.common import config as config_lib
    from sim2real.rl.episodes import episodes
    from sim2real.training.driver import TrainConfig, train

    k = per_gpu or a.n
    cfg = config_lib.load(TrainConfig, [
        f"config={os.path.join(HERE, '..', 'configs', 'hopper.yaml')}", f"ppo.num_envs={a.ppo_envs * k}",
        f"ppo.num_minibatches={a.ppo_minibatches_total or a.ppo_minibatches * k}",
        f"ppo.num_steps={a.ppo_num_steps}", "devices=all", f"total_steps={int(a.ppo_steps)}",
        f"updates_per_chunk={a.ppo_chunk}", "checkpoint_every=1000", f"num_seeds={a.seeds}", f"seed={a.seed}",
        f"name=gpus{a.n}", "out_dir=/tmp/multi_gpu_runs", "overwrite=true", "progress=false", "tensorboard=false",
        *([f"ppo.lr={a.ppo_lr}"] if a.ppo_lr else []),
        *[f"ppo.{kv.replace(':', '=', 1)}" for kv in a.ppo_set.split(",") if kv]])
    stamps = []
    out = train(cfg, on_chunk=lambda c, m: stamps.append(time.perf_counter()))
    rows = list(csv.DictReader(open(os.path.join(out["run_dir"], "metrics.csv"))))
    per_chunk = cfg.updates_per_chunk * cfg.ppo.batch_size * cfg.num_seeds
    # the first chunk holds the compilation; the last may be partial: time whole chunks after the first
    full = [t1 - t0 for t0, t1 in zip(stamps[:-2], stamps[1:-1])] if len(stamps) > 2 else [stamps[-1] - stamps[0]]
    env, algo = out["env"], out["algo"]
    zs = np.tile(env.default_z(), (a.eval_episodes, 1))
    evaluate = jax.jit(lambda p, s: episodes(env, algo.ppo, p, s, zs, jax.random.PRNGKey(1)))
    finals = []
    for s in range(cfg.num_seeds):
        params, stats = algo.policy(jax.tree_util.tree_map(lambda x: x[s], out["state"]))
        finals.append(float(np.mean(evaluate(params, stats)["return"])))
    curve = [(int(r["seed"]), int(r["env_steps"]), float(r["episode_return"])) for r in rows
             if float(r.get("episodes", 0) or 0) > 0]
    return {"num_envs": cfg.ppo.num_envs, "num_minibatches": cfg.ppo.num_minibatches, "seeds": cfg.num_seeds,
            "clip_eps": cfg.ppo.clip_eps, "num_epochs": cfg.ppo.num_epochs, "lr": cfg.ppo.lr,
            "env_steps_per_s": per_chunk / float(np.median(full)), "chunks_timed": len(full),
            "final_return_per_seed": finals, "final_return_mean": float(np.mean(finals)), "curve": curve}


def stage_reps(a: Settings) -> dict:
    import jax

    reps_update = _sibling("reps_update")
    so, st, real = reps_update.setup(a.reps_samples, a.reps_horizon, 1, spread=True)
    step = jax.jit(so.reps_step)
    compile_s, sec, _ = reps_update.timed(lambda s: step(s, real), st, a.repeats)
    return {"samples": a.reps_samples, "horizon": a.reps_horizon, "seconds_per_update": sec,
            "env_steps_per_s": a.reps_samples * a.reps_horizon / sec, "compile_s": compile_s}


def stage_esmaml(a: Settings) -> dict:
    import jax

    from sim2real.common import config as config_lib
    from sim2real.envs import make
    from sim2real.training.driver import TrainConfig

    esm = _sibling("es_maml_hopper")
    cfg = config_lib.load(TrainConfig, esm.BASE)
    es = esm.make_esmaml(make("hopper"), dataclasses.replace(cfg.ppo, data_parallel=True),
                         esm.Settings(population=a.population, scale=a.es_scale))
    st = jax.jit(es.init)(jax.random.PRNGKey(0))
    compile_s, sec, _ = _sibling("reps_update").timed(jax.jit(es.update), st, a.repeats)
    return {"population": a.population, "seconds_per_meta_iteration": sec, "meta_iterations_per_s": 1.0 / sec,
            "env_steps_per_s": es.env_steps_per_update() / sec, "compile_s": compile_s}


def stage_ppo_total(a: Settings) -> dict:
    return stage_ppo(a, per_gpu=max(_counts(a)))


STAGES = {"env": stage_env, "ppo": stage_ppo, "ppo_total": stage_ppo_total, "reps": stage_reps,
          "esmaml": stage_esmaml}


def run_one(a: Settings) -> None:
    """Child process: one stage on the GPUs this process sees; its result as one JSON line."""
    import jax

    res = STAGES[a.stage](a)
    res.update(stage=a.stage, gpus=len(jax.devices()), device=jax.devices()[0].device_kind, jax=jax.__version__)
    print("RESULT " + json.dumps(res), flush=True)


def main(a: Settings):
    if a.stage:
        return run_one(a)
    os.makedirs(a.out, exist_ok=True)
    rows = []
    for stage in a.stages.split(","):
        if stage not in STAGES:
            raise SystemExit(f"stages: unknown stage {stage!r} (choose from {', '.join(STAGES)})")
        counts = _counts(a)
        for n in counts:
            if stage == "ppo_total" and n == max(counts):
                continue  # that count's own ppo row is this configuration
            env = dict(os.environ, CUDA_VISIBLE_DEVICES=",".join(map(str, range(n))), PYTHONUNBUFFERED="1")
            args = [sys.executable, __file__, *sys.argv[1:], f"stage={stage}", f"n={n}"]
            t0 = time.time()
            try:
                p = subprocess.run(args, env=env, capture_output=True, text=True, timeout=a.timeout)
                rc, text = p.returncode, p.stdout + p.stderr
            except subprocess.TimeoutExpired as e:
                rc, text = "timeout", str(e.stdout or "") + str(e.stderr or "")
            line = next((ln for ln in text.splitlines() if ln.startswith("RESULT ")), None)
            row = json.loads(line[7:]) if line else {"stage": stage, "gpus": n, "error": text[-1500:]}
            row.update(rc=rc, wall_s=round(time.time() - t0, 1))
            rows.append(row)
            print({k: v for k, v in row.items() if k != "curve"}, flush=True)
            write(rows, a)  # after every stage: a call cut short keeps what finished


def write(rows, a: Settings):
    cols = ["stage", "gpus", "device", "rc", "env_steps_per_s", "speedup", "seconds_per_update",
            "seconds_per_meta_iteration", "meta_iterations_per_s", "final_return_mean", "final_return_per_seed",
            "batch", "num_envs", "num_minibatches", "clip_eps", "num_epochs", "lr", "seeds", "samples", "horizon",
            "population", "compile_s", "chunks_timed", "wall_s", "jax", "error"]
    base = {r["stage"]: r.get("env_steps_per_s") for r in rows if r.get("gpus") == 1 and r.get("rc") == 0}
    for r in rows:
        if r.get("env_steps_per_s") and base.get(r["stage"]) and r["stage"] != "ppo_total":
            r["speedup"] = r["env_steps_per_s"] / base[r["stage"]]
    path = os.path.join(a.out, f"{a.tag}.csv")
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=cols, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({c: (f"{r[c]:.4g}" if isinstance(r.get(c), float) else r.get(c, "")) for c in cols})
    print(f"wrote {path}")
    curves = [r for r in rows if r["stage"] in ("ppo", "ppo_total") and r.get("curve")]
    if curves:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 4))
        for r, color in zip(curves, ("C0", "C1", "C2", "C3", "C4")):
            for s in sorted({c[0] for c in r["curve"]}):
                pts = sorted((x, y) for seed, x, y in r["curve"] if seed == s)
                ax.plot(*zip(*pts), color=color, alpha=0.8,
                        label=f"{r['gpus']} GPU{'s' if r['gpus'] > 1 else ''}: {r['num_envs']} envs, "
                              f"{r['num_minibatches']} minibatches" if s == 0 else None,
                        linestyle="--" if r["stage"] == "ppo_total" else "-")
        ax.set_xlabel("env steps per seed")
        ax.set_ylabel("training episode return")
        dashed = any(r["stage"] == "ppo_total" for r in curves)
        ax.set_title("PPO hopper, same envs per GPU" + ("; dashed: one GPU with the largest\ncount's whole batch"
                                                        if dashed else "") + f" ({curves[0].get('device', '')})",
                     fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend()
        fig.tight_layout()
        fig.savefig(os.path.join(a.out, f"{a.tag}_ppo.png"), dpi=120)
        with open(os.path.join(a.out, f"{a.tag}_ppo_curves.json"), "w") as f:
            json.dump({f"{r['stage']}_{r['gpus']}": r["curve"] for r in curves}, f)


if __name__ == "__main__":
    main(settings(Settings, sys.argv[1:]))
