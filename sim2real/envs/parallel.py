"""Split a batch of envs over the host's devices: every CPU core, or every GPU.

Why: XLA runs one CPU device's program on little more than one core for the many small ops of an
MJX step (1.5 of 2 cores busy at 1,024 hopper envs). Declaring one CPU device per core and giving
each device a slice of the env batch puts every core to work; nothing crosses slices in an env
step, so no communication is needed.

Two ways, for two kinds of function:

* ``batch_map(fn, batch)`` -- for functions that treat envs independently (rollouts of a fixed
  policy, physics sweeps). Each device runs ``fn`` on its own slice (``jax.shard_map``), so
  data-dependent loops (MJX's solver iterations, ``while_loop``) stop when *that slice* has
  converged instead of waiting on a cross-device reduction every iteration. The faster of the two
  (hopper, 2 cores, one-off measurement outside the committed benchmark: 45k vs 30k env-steps/s
  at 4,096 envs). ``env_slices`` is the same inside a larger jitted function (PPO's rollout with
  ``ppo.split_envs``), with ``gather_whole`` to bring the results back whole.
* ``shard_batch`` + ``jax.jit(..., out_shardings=batch_sharding(batch))`` -- for anything, including
  functions that reduce over the batch (a PPO update): XLA's partitioner inserts the
  communication.

    import sim2real.envs.parallel as par
    par.use_cpu_cores()                 # first, before any JAX computation
    roll = par.batch_map(roll, batch)   # roll(state, z, keys) -> same, leaves [B, ...]
    state, z, keys = roll(state, z, keys)

Results are the same as on one device (``tests/test_parallel.py``). On a one-GPU host both are
the plain single-device computation.
"""
from __future__ import annotations

import os
from typing import Callable

import jax
from jax.sharding import Mesh, NamedSharding, PartitionSpec


def cpu_cores() -> int:
    """The CPU cores this process may run on: its affinity mask where the OS has one (``taskset``,
    a container's cpuset), else every core of the host. ``os.cpu_count()`` counts the host's, so
    on a 16-core host a process pinned to 2 would declare 16 devices and oversubscribe its 2."""
    try:
        return len(os.sched_getaffinity(0)) or 1
    except AttributeError:  # macOS, Windows: no affinity mask in the os module
        return os.cpu_count() or 1


def use_cpu_cores(n: int | None = None) -> int:
    """Expose ``n`` CPU devices (default: one per core, ``cpu_cores()``); call before JAX runs anything.

    Returns the number of CPU devices now visible. Raises ``RuntimeError`` if JAX's backends are
    already initialised with a different count (the setting only applies at start-up).
    """
    n = int(n or cpu_cores())
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
    avoid_shardy_crash(devs[:n])
    return devs[:n]


def avoid_shardy_crash(devices=None) -> bool:
    """Lower with GSPMD instead of Shardy where a ``shard_map`` spans several GPUs.

    Why: XLA in JAX 0.11.2 (CUDA) segfaults while compiling any ``jax.shard_map`` whose body runs an
    MJX step over 2 GPUs when Shardy partitions it -- a contact-free pendulum's single step too --
    and compiles and runs the same program with GSPMD (``benchmarks/xla_multigpu_repro.py``;
    ``benchmarks/results/multi_gpu/README.md``). JAX 0.11.2's XLA does the same over several CPU
    devices (the diagnosis's segments split over 2: a segfault with Shardy; GSPMD gives the
    one-device numbers to 1e-6; ``tests/test_sysid.py``'s two-device case, run on the device
    machine's CPUs on 2026-11-28). The setting is part of jit's cache key, so it is made before
    anything is traced (PPO's constructor, ``batch_map``, the training driver call this); CPU
    devices keep Shardy on the JAX 0.9 that CI runs. Returns whether GSPMD is now in use.
    """
    devices = jax.devices() if devices is None else devices
    crashes = devices[0].platform == "gpu" or tuple(int(p) for p in jax.__version__.split(".")[:2]) >= (0, 11)
    if len(devices) > 1 and crashes and jax.config.jax_use_shardy_partitioner:
        jax.config.update("jax_use_shardy_partitioner", False)
    return not jax.config.jax_use_shardy_partitioner


def split_keys(keys, n: int = 2):
    """Per-env keys ``[B, 2]`` -> ``n`` arrays of per-env keys ``[B, 2]`` (a leading axis of ``n``).

    Every env draws from its own key, so the draws do not depend on how the batch is split over
    devices and each device draws only its own slice.
    """
    return jax.vmap(lambda k: jax.random.split(k, n), out_axes=1)(keys)


