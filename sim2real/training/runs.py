"""A training run's folder, below the algorithms: what the driver (``train.py``) writes and what
evaluation, recording and warm starts read back.

``out_dir/name/`` holds ``config.yaml`` (the resolved :class:`TrainConfig`), ``metrics.csv`` (one
row per update and seed), ``arrays.npz`` (array-valued metrics, ``[seed, update, ...]``), ``tb/``
(TensorBoard), ``checkpoints/`` (orbax, whole algorithm states) and, once finished,
``policy.msgpack``. No algorithm imports this module; it builds algorithms only through
``algos.registry`` (to read a saved run back).
"""
from __future__ import annotations

import csv
import dataclasses
import os
import time
from typing import Any, Literal

import jax
import numpy as np

from sim2real.training import checkpoint
from sim2real.common import output
from sim2real.common import config as config_lib
from sim2real.algos.base import DRConfig
from sim2real.envs import make
from sim2real.rl.ppo import PPOConfig


@dataclasses.dataclass(frozen=True)
class TestConfig:
    """Test physics on which the driver evaluates every seed's deterministic policy while it trains
    (``test.csv``, ``test.npz`` in the run folder): out-of-distribution curves in the same run.

    Attributes:
      every: chunks between evaluations (0: none). The policy is evaluated before the first chunk,
        before every ``every``-th chunk after it, and after the last chunk.
      params: names of the physics parameters the points set (the others at the env's defaults).
      points: one test context per entry, its values in ``params``' order and units.
      episodes: full episodes per context and seed.
      seed: PRNG seed of the episodes' initial states (the same at every evaluation).
      out_of_bounds: a point outside a parameter's physical bounds is refused before the run starts
        (``refuse``) or simulated at the nearest bound (``clip``: a test range that reaches past
        the bounds, as the LSDR paper's does).
      adapt: score each seed's policy after the algorithm's adaptation operator on each test context
        (ES-MAML's few-shot evaluation; refused for algorithms without one). The adaptation's env
        steps are not counted in the run's budget.
    """

    every: int = 0
    params: tuple[str, ...] = ()
    points: tuple[tuple[float, ...], ...] = ()
    episodes: int = 1
    seed: int = 7
    out_of_bounds: Literal["refuse", "clip"] = "refuse"
    adapt: bool = False


