"""Several processes (jax.distributed, one per host or per GPU) run data-parallel PPO as one
process with all the devices would: checked with 2 processes of one CPU device each, through the
training driver (``processes=2``) and through the Python API (``data_parallel.globalize``); the
driver's data-parallel run on one device computes the same.

Subprocesses: the device count and the distributed runtime are fixed when JAX starts.
"""
import csv
import os
import socket
import subprocess
import sys
import textwrap

import numpy as np
import pytest

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
    np.save(out, np.concatenate([np.ravel(data_parallel.host_value(x)) for x in leaves]))
""")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


DRIVER = textwrap.dedent("""
    import sys, jax, numpy as np
    mode, phase, out, npy = sys.argv[1:5]
    from sim2real.common import config as config_lib
    from sim2real.rl.data_parallel import host_value
    from sim2real.training.driver import config_from_args, train
    args = ["env=pendulum", "algo=udr", "dr.params=[mass:pole]", "dr.low=[0.7]", "dr.high=[1.3]", "ppo.num_envs=8",
            "ppo.num_steps=16", "ppo.num_minibatches=4", "ppo.net.hidden=[16]", "num_seeds=2", "total_steps=512",
            "updates_per_chunk=2", "progress=false", "tensorboard=false", f"out_dir={out}", "name=r",
            "test.every=1", "test.params=[mass:pole]", "test.points=[[0.8],[1.2]]"]
    if phase == "first":     # stop after the first of the run's 2 chunks
        args += ["max_chunks=1"]
    elif phase == "resume":  # continue from its checkpoint with the saved config
        args = ["resume=true", f"out_dir={out}", "name=r", "progress=false"]
    n = 1 if mode == "single" else 2  # the devices of the whole run
    if mode == "process":  # one of 2 processes, one CPU device each, as on 2 hosts
        args += ["processes=2", f"process_id={sys.argv[5]}", f"coordinator=localhost:{sys.argv[6]}"]
    else:                  # one process with 2 CPU devices, or with one ("single": the same program unsplit)
        from sim2real.envs import parallel
        assert parallel.use_cpu_cores(n) == n
        args += ["devices=all"] if n == 2 else ["ppo.data_parallel=true"]
    from sim2real.training import driver
    made = []  # the driver's jitted chunk, to count its compilations
    make_chunk = driver.make_chunk
    driver.make_chunk = lambda *a: made.append(make_chunk(*a)) or made[-1]
    res = train(config_from_args(args))
    assert len(jax.devices()) == n and res["state"].runner.z.sharding.device_set == set(jax.devices())
    if phase == "all":
        # two chunks, one compilation: the initial state has the shardings every update returns
        # (a state committed to one device made the second chunk compile again)
        assert made[0]._cache_size() == 1, made[0]._cache_size()
    leaves = jax.tree_util.tree_leaves((res["state"].params, res["state"].obs_stats))
    np.save(npy, np.concatenate([np.ravel(host_value(x)) for x in leaves]))
""")


def _driver(tmp_path, phases, one_device=False):
    """Run the driver on 2 processes (each phase of ``phases`` in turn) and on one process with 2
    devices; both must end with the same parameters, run folder, metrics and test log. ``one_device``:
    also on one process with one device (``ppo.data_parallel=true``), the same parameters."""
    run = lambda *a: subprocess.Popen([sys.executable, "-c", DRIVER, *map(str, a)],  # noqa: E731
                                      stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)

    def wait(procs):
        for p in procs:
            _, err = p.communicate(timeout=600)
            assert p.returncode == 0, err[-3000:]

    for phase in phases:
        port = _free_port()
        wait([run("process", phase, tmp_path / "multi", tmp_path / f"p{k}.npy", k, port) for k in (0, 1)])
        if phase == "first":
            assert sorted(os.listdir(tmp_path / "multi" / "r" / "checkpoints")) == ["1"]
    wait([run("one", "all", tmp_path / "one", tmp_path / "one.npy"),
          *([run("single", "all", tmp_path / "single", tmp_path / "single.npy")] if one_device else [])])
    ref = np.load(tmp_path / "one.npy")
    for k in (0, 1):
        np.testing.assert_allclose(np.load(tmp_path / f"p{k}.npy"), ref, rtol=1e-6, atol=1e-7)
    if one_device:  # one device computes what two do, to float rounding (sums split differently)
        np.testing.assert_allclose(np.load(tmp_path / "single.npy"), ref, rtol=1e-5, atol=1e-6)
    multi, single = tmp_path / "multi" / "r", tmp_path / "one" / "r"
    assert sorted(os.listdir(multi)) == sorted(os.listdir(single))
    assert sorted(os.listdir(multi / "checkpoints")) == ["1", "2"]
    rows = lambda d, f: [{k: v for k, v in r.items() if k != "wall_seconds"} for r in csv.DictReader(open(d / f))]  # noqa: E731
    assert rows(multi, "metrics.csv") == rows(single, "metrics.csv")
    assert rows(multi, "test.csv") == rows(single, "test.csv")


def test_the_training_driver_in_two_processes_trains_as_one_process_with_two_devices(tmp_path):
    """``scripts/train.py ... processes=2 process_id=K coordinator=host:port`` on 2 processes of
    one CPU device each ends with the parameters of one process with 2 devices, and of one with
    one device (``ppo.data_parallel``: each device collects and learns on its envs, gradients
    summed over devices; 2 seeds vmapped, 4 updates in 2 chunks, compiled once); process 0 alone
    writes the run folder (config, metrics, tests, policy), both write the checkpoints."""
    _driver(tmp_path, ["all"], one_device=True)


@pytest.mark.slow  # five processes, each starting JAX and compiling (~115 s on 2 cores; make test-slow)
def test_the_training_driver_in_two_processes_resumes_as_one_process_with_two_devices(tmp_path):
    """The same, stopped after one chunk and resumed (``resume=true``, the same processes option):
    the resumed pair ends as one process with 2 devices run without a stop."""
    _driver(tmp_path, ["first", "resume"])


def test_processes_need_a_coordinator_and_an_index_in_range():
    from sim2real.common import config as config_lib
    from sim2real.training.driver import TrainConfig, validate

    for bad, match in ((["processes=2"], "coordinator"), (["processes=2", "process_id=2", "coordinator=h:1"], "process_id"),
                       (["processes=0"], "processes")):
        with pytest.raises(config_lib.ConfigError, match=match):
            validate(config_lib.load(TrainConfig, bad))


@pytest.mark.slow  # the driver test above checks the same through the training driver
def test_two_processes_compute_the_update_of_one_process_with_two_devices(tmp_path):
    """jax.distributed with 2 processes of one CPU device each (gloo collectives), the same
    program: both end with the parameters one process with 2 devices computes."""
    port = _free_port()
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
