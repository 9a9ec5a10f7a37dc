"""Videos of a trained policy under several physics, side by side.

``render_run(RenderConfig(...))`` is what ``sim2real-render`` runs: the run's policy is rolled in
its own env (MJX) under each physics vector, and the rollouts are drawn with MuJoCo's offscreen
``Renderer`` into one video, one panel per physics, labelled. By default the panels are the run's
nominal physics and the lowest and highest corners of its randomisation box.

Rendering needs an OpenGL context without a display: EGL (``MUJOCO_GL=egl``, a GPU's or Mesa's
software one), else OSMesa; the first that works is used unless ``MUJOCO_GL`` is set.
"""
from __future__ import annotations

import copy
import dataclasses
import os

import numpy as np


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


def gl_backend() -> str:
    """Pick (and set) ``MUJOCO_GL``: the user's choice, else the first of egl, osmesa that renders."""
    import subprocess
    import sys

    if os.environ.get("MUJOCO_GL"):
        return _use(os.environ["MUJOCO_GL"])
    probe = ("import mujoco; m = mujoco.MjModel.from_xml_string('<mujoco><worldbody><geom size=\".1\"/>"
             "</worldbody></mujoco>'); mujoco.Renderer(m, 8, 8).render()")
    for backend in ("egl", "osmesa"):  # probed in a child: a failed context can take the process down
        env = dict(os.environ, MUJOCO_GL=backend, PYOPENGL_PLATFORM=backend)
        if subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True, timeout=120).returncode == 0:
            os.environ["MUJOCO_GL"] = os.environ["PYOPENGL_PLATFORM"] = backend
            return _use(backend)
    raise RuntimeError("no headless OpenGL for MuJoCo's Renderer: install EGL (libegl1 with a GPU driver or "
                       "Mesa's libegl-mesa0) or OSMesa (libosmesa6), or set MUJOCO_GL")


def _use(backend: str) -> str:
    """Make MuJoCo's ``Renderer`` take ``backend``'s context even though ``mujoco`` was imported
    before ``MUJOCO_GL`` was set (it reads the variable once, at import, and then looks the
    context class up on its ``gl_context`` module at every ``Renderer``)."""
    import importlib

    try:
        gl_context = importlib.import_module("mujoco.rendering.classic.gl_context")  # mujoco >= 3.4
    except ImportError:
        gl_context = importlib.import_module("mujoco.gl_context")
    if backend in ("egl", "osmesa", "glfw"):
        gl_context.GLContext = importlib.import_module(f"mujoco.{backend}").GLContext
    return backend


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


def frames(mj_model, qpos: np.ndarray, width: int, height: int, label: str, ghost: np.ndarray | None = None,
           captions: list[str] | None = None) -> np.ndarray:
    """``[T, H, W, 3]`` uint8 frames of the positions ``qpos [T, nq]`` with ``label`` written on them;
    the camera follows the first moving body (a hopper leaves a fixed view). ``ghost [T, nq]``: a
    second pose drawn translucent over the first (what a prediction should have matched);
    ``captions``: a line per frame under the label. With either, the world frame's axes are drawn
    as a fixed reference (a slide's motion is invisible without one)."""
    import mujoco
    from PIL import Image, ImageDraw

    mj_model = copy.copy(mj_model)  # (a lit copy: the bundled scenes have no lights of their own)
    mj_model.vis.headlight.ambient[:] = 0.45
    mj_model.vis.headlight.diffuse[:] = 0.75
    data = mujoco.MjData(mj_model)
    shadow = mujoco.MjData(mj_model)
    cam = mujoco.MjvCamera()
    mujoco.mjv_defaultFreeCamera(mj_model, cam)
    cam.distance, cam.elevation, cam.azimuth = 3.5 * mj_model.stat.extent, -10.0, 90.0  # from the side
    root = [mj_model.jnt_type[j] for j in range(mj_model.njnt) if mj_model.jnt_bodyid[j] == 1]
    if mujoco.mjtJoint.mjJNT_FREE in root or root.count(mujoco.mjtJoint.mjJNT_SLIDE) >= 2:
        cam.type, cam.trackbodyid = mujoco.mjtCamera.mjCAMERA_TRACKING, 1  # a walker travels: follow it
    opt = mujoco.MjvOption()
    if ghost is not None or captions is not None:
        opt.frame = mujoco.mjtFrame.mjFRAME_WORLD
    out = np.zeros((len(qpos), height, width, 3), np.uint8)
    with mujoco.Renderer(mj_model, height, width) as r:
        for t, q in enumerate(qpos):
            data.qpos[:] = q[: mj_model.nq]
            mujoco.mj_forward(mj_model, data)
            r.update_scene(data, camera=cam, scene_option=opt)
            if ghost is not None:
                shadow.qpos[:] = ghost[t, : mj_model.nq]
                mujoco.mj_forward(mj_model, shadow)
                n0 = r.scene.ngeom
                mujoco.mjv_addGeoms(mj_model, shadow, mujoco.MjvOption(), mujoco.MjvPerturb(),
                                    mujoco.mjtCatBit.mjCAT_DYNAMIC, r.scene)
                for g in range(n0, r.scene.ngeom):
                    r.scene.geoms[g].rgba[:] = (0.9, 0.9, 0.9, 0.35)
            img = Image.fromarray(r.render())
            draw = ImageDraw.Draw(img)
            draw.text((6, 4), label, fill=(255, 255, 255))
            if captions is not None:
                draw.text((6, 16), captions[t], fill=(255, 230, 120))
            out[t] = np.asarray(img)
    return out


def write_video(path: str, video: np.ndarray, fps: float) -> None:
    """``video [T, H, W, 3]`` uint8 as a GIF (Pillow) or an MP4 (imageio-ffmpeg)."""
    ext = os.path.splitext(path)[1].lower()
    tmp = path + ".part" + ext
    if ext == ".gif":
        from PIL import Image

        imgs = [Image.fromarray(f) for f in video]
        imgs[0].save(tmp, save_all=True, append_images=imgs[1:], duration=int(round(1000 / fps)), loop=0)
    else:
        import imageio_ffmpeg

        w = imageio_ffmpeg.write_frames(tmp, (video.shape[2], video.shape[1]), fps=fps, macro_block_size=1)
        w.send(None)
        for f in video:
            w.send(np.ascontiguousarray(f))
        w.close()
    os.replace(tmp, path)  # no half-written video under the final name


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
