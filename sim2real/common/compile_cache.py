"""JAX's persistent compilation cache, turned on by the command-line tools (``sim2real-*``).

Why: every command compiles its simulation for the model at hand before it runs anything -- a
diagnosis of a 3-link arm spends about 8 s of its 43 s there, of a pendulum about 3 s of 11 (2-core
CPU). Run again on the same robot (another diagnosis of recordings of the same lengths, other
settings, a training resumed) XLA would compile the very same programs again. JAX keeps compiled
programs on disk, keyed by the program, its shapes, the backend and the jax and jaxlib versions;
a hit loads the program the compile would have made, so results do not change (a diagnosis run
cold and then from the cache gave the same ``diagnosis.json``: 43.4 -> 37.1 s for the arm,
11.2 -> 8.5 s for the DFKI pendulum).

Where: ``$SIM2REAL_COMPILE_CACHE``, else ``$XDG_CACHE_HOME/sim2real/xla``, else
``~/.cache/sim2real/xla``; ``SIM2REAL_COMPILE_CACHE=off`` leaves it off. Programs that compiled
in under a second are not kept (JAX's default). Nothing caps the folder's size (about 0.5 MB a
diagnosed model; JAX's own eviction needs the ``filelock`` package): delete it whenever you like.
Library calls (``sim2real.diagnose`` from Python, the tests) are left as JAX has them.
"""
from __future__ import annotations

import os

ENV = "SIM2REAL_COMPILE_CACHE"
OFF = ("off", "0", "false", "no", "")


def cache_dir(environ=None) -> str | None:
    """The cache folder the environment asks for (``None``: off)."""
    env = os.environ if environ is None else environ
    if ENV in env:
        v = env[ENV].strip()
        return None if v.lower() in OFF else os.path.expanduser(v)
    base = env.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return os.path.join(base, "sim2real", "xla")


def enable() -> str | None:
    """Point JAX's persistent compilation cache at ``cache_dir()`` unless the user already set
    one (``JAX_COMPILATION_CACHE_DIR`` or ``jax.config``); returns the folder used, or ``None``."""
    import jax

    if jax.config.jax_compilation_cache_dir:  # the user's own choice stands
        return jax.config.jax_compilation_cache_dir
    path = cache_dir()
    if path is None:
        return None
    try:
        os.makedirs(path, exist_ok=True)
    except OSError:  # a read-only home: compile as before, nothing kept
        return None
    jax.config.update("jax_compilation_cache_dir", path)
    return path
