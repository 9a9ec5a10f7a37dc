"""Data-parallel PPO: every device steps its slice of the envs and learns on it; gradients,
advantage and observation statistics are summed over devices, so parameters stay replicated.

One ``jax.shard_map`` over the mesh axis ``"batch"`` (``envs/parallel.py``) runs the whole update:
the collection (``rl/rollout.collect`` on the device's envs), GAE (per env, no communication),
and the epochs. What crosses devices, by ``psum``: each minibatch's gradient with its
loss metrics (one all-reduce each), every minibatch's weight and advantage moments (one for the
whole update, before the epochs), the observation statistics and the episode statistics.

Minibatches are *stratified by env*: in every epoch each env permutes its own ``T`` steps with a
key folded from its global index and gives ``T / num_minibatches`` of them to each minibatch. A
minibatch is therefore the same set of samples whether the envs sit on 1 device or N, and the
update is the same to float rounding (``tests/test_multiprocess.py``; it differs from ``PPO.learn``'s
permutation over all samples, so ``ppo.data_parallel=true`` is a different, equally valid sampling
of minibatches, not the same numbers as ``false``). Feed-forward policies only (a recurrent
policy's minibatches are whole env sequences, whose split over devices would vary in size).
"""
from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import optax
from jax.sharding import PartitionSpec

from sim2real.envs import parallel
from sim2real.rl import normalize
from sim2real.rl.rollout import collect

AXIS = "batch"


def check(cfg) -> None:
    """Refuse settings data-parallel PPO cannot run, naming the key."""
    if cfg.net.kind != "mlp":
        raise ValueError("ppo.data_parallel=true needs ppo.net.kind=mlp (recurrent minibatches are whole env "
                         "sequences; their split over devices is not implemented)")
    if cfg.num_steps % cfg.num_minibatches:
        raise ValueError(f"ppo.data_parallel=true: ppo.num_steps={cfg.num_steps} must be divisible by "
                         f"ppo.num_minibatches={cfg.num_minibatches} (each env gives every minibatch the same "
                         "number of its steps)")


def _psum(x):
    return jax.lax.psum(x, AXIS)


def update(ppo, st, sample):
    """``PPO.update`` with the envs split over ``parallel.batch_devices(num_envs)``: ``(state, metrics)``."""
    cfg = ppo.cfg
    B, T, n_mb = cfg.num_envs, cfg.num_steps, cfg.num_minibatches
    mesh = parallel.batch_sharding(B).mesh
    key, k_col, k_learn = jax.random.split(st.key, 3)

    def local(runner, params, opt_state, obs_stats, k_col, k_learn):
        b = runner.z.shape[0]
        first = jax.lax.axis_index(AXIS) * b  # global index of this device's first env
        keys = jax.lax.dynamic_slice_in_dim(jax.random.split(k_col, (T, B)), first, b, axis=1)
        runner, batch, ep = collect(ppo.env, ppo.net, params, obs_stats, ppo.ctx, runner, None, sample, T,
                                    step_keys=keys)
        adv, ret = ppo.advantages(batch)                                   # [T, b], per env
        env_ids = first + jnp.arange(b)
        m = T // n_mb

        def minibatches(k):  # one epoch's minibatches: each [n, b * m, ...]
            perm = jax.vmap(lambda e: jax.random.permutation(jax.random.fold_in(k, e), T))(env_ids)  # [b, T]
            idx = perm.reshape(b, n_mb, m).transpose(1, 0, 2)                                      # [n, b, m]

            def pick(x):  # [T, b, ...] -> [n, b * m, ...]
                xt = jnp.moveaxis(x, 0, 1)                                                         # [b, T, ...]
                g = jax.vmap(lambda i: jax.vmap(lambda row, j: row[j])(xt, i))(idx)                # [n, b, m, ...]
                return g.reshape((n_mb, b * m) + x.shape[2:])

            return jax.tree_util.tree_map(pick, (batch.replace(carry0=None), adv, ret))

        # Every minibatch's weight and advantage moments, all epochs at once, in one all-reduce
        # before the gradient steps. They depend on the data only (not on the parameters), so this
        # is the same sum as taking them minibatch by minibatch; it takes a collective out of each
        # gradient step's sequential chain (the one left is the gradient's). Raw moments
        # (variance = E[a^2] - mean^2) are exact enough: GAE advantages have a mean small against
        # their spread, far from where float32 cancellation bites.
        def moments_of(k):  # [n, 3]: each minibatch's weight, sum of advantages, sum of their squares
            mb, a, _ = minibatches(k)
            return jnp.stack([mb.valid.sum(-1), jnp.sum(mb.valid * a, -1), jnp.sum(mb.valid * jnp.square(a), -1)], -1)

        epoch_keys = jax.random.split(k_learn, cfg.num_epochs)
        moments = _psum(jax.vmap(moments_of)(epoch_keys))                                  # [epochs, n, 3]

        def epoch(carry, k_mom):
            k, mom = k_mom

            def minibatch(carry, mb_data):
                params, opt_state = carry
                (mb, a, r), (w_sum, s1, s2) = mb_data
                w_sum = jnp.maximum(w_sum, 1.0)
                if cfg.normalize_adv:  # over the whole minibatch, all devices
                    mu = s1 / w_sum
                    a = (a - mu) / (jnp.sqrt(jnp.maximum(s2 / w_sum - jnp.square(mu), 0.0)) + 1e-8)
                grads, info = jax.grad(ppo._loss, has_aux=True)(params, mb, a, r, w_sum)
                grads, info = _psum((grads, info))  # one collective for both
                updates, opt_state = ppo.tx.update(grads, opt_state, params)
                return (optax.apply_updates(params, updates), opt_state), info

            return jax.lax.scan(minibatch, carry, (minibatches(k), tuple(mom.T)))

        (params, opt_state), info = jax.lax.scan(epoch, (params, opt_state), (epoch_keys, moments))
        if cfg.normalize_obs:
            x = batch.raw_obs.reshape(-1, batch.raw_obs.shape[-1])
            n = _psum(x.shape[0])
            mean = _psum(x.sum(0)) / n
            var = _psum(jnp.square(x - mean).sum(0)) / n
            obs_stats = normalize.merge(obs_stats, mean, var, n)
        metrics = jax.tree_util.tree_map(jnp.mean, info)
        metrics["mean_reward"] = _psum(batch.reward.sum()) / (T * B)
        ep = jax.tree_util.tree_map(_psum, ep)
        return runner, params, opt_state, obs_stats, metrics, ep

    rep = PartitionSpec()
    run = jax.shard_map(local, mesh=mesh, in_specs=(parallel.ENVS, rep, rep, rep, rep, rep),
                        out_specs=(parallel.ENVS, rep, rep, rep, rep, rep), check_vma=False)
    runner, params, opt_state, obs_stats, metrics, ep = run(st.runner, st.params, st.opt_state, st.obs_stats,
                                                            k_col, k_learn)
    st = st.replace(runner=runner, params=params, opt_state=opt_state, obs_stats=obs_stats, key=key,
                    update_step=st.update_step + 1)
    return st, metrics, ep


