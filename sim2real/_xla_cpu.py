"""XLA settings for CPU, made before JAX starts its backends: one when ``sim2real`` is imported
(``configure``), one by the diagnose command (``split_cores``).

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
DEVICES = "--xla_force_host_platform_device_count"


def _started() -> bool:
    if "jax" not in sys.modules:
        return False
    from jax._src import xla_bridge

    return xla_bridge.backends_are_initialized()


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
    if _started():
        return False
    os.environ["XLA_FLAGS"] = (flags + f" {FLAG}=false").strip()
    return True


def split_cores(cores: int | None = None, most: int = 8) -> int:
    """Ask XLA for one CPU device per core (a power of two, at most ``most``) and return how many.

    Why: XLA runs one program on one CPU device at about one core, so the diagnosis's batched
    simulations (``sysid.shooting``) used one core of many; over several devices they run side by
    side. Only a process that is about to diagnose asks (it changes ``jax.devices()``); nothing
    is changed where the user set the count, or JAX has started (then 0 is returned).
    """
    flags = os.environ.get("XLA_FLAGS", "")
    if DEVICES in flags or _started():
        return 0
    if cores is None:
        cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    n = 1
    while n * 2 <= min(cores, most):
        n *= 2
    if n > 1:
        os.environ["XLA_FLAGS"] = (flags + f" {DEVICES}={n}").strip()
    return n
