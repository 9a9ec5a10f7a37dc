"""Splitting the env batch over CPU devices (sim2real.parallel) gives the same rollout as one device.

Runs in a subprocess: the CPU device count can only be chosen before JAX starts, and this test
process already has one device.
"""
import subprocess
import sys
import textwrap

SCRIPT = textwrap.dedent("""
    import jax, jax.numpy as jnp, numpy as np
    from sim2real import parallel
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
    try:
        parallel.shard_batch({"a": jnp.zeros(4), "b": jnp.zeros(3)})
    except ValueError as e:
        assert "leading batch axis" in str(e)
    else:
        raise AssertionError("mismatched batch sizes accepted")
    print("OK")
""")


def test_split_batch_matches_one_device():
    r = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0 and "OK" in r.stdout, r.stderr[-3000:]
