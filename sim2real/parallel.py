"""Split a batch of envs over the host's devices: every CPU core, or every GPU.

Why: XLA runs one CPU device's program on little more than one core for the many small ops of an
MJX step (1.5 of 2 cores busy at 1,024 hopper envs). Declaring one CPU device per core and
sharding the env batch's leading axis over them lets the partitioner run each slice of the batch
on its own core; nothing crosses slices in an env step, so no communication is added. On a GPU
host the same call shards over the GPUs.

    import sim2real.parallel as par
    par.use_cpu_cores()                 # first, before any JAX computation
    state, z = par.shard_batch((state, z))
    roll = jax.jit(roll, out_shardings=par.batch_sharding(batch))   # keeps the carry's layout

Results are the same as on one device (``tests/test_parallel.py``).
"""
from __future__ import annotations

import os

import jax
from jax.sharding import Mesh, NamedSharding, PartitionSpec


def use_cpu_cores(n: int | None = None) -> int:
    """Expose ``n`` CPU devices (default: one per core); call before JAX runs anything.

    Returns the number of CPU devices now visible. Raises ``RuntimeError`` if JAX's backends are
    already initialised with a different count (the setting only applies at start-up).
    """
    n = int(n or os.cpu_count() or 1)
    if n < 1:
        raise ValueError(f"use_cpu_cores: n must be >= 1, got {n}")
    try:
        jax.config.update("jax_num_cpu_devices", n)
    except RuntimeError as e:  # backends already up: fine only if they already have n CPU devices
        have = len(jax.devices("cpu"))
        if have != n:
            raise RuntimeError(f"use_cpu_cores({n}) must run before JAX computes anything; "
                               f"this process already has {have} CPU device(s)") from e
    return len(jax.devices("cpu"))


def batch_devices(batch: int) -> list:
    """The default backend's devices the batch is split over: as many as divide ``batch``."""
    devs = jax.devices()
    n = len(devs)
    while batch % n:
        n -= 1
    return devs[:n]


def batch_sharding(batch: int) -> NamedSharding:
    """Sharding of arrays whose leading axis is the env batch ``[B, ...]`` over ``batch_devices``."""
    return NamedSharding(Mesh(batch_devices(batch), ("batch",)), PartitionSpec("batch"))


def shard_batch(tree):
    """Place every leaf ``[B, ...]`` of ``tree`` (same ``B`` throughout) split along ``B``."""
    leaves = jax.tree_util.tree_leaves(tree)
    if not leaves:
        return tree
    sizes = {x.shape[0] if getattr(x, "ndim", 0) else None for x in leaves}
    if len(sizes) != 1 or None in sizes:
        raise ValueError(f"shard_batch: every leaf needs the same leading batch axis, got {sorted(map(str, sizes))}")
    return jax.device_put(tree, batch_sharding(sizes.pop()))
