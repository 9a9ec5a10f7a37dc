"""Several processes (jax.distributed, one per host or per GPU) run data-parallel PPO as one
process with all the devices would: checked with 2 processes of one CPU device each.

Subprocesses: the device count and the distributed runtime are fixed when JAX starts.
"""
import subprocess
import sys
import textwrap

import numpy as np

MULTI_PROCESS = textwrap.dedent("""
    import sys, jax, numpy as np
    mode, out = sys.argv[1], sys.argv[2]
    if mode == "process":  # one of 2 processes with one CPU device each, as on 2 hosts
        jax.config.update("jax_cpu_collectives_implementation", "gloo")
        jax.distributed.initialize(coordinator_address=f"localhost:{sys.argv[4]}", num_processes=2,
                                   process_id=int(sys.argv[3]))
        assert len(jax.local_devices()) == 1 and len(jax.devices()) == 2
    else:                  # one process with 2 CPU devices
        from sim2real.envs import parallel
        assert parallel.use_cpu_cores(2) == 2
    import jax.numpy as jnp
    from sim2real.envs import make
    from sim2real.rl import data_parallel, networks
    from sim2real.rl.ppo import PPO, PPOConfig
    env = make("pendulum", episode_length=20)
    cfg = PPOConfig(num_envs=8, num_steps=16, num_minibatches=4, num_epochs=2, net=networks.NetConfig(hidden=(16,)),
                    data_parallel=True)
    ppo = PPO(env, cfg, 10)
    i = env.spec.indices(["mass:pole"])[0]
    sample = lambda k: jnp.asarray(env.default_z()).at[i].set(jax.random.uniform(k, minval=0.7, maxval=1.3))
    st = data_parallel.globalize(ppo, jax.jit(lambda k: ppo.init(k, sample))(jax.random.PRNGKey(0)))
    update = jax.jit(lambda s: ppo.update(s, sample))
    for _ in range(2):
        st, m = update(st)
    leaves = jax.tree_util.tree_leaves((st.params, st.obs_stats))
    np.save(out, np.concatenate([np.ravel(data_parallel.local_value(x)) for x in leaves]))
""")


def test_two_processes_compute_the_update_of_one_process_with_two_devices(tmp_path):
    """jax.distributed with 2 processes of one CPU device each (gloo collectives), the same
    program: both end with the parameters one process with 2 devices computes."""
    import socket

    with socket.socket() as s:
        s.bind(("localhost", 0))
        port = s.getsockname()[1]
    run = lambda *a: subprocess.Popen([sys.executable, "-c", MULTI_PROCESS, *map(str, a)],  # noqa: E731
                                      stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    procs = [run("process", tmp_path / f"p{k}.npy", k, port) for k in (0, 1)]
    for p in procs:
        _, err = p.communicate(timeout=600)
        assert p.returncode == 0, err[-3000:]
    one = run("one", tmp_path / "one.npy")
    _, err = one.communicate(timeout=600)
    assert one.returncode == 0, err[-3000:]
    ref = np.load(tmp_path / "one.npy")
    for k in (0, 1):
        np.testing.assert_allclose(np.load(tmp_path / f"p{k}.npy"), ref, rtol=1e-6, atol=1e-7)
