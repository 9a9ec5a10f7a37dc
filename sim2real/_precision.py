"""sim2real computes in float32, whatever JAX's ``jax_enable_x64`` says.

Why: the physics vectors (``physics/params.py``), the effect states that scans carry, the fits'
start values and the networks are float32 by design, while under ``JAX_ENABLE_X64=1`` (common in
system-identification code) ``mjx.put_model`` keeps MuJoCo's float64 and ``jnp.zeros`` makes
float64: the two met in a scan's carry and training and the diagnosis both stopped with "carry
input and carry output must have equal types". The commands (``common/cli.py: main_guard``) and
the public entry points (``train``, ``diagnose``) run under :func:`float32` (the diagnosis under
the bits of its own ``precision`` setting, its simulator and fits taking their float type from
:func:`real`), so the flag changes neither what they compute nor their answers (a pendulum's
policy byte-identical, EMPS's diagnosis the same). An env stepped from the user's own code
follows the user's flag (``env.reset`` and ``env.step`` run in float64 under it).
"""
from __future__ import annotations

import contextlib
import functools

import numpy as np


@contextlib.contextmanager
def float32():
    """Within the block JAX's 64-bit types are off (a thread-local setting, restored on exit)."""
    import jax

    with jax.enable_x64(False):
        yield


def in_float32(fn):
    """``fn`` run under :func:`float32` (a decorator for entry points)."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with float32():
            return fn(*args, **kwargs)

    return wrapper


def real() -> np.dtype:
    """The floating-point type JAX computes in here and now: float32, or float64 inside
    ``jax.enable_x64(True)`` (the diagnosis' ``precision=64``). Arrays that meet in a scan's
    carry are made with it, so the carry's types match in either."""
    import jax

    return np.dtype(jax.dtypes.canonicalize_dtype(np.float64))