@dataclasses.dataclass(frozen=True)
class TrainConfig:
    """One training run.

    Attributes:
      name: run name; the run folder is ``out_dir/name``.
      env: env name (``sim2real.envs.names()``).
      env_options: EnvConfig overrides, e.g. ``{episode_length: 500}``.
      algo: ``udr`` (uniform DR; fixed physics when ``dr.params`` is empty), ``lsdr`` (with
        ``algo_options.epopt`` for EPOpt-PPO), ``fixed_dr`` (LSDR's harness, distribution frozen),
        ``es_maml`` (one update = one meta-iteration; ``ppo`` is its inner loop), ``simopt`` (one
        update = one SimOpt iteration; the real side is ``algo_options.real``: a target env or
        recordings, ``algos/simopt.py``).
      seed: base PRNG seed.
      num_seeds: independent seeds trained in parallel (vmapped).
      total_steps: env steps per seed (ES-MAML: the population's inner loops and scoring episodes;
        SimOpt counts its own iterations, ``algo_options.iterations``).
      updates_per_chunk: PPO iterations per jitted chunk (logging/checkpoint granularity).
      checkpoint_every: chunks between checkpoints (the last chunk is always saved).
      keep_checkpoints: how many checkpoints to keep.
      out_dir: parent folder of run folders.
      resume: continue from the latest checkpoint of ``out_dir/name``.
      overwrite: delete an existing run folder instead of refusing to start.
      max_chunks: stop after this many chunks in this invocation (0: run to the end).
      tensorboard: also write TensorBoard event files.
      logger: ``wandb``: also log to Weights & Biases (the ``wandb`` package, not installed by
        sim2real: ``pip install wandb``), the run's config as its config, the seed means per chunk.
      wandb_mode: ``offline`` (default: files under ``<run>/wandb``, ``wandb sync`` uploads them
        later), ``online`` or ``disabled``.
      wandb_project: the W&B project.
      progress: draw a progress bar.
      devices: ``auto`` (default): on a host with several GPUs, a new run splits its envs, PPO
        update and outer-loop samples over all of them (``ppo.data_parallel=true``, written into
        the run's ``config.yaml``) where the PPO settings allow it (an MLP policy,
        ``ppo.num_steps`` divisible by ``ppo.num_minibatches``, ``ppo.num_envs`` by the GPU
        count); one device otherwise. ``all``: the same on any host (every CPU core as a device
        on a CPU host), refused where the settings do not allow it. ``one``: as
        ``ppo.split_envs`` / ``ppo.data_parallel`` say.
      processes: several processes train one run together (``jax.distributed``; one per host or
        per GPU): how many. Every process runs the same command but for ``process_id``; the envs
        are split over all their devices (``ppo.data_parallel``); process 0 writes the run folder,
        all take part in the checkpoints (one filesystem, shared by the hosts).
      process_id: this process's index, from 0 to ``processes - 1``.
      coordinator: ``host:port`` where process 0 listens (``processes > 1``).
      ppo: PPO settings.
      dr: domain-randomisation box.
      test: physics the policy is evaluated on while it trains (``TestConfig``; off by default).
      algo_options: algorithm-specific settings (see the algorithm's config class).
    """

    name: str = "run"
    env: str = "pendulum"
    env_options: dict[str, Any] = dataclasses.field(default_factory=dict)
    algo: str = "udr"
    seed: int = 0
    num_seeds: int = 1
    total_steps: int = 1_000_000
    updates_per_chunk: int = 10
    checkpoint_every: int = 1
    keep_checkpoints: int = 2
    out_dir: str = "runs"
    resume: bool = False
    overwrite: bool = False
    max_chunks: int = 0
    tensorboard: bool = True
    logger: Literal["none", "wandb"] = "none"
    wandb_mode: Literal["offline", "online", "disabled"] = "offline"
    wandb_project: str = "sim2real"
    progress: bool = True
    devices: Literal["auto", "all", "one"] = "auto"
    processes: int = 1
    process_id: int = 0
    coordinator: str = ""
    ppo: PPOConfig = PPOConfig()
    dr: DRConfig = DRConfig()
    test: TestConfig = TestConfig()
    algo_options: dict[str, Any] = dataclasses.field(default_factory=dict)

    @property
    def num_updates(self) -> int:
        """PPO updates in ``total_steps`` (what the PPO-based algorithms anneal over)."""
        return max(1, self.total_steps // self.ppo.batch_size)


def build_algo(cfg: TrainConfig, env):
    """The configured outer loop, started from its warm start's policy where it names one."""
    from sim2real.algos import registry

    algo = registry.build(cfg.algo, env, cfg)
    if algo.warm_start_from:
        algo.start_from(*_warm_start(algo.warm_start_from, algo, cfg.num_seeds), cfg.num_seeds)
    return algo


def _warm_start(run_dir: str, algo, num_seeds: int):
    """``(params, obs_stats)`` of a finished run, checked against the run it starts."""
    try:
        wcfg, wenv, _, params, stats = load_policy(run_dir)
    except FileNotFoundError as e:
        raise FileNotFoundError(f"algo_options.warm_start: {e}") from e
    env, name = algo.env, type(algo).__name__
    if wenv.name != env.name or wenv.obs_size != env.obs_size:
        raise ValueError(f"warm_start '{run_dir}' trained env '{wenv.name}' (obs {wenv.obs_size}), "
                         f"this {name} runs '{env.name}' (obs {env.obs_size})")
    if wcfg.ppo.net != algo.ppo.cfg.net:
        raise ValueError(f"warm_start '{run_dir}' has network {wcfg.ppo.net}, this {name} has "
                         f"ppo.net = {algo.ppo.cfg.net}; set the same ppo.net")
    n = jax.tree_util.tree_leaves(params)[0].shape[0]
    k = algo.warm_start_seed
    if k >= 0:  # one seed of the run starts them all (a loop fine-tunes the policy it recorded)
        if k >= n:
            raise ValueError(f"algo_options.warm_start_seed={k}: '{run_dir}' holds seeds 0..{n - 1}")
        params, stats = jax.tree_util.tree_map(lambda x: np.asarray(x)[k:k + 1], (params, stats))
        n = 1
    if n not in (1, num_seeds):
        raise ValueError(f"warm_start '{run_dir}' holds {n} seeds; this run has num_seeds={num_seeds} "
                         f"(set num_seeds={n}, or warm-start from a run with one seed)")
    return params, stats


class Run:
    """A run folder: resolved config, metrics.csv, TensorBoard events, checkpoints/."""

    def __init__(self, cfg: TrainConfig):
        self.cfg = cfg
        self.dir = os.path.join(cfg.out_dir, cfg.name)
        self.ckpt_dir = os.path.abspath(os.path.join(self.dir, "checkpoints"))
        self.metrics_path = os.path.join(self.dir, "metrics.csv")

    def check(self) -> None:
        """Refuse a run folder that may not be used (before anything is written)."""
        cfg = self.cfg
        if cfg.resume:
            output.check(self.dir, "run", keep_existing=True, key="name")
            if not os.path.exists(self.ckpt_dir):
                raise FileNotFoundError(f"resume=true but '{self.ckpt_dir}' holds no checkpoint")
        else:
            if os.path.isdir(self.dir) and os.listdir(self.dir) and not cfg.overwrite:
                raise FileExistsError(f"run folder '{self.dir}' exists; pass resume=true to continue it, "
                                      "overwrite=true to replace it, or another name=")
            output.check(self.dir, "run", overwrite=cfg.overwrite, key="name")

    def prepare(self) -> None:
        """Create the run folder (a folder sim2real did not make is never replaced:
        ``sim2real.common.output``) and write the resolved config."""
        self.check()
        if not self.cfg.resume:
            output.create(self.dir, "run", overwrite=self.cfg.overwrite, key="name")
        config_lib.save(self.cfg, os.path.join(self.dir, "config.yaml"))


class MetricsLogger:
    """metrics.csv (one row per update and seed) and TensorBoard scalars (seed means)."""

    def __init__(self, run: Run, cfg: TrainConfig, resume_from_update: int, steps_per_update: int):
        self.cfg, self.path, self.per_update = cfg, run.metrics_path, steps_per_update
        self.arrays_path = os.path.join(run.dir, "arrays.npz")
        self.arrays = {}
        if resume_from_update and os.path.exists(self.arrays_path):
            with np.load(self.arrays_path) as f:
                self.arrays = {k: f[k][:, :resume_from_update] for k in f.files}
        if resume_from_update and os.path.exists(self.path):
            # drop rows logged after the checkpoint we resume from (the interrupted tail)
            with open(self.path) as f:
                rows = list(csv.DictReader(f))
            keep = [r for r in rows if int(r["update"]) < resume_from_update]
            self.header = list(rows[0].keys()) if rows else None
            self._rewrite(keep)
        else:
            self.header = None
            if os.path.exists(self.path):
                os.remove(self.path)
        self.tb = None
        if cfg.tensorboard:
            try:
                from tensorboardX import SummaryWriter

                self.tb = SummaryWriter(os.path.join(run.dir, "tb"))
            except ImportError:  # optional at run time; declared in pyproject
                self.tb = None
        if self.tb is not None:  # the resolved config, readable beside the curves
            import yaml

            from sim2real.common.config import to_dict
            self.tb.add_text("config", "```yaml\n" + yaml.safe_dump(to_dict(cfg), sort_keys=False) + "```",
                             resume_from_update * steps_per_update)
        self.last = {}
        self.wandb = None
        if cfg.logger == "wandb":
            import wandb

            from sim2real.common.config import to_dict
            self.wandb = wandb.init(project=cfg.wandb_project, name=cfg.name, dir=run.dir, mode=cfg.wandb_mode,
                                    config=to_dict(cfg), id=f"{cfg.name}-{os.path.basename(run.dir)}", resume="allow")
        self.t_start = time.time()

    def hparams(self) -> dict:
        """The config's scalar settings, flattened (``ppo.lr``...): TensorBoard's HPARAMS tab."""
        from sim2real.common.config import to_dict

        flat = {}

        def walk(d, prefix=""):
            for k, v in d.items():
                if isinstance(v, dict):
                    walk(v, f"{prefix}{k}.")
                elif isinstance(v, (bool, int, float, str)):
                    flat[prefix + k] = v
                else:  # a tuple (a box, hidden sizes): as text
                    flat[prefix + k] = str(v)
        walk(to_dict(self.cfg))
        return flat

    def _rewrite(self, rows):
        with open(self.path, "w", newline="") as f:
            if self.header:
                w = csv.DictWriter(f, fieldnames=self.header)
                w.writeheader()
                w.writerows(rows)

    def write(self, chunk_index: int, metrics: dict, seconds: float):
        cfg = self.cfg
        arrays = {k: v for k, v in metrics.items() if np.ndim(v) > 2}
        metrics = {k: v for k, v in metrics.items() if np.ndim(v) <= 2}
        if arrays:
            self._write_arrays(arrays)
        names = sorted(metrics)
        k = cfg.updates_per_chunk
        header = ["update", "seed", "env_steps", "wall_seconds"] + names
        new_file = not os.path.exists(self.path) or os.path.getsize(self.path) == 0
        with open(self.path, "a", newline="") as f:
            w = csv.writer(f)
            if new_file:
                w.writerow(header)
            for j in range(k):
                u = chunk_index * k + j
                for s in range(cfg.num_seeds):
                    w.writerow([u, s, (u + 1) * self.per_update, f"{time.time() - self.t_start:.2f}"]
                               + [f"{float(metrics[n][s, j]):.6g}" for n in names])
        if self.tb is not None:
            u = (chunk_index + 1) * k
            for n in names:
                last = metrics[n][:, -1]
                if np.isfinite(last).any():  # (no episode ended: no point, not a 0)
                    self.tb.add_scalar(n, float(np.nanmean(last)), u * self.per_update)
                    self.last[n] = float(np.nanmean(last))
            self.tb.add_scalar("steps_per_second", k * self.per_update * cfg.num_seeds / seconds,
                               u * self.per_update)
        if self.wandb is not None:
            last = {n: float(np.nanmean(metrics[n][:, -1])) for n in names if np.isfinite(metrics[n][:, -1]).any()}
            self.wandb.log({**last, "steps_per_second": k * self.per_update * cfg.num_seeds / seconds},
                           step=(chunk_index + 1) * k * self.per_update)

    def _write_arrays(self, arrays: dict):
        """Array-valued metrics (e.g. LSDR's distribution) -> ``arrays.npz``, ``[seed, update, ...]``."""
        for k, v in arrays.items():
            self.arrays[k] = np.concatenate([self.arrays[k], v], axis=1) if k in self.arrays else v
        tmp = self.arrays_path + ".tmp.npz"
        np.savez_compressed(tmp, **self.arrays)
        os.replace(tmp, self.arrays_path)

    def close(self):
        if self.wandb is not None:
            self.wandb.finish()
        if self.tb is not None:
            # the settings against the last logged metrics (seed means), one row per run
            metrics = {f"hparam/{k}": v for k, v in self.last.items() if k in ("episode_return", "fitness_mean")}
            if metrics:
                self.tb.add_hparams(self.hparams(), metrics, name="hparams")
            self.tb.close()


def test_physics(test: TestConfig, env) -> np.ndarray:
    """The test contexts ``[N, P]`` of ``test`` (checked: names, lengths, bounds, before any write)."""
    from sim2real.common.config import ConfigError

    if test.every < 0 or test.episodes < 1:
        raise ConfigError(f"test.every={test.every}, test.episodes={test.episodes}: every >= 0 (0: no "
                          "test), episodes >= 1")
    if not test.points:
        raise ConfigError("test.every > 0 needs test.params and test.points (one list of values per context)")
    idx = env.spec.indices(list(test.params))  # an unknown name lists the known ones
    zs = np.tile(env.default_z(), (len(test.points), 1))
    for k, point in enumerate(test.points):
        if len(point) != len(test.params):
            raise ConfigError(f"test.points[{k}] has {len(point)} values for {len(test.params)} test.params "
                              f"({', '.join(test.params)})")
        zs[k, idx] = point
    if test.out_of_bounds == "clip":
        return np.clip(zs, env.spec.low, env.spec.high).astype(np.float32)
    env.spec.validate(zs, where="test.points (test.out_of_bounds=clip simulates the nearest bound)")
    return zs.astype(np.float32)


class TestLog:
    """``test.csv`` (one row per evaluation and seed: mean return over the test contexts) and
    ``test.npz`` (``returns [E, S, N]``, ``chunk [E]`` = chunks done when evaluated, ``env_steps [E]``
    per seed, ``z [N, P]``, ``params``, ``points [N, D]``). A resumed run drops what was logged at or
    after the checkpoint it resumes from (the interrupted tail), like ``MetricsLogger``."""

    def __init__(self, run: Run, cfg: TrainConfig, zs: np.ndarray, resume_from_chunk: int):
        self.cfg, self.zs = cfg, zs
        self.csv_path = os.path.join(run.dir, "test.csv")
        self.npz_path = os.path.join(run.dir, "test.npz")
        self.returns, self.chunks, self.steps = [], [], []
        if resume_from_chunk and os.path.exists(self.npz_path):
            with np.load(self.npz_path) as f:
                keep = f["chunk"] < resume_from_chunk
                self.returns, self.chunks, self.steps = list(f["returns"][keep]), list(f["chunk"][keep]), list(f["env_steps"][keep])
        self._save()

    def write(self, chunks_done: int, env_steps: int, returns: np.ndarray) -> None:
        """``returns [S, N]``: every seed's mean episode return on every test context."""
        self.returns.append(np.asarray(returns, np.float32))
        self.chunks.append(chunks_done)
        self.steps.append(env_steps)
        self._save()

    def _save(self) -> None:
        t = self.cfg.test
        S, N = self.cfg.num_seeds, len(self.zs)
        returns = np.stack(self.returns) if self.returns else np.zeros((0, S, N), np.float32)
        tmp = self.npz_path + ".tmp.npz"
        np.savez(tmp, returns=returns, chunk=np.asarray(self.chunks, np.int64),
                 env_steps=np.asarray(self.steps, np.int64), z=self.zs, params=np.asarray(t.params),
                 points=np.asarray(t.points, np.float64).reshape(N, len(t.params)))
        os.replace(tmp, self.npz_path)
        with open(self.csv_path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["chunk", "env_steps", "seed", "test_return"])
            for r, c, n in zip(self.returns, self.chunks, self.steps):
                for s in range(S):
                    w.writerow([int(c), int(n), s, f"{float(np.mean(r[s])):.6g}"])


class Progress:
    """rich progress bar: env steps, steps/s, latest episode return."""

    def __init__(self, cfg: TrainConfig, total: int, done: int):
        self.enabled = cfg.progress
        if not self.enabled:
            return
        from rich.progress import BarColumn, MofNCompleteColumn, Progress as RP, TextColumn, TimeRemainingColumn

        self.p = RP(TextColumn(f"[bold]{cfg.name}[/] {cfg.env}/{cfg.algo}"), BarColumn(), MofNCompleteColumn(),
                    TextColumn("{task.fields[info]}"), TimeRemainingColumn())
        self.p.start()
        self.task = self.p.add_task("train", total=total, completed=done, info="compiling...")
        self.last_return = None

    def advance(self, sps: float, steps: int, metrics: dict):
        if not self.enabled:
            return
        ret = metrics.get("episode_return")
        eps = metrics.get("episodes")
        info = f"{sps:,.0f} steps/s"
        if ret is not None and eps is not None and np.sum(eps) > 0:
            self.last_return = episode_mean(ret, eps)
        if self.last_return is not None:  # the last known return (no episode may end in a chunk)
            info += f"  return {self.last_return:,.1f}"
        elif "fitness_mean" in metrics:  # ES-MAML: return after adaptation, population mean
            info += f"  fitness {np.mean(metrics['fitness_mean'][:, -1]):,.1f}"
        elif np.isfinite(metrics.get("eval_return", np.nan)).any():  # SimOpt: return on the target
            info += f"  target return {np.nanmean(metrics['eval_return'][:, -1]):,.1f}"
        self.p.update(self.task, advance=steps, info=info)

    def close(self):
        if self.enabled:
            self.p.stop()


def export_policy(algo, state, path: str, write: bool = True) -> None:
    """Write the policies of all seeds (params + observation statistics) as one msgpack file.

    Small (no env state), so it travels where checkpoints are too big: evaluate it with
    ``load_policy`` on another machine, e.g. in native MuJoCo. Of several processes
    (``jax.distributed``) every one calls this (the policy is gathered from all of them) and the
    one with ``write`` writes.
    """
    from flax import serialization

    from sim2real.rl.data_parallel import host_value

    params, stats = jax.tree_util.tree_map(host_value, algo.policy(state))
    if not write:
        return
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(serialization.to_bytes({"params": params, "obs_stats": stats}))
    os.replace(tmp, path)


def _without_warm_start(cfg: TrainConfig) -> TrainConfig:
    """A saved run's config for loading it: its trained state replaces any warm start, so the
    warm start's source need not exist any more (nor what was set about it: ``warm_std``)."""
    if "warm_start" not in cfg.algo_options:
        return cfg
    return dataclasses.replace(cfg, algo_options={k: v for k, v in cfg.algo_options.items()
                                                  if k not in ("warm_start", "warm_std")})


def _rebuild(run_dir: str):
    """``(cfg, env, algo)`` of a saved run, from its ``config.yaml`` (without its warm start)."""
    path = os.path.join(run_dir, "config.yaml")
    if not os.path.exists(path):
        raise FileNotFoundError(f"'{run_dir}' is not a run folder: it has no config.yaml")
    cfg = config_lib.load(TrainConfig, [f"config={path}"])
    env = make(cfg.env, **cfg.env_options)
    return cfg, env, build_algo(_without_warm_start(cfg), env)


def load_policy(run_dir: str):
    """``(cfg, env, algo, params, obs_stats)`` from a run folder's ``policy.msgpack`` (leading seed axis)."""
    from flax import serialization

    path = os.path.join(run_dir, "policy.msgpack")
    if not os.path.exists(path):
        raise FileNotFoundError(f"no policy.msgpack in '{run_dir}' (was the run finished?)")
    cfg, env, algo = _rebuild(run_dir)
    template = jax.eval_shape(jax.vmap(algo.init), jax.random.split(jax.random.PRNGKey(0), cfg.num_seeds))
    params, stats = jax.eval_shape(algo.policy, template)
    zeros = jax.tree_util.tree_map(lambda x: np.zeros(x.shape, x.dtype), {"params": params, "obs_stats": stats})
    with open(path, "rb") as f:
        d = serialization.from_bytes(zeros, f.read())
    return cfg, env, algo, d["params"], d["obs_stats"]


def load_run(run_dir: str, step: int | None = None):
    """Config, env, algorithm and restored state of a run folder (for evaluation)."""
    cfg, env, algo = _rebuild(run_dir)
    template = jax.jit(jax.vmap(algo.init))(jax.random.split(jax.random.PRNGKey(cfg.seed), cfg.num_seeds))
    ckpt = os.path.join(run_dir, "checkpoints")
    if not os.path.isdir(ckpt):
        raise FileNotFoundError(f"no checkpoint in '{ckpt}'")
    mngr = checkpoint.manager(ckpt, cfg.keep_checkpoints)
    step = mngr.latest_step() if step is None else step
    if step is None:
        raise FileNotFoundError(f"no checkpoint in '{ckpt}'")
    return cfg, env, algo, checkpoint.restore(mngr, step, template)


def episode_mean(values, eps) -> float:
    """Mean of a per-update episode statistic weighted by the episodes that ended in each update
    (``values``, ``eps``: same shape; ``values`` is NaN where none ended, and weighs nothing there)."""
    values, eps = np.asarray(values), np.asarray(eps)
    return float(np.sum(np.where(eps > 0, values * eps, 0.0)) / np.sum(eps))


def summary(metrics: dict) -> dict:
    """Means over seeds and updates; episode statistics weighted by the episodes that ended."""
    out = {k: float(np.nanmean(np.asarray(v))) if np.isfinite(np.asarray(v)).any() else float("nan")
           for k, v in metrics.items()}
    eps = np.asarray(metrics.get("episodes", 0))
    for k in ("episode_return", "episode_length"):
        if k in metrics:
            if np.sum(eps) > 0:
                out[k] = episode_mean(metrics[k], eps)
            else:  # no episode ended in these updates: there is no episode statistic to report
                del out[k]
    return out


