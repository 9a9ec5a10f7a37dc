"""SimOpt: REPS (KL bound, dual, toy convergence), the smoothed discrepancy, and SimOpt on a pendulum."""
import os

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.ndimage import gaussian_filter1d

from sim2real.algos import reps
from sim2real.algos.base import DRConfig
from sim2real.algos.simopt import SimOpt, SimOptConfig, real_from_recordings, save_recordings
from sim2real.envs import make
from sim2real.rl.ppo import PPOConfig
from sim2real.sysid import discrepancy
from sim2real.sysid.recordings import RecordingError


# ------------------------------------------------------------------------------------ REPS ----
@pytest.mark.parametrize("eps", [0.1, 0.5, 1.0, 2.0])
def test_reps_respects_kl_bound_and_minimises_dual(eps):
    c = jax.random.gamma(jax.random.PRNGKey(1), 2.0, (500,)) * 30.0 + 100.0
    w, eta, kl = reps.weights(c, eps, eta_min=1e-6)
    assert float(jnp.sum(w)) == pytest.approx(1.0, abs=1e-5)
    kl_np = float(np.sum(np.asarray(w) * np.log(np.asarray(w) * len(c) + 1e-30)))
    assert kl_np <= eps + 1e-4
    # the bound is active (eta is above its minimum), so the solution sits on it
    assert kl_np == pytest.approx(eps, rel=1e-3)
    # eta minimises the dual: nearby temperatures are no better
    g = float(reps.dual(eta, c, eps))
    for f in (0.9, 1.1):
        assert g <= float(reps.dual(eta * f, c, eps)) + 1e-4
    # lower cost -> higher weight
    order = np.argsort(np.asarray(c))
    assert np.all(np.diff(np.asarray(w)[order]) <= 1e-9)


def test_reps_minimum_temperature_and_nonfinite_costs():
    c = jnp.array([0.0, 1.0, 2.0, jnp.nan, jnp.inf, 3.0])
    w, eta, kl = reps.weights(c, epsilon=100.0, eta_min=0.5)  # a loose bound: eta_min is active
    assert np.all(np.isfinite(np.asarray(w)))
    assert float(w[3]) == 0.0 and float(w[4]) == 0.0
    assert float(kl) < 100.0
    assert float(eta) == pytest.approx(0.5 * float(jnp.std(jnp.array([0.0, 1, 2, 3, 3, 3]))), rel=1e-3)
    mean, cov, _ = reps.update(jnp.arange(12.0).reshape(6, 2), c, 1.0)
    assert np.all(np.isfinite(np.asarray(mean))) and np.all(np.isfinite(np.asarray(cov)))


def test_reps_converges_on_quadratic():
    """Minimise ||xi - xi*||^2 from N(0, I): the mean reaches xi* and the spread shrinks."""
    target = jnp.array([2.0, -1.0, 0.5])
    mean, cov = jnp.zeros(3), jnp.eye(3)

    @jax.jit
    def step(mean, cov, key):
        xi = jax.random.multivariate_normal(key, mean, cov, (200,))
        m, c, info = reps.update(xi, jnp.sum((xi - target) ** 2, -1), 0.5)
        return m, c, info["kl"]

    key = jax.random.PRNGKey(0)
    for _ in range(40):
        key, k = jax.random.split(key)
        mean, cov, kl = step(mean, cov, k)
        assert float(kl) <= 0.5 + 1e-4
    np.testing.assert_allclose(np.asarray(mean), np.asarray(target), atol=0.05)
    assert float(jnp.max(jnp.diagonal(cov))) < 0.05


# ------------------------------------------------------------------------------ discrepancy ----
@pytest.mark.parametrize("std,trunc", [(5.0, 4.0), (2.0, 2.0), (0.0, 4.0)])
def test_smoothed_discrepancy_matches_numpy(std, trunc):
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(2, 60, 3)), rng.normal(size=(2, 60, 3))
    W = np.array([0.5, 1.0, 2.0])
    mask = np.ones((2, 60))
    mask[1, 45:] = 0
    got = np.asarray(discrepancy.discrepancy(a, b, W, 0.5, 1.0, std, trunc, mask))
    if std > 0:
        sa = gaussian_filter1d(a, std, axis=1, mode="nearest", truncate=trunc)
        sb = gaussian_filter1d(b, std, axis=1, mode="nearest", truncate=trunc)
    else:
        sa, sb = a, b
    d = (sa - sb) * W
    ref = ((0.5 * np.abs(d).sum(-1) + 1.0 * (d**2).sum(-1)) * mask).sum(-1)
    np.testing.assert_allclose(got, ref, rtol=1e-5)


