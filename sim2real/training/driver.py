"""Training driver: chunks of ``jit(vmap_seeds(scan(update)))`` with logging and checkpoints between.

The one driver of every outer loop (``algos/base.py: OuterLoop``; UDR, LSDR, ES-MAML, SimOpt).
The Python loop only logs (CSV, TensorBoard, a progress bar), checkpoints (orbax) and resumes
(the run folder: ``runs.py``);
everything inside a chunk is pure and jitted, so an interrupted run resumed from its checkpoint
ends with the same parameters as an uninterrupted one (``tests/test_train.py``).
"""
from __future__ import annotations

import dataclasses
import os
import time
import warnings

import jax
import jax.numpy as jnp
import numpy as np

from sim2real._precision import in_float32
from sim2real.rl import data_parallel
from sim2real.rl.data_parallel import host_value
from sim2real.training import checkpoint
from sim2real.envs import parallel
from sim2real.common import config as config_lib
from sim2real.envs import make
# TrainConfig and build_algo live with the run folder (``runs.py``, below the algorithms) and are
# re-exported here: ``train(cfg)`` takes the one and calls the other
from sim2real.training.runs import (MetricsLogger, Progress, Run, TestLog, TrainConfig, _without_warm_start, build_algo,
                                    export_policy, test_physics)


def steps_per_update(cfg: TrainConfig, algo) -> int:
    """Env steps per seed in one ``algo.update`` (``OuterLoop.env_steps_per_update``)."""
    return int(algo.env_steps_per_update())


