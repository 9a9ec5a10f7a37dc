"""Frames and videos of MuJoCo poses, drawn offscreen: what the diagnosis report and the policy
videos (``tools.render``, ``tools.evaluate``) both draw with.

Rendering needs an OpenGL context without a display: EGL (``MUJOCO_GL=egl``, a GPU's or Mesa's
software one), else OSMesa; the first that works is used unless ``MUJOCO_GL`` is set.
"""
from __future__ import annotations

import copy
import os

import numpy as np


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
