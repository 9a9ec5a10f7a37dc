"""Evaluate a trained policy over a set (or grid) of physics vectors, deterministically.

``evaluate_run(EvaluateConfig(...))`` is what ``scripts/evaluate.py`` runs: a run folder's policy
over a grid of one or two physics parameters, written as ``returns.csv`` and a heat map.
"""
from __future__ import annotations

import dataclasses
import os

import jax
import jax.numpy as jnp
import numpy as np

from sim2real.envs.base import Env
from sim2real.rl.episodes import episodes


def grid(env: Env, axes: dict[str, np.ndarray], base=None) -> tuple[np.ndarray, list[str]]:
    """Physics vectors ``[prod(len), P]`` for the Cartesian grid over named axes (others at ``base``)."""
    names = list(axes)
    mesh = np.meshgrid(*[np.asarray(axes[n], np.float32) for n in names], indexing="ij")
    base = env.default_z() if base is None else np.asarray(base, np.float32)
    zs = np.tile(base, (mesh[0].size, 1))
    for n, m in zip(names, mesh):
        zs[:, env.spec.index(n)] = m.ravel()
    return zs, names


def parse_axis(text: str) -> tuple[str, np.ndarray]:
    """``'mass:pole=0.5:2.0:8'`` -> ``('mass:pole', linspace(0.5, 2.0, 8))``; also ``name=a,b,c``."""
    if "=" not in text:
        raise ValueError(f"grid axis '{text}' must look like name=low:high:count or name=v1,v2,...")
    name, spec = text.rsplit("=", 1)
    try:
        if ":" in spec:
            lo, hi, num = spec.split(":")
            lo, hi, num = float(lo), float(hi), int(num)
            if num < 1:
                raise ValueError(f"grid axis '{text}': the count must be at least 1 (got {num})")
            values = np.linspace(lo, hi, num)
        else:
            values = np.array([float(v) for v in spec.split(",")])
    except ValueError as e:
        if "count must be" in str(e):
            raise
        raise ValueError(f"grid axis '{text}': cannot read '{spec}' as low:high:count or a list") from None
    if not np.all(np.isfinite(values)):
        raise ValueError(f"grid axis '{text}': values must be finite")
    return name, values


@dataclasses.dataclass(frozen=True)
class EvaluateConfig:
    """Evaluation of a run's policy over a physics grid (``scripts/evaluate.py``).

    Attributes:
      run: the run folder (its latest checkpoint, or ``policy.msgpack`` without ``checkpoints/``).
      x: first grid axis, ``name=low:high:count`` or ``name=v1,v2,...`` (a physics parameter).
      y: optional second axis, same form.
      episodes: deterministic episodes per grid cell and seed.
      out: output folder (default ``<run>/eval/<axes>``, e.g. ``eval/mass-pole__gain-motor``: one
        folder per grid; only an evaluation folder is replaced).
      seed: PRNG seed of the episodes' initial states.
      adapt: adapt the policy to each cell first (ES-MAML's adaptation operator: few-shot evaluation);
        the un-adapted returns go to ``returns_before.csv``.
      videos: also a GIF per corner of the grid (one episode of seed 0's policy under that
        corner's physics; ``video_<name>=<value>[__<name>=<value>].gif``); needs headless
        OpenGL (EGL or OSMesa) for MuJoCo's renderer.
      progress: draw a progress bar.
    """

    run: str = ""
    x: str = ""
    y: str = ""
    episodes: int = 4
    out: str = ""
    seed: int = 123
    adapt: bool = False
    videos: bool = False
    progress: bool = True


