"""Splitting the env batch over CPU devices (sim2real.envs.parallel) gives the same rollout as one device.

Runs in a subprocess: the CPU device count can only be chosen before JAX starts, and this test
process already has one device.
"""
import subprocess
import sys
import textwrap

import pytest

SCRIPT = textwrap.dedent("""
    import jax, jax.numpy as jnp, numpy as np
    from sim2real.envs import parallel
    assert parallel.use_cpu_cores(2) == 2
    from sim2real.envs import make
    env = make("pendulum")
    B = 6
    keys = jax.random.split(jax.random.PRNGKey(0), B)
    z = jnp.tile(jnp.asarray(env.default_z()), (B, 1))
    z = z.at[:, env.spec.indices(["mass:pole"])[0]].set(jnp.linspace(0.8, 1.4, B))
    state = jax.vmap(env.reset)(keys, z)
    acts = jax.random.uniform(jax.random.PRNGKey(1), (30, B, env.action_size), minval=-1, maxval=1)

    def roll(state, z):
        f = lambda s, a: (jax.vmap(env.step)(s, a, z), None)
        return jax.lax.scan(f, state, acts)[0]

    one = jax.jit(roll)(state, z)
    sh = parallel.batch_sharding(B)
    split = jax.jit(roll, out_shardings=sh)(*parallel.shard_batch((state, z)))
    assert len(split.obs.sharding.device_set) == 2, split.obs.sharding
    np.testing.assert_allclose(np.asarray(split.obs), np.asarray(one.obs), rtol=1e-5, atol=1e-6)

    # batch_map: each device rolls its own slice out (per-env keys draw the actions), same result
    def roll_keys(state, z, keys):
        def f(c, _):
            s, k = c
            k, ka = jax.vmap(jax.random.split, out_axes=1)(k)
            a = jax.vmap(lambda kk: jax.random.uniform(kk, (env.action_size,), minval=-1, maxval=1))(ka)
            return (jax.vmap(env.step)(s, a, z), k), None
        s, k = jax.lax.scan(f, (state, keys), None, length=30)[0]
        return s, z, k

    one_k = jax.jit(roll_keys)(state, z, keys)
    mapped = parallel.batch_map(roll_keys, B)
    split_k = mapped(state, z, keys)
    assert len(split_k[0].obs.sharding.device_set) == 2, split_k[0].obs.sharding
    np.testing.assert_allclose(np.asarray(split_k[0].obs), np.asarray(one_k[0].obs), rtol=1e-5, atol=1e-6)
    assert not np.allclose(np.asarray(split_k[0].obs), np.asarray(state.obs))  # it did move
    again = mapped(*split_k)                        # outputs feed back in
    np.testing.assert_allclose(np.asarray(again[0].obs), np.asarray(jax.jit(roll_keys)(*one_k)[0].obs),
                               rtol=1e-5, atol=1e-6)
    assert len(parallel.batch_devices(3)) == 1      # an odd batch stays on one device

    # PPO's rollout with ppo.split_envs: each device steps its envs (with resets that draw new
    # physics from per-env keys), the same batch comes out
    env = make("pendulum", episode_length=15)
    from sim2real.rl import networks
    from sim2real.rl.ppo import PPOConfig
    from sim2real.rl.rollout import Context, collect, init_runner
    net_cfg = PPOConfig(net=networks.NetConfig(hidden=(8,))).net
    net, params = networks.init_params(jax.random.PRNGKey(2), net_cfg, env.obs_size, 0, env.action_size)
    from sim2real.rl import normalize
    stats = normalize.init(env.obs_size)
    i_mass = int(env.spec.indices(["mass:pole"])[0])
    sample = lambda k: jnp.asarray(env.default_z()).at[i_mass].set(jax.random.uniform(k, (), minval=0.8, maxval=1.4))
    # built under jit like the driver's state (eager arrays are committed to device 0)
    runner = jax.jit(lambda k: init_runner(env, k, B, sample, 0))(jax.random.PRNGKey(3))
    col = lambda split: jax.jit(lambda r, k: collect(env, net, params, stats, Context.empty(), r, k, sample, 40,
                                                     split=split))
    r1, b1, s1 = col(False)(runner, jax.random.PRNGKey(4))
    r2, b2, s2 = col(True)(runner, jax.random.PRNGKey(4))
    assert len(r2.z.sharding.device_set) == 2, r2.z.sharding   # the runner stays split
    assert int(s1["episodes"]) == int(s2["episodes"]) == 2 * B  # two resets per env in 40 steps
    for a, b in ((b1.obs, b2.obs), (b1.action, b2.action), (b1.reward, b2.reward), (b1.z, b2.z)):
        np.testing.assert_allclose(np.asarray(b), np.asarray(a), rtol=1e-5, atol=1e-5)
    assert len(np.unique(np.asarray(b1.z)[:, :, i_mass])) > B  # resets drew new masses
    # called eagerly, on a runner built eagerly (committed to one device): the same batch
    eager = init_runner(env, jax.random.PRNGKey(3), B, sample, 0)
    r3, b3, s3 = collect(env, net, params, stats, Context.empty(), eager, jax.random.PRNGKey(4), sample, 40,
                         split=True)
    assert len(r3.z.sharding.device_set) == 2, r3.z.sharding
    np.testing.assert_allclose(np.asarray(b3.obs), np.asarray(b1.obs), rtol=1e-5, atol=1e-5)
    try:
        parallel.shard_batch({"a": jnp.zeros(4), "b": jnp.zeros(3)})
    except ValueError as e:
        assert "leading batch axis" in str(e)
    else:
        raise AssertionError("mismatched batch sizes accepted")
    print("OK")
""")


@pytest.mark.slow  # about 50 s on 2 cores (a subprocess compiling on one and two devices); moved 2026-12-06 when the suite took 969 s
def test_split_batch_matches_one_device():
    r = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0 and "OK" in r.stdout, r.stderr[-3000:]


def test_data_parallel_refuses_what_it_cannot_split():
    import pytest

    from sim2real.rl import networks
    from sim2real.rl.ppo import PPOConfig, check

    with pytest.raises(ValueError, match="ppo.net.kind=mlp"):
        check(PPOConfig(data_parallel=True, net=networks.NetConfig(kind="lstm")))
    with pytest.raises(ValueError, match="ppo.num_steps=10 must be divisible by ppo.num_minibatches=4"):
        check(PPOConfig(data_parallel=True, num_steps=10, num_envs=4))



def test_one_device_per_core_the_process_may_use():
    """A process pinned to one core (``taskset``, a container's cpuset) declares one CPU device,
    not one per core of the host: ``os.cpu_count()`` would oversubscribe that core."""
    import os

    import pytest

    if not hasattr(os, "sched_setaffinity"):
        pytest.skip("no CPU affinity on this OS")
    script = textwrap.dedent("""
        import os
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
        from sim2real.envs import parallel
        assert parallel.cpu_cores() == 1, parallel.cpu_cores()
        assert parallel.use_cpu_cores() == 1
        print("ok", os.cpu_count())
    """)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.startswith("ok")