def num_chunks(cfg: TrainConfig, algo, done: int = 0) -> int:
    """Chunks of ``updates_per_chunk`` updates that cover the run (``OuterLoop.total_updates``:
    ``total_steps`` worth, at least one; ``done``: updates before this call)."""
    updates = algo.total_updates(cfg.total_steps, done)
    return -(-updates // cfg.updates_per_chunk)


def make_chunk(algo, updates: int):
    """``jit(chunk)(state [S, ...], first_update) -> (state, metrics [S, K, ...])``.

    The scan over updates is outside the vmap over seeds so that the update index stays an
    unbatched scalar: algorithms that do something only every n-th update (LSDR's distribution
    step) branch on it with a real ``lax.cond`` (under vmap a batched predicate turns ``cond``
    into a ``select`` that runs both branches at every update).
    """
    takes_index = algo.takes_update_index

    def body(c, i):
        return jax.vmap(lambda s: algo.update(s, i) if takes_index else algo.update(s))(c)

    def chunk(state, first):
        state, metrics = jax.lax.scan(body, state, first + jnp.arange(updates))
        return strong_types(state), jax.tree_util.tree_map(lambda x: jnp.swapaxes(x, 0, 1), metrics)

    return jax.jit(chunk)


def make_tester(cfg: TrainConfig, env, algo):
    """``jit(test)(state [S, ...]) -> returns [S, N]``: every seed's deterministic policy on the
    test contexts ``zs [N, P]`` (``TestConfig``), mean over ``test.episodes`` full episodes; with
    ``zs``. ``(None, None)`` when ``test.every`` is 0."""
    if not cfg.test.every:
        return None, None
    from sim2real.rl.episodes import episodes

    if cfg.test.adapt and not algo.adapts:
        raise config_lib.ConfigError(f"test.adapt=true needs an algorithm with an adaptation operator "
                                     f"(es_maml), not algo={cfg.algo}")
    zs = test_physics(cfg.test, env)
    key = jax.random.PRNGKey(cfg.test.seed)

    def score(params, stats, z):  # [N, P] -> [N]
        return episodes(env, algo.ppo, params, stats, z, key, cfg.test.episodes)["return"].mean(-1)

    def one(state):
        params, stats = algo.policy(state)
        if not cfg.test.adapt:
            return score(params, stats, jnp.asarray(zs))

        def cell(z, k):  # the same adaptation keys at every evaluation, like the episodes'
            p2, s2, _ = algo.adapt(params, stats, z, k)
            return score(p2, s2, z[None])[0]
        return jax.vmap(cell)(jnp.asarray(zs), jax.random.split(jax.random.fold_in(key, 1), len(zs)))

    return jax.jit(jax.vmap(one)), zs


def strong_types(tree):
    """The same arrays without weak types. The state goes in and out of the jitted chunk; a weakly
    typed leaf (evosax makes some) changes its input signature and compiles the chunk again."""
    return jax.tree_util.tree_map(lambda x: jax.lax.convert_element_type(x, jnp.asarray(x).dtype), tree)


def _use_cpu_cores():
    """One CPU device per core for ``ppo.split_envs``; only possible before JAX has started."""
    try:
        parallel.use_cpu_cores()
    except RuntimeError:
        warnings.warn(f"ppo.split_envs: JAX already runs with {len(jax.devices('cpu'))} CPU device(s) "
                      f"(the count is fixed when JAX starts); rollouts are split over those", stacklevel=3)


# Keys that may differ between a run's saved config and the one it is resumed with: they change
# how long it runs and what it reports, not what it computes.
RESUMABLE_KEYS = ("total_steps", "max_chunks", "checkpoint_every", "keep_checkpoints", "tensorboard", "progress",
                  "resume", "overwrite", "logger", "wandb_mode", "wandb_project", "processes", "process_id",
                  "coordinator")


class _Silent:
    """What a process other than 0 has instead of the run folder's writers."""

    def __getattr__(self, name):
        return lambda *a, **k: None


def _join_processes(cfg: TrainConfig) -> None:
    """``jax.distributed`` for ``processes > 1``: every process, before JAX computes anything."""
    # CPU devices of several processes talk through gloo (GPUs through NCCL; this changes nothing there)
    jax.config.update("jax_cpu_collectives_implementation", "gloo")
    jax.distributed.initialize(coordinator_address=cfg.coordinator, num_processes=cfg.processes,
                               process_id=cfg.process_id)


def resolve_devices(cfg: TrainConfig) -> TrainConfig:
    """``devices=all|auto`` -> ``ppo.data_parallel`` (``TrainConfig.devices``). ``auto`` looks at
    the devices JAX sees only when no split was asked for, so a CPU host can still be given one
    device per core first."""
    if cfg.processes > 1:  # the split over processes is data-parallel PPO's
        if cfg.ppo.split_envs:
            raise config_lib.ConfigError(f"processes={cfg.processes}: needs ppo.data_parallel (the envs split over "
                                         "every process's devices), not ppo.split_envs (one host's rollouts)")
        cfg = dataclasses.replace(cfg, devices="all")
    if cfg.devices == "one" or cfg.ppo.spreads:
        return cfg
    on = dataclasses.replace(cfg, ppo=dataclasses.replace(cfg.ppo, data_parallel=True))
    if cfg.devices == "auto":
        devs = jax.devices()
        if len(devs) < 2 or devs[0].platform != "gpu":
            return cfg
    try:
        data_parallel.check(on.ppo)
    except ValueError as e:
        if cfg.devices == "all":
            raise config_lib.ConfigError(f"devices=all: {e}") from None
        warnings.warn(f"devices=auto: {len(devs)} GPUs, but training on one ({e})")
        return cfg
    if cfg.devices == "auto" and cfg.ppo.num_envs % len(devs):
        warnings.warn(f"devices=auto: ppo.num_envs={cfg.ppo.num_envs} is not divisible by the {len(devs)} GPUs; "
                      f"splitting over those that divide it")
    return on


def validate(cfg: TrainConfig) -> None:
    """Refuse a config that cannot run, naming the key: before any folder is made or anything compiled."""
    if not cfg.name or os.sep in cfg.name or cfg.name in (".", ".."):
        raise config_lib.ConfigError(f"name={cfg.name!r}: a run name, without '{os.sep}' (the folder is out_dir/name)")
    for key in ("num_seeds", "total_steps", "updates_per_chunk", "checkpoint_every", "keep_checkpoints"):
        if getattr(cfg, key) < 1:
            raise config_lib.ConfigError(f"{key}={getattr(cfg, key)}: must be a positive integer")
    if cfg.max_chunks < 0:
        raise config_lib.ConfigError(f"max_chunks={cfg.max_chunks}: must be >= 0 (0: run to the end)")
    if cfg.logger == "wandb":
        try:
            import wandb  # noqa: F401
        except ImportError:
            raise config_lib.ConfigError("logger=wandb needs the wandb package (pip install wandb); "
                                         "sim2real does not install it") from None
    if cfg.processes < 1 or not 0 <= cfg.process_id < cfg.processes:
        raise config_lib.ConfigError(f"processes={cfg.processes}, process_id={cfg.process_id}: need processes >= 1 "
                                     "and 0 <= process_id < processes")
    if cfg.processes > 1 and not cfg.coordinator:
        raise config_lib.ConfigError(f"processes={cfg.processes}: coordinator=host:port of process 0 is needed")
    if cfg.resume and cfg.overwrite:
        raise config_lib.ConfigError("resume=true and overwrite=true contradict each other; choose one")
    from sim2real.rl.ppo import check

    check(cfg.ppo)


def _saved_config(out_dir, name) -> str:
    """Path of the ``config.yaml`` of run ``out_dir/name``, which a resume needs."""
    path = os.path.join(str(out_dir), str(name), "config.yaml")
    if not os.path.exists(path):
        raise FileNotFoundError(f"resume=true but '{path}' does not exist (no run named '{name}' in '{out_dir}')")
    return path


def config_from_args(argv: list[str]) -> TrainConfig:
    """The command line's config. With ``resume=true`` the run's saved ``config.yaml`` is the config:
    ``name``/``out_dir`` (given, or read from ``config=``) find it, and other ``key=value``s may only
    change ``RESUMABLE_KEYS`` and the algorithm's resumable options (anything else is refused, listed)."""
    path, overrides = config_lib.parse_args(argv)
    if overrides.get("resume") is not True:
        return config_lib.load(TrainConfig, argv)
    if overrides.get("overwrite") is True:  # (before looking for the run: the clearer message)
        raise config_lib.ConfigError("resume=true and overwrite=true contradict each other; choose one")
    start = config_lib.load(TrainConfig, ([f"config={path}"] if path else []))
    saved = _saved_config(overrides.get("out_dir", start.out_dir), overrides.get("name", start.name))
    options = _resumable_options(config_lib.load(TrainConfig, [f"config={saved}"]).algo)
    allowed = RESUMABLE_KEYS + tuple(f"algo_options.{k}" for k in options)
    bad = sorted(k for k in overrides if k not in allowed + ("name", "out_dir"))
    if bad:
        raise config_lib.ConfigError(f"resume=true continues the run with its saved config ({saved}); only "
                                     f"{', '.join(allowed)} may change, not {', '.join(bad)}")
    # (a run created with overwrite=true is continued, not replaced: the saved flag does not carry over)
    overrides = {"overwrite": False, **overrides}
    return config_lib.load(TrainConfig, [f"config={saved}"] + [f"{k}={v if not isinstance(v, bool) else str(v).lower()}"
                                                              for k, v in overrides.items()])


def resume_config(cfg: TrainConfig) -> TrainConfig:
    """The config a run is resumed with: its saved ``config.yaml``, with only ``RESUMABLE_KEYS`` taken
    from ``cfg``; any other difference is refused with the list of differences."""
    saved = config_lib.load(TrainConfig, [f"config={_saved_config(cfg.out_dir, cfg.name)}"])
    options = _resumable_options(saved.algo)
    mine, theirs = config_lib.to_dict(cfg), config_lib.to_dict(saved)
    for d in (mine, theirs):  # (the resumable options are compared by neither)
        d["algo_options"] = {k: v for k, v in d["algo_options"].items() if k not in options}
    diffs = [f"{k}: run has {theirs[k]!r}, given {mine[k]!r}" for k in mine
             if k not in RESUMABLE_KEYS and mine[k] != theirs[k]]
    if diffs:
        raise config_lib.ConfigError("resume=true continues the run as it was configured; these settings differ "
                                     "from its saved config.yaml (give them as saved, or start a new run "
                                     "with another name=):\n  " + "\n  ".join(diffs))
    opts = {**saved.algo_options, **{k: cfg.algo_options[k] for k in options if k in cfg.algo_options}}
    return dataclasses.replace(saved, algo_options=opts, **{k: getattr(cfg, k) for k in RESUMABLE_KEYS})


def _resumable_options(algo: str) -> tuple[str, ...]:
    """``algo_options`` keys that ``resume=true`` may change for ``algo`` (``algos.registry``)."""
    from sim2real.algos import registry

    return registry.resumable_options(algo)


@in_float32
def train(cfg: TrainConfig, on_chunk=None) -> dict:
    """Run (or resume) training; returns ``{'state', 'metrics', 'run_dir', 'algo', 'env', 'finished'}``.

    ``on_chunk(chunk_index, metrics)``, if given, is called after every chunk with its metrics
    (numpy ``[S, K, ...]``, as ``metrics.csv`` and ``arrays.npz`` get them) for a caller that keeps
    its own records (a benchmark).

    Nothing is written until the config is validated and the algorithm built; a resume that fails
    or is refused changes nothing on disk. SIGINT / SIGTERM stop after the chunk under way, with a
    checkpoint (``sim2real.common.cli.Stopped``)."""
    from sim2real.common.cli import Stopped, stop_on_signal

    validate(cfg)
    if cfg.processes > 1:  # before JAX computes anything
        _join_processes(cfg)
    if cfg.resume:
        cfg = resume_config(cfg)
    else:  # (a resumed run keeps the split its config.yaml holds)
        cfg = resolve_devices(cfg)
    if cfg.ppo.spreads and cfg.processes == 1:  # (on a GPU host the CPU device count changes nothing)
        _use_cpu_cores()
    primary = jax.process_index() == 0  # the one process that writes the run folder
    env = make(cfg.env, **cfg.env_options)
    if not cfg.resume:  # (a resumed run's config.yaml holds the resolved box already)
        from sim2real.algos import from_diagnosis

        cfg = dataclasses.replace(cfg, dr=from_diagnosis.resolve(cfg.dr, env))
    algo = build_algo(_without_warm_start(cfg) if cfg.resume else cfg, env)  # resume: the checkpoint is the start
    run = Run(cfg)
    if primary:
        run.check()
    seeds = jax.random.split(jax.random.PRNGKey(cfg.seed), cfg.num_seeds)
    # created under jit, so the state's arrays have exactly the layout chunk outputs have
    # (an eagerly built state costs a second compilation of the chunk on CPU)
    init = jax.jit(lambda k: strong_types(algo.init_seeds(k)))  # (init_seeds: warm starts)
    chunk = make_chunk(algo, cfg.updates_per_chunk)
    per_update = steps_per_update(cfg, algo)
    tester, test_zs = make_tester(cfg, env, algo)
    start = 0
    if cfg.resume:
        mngr = checkpoint.manager(run.ckpt_dir, cfg.keep_checkpoints, create=False)
        step = mngr.latest_step()
        if step is None:
            raise FileNotFoundError(f"resume=true but '{run.ckpt_dir}' holds no checkpoint")
        try:
            state = checkpoint.restore(mngr, step, init(seeds))
        except (ValueError, KeyError) as e:
            raise ValueError(f"resume=true: the checkpoint in '{run.ckpt_dir}' does not fit this run's state "
                             f"({str(e).splitlines()[0][:200]})") from None
        start = step
        n_chunks = num_chunks(cfg, algo, done=start * cfg.updates_per_chunk)
        if start >= n_chunks:
            mngr.close()
            return {"state": state, "metrics": None, "run_dir": run.dir, "algo": algo, "env": env, "finished": True}
    else:
        state = init(seeds)
        n_chunks = num_chunks(cfg, algo)
    if primary:
        run.prepare()  # the first write: config validated, algorithm built, checkpoint read
    if cfg.processes > 1:  # the others wait for the folder (an overwrite deletes it first)
        from jax.experimental import multihost_utils

        multihost_utils.sync_global_devices("sim2real: run folder ready")
    mngr = checkpoint.manager(run.ckpt_dir, cfg.keep_checkpoints)
    logger = (MetricsLogger(run, cfg, resume_from_update=start * cfg.updates_per_chunk, steps_per_update=per_update)
              if primary else _Silent())
    tests = (TestLog(run, cfg, test_zs, start) if primary else _Silent()) if tester else None

    def test(chunks_done):
        tests.write(chunks_done, chunks_done * cfg.updates_per_chunk * per_update, host_value(tester(state)))

    end = n_chunks if not cfg.max_chunks else min(n_chunks, start + cfg.max_chunks)
    bar = Progress(dataclasses.replace(cfg, progress=cfg.progress and primary),
                   total=n_chunks * cfg.updates_per_chunk * per_update, done=start * cfg.updates_per_chunk * per_update)
    last = None
    try:
        with stop_on_signal() as stop:
            for c in range(start, end):
                if tester and c % cfg.test.every == 0:
                    test(c)
                t0 = time.perf_counter()
                state, metrics = chunk(state, c * cfg.updates_per_chunk)
                metrics = jax.tree_util.tree_map(host_value, metrics)  # [S, K] per metric
                dt = time.perf_counter() - t0
                logger.write(c, metrics, dt)
                if on_chunk is not None:
                    on_chunk(c, metrics)
                last = metrics
                done_chunks = c + 1
                if tester and done_chunks == n_chunks:  # (before the checkpoint: a resume redoes it)
                    test(done_chunks)
                if done_chunks % cfg.checkpoint_every == 0 or done_chunks == end or stop.requested:
                    checkpoint.save(mngr, done_chunks, state)
                bar.advance(cfg.updates_per_chunk * per_update * cfg.num_seeds / dt,
                            cfg.updates_per_chunk * per_update, metrics)
                if stop.requested:
                    raise Stopped(f"{stop.signal_name} after chunk {done_chunks} of {n_chunks}; checkpoint saved in "
                                  f"'{run.ckpt_dir}'; continue with name={cfg.name} resume=true")
    finally:
        mngr.wait_until_finished()
        bar.close()
        logger.close()
    export_policy(algo, state, os.path.join(run.dir, "policy.msgpack"), write=primary)
    return {"state": state, "metrics": last, "run_dir": run.dir, "algo": algo, "env": env, "finished": end == n_chunks}
