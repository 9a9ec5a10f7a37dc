"""One XLA setting for CPU, made when ``sim2real`` is imported, before JAX starts its backends.

Why: with jaxlib 0.9's CPU fusion emitters a vmapped MJX step slows down about tenfold per link
of a serial chain from five links on -- the time is spent running ``mjx.kinematics``, not
compiling it -- so a 7-joint arm stepped at 5.9 ms per env-step against 0.009 ms for 4 links, and
a diagnosis of a real KUKA LWR4+ did not get through its first simulation in 30 minutes.
``--xla_cpu_use_fusion_emitters=false`` steps that arm at ~0.02 ms, compiles the bundled envs ~30%
faster and steps hopper 38% faster (halfcheetah 23% slower): ``benchmarks/xla_cpu_chain_repro.py``.
Set only where the flag exists (jaxlib 0.9; jaxlib 0.11.2 aborts on it as an unknown flag), the
user has not set it either way, and XLA has not read ``XLA_FLAGS`` yet (it does so once).
"""
from __future__ import annotations

import os
import sys

FLAG = "--xla_cpu_use_fusion_emitters"


def configure() -> bool:
    """Add ``FLAG=false`` to ``XLA_FLAGS`` where it is safe; returns whether it was added."""
    flags = os.environ.get("XLA_FLAGS", "")
    if FLAG in flags:
        return False
    try:
        from importlib.metadata import version

        if not version("jaxlib").startswith("0.9."):
            return False
    except Exception:  # no jaxlib: nothing to configure
        return False
    if "jax" in sys.modules:
        from jax._src import xla_bridge

        if xla_bridge.backends_are_initialized():
            return False
    os.environ["XLA_FLAGS"] = (flags + f" {FLAG}=false").strip()
    return True