# ---------------------------------------------------------------------------- SimOpt itself ----
TRUTH = {"sensor_offset:hinge": 0.4, "mass:pole": 1.5}


@pytest.fixture(scope="module")
def simopt():
    env = make("pendulum", episode_length=60)
    dr = DRConfig(params=("sensor_offset:hinge", "mass:pole"), low=(-1.0, 0.3), high=(1.0, 3.0))
    cfg = SimOptConfig(init_mean=(0.0, 1.0), init_std=(0.3, 0.4), num_samples=64, reps_updates=4,
                       real_rollouts=2, ppo_updates=1, eval_episodes=0, signal_weights=(1.0, 0.1))
    so = SimOpt(env, PPOConfig(num_envs=8, num_steps=8, num_minibatches=2), dr, cfg)
    zt = jnp.asarray(env.z_of(**TRUTH))
    st = so.init(jax.random.PRNGKey(0))
    real = jax.jit(lambda s: so.target_rollouts(s, zt, jax.random.PRNGKey(3), 2))(st)
    return so, st, zt, real


def test_target_rollouts_take_their_own_horizon(simopt):
    # the reported return uses whole episodes even when the discrepancy compares fewer steps
    so, st, zt, real = simopt
    assert real.signals.shape[1] == so.horizon
    longer = jax.jit(lambda s: so.target_rollouts(s, zt, jax.random.PRNGKey(3), 2, horizon=so.horizon + 7))(st)
    assert longer.signals.shape[1] == so.horizon + 7
    np.testing.assert_allclose(np.asarray(longer.signals[:, :so.horizon]), np.asarray(real.signals), atol=1e-6)


def test_discrepancy_is_zero_at_the_truth(simopt):
    so, st, zt, real = simopt
    xi = jnp.array([[0.4, 1.5], [0.0, 1.0], [0.4, 1.0], [0.0, 1.5]])
    c = np.asarray(jax.jit(lambda x: so.costs(st, x, real, jax.random.PRNGKey(1)))(xi))
    assert c[0] < 1e-3 * c[1:].min()


def test_reps_moves_the_distribution_to_the_hidden_physics(simopt):
    so, st, zt, real = simopt
    st2, info = jax.jit(lambda s: so.adapt(s, real))(st)
    assert np.all(np.asarray(info["kl"]) <= so.cfg.epsilon + 1e-4)
    before = np.abs(np.asarray(st.mean) - np.array([0.4, 1.5])) / so.init_std
    after = np.abs(np.asarray(st2.mean) - np.array([0.4, 1.5])) / so.init_std
    assert after[0] < 0.25 * before[0]  # the offset is found (the mass is weakly observable here)
    assert after.sum() < before.sum()


@pytest.mark.slow  # compiles PPO training + target rollouts + REPS as one program (~1.5 min on 2 cores)
def test_iteration_is_jittable_and_vmaps_over_seeds(simopt):
    so, _, zt, _ = simopt
    st = jax.jit(jax.vmap(so.init))(jax.random.split(jax.random.PRNGKey(0), 2))
    st2, m = jax.jit(jax.vmap(lambda s: so.iteration(s, zt)))(st)
    assert m["mean"].shape == (2, 2) and m["reps_kl"].shape == (2, so.cfg.reps_updates)
    assert not np.allclose(np.asarray(st2.mean[0]), np.asarray(st2.mean[1]))  # seeds differ
    assert np.all(np.isfinite(np.asarray(st2.cov)))


def test_recordings_round_trip_and_errors(simopt, tmp_path):
    so, st, zt, real = simopt
    paths = save_recordings(so, real, str(tmp_path))
    back = real_from_recordings(so, paths)
    np.testing.assert_allclose(np.asarray(back.signals), np.asarray(real.signals), atol=1e-6)
    np.testing.assert_allclose(np.asarray(back.qpos0), np.asarray(real.qpos0), atol=1e-6)
    # the recorded real side gives the same costs as the live target
    xi = jnp.array([[0.4, 1.5], [0.0, 1.0]])
    f = jax.jit(lambda r: so.costs(st, xi, r, jax.random.PRNGKey(1)))
    np.testing.assert_allclose(np.asarray(f(back)), np.asarray(f(real)), rtol=1e-4, atol=1e-4)
    bad = os.path.join(str(tmp_path), "bad.csv")
    with open(paths[0]) as f:
        lines = f.read().splitlines()
    with open(bad, "w") as f:  # drop the qpos column
        for ln in lines:
            f.write(",".join(v for j, v in enumerate(ln.split(",")) if j != 1) + "\n")
    with pytest.raises(RecordingError, match="bad.csv"):
        real_from_recordings(so, [bad])


