"""Envs: MJX vs native MuJoCo parity, physics that matters, no retrace, no NaN at the corners."""
import functools

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest

from conftest import T_ROLLOUT, env_for, run_rows, smooth_actions
from sim2real.envs.autoreset import step_autoreset
from sim2real.physics.model_apply import to_mjmodel

ENVS = ["pendulum", "cartpole", "arm2", "prismatic", "hopper", "halfcheetah"]
CONTACT = {"hopper", "halfcheetah"}
T = T_ROLLOUT


def modified_z(env):
    """Nominal parameters moved off their defaults (masses, damping, gains, friction, gravity)."""
    vals = {"gravity": 9.0}
    for p in env.spec.params:
        if p.kind == "body_mass":
            vals[p.name] = p.default * 1.3
        elif p.kind == "joint_damping":
            vals[p.name] = p.default * 2 + 0.01
        elif p.kind == "actuator_gain":
            vals[p.name] = p.default * 0.8
        elif p.kind == "geom_friction":
            vals[p.name] = p.default * 0.7
    return env.z_of(**vals)


def corners(env):
    """Each parameter alone at its low and at its high bound, plus all-low and all-high."""
    spec = env.spec
    rows = []
    for i in range(len(spec)):
        for bound in (spec.low[i], spec.high[i]):
            z = spec.default.copy()
            z[i] = bound
            rows.append(z)
    return np.stack(rows + [spec.low.copy(), spec.high.copy()])


@functools.lru_cache(maxsize=None)
def results(name):
    """One compiled batch per env: row 0 default, row 1 modified, rows 2.. the corners."""
    env = env_for(name)
    zs = np.concatenate([env.default_z()[None], modified_z(env)[None], corners(env)])
    key = jax.random.PRNGKey(0)
    return zs, smooth_actions(env, T), key, run_rows(name, zs, key)


def native_rollout(env, z, key, actions):
    m = to_mjmodel(env.physics, z)
    s0 = env.reset(key, jnp.asarray(z))
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:] = np.asarray(s0.data.qpos), np.asarray(s0.data.qvel)
    out = []
    for a in np.asarray(actions):
        d.ctrl[:] = np.clip(a, env.ctrl_low, env.ctrl_high)
        for _ in range(env.config.frame_skip):
            mujoco.mj_step(m, d)
        out.append(d.qpos.copy())
    return np.array(out)


@pytest.mark.parametrize("name", ENVS)
def test_mjx_matches_native_mujoco(name):
    """Same physics and actions -> same trajectory (contact envs: first 20 steps, chaos after)."""
    env = env_for(name)
    zs, acts, key, out = results(name)
    horizon, tol = (20, 5e-3) if name in CONTACT else (T, 1e-4)
    for row in (0, 1):
        ref = native_rollout(env, zs[row], key, acts)
        err = np.abs(out["qpos"][row][:horizon] - ref[:horizon]).max()
        scale = max(1.0, np.abs(ref).max())
        assert err / scale < tol, f"{name} row {row}: err {err}"


@pytest.mark.parametrize("name", ENVS)
def test_different_physics_different_trajectory(name):
    _, _, _, out = results(name)
    assert np.abs(out["qpos"][0] - out["qpos"][1]).max() > 1e-3


@pytest.mark.parametrize("name", ENVS)
def test_no_nan_at_parameter_corners(name):
    """Every parameter at each bound (others default), all-low and all-high: nothing non-finite."""
    _, _, _, out = results(name)
    for k in ("qpos", "qvel", "obs", "reward"):
        assert np.isfinite(out[k][2:]).all(), k


def test_hopper_terminates_without_truncating():
    _, _, _, out = results("hopper")
    assert out["terminated"][0].any()          # random torques make it fall
    assert not out["truncated"][0].any()       # 40 steps is far from the 1000-step limit


def test_time_limit_truncates_not_terminates(key):
    env = env_for("pendulum").__class__(episode_length=5)
    z = jnp.asarray(env.default_z())
    s = env.reset(key, z)
    flags = []
    for _ in range(5):
        s = env.step(s, jnp.zeros(1), z)
        flags.append((bool(s.terminated), bool(s.truncated)))
    assert flags[:4] == [(False, False)] * 4 and flags[4] == (False, True)


def test_diverged_physics_terminates_and_stays_finite(key):
    env = env_for("pendulum")
    z = jnp.asarray(env.default_z())
    s = env.reset(key, z)
    s1 = env.step(s, jnp.array([jnp.nan]), z)
    assert bool(s1.terminated) and float(s1.metrics["diverged"]) == 1.0
    assert np.isfinite(np.asarray(s1.obs)).all() and np.isfinite(np.asarray(s1.data.qpos)).all()
    np.testing.assert_array_equal(np.asarray(s1.data.qpos), np.asarray(s.data.qpos))


def test_no_retrace_when_physics_or_distribution_changes(key):
    """Changing z, or the parameters of the distribution z is drawn from, reuses the trace."""
    env = env_for("pendulum")
    traces = []
    idx = env.spec.index("mass:pole")
    base = jnp.asarray(env.default_z())

    @jax.jit
    def run(state, z, key, lo, hi):
        traces.append(1)
        sample = lambda k: base.at[idx].set(jax.random.uniform(k, (), minval=lo, maxval=hi))
        keys = jax.random.split(key, z.shape[0])
        step = lambda s, zz, k: step_autoreset(env, s, zz, jnp.ones(1), k, sample)
        return jax.vmap(step)(state, z, keys)

    B = 4
    zs = jnp.tile(base, (B, 1))
    state = jax.vmap(env.reset)(jax.random.split(key, B), zs)
    out1 = run(state, zs, key, 0.5, 1.5)
    zs2 = zs.at[:, idx].set(jnp.array([0.3, 0.6, 1.2, 2.0]))
    out2 = run(state, zs2, key, 2.0, 3.0)
    assert len(traces) == 1
    assert not np.allclose(np.asarray(out1[0].data.qpos), np.asarray(out2[0].data.qpos))


def test_reset_draws_new_physics(key):
    """On done the auto-reset samples z from the sampler, in jit."""
    env = env_for("pendulum").__class__(episode_length=1)
    idx = env.spec.index("mass:pole")
    base = jnp.asarray(env.default_z())
    sample = lambda k: base.at[idx].set(jax.random.uniform(k, (), minval=2.0, maxval=3.0))
    s = env.reset(key, base)
    s2, z2, tr, done = jax.jit(lambda s, z, k: step_autoreset(env, s, z, jnp.zeros(1), k, sample))(s, base, key)
    assert bool(done) and bool(tr.truncated)
    assert 2.0 <= float(z2[idx]) <= 3.0 and int(s2.t) == 0
    assert float(tr.z[idx]) == pytest.approx(1.0)  # the finished step ran under the old physics


def test_an_env_module_is_found_by_its_name_without_a_registry_line(tmp_path, monkeypatch):
    import sim2real.envs as pkg
    from sim2real.envs import registry

    (tmp_path / "toy_env.py").write_text(
        "from sim2real.envs.pendulum import Pendulum\n\n\nclass Toy(Pendulum):\n    name = 'toy_pendulum'\n")
    monkeypatch.setattr(pkg, "__path__", [*pkg.__path__, str(tmp_path)])
    monkeypatch.setattr(registry, "_ENVS", {})
    assert "toy_pendulum" in registry.names() and "pendulum" in registry.names()
    assert registry.make("toy_pendulum").name == "toy_pendulum"
    monkeypatch.setattr(registry, "_ENVS", {})  # (the next lookup reloads without the toy)