def evaluate_run(cfg: EvaluateConfig) -> dict:
    """Evaluate every seed of ``cfg.run`` over the grid; writes ``returns.csv`` (+ ``returns_before.csv``
    with ``adapt``; the mean over seeds, their standard deviation and every seed's) and ``returns.png``
    (with the seeds' spread) into ``cfg.out`` (moved into place when complete). Randomised parameters
    that are not on the grid are held at the centre of the run's training box (the others at the
    run's fixed physics); the plot says so.

    Returns ``{'out', 'names', 'z' [N, P], 'returns' (grid-shaped, mean over seeds), 'before'}``.
    Everything is checked (run folder, axes, names, bounds, adapt) before anything is written.
    """
    from sim2real.common import config as config_lib
    from sim2real.common import output
    from sim2real.common.plots import heatmap
    from sim2real.common.progress import Bar
    from sim2real.training.runs import load_policy, load_run

    if not cfg.run or not cfg.x:
        raise config_lib.ConfigError("evaluate needs run=RUN_DIR and x=name=low:high:count")
    run = cfg.run
    if not os.path.isdir(run) or not os.path.exists(os.path.join(run, "config.yaml")):
        raise FileNotFoundError(f"run={run}: not a run folder (no config.yaml)")
    if cfg.episodes < 1:
        raise config_lib.ConfigError(f"episodes={cfg.episodes!r}: must be a positive integer")
    try:
        axes = dict([parse_axis(cfg.x)] + ([parse_axis(cfg.y)] if cfg.y else []))
    except ValueError as e:
        raise config_lib.ConfigError(str(e)) from None
    out = cfg.out or os.path.join(run, "eval", "__".join(n.replace(":", "-") for n in axes))
    inputs = [os.path.join(run, "config.yaml")]
    output.check(out, "evaluation", inputs=inputs, overwrite=True)
    if os.path.isdir(os.path.join(run, "checkpoints")):
        rcfg, env, algo, state = load_run(run)
        all_params, all_stats = algo.policy(state)           # leading seed axis
    else:  # a run folder copied without its checkpoints: the exported policies
        rcfg, env, algo, all_params, all_stats = load_policy(run)
    for n in axes:
        env.spec.index(n)  # an unknown name lists the known ones
    base = np.asarray(algo.space.base, np.float32).copy()
    held = {}  # randomised parameters off the grid: the training box's centre, not the env default
    for n, lo, hi in zip(rcfg.dr.params, rcfg.dr.low, rcfg.dr.high):
        if n not in axes:
            base[env.spec.index(n)] = held[n] = (lo + hi) / 2
    zs, names = grid(env, axes, base=base)
    env.check_z(zs)
    if cfg.adapt and not algo.adapts:
        raise config_lib.ConfigError(f"adapt=true needs an algorithm with an adaptation operator "
                                     f"(es_maml); run '{run}' trained algo '{rcfg.algo}'")
    if cfg.videos:
        from sim2real.common.video import gl_backend

        try:
            gl_backend()
        except RuntimeError as e:
            raise config_lib.ConfigError(f"videos=true: {e}") from None
    key = jax.random.PRNGKey(cfg.seed)
    shape = [len(v) for v in axes.values()]
    n_ep = cfg.episodes

    def cell_adapted(params, stats, z, k):
        # the same U as in meta-training, then the deterministic test episodes
        p2, s2, _ = algo.adapt(params, stats, z, jax.random.fold_in(k, 1))
        return episodes(env, algo.ppo, p2, s2, z[None], k, n_ep)["return"].mean()

    adapted = jax.jit(jax.vmap(cell_adapted, in_axes=(None, None, 0, None)))
    # jitted whole: run eagerly, the env's reset (a Playground task's 200 settling steps) would be
    # dispatched op by op before the scan, minutes where the compiled call takes seconds
    plain = jax.jit(lambda params, stats, z, k: episodes(env, algo.ppo, params, stats, z, k, n_ep)["return"])
    rets, before = [], []
    label = f"{len(zs)} physics x {n_ep} episodes" + (", adapted first" if cfg.adapt else "")
    with Bar(cfg.progress, rcfg.num_seeds * (1 + cfg.adapt), label) as bar:
        for s in range(rcfg.num_seeds):
            params, stats = jax.tree_util.tree_map(lambda x: x[s], (all_params, all_stats))
            before.append(np.asarray(plain(params, stats, jnp.asarray(zs), key)).mean(1))
            bar.step(text=f"seed {s}: evaluated")
            if cfg.adapt:
                rets.append(np.asarray(adapted(params, stats, jnp.asarray(zs), key)))
                bar.step(text=f"seed {s}: adapted and evaluated")
    per_seed = np.asarray(rets if cfg.adapt else before)          # [S, N]
    ret, spread = per_seed.mean(0).reshape(shape), per_seed.std(0).reshape(shape)

    def write(path, seeds):  # seeds [S, N]
        with open(path, "w") as f:
            f.write(",".join(names) + ",return,std," + ",".join(f"seed_{s}" for s in range(len(seeds))) + "\n")
            for i, z in enumerate(zs):
                f.write(",".join(f"{z[env.spec.index(n)]:.6g}" for n in names)
                        + f",{seeds[:, i].mean():.6g},{seeds[:, i].std():.6g},"
                        + ",".join(f"{v:.6g}" for v in seeds[:, i]) + "\n")

    # written aside and moved into place when complete; only an evaluation folder is replaced
    with output.staged(out, "evaluation", inputs=inputs, overwrite=True) as tmp:
        write(os.path.join(tmp, "returns.csv"), per_seed)
        if cfg.adapt:
            write(os.path.join(tmp, "returns_before.csv"), np.asarray(before))
        box = {n: (lo, hi) for n, lo, hi in zip(rcfg.dr.params, rcfg.dr.low, rcfg.dr.high)}
        title = f"{rcfg.name}: mean return" + (" after adaptation" if cfg.adapt else "")
        subtitle = (f"{rcfg.num_seeds} seed(s) x {n_ep} deterministic episode(s) per cell"
                    + ("; held at the training box's centre: " + ", ".join(f"{n}={v:.3g}" for n, v in held.items())
                       if held else "") + "; other physics at the run's fixed values")
        heatmap(axes, ret, os.path.join(tmp, "returns.png"), title=title, box=box, spread=spread, subtitle=subtitle)
        if cfg.videos:
            corner_videos(env, algo, all_params, all_stats, base, axes, tmp, key)
    return {"out": out, "names": names, "z": zs, "returns": ret, "std": spread, "per_seed": per_seed, "held": held,
            "before": np.mean(before, 0).reshape(shape) if cfg.adapt else None}


def corner_videos(env, algo, all_params, all_stats, base, axes: dict[str, np.ndarray], out: str, key) -> list[str]:
    """One GIF per corner of the grid (the first and last value of every axis), seed 0's policy,
    one episode; returns the files written into ``out``."""
    import itertools

    from sim2real.tools.record import policy
    from sim2real.common.video import write_video
    from sim2real.tools.render import policy_frames

    params, stats = jax.tree_util.tree_map(lambda x: x[0], (all_params, all_stats))
    act = policy(env, algo.ppo, params, stats, base)
    files = []
    for corner in itertools.product(*[sorted({float(v[0]), float(v[-1])}) for v in axes.values()]):
        z = np.asarray(base, np.float32).copy()
        for n, v in zip(axes, corner):
            z[env.spec.index(n)] = v
        label = ", ".join(f"{n}={v:.3g}" for n, v in zip(axes, corner))
        video, _ = policy_frames(env, act, z, label, 1, 320, 240, key)
        name = "video_" + "__".join(f"{n.replace(':', '-')}={v:.4g}" for n, v in zip(axes, corner)) + ".gif"
        write_video(os.path.join(out, name), video, 1.0 / env.dt)
        files.append(name)
    return files