ENVS = PartitionSpec("batch")              # [B, ...]
ENVS_OVER_TIME = PartitionSpec(None, "batch")  # [T, B, ...]


def batch_sharding(batch: int) -> NamedSharding:
    """Sharding of arrays whose leading axis is the env batch ``[B, ...]`` over ``batch_devices``."""
    return NamedSharding(Mesh(batch_devices(batch), ("batch",)), ENVS)


def shard_batch(tree):
    """Place every leaf ``[B, ...]`` of ``tree`` (same ``B`` throughout) split along ``B``."""
    leaves = jax.tree_util.tree_leaves(tree)
    if not leaves:
        return tree
    sizes = {x.shape[0] if getattr(x, "ndim", 0) else None for x in leaves}
    if len(sizes) != 1 or None in sizes:
        raise ValueError(f"shard_batch: every leaf needs the same leading batch axis, got {sorted(map(str, sizes))}")
    return jax.device_put(tree, batch_sharding(sizes.pop()))


def env_slices(fn: Callable, batch: int, in_specs=ENVS, out_specs=ENVS) -> Callable:
    """``fn`` run by each device on its slice of the env batch (``jax.shard_map``), callable inside
    ``jit``; ``fn`` itself when only one device divides ``batch``.

    ``fn`` must treat envs independently (a reduction over the batch would see one slice). The
    specs (pytree prefixes of the arguments / outputs) name the env axis ``"batch"``: ``ENVS``
    for ``[B, ...]`` leaves, ``ENVS_OVER_TIME`` for ``[T, B, ...]``.
    """
    mesh = batch_sharding(batch).mesh
    if mesh.size == 1:
        return fn
    # check_vma=False: MJX's solver runs lax.cond inside scans whose branches return values that
    # are not marked per-device, which the varying-axes check rejects; each slice's loop is
    # independent here by construction (fn treats envs independently).
    return jax.shard_map(fn, mesh=mesh, in_specs=in_specs, out_specs=out_specs, check_vma=False)


def gather_whole(tree, batch: int):
    """Inside ``jit``: every device holds all of ``tree`` (outputs of :func:`env_slices` with the
    same ``batch``), so what follows runs as on one device; ``tree`` unchanged on one device."""
    mesh = batch_sharding(batch).mesh
    if mesh.size == 1:
        return tree
    return jax.lax.with_sharding_constraint(tree, NamedSharding(mesh, PartitionSpec()))


def spread(fn: Callable, batch: int, on: bool = True, shared: int = 0) -> Callable:
    """``fn`` over a leading batch axis (samples, population members, episodes), each device
    running its slice (:func:`env_slices`) and the results gathered whole (:func:`gather_whole`),
    callable inside ``jit``. ``fn`` itself when ``on`` is false or one device divides ``batch``.

    The outer loops' independent work goes through this: SimOpt's REPS samples, the ES-MAML
    population, the evaluation episodes of LSDR/ADR/DORAEMON and of the training driver's tests.
    ``on`` is the PPO config's ``spreads`` (``split_envs`` or ``data_parallel``). The first
    ``shared`` arguments are given whole to every device (policy parameters, recordings); the
    rest are split along their leading axis. Pass what ``fn`` needs whole as such an argument,
    not by closure: an array closed over keeps its placement over the devices inside the
    per-device program, which JAX (0.10 and later) refuses at the first indexing.
    """
    if not on:
        return fn

    def run(*args):
        mapped = env_slices(fn, batch, in_specs=(PartitionSpec(),) * shared + (ENVS,) * (len(args) - shared))
        return mapped(*args) if mapped is fn else gather_whole(mapped(*args), batch)

    return run


def batch_map(fn: Callable, batch: int) -> Callable:
    """``jit(fn)`` with each device running ``fn`` on its slice of the batch.

    Args:
      fn: function whose every argument and output is a pytree of ``[B, ...]`` leaves (per-env
        PRNG keys included, so the draws do not depend on how the batch is split) and which treats
        envs independently: a reduction over the batch inside ``fn`` would only see one slice.
      batch: ``B``.
    Returns:
      The jitted function (arguments are split on the way in where they are not already);
      outputs stay split, so feeding them back costs no copy. Falls back to
      plain ``jax.jit(fn)`` when only one device divides ``B``.
    """
    sharding = batch_sharding(batch)
    if sharding.mesh.size == 1:
        return jax.jit(fn)
    mapped = jax.jit(env_slices(fn, batch))

    def run(*args):
        # a no-op for arguments already split this way (a previous call's outputs)
        return mapped(*jax.device_put(args, sharding))

    return run
