"""``mujoco.mjx``, imported without its "Failed to import warp" lines when Warp is absent.

mujoco.mjx tries its optional Warp backend on import and *prints* (not logs) two lines when the
``warp`` module is missing, on every process start. This package uses the JAX backend only, so
those two lines are dropped; anything else printed (Warp installed but broken, for instance) is
passed through to stdout. Modules that need MJX import it from here (``from sim2real._mjx import
mjx``), so ``import sim2real`` alone imports neither MJX nor JAX.
"""
from __future__ import annotations

import contextlib
import importlib
import io
import sys


def _import_quietly():
    if "mujoco.mjx" in sys.modules:
        return sys.modules["mujoco.mjx"]
    buf = io.StringIO()
    try:
        with contextlib.redirect_stdout(buf):
            mod = importlib.import_module("mujoco.mjx")
    finally:
        for line in buf.getvalue().splitlines(keepends=True):
            if line.startswith(("Failed to import warp:", "Failed to import mujoco_warp:")) \
                    and "No module named 'warp'" in line:
                continue
            sys.stdout.write(line)
    return mod


mjx = _import_quietly()