def test_recordings_without_qvel_differentiate_positions_as_the_diagnosis_does(simopt, tmp_path):
    """No ``qvel`` columns: velocities are the Trajectory's Savitzky-Golay derivative of the
    positions; a recording too short to differentiate is refused by name (by the reader)."""
    so, st, zt, real = simopt
    paths = save_recordings(so, real, str(tmp_path))
    stripped = []
    for i, path in enumerate(paths):
        with open(path) as f:
            rows = [ln.split(",") for ln in f.read().splitlines()]
        keep = [j for j, h in enumerate(rows[0]) if not h.startswith("qvel:")]
        stripped.append(os.path.join(str(tmp_path), f"noqvel_{i}.csv"))
        with open(stripped[-1], "w") as f:
            f.write("\n".join(",".join(r[j] for j in keep) for r in rows) + "\n")
    back = real_from_recordings(so, stripped)
    nq = so.env.mj_model.nq
    q_back, q_real = np.asarray(back.signals[..., :nq]), np.asarray(real.signals[..., :nq])
    np.testing.assert_allclose(q_back, q_real, atol=1e-6)
    v_back, v_real = np.asarray(back.signals[..., nq:]), np.asarray(real.signals[..., nq:])
    assert np.sqrt(np.mean((v_back - v_real) ** 2)) < 0.1 * np.sqrt(np.mean(v_real ** 2))
    short = os.path.join(str(tmp_path), "short.csv")
    with open(stripped[0]) as f:
        lines = f.read().splitlines()[:6]  # header + 5 rows
    with open(short, "w") as f:
        f.write("\n".join(lines) + "\n")
    with pytest.raises(RecordingError, match="short.csv: only 5 samples"):
        real_from_recordings(so, [short])


def test_bad_config_is_named():
    env = make("pendulum")
    dr = DRConfig(params=("mass:pole",), low=(0.3,), high=(3.0,))
    with pytest.raises(ValueError, match="init_mean"):
        SimOpt(env, PPOConfig(), dr, SimOptConfig(init_mean=(1.0, 2.0)))
    with pytest.raises(ValueError, match="signal_weights"):
        SimOpt(env, PPOConfig(), dr, SimOptConfig(signal_weights=(1.0,)))
    with pytest.raises(KeyError, match="mass:pol"):
        SimOpt(env, PPOConfig(), DRConfig(params=("mass:pol",), low=(0.3,), high=(3.0,)), SimOptConfig())


