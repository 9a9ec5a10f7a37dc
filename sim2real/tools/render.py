"""Videos of a trained policy under several physics, side by side.

``render_run(RenderConfig(...))`` is what ``sim2real-render`` runs: the run's policy is rolled in
its own env (MJX) under each physics vector, and the rollouts are drawn with MuJoCo's offscreen
``Renderer`` into one video, one panel per physics, labelled. By default the panels are the run's
nominal physics and the lowest and highest corners of its randomisation box. The drawing itself
(and the choice of a headless OpenGL) is ``common.video``'s.
"""
from __future__ import annotations

import dataclasses
import os

import numpy as np

from sim2real.common.video import frames, gl_backend, write_video


@dataclasses.dataclass(frozen=True)
class RenderConfig:
    """What ``sim2real-render`` draws and where it writes.

    Attributes:
      run: the trained run folder.
      physics: panels, each ``name=value,...`` (the run's env with those physics values) or
        ``nominal`` / ``low`` / ``high`` (the run's physics; the corners of its DR box).
      episodes: episodes per panel, played one after another.
      steps: control steps per episode (0: the env's episode length).
      width, height: pixels of one panel.
      out: the video file, ``.gif`` (Pillow) or ``.mp4`` (needs imageio-ffmpeg).
      fps: frames per second (0: real time, one frame per control step).
      seed: initial states; run_seed: which of the run's seeds acts.
      overwrite: replace an existing file of that name.
    """

    run: str = ""
    physics: tuple[str, ...] = ("nominal", "low", "high")
    episodes: int = 1
    steps: int = 0
    width: int = 320
    height: int = 240
    out: str = "video.gif"
    fps: float = 0.0
    seed: int = 0
    run_seed: int = 0
    overwrite: bool = False


def panels(cfg: RenderConfig, env, rcfg, base) -> list[tuple[str, np.ndarray]]:
    """``(label, z [P])`` per panel."""
    from sim2real.common.config import ConfigError

    box = dict(zip(rcfg.dr.params, zip(rcfg.dr.low, rcfg.dr.high)))
    out = []
    for spec in cfg.physics:
        z = np.asarray(base, np.float32).copy()
        if spec in ("low", "high"):
            if not box:
                raise ConfigError(f"physics: '{spec}' is a corner of the run's DR box, and run '{cfg.run}' has none")
            for n, (lo, hi) in box.items():
                z[env.spec.index(n)] = lo if spec == "low" else hi
            label = spec + ": " + ", ".join(f"{n}={lo if spec == 'low' else hi:.3g}" for n, (lo, hi) in box.items())
        elif spec == "nominal":
            label = "nominal"
        else:
            label = spec
            for item in spec.split(","):
                if "=" not in item:
                    raise ConfigError(f"physics: '{spec}' is not name=value,... nor nominal/low/high")
                n, v = item.split("=", 1)
                try:
                    z[env.spec.index(n.strip())] = float(v)
                except ValueError:
                    raise ConfigError(f"physics: '{spec}': '{v}' is not a number") from None
        env.check_z(z[None])
        out.append((label, z))
    return out


def policy_frames(env, act, z, label: str, episodes: int, width: int, height: int, key) -> tuple[np.ndarray, np.ndarray]:
    """``(frames [T, H, W, 3], returns [episodes])``: ``episodes`` of the policy ``act``
    (``tools.record.policy``) in ``env`` under physics ``z``, played one after another."""
    from sim2real.tools.record import simulated

    r = simulated(env, z, act, episodes, key)
    q = np.concatenate([r.qpos[e, : r.length[e]] for e in range(episodes)])
    return frames(env.mj_model, q, width, height, label), r.ret


def render_run(cfg: RenderConfig) -> dict:
    """Roll and draw; returns ``{"out", "labels", "returns" [panels, episodes], "frames"}``."""
    import jax

    from sim2real.common.config import ConfigError
    from sim2real.tools.record import policy
    from sim2real.training.runs import load_policy

    ext = os.path.splitext(cfg.out)[1].lower()
    if not cfg.run or not os.path.exists(os.path.join(cfg.run, "config.yaml")):
        raise FileNotFoundError(f"run={cfg.run}: not a run folder (no config.yaml)")
    if ext not in (".gif", ".mp4"):
        raise ConfigError(f"out={cfg.out}: a .gif or .mp4 file")
    if ext == ".mp4":
        try:
            import imageio_ffmpeg  # noqa: F401
        except ImportError:
            raise ConfigError("out=*.mp4 needs imageio-ffmpeg (pip install imageio-ffmpeg); .gif needs nothing more") from None
    if os.path.exists(cfg.out) and not cfg.overwrite:
        raise FileExistsError(f"out={cfg.out} exists (overwrite=true replaces it)")
    for key in ("episodes", "width", "height"):
        if getattr(cfg, key) < 1:
            raise ConfigError(f"{key}={getattr(cfg, key)}: must be a positive integer")
    if not cfg.physics:
        raise ConfigError("physics: at least one panel")
    rcfg, env, algo, params, stats = load_policy(cfg.run)
    if not 0 <= cfg.run_seed < rcfg.num_seeds:
        raise ConfigError(f"run_seed={cfg.run_seed}: run '{cfg.run}' has seeds 0..{rcfg.num_seeds - 1}")
    base = np.asarray(algo.space.base, np.float32)
    todo = panels(cfg, env, rcfg, base)
    gl_backend()
    params, stats = jax.tree_util.tree_map(lambda x: x[cfg.run_seed], (params, stats))
    act = policy(env, algo.ppo, params, stats, base)
    if cfg.steps:
        env = env.__class__(dataclasses.replace(env.config, episode_length=cfg.steps))
    videos, returns = [], []
    for label, z in todo:
        v, ret = policy_frames(env, act, z, label, cfg.episodes, cfg.width, cfg.height, jax.random.PRNGKey(cfg.seed))
        videos.append(v)
        returns.append(ret)
    T = max(len(v) for v in videos)  # a panel whose episode ended early holds its last frame
    video = np.concatenate([np.concatenate([v, np.repeat(v[-1:], T - len(v), 0)]) for v in videos], axis=2)
    os.makedirs(os.path.dirname(os.path.abspath(cfg.out)), exist_ok=True)
    write_video(cfg.out, video, cfg.fps or 1.0 / env.dt)
    return {"out": cfg.out, "labels": [label for label, _ in todo], "returns": np.asarray(returns), "frames": video.shape}
