"""Parameter spec: names, bounds, shapes, and the errors users see."""
import numpy as np
import pytest

from conftest import env_for
from sim2real.envs import make
from sim2real.physics.params import Subspace, clip


def test_unknown_env_lists_known_names():
    with pytest.raises(KeyError) as e:
        make("hoper")
    msg = str(e.value)
    assert "hoper" in msg and "'hopper'" in msg and "pendulum" in msg


def test_unknown_env_option():
    with pytest.raises(ValueError, match="frame_skp.*Did you mean: env_options.frame_skip"):
        make("pendulum", frame_skp=3)


def test_unknown_parameter_suggests_nearest():
    env = env_for("hopper")
    with pytest.raises(KeyError) as e:
        env.z_of(torso_sise=0.1)
    assert "'torso_size'" in str(e.value) and "density" in str(e.value)


@pytest.mark.parametrize("value", [-0.2, 0.9, float("nan")])
def test_out_of_bounds_value_rejected_with_bounds(value):
    env = env_for("hopper")
    with pytest.raises(ValueError) as e:
        env.z_of(torso_size=value)
    assert "torso_size" in str(e.value)


def test_wrong_shape_rejected():
    env = env_for("pendulum")
    with pytest.raises(ValueError, match=rf"expected \[\.\.\., {len(env.spec)}\]"):
        env.check_z(np.zeros(3))
    with pytest.raises(ValueError, match="joint_damping"):
        z = env.default_z()
        z[env.spec.index("joint_damping")] = -1.0
        env.check_z(z)


def test_every_default_inside_bounds_and_clip_rule():
    for name in ["pendulum", "hopper", "prismatic"]:
        spec = env_for(name).spec
        assert np.all(spec.low <= spec.default) and np.all(spec.default <= spec.high)
        far = np.where(np.arange(len(spec)) % 2 == 0, spec.high * 10 + 10, spec.low * 10 - 10)
        clipped = np.asarray(clip(spec, far))
        assert np.all(clipped <= spec.high) and np.all(clipped >= spec.low)


def test_subspace_expand_take_roundtrip():
    spec = env_for("hopper").spec
    sub = Subspace(spec, ("torso_size", "friction"))
    full = np.asarray(sub.expand(np.array([[0.07, 1.5]])))
    assert full.shape == (1, len(spec))
    np.testing.assert_allclose(np.asarray(sub.take(full)), [[0.07, 1.5]])
    rest = np.delete(full[0], sub.idx)
    np.testing.assert_array_equal(rest, np.delete(spec.default, sub.idx))
    with pytest.raises(KeyError):
        Subspace(spec, ("torso",))


def test_out_of_bounds_terminate_rule():
    """``out_of_bounds='terminate'``: a z outside the bounds ends the episode at its first step with
    reward 0 (counted as diverged); inside the bounds it steps exactly as the default ``clip`` env."""
    import jax
    import jax.numpy as jnp

    with pytest.raises(ValueError, match="out_of_bounds='drop'.*terminate"):
        make("pendulum", out_of_bounds="drop")
    clip_env, term_env = env_for("pendulum"), make("pendulum", out_of_bounds="terminate")
    inside = jnp.asarray(clip_env.default_z())
    outside = inside.at[clip_env.spec.index("joint_damping")].set(-0.5)
    act = jnp.array([0.3])

    def one(env, z):
        s = env.reset(jax.random.PRNGKey(0), z)
        return env.step(s, act, z)

    a, b = jax.jit(lambda z: one(clip_env, z))(inside), jax.jit(lambda z: one(term_env, z))(inside)
    for x, y in zip(jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b)):
        np.testing.assert_array_equal(np.asarray(x), np.asarray(y))
    assert not bool(b.terminated)
    c = jax.jit(lambda z: one(clip_env, z))(outside)  # clipped to damping 0: simulates on
    d = jax.jit(lambda z: one(term_env, z))(outside)
    assert not bool(c.terminated) and float(c.metrics["diverged"]) == 0.0
    assert bool(d.terminated) and not bool(d.truncated)
    assert float(d.reward) == 0.0 and float(d.metrics["diverged"]) == 1.0


def test_spec_prints_every_parameter_with_its_bounds():
    from sim2real.envs import make

    spec = make("pendulum").spec
    lines = str(spec).splitlines()
    assert len(lines) == len(spec) + 1                      # header + one row each
    for line, p in zip(lines[1:], spec.params):
        assert line.split()[0] == p.name and f"{p.high:.4g}" in line
