"""Orbax checkpoints of whole algorithm states (policy, optimiser, envs, PRNG keys).

Orbax refuses zero-size arrays (MJX data has some, e.g. ``act`` for models without activations),
so a state is saved as a flat dict of its non-empty leaves and rebuilt on a template.
"""
from __future__ import annotations

import os

import jax
import numpy as np
import orbax.checkpoint as ocp


def manager(directory: str, keep: int = 2, create: bool = True) -> ocp.CheckpointManager:
    """``create=False``: read an existing folder only (a refused resume must not write)."""
    return ocp.CheckpointManager(os.path.abspath(directory),
                                 options=ocp.CheckpointManagerOptions(max_to_keep=keep, create=create))


def _flat(state) -> dict[str, jax.Array]:
    leaves = jax.tree_util.tree_leaves(state)
    return {f"{i:05d}": x for i, x in enumerate(leaves) if np.size(x) > 0}


def save(mngr: ocp.CheckpointManager, step: int, state) -> None:
    mngr.save(step, args=ocp.args.StandardSave(_flat(state)))


def restore(mngr: ocp.CheckpointManager, step: int, template):
    leaves, treedef = jax.tree_util.tree_flatten(template)
    saved = mngr.restore(step, args=ocp.args.StandardRestore(_flat(template)))
    out = [_like(saved[f"{i:05d}"], x) if f"{i:05d}" in saved else x for i, x in enumerate(leaves)]
    return jax.tree_util.tree_unflatten(treedef, out)


def _like(x, template):
    """``x`` placed as ``template`` is: same dtype, same sharding, committed only if it is.

    Orbax hands back arrays committed to a device while a jitted function's fresh outputs are
    not; jit keys its cache on that, so a resumed run would compile its chunk twice (the restored
    state, then the chunk's own outputs) -- ~25 s per compile of the PPO chunk on CPU.
    """
    if getattr(template, "committed", True):
        return jax.device_put(x, template.sharding).astype(template.dtype)
    return jax.numpy.asarray(np.asarray(x), dtype=template.dtype)
