"""sim2real: JAX-native, massively batched sim-to-real training and sim-vs-real diagnosis."""
import contextlib as _contextlib
import importlib as _importlib
import io as _io
import sys as _sys

__version__ = "0.1.0"


def _import_mjx_quietly() -> None:
    """Import ``mujoco.mjx`` without its "Failed to import warp" lines when Warp is absent.

    mujoco.mjx tries its optional Warp backend on import and *prints* (not logs) two lines when
    the ``warp`` module is missing, on every process start. This package uses the JAX backend
    only, so those two lines are dropped; anything else printed (Warp installed but broken, for
    instance) is passed through to stdout.
    """
    buf = _io.StringIO()
    try:
        with _contextlib.redirect_stdout(buf):
            _importlib.import_module("mujoco.mjx")
    finally:
        for line in buf.getvalue().splitlines(keepends=True):
            if line.startswith(("Failed to import warp:", "Failed to import mujoco_warp:")) \
                    and "No module named 'warp'" in line:
                continue
            _sys.stdout.write(line)


_import_mjx_quietly()
