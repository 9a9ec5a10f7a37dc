"""Videos of a trained policy under several physics, side by side (MuJoCo's offscreen Renderer).

    sim2real-render run=runs/pendulum_udr out=video.gif
    sim2real-render run=runs/hopper "physics=[nominal,mass:torso=9.0,friction=0.5]" episodes=2 out=hopper.mp4

``physics``: one panel per entry, ``name=value,...`` or ``nominal`` / ``low`` / ``high`` (the
corners of the run's DR box; the default is all three). ``.gif`` needs nothing more, ``.mp4``
needs imageio-ffmpeg. Headless: EGL, else OSMesa (``MUJOCO_GL`` overrides).
"""
import sys

from sim2real.common import compile_cache
from sim2real.common.cli import main_guard


def main(argv):
    from sim2real.common import config as config_lib
    from sim2real.tools.render import RenderConfig, render_run

    res = render_run(config_lib.load(RenderConfig, argv))
    T, H, W, _ = res["frames"]
    print(f"wrote {res['out']}: {T} frames of {W} x {H}; returns per panel: "
          + "; ".join(f"{label}: {r.mean():.1f}" for label, r in zip(res["labels"], res["returns"])))


HELP = ('sim2real.tools.render:RenderConfig',)  # the typed configs whose keys ``-h`` lists


def run(argv=None):
    """Console entry point ``sim2real-render`` (and ``python -m sim2real render``)."""
    compile_cache.enable()  # compiled programs kept between runs (common/compile_cache.py says why)
    main_guard(main, sys.argv[1:] if argv is None else argv, doc=__doc__, configs=HELP)


if __name__ == "__main__":
    run()