def _state_shardings(ppo):
    """``(split, whole)``: the runner's sharding (its env axis over the mesh) and everything else's
    (replicated on the mesh)."""
    mesh = parallel.batch_sharding(ppo.cfg.num_envs).mesh
    return jax.sharding.NamedSharding(mesh, parallel.ENVS), jax.sharding.NamedSharding(mesh, PartitionSpec())


def place(ppo, st):
    """``st`` (inside ``jit``, per seed) constrained to the shardings ``update`` returns: the runner
    split along its env axis over the mesh, everything else replicated on it. A state built
    without them (committed to one device) has other input shardings than every later update's
    output, so the training driver's jitted chunk compiled a second time on its second call (a
    whole compilation: 29 s of a 4.6 s chunk for hopper on 2 CPU devices)."""
    split, whole = _state_shardings(ppo)
    runner = jax.tree_util.tree_map(lambda x: jax.lax.with_sharding_constraint(x, split), st.runner)
    rest = jax.tree_util.tree_map(lambda x: jax.lax.with_sharding_constraint(x, whole), st.replace(runner=None))
    return rest.replace(runner=runner)


def globalize(ppo, st):
    """A PPO state (one seed, as ``PPO.init`` returns it) as arrays over every process's devices:
    the runner split along its env axis, everything else replicated. Needed when several
    processes run the same program (``jax.distributed.initialize``, one process per host or per
    GPU): each process holds only its devices' parts. Every process must pass the same ``st``
    (same seed, same config); it keeps only what its devices hold."""
    split, whole = _state_shardings(ppo)

    def put(x, sharding):
        if isinstance(x, jax.Array) and x.sharding == sharding:  # placed so by ``PPO.init`` already
            return x
        x = jax.device_get(x)
        return jax.make_array_from_callback(x.shape, sharding, lambda idx: x[idx])

    runner = jax.tree_util.tree_map(lambda x: put(x, split), st.runner)
    rest = jax.tree_util.tree_map(lambda x: put(x, whole), st.replace(runner=None))
    return rest.replace(runner=runner)


def host_value(x):
    """``x`` as a numpy array in this process, whatever its placement: a global array of several
    processes (``jax.distributed``) is gathered from all of them first."""
    if isinstance(x, jax.Array) and not x.is_fully_addressable:
        from jax.experimental import multihost_utils

        return np.asarray(multihost_utils.process_allgather(x, tiled=True))
    return np.asarray(x)