# ------------------------------------------------------------------------------ the driver ----
@pytest.mark.slow  # four driver runs; tracing the vmapped SimOpt iteration takes ~30 s each on 2 cores
def test_driver_interrupted_and_resumed_equals_uninterrupted(tmp_path):
    """SimOpt run by the one training driver (``algo: simopt``): stop after two iterations, resume,
    end as an uninterrupted run (state, per-iteration metrics.csv and the distribution history in
    arrays.npz); with recordings, ``resume=true`` may bring new ones (and nothing else)."""
    from sim2real.common import config as config_lib
    from sim2real.training.driver import TrainConfig, config_from_args, train

    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

    def cfg(*extra):
        return config_lib.load(TrainConfig, [
            f"config={root}/configs/simopt_pendulum.yaml", f"out_dir={tmp_path}", "progress=false",
            "tensorboard=false", "ppo.num_envs=8", "ppo.num_steps=16", "ppo.net.hidden=[16,16]",
            "algo_options.iterations=2", "algo_options.init_ppo_updates=3", "algo_options.ppo_updates=2",
            "algo_options.num_samples=16", "algo_options.eval_episodes=0", *extra])

    full = train(cfg("name=full"))
    part = train(cfg("name=part", "max_chunks=2"))
    assert not part["finished"]
    resumed = train(cfg("name=part", "resume=true"))
    assert resumed["finished"]
    for a, b in zip(jax.tree_util.tree_leaves(full["state"]), jax.tree_util.tree_leaves(resumed["state"])):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    lines = [open(tmp_path / n / "metrics.csv").read().splitlines() for n in ("full", "part")]
    assert len(lines[0]) == 1 + 3 and "mean:sensor_offset:hinge" in lines[0][0]
    drop = lambda ln: [v for j, v in enumerate(ln.split(",")) if j != 3]  # (not the wall-clock column)
    assert [drop(x) for x in lines[0]] == [drop(x) for x in lines[1]]
    d_full, d_part = (np.load(tmp_path / n / "arrays.npz") for n in ("full", "part"))
    assert d_full["dist_mean"].shape == (1, 3, 2) and d_full["dist_cov"].shape == (1, 3, 2, 2)
    for k in ("dist_mean", "dist_cov"):
        np.testing.assert_array_equal(d_full[k], d_part[k])

    # the hardware loop: one iteration per call, each on recordings of the policy the last one wrote
    so = full["algo"]
    st = jax.tree_util.tree_map(lambda x: x[0], full["state"])
    zt = jnp.asarray(so.z_target)
    paths = save_recordings(so, so.target_rollouts(st, zt, jax.random.PRNGKey(3), 2), str(tmp_path / "rec"))
    hw = cfg("name=hw", "algo_options.real=recordings", "algo_options.target={}",
             f"algo_options.recordings=[{','.join(paths)}]")
    first = train(hw)
    again = config_from_args([f"out_dir={tmp_path}", "name=hw", "resume=true", f"algo_options.recordings=[{paths[0]}]"])
    assert again.algo_options["recordings"] == [paths[0]] or again.algo_options["recordings"] == (paths[0],)
    second = train(again)
    rows = open(tmp_path / "hw" / "metrics.csv").read().splitlines()
    assert [r.split(",")[0] for r in rows[1:]] == ["0", "1"]
    assert not all(np.array_equal(np.asarray(a), np.asarray(b)) for a, b in
                   zip(jax.tree_util.tree_leaves(first["state"]), jax.tree_util.tree_leaves(second["state"])))
    with pytest.raises(config_lib.ConfigError, match="algo_options.num_samples"):
        config_from_args([f"out_dir={tmp_path}", "name=hw", "resume=true", "algo_options.num_samples=8"])


@pytest.mark.slow  # 40-67 s on 2 cores; moved 2026-12-06 when the suite took 969 s (SimOpt's own tests stay)
def test_simopt_runs_through_the_training_script(tmp_path, capsys):
    """``python scripts/train.py config=configs/simopt_pendulum.yaml``: SimOpt is an outer loop of the
    one driver; its run folder is read back like any other (``load_policy``)."""
    import importlib.util

    from sim2real.training.runs import load_policy

    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    spec = importlib.util.spec_from_file_location("train_script", os.path.join(root, "scripts", "train.py"))
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    script.main([f"config={root}/configs/simopt_pendulum.yaml", f"out_dir={tmp_path}", "name=so", "progress=false",
                 "tensorboard=false", "ppo.num_envs=8", "ppo.num_steps=16", "ppo.net.hidden=[16,16]",
                 "algo_options.iterations=1", "algo_options.init_ppo_updates=2", "algo_options.ppo_updates=1",
                 "algo_options.num_samples=16", "algo_options.eval_episodes=2", "algo_options.horizon=20"])
    assert "run folder" in capsys.readouterr().out
    rows = open(tmp_path / "so" / "metrics.csv").read().splitlines()
    assert len(rows) == 1 + 2  # iterations + 1 updates, one seed
    head = rows[0].split(",")
    for col in ("mean:sensor_offset:hinge", "std:mass:pole", "eval_return", "reps_kl"):
        assert col in head
    # REPS moved the distribution away from its start after the first iteration
    first, second = (dict(zip(head, r.split(","))) for r in rows[1:])
    assert float(first["mean:sensor_offset:hinge"]) == 0.0
    assert float(second["mean:sensor_offset:hinge"]) != 0.0 and np.isfinite(float(second["eval_return"]))
    cfg, env, algo, params, stats = load_policy(str(tmp_path / "so"))
    assert cfg.algo == "simopt" and type(algo).__name__ == "SimOpt"
    assert jax.tree_util.tree_leaves(params)[0].shape[0] == 1
