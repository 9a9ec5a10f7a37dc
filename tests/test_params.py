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
    with pytest.raises(TypeError, match="frame_skp"):
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
