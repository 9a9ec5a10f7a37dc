"""ADR: the bound rule on given buffers, and bounds that follow what the policy can do on a toy."""
import jax.numpy as jnp
import numpy as np
import pytest
from conftest import BALANCE

from sim2real.common import config as config_lib
from sim2real.envs import make
from sim2real.training.driver import TrainConfig, build_algo, train



def adr_for(*extra):
    cfg = config_lib.load(TrainConfig, ["env=pendulum", "algo=adr", "dr.params=[mass:pole,coulomb:hinge]",
                                        "dr.low=[0.2,0.0]", "dr.high=[3.0,1.0]", "ppo.num_envs=8", "ppo.num_steps=8",
                                        "ppo.num_minibatches=2", "algo_options.t_low=-300",
                                        "algo_options.t_high=-100", "algo_options.buffer_size=4", *extra])
    return build_algo(cfg, make("pendulum"))


def test_full_buffers_move_their_bound_and_empty():
    """Mass: both sides good -> both widen by step x width; Coulomb: lower side bad, upper side not
    yet full -> only the lower bound moves inwards; between the thresholds nothing moves."""
    algo = adr_for("algo_options.step=0.1")
    low, high = jnp.array([1.0, 0.4]), jnp.array([1.2, 0.6])
    buf_n = jnp.array([[4.0, 5.0], [4.0, 3.0]])
    buf_sum = jnp.array([[-50.0, -90.0], [-400.0, -4000.0]]) * buf_n
    lo, hi, s, n = algo.move_bounds(low, high, buf_sum, buf_n)
    np.testing.assert_allclose(lo, [1.0 - 0.28, 0.5], atol=1e-6)
    np.testing.assert_allclose(hi, [1.2 + 0.28, 0.6], atol=1e-6)
    np.testing.assert_array_equal(n, [[0, 0], [0, 3]])
    np.testing.assert_array_equal(s, [[0, 0], [0, -12000]])
    # between the thresholds: the buffer empties, the bound stays
    lo, hi, _, n = algo.move_bounds(low, high, jnp.full((2, 2), -200.0 * 4), jnp.full((2, 2), 4.0))
    np.testing.assert_allclose(lo, low)
    np.testing.assert_allclose(hi, high)
    assert float(n.sum()) == 0


def test_bounds_stay_in_the_limit_box_and_never_cross():
    algo = adr_for("algo_options.step=0.5")
    full = jnp.full((2, 2), 4.0)
    lo, hi, _, _ = algo.move_bounds(jnp.array([0.3, 0.1]), jnp.array([2.9, 0.9]), full * -10.0, full)
    np.testing.assert_allclose(lo, [0.2, 0.0])  # widened past the limit: clipped to it
    np.testing.assert_allclose(hi, [3.0, 1.0])
    lo, hi, _, _ = algo.move_bounds(jnp.array([1.0, 0.4]), jnp.array([1.5, 0.5]), full * -1000.0, full)
    np.testing.assert_allclose(lo, hi)           # both shrink past each other: they meet half-way
    np.testing.assert_allclose(lo, [1.25, 0.45])


def test_bad_settings_are_refused_by_name():
    with pytest.raises(ValueError, match="t_low"):
        adr_for("algo_options.t_low=0", "algo_options.t_high=-1")
    with pytest.raises(ValueError, match="init_low/init_high for 'mass:pole'"):
        adr_for("algo_options.init_low=[0.1,0]", "algo_options.init_high=[1,0]")
    with pytest.raises(ValueError, match="num_evals"):
        adr_for("algo_options.num_evals=3")


def test_a_tiny_adr_run_writes_bounds_inside_the_limit_box(tmp_path):
    """ADR through the training driver at toy size (its jitted outer step, the arrays it writes):
    the bounds of every update lie inside the limit box, low <= high."""
    cfg = config_lib.load(TrainConfig, BALANCE + [
        f"out_dir={tmp_path}", "name=adr", "algo=adr", "total_steps=16384", "progress=false", "tensorboard=false",
        "ppo.num_envs=16", "ppo.num_steps=16", "ppo.net.hidden=[16]", "algo_options.init_low=[0.4]",
        "algo_options.init_high=[0.6]", "algo_options.num_evals=4", "algo_options.buffer_size=2"])
    train(cfg)
    with np.load(tmp_path / "adr" / "arrays.npz") as f:
        low, high = f["adr_low"][0, :, 0], f["adr_high"][0, :, 0]
    assert len(low) >= 2 and np.isfinite(low).all() and np.isfinite(high).all()
    assert (0.2 <= low).all() and (low <= high).all() and (high <= 3.0).all()


# ~60 s on 2 cores (make test-slow); the fast set keeps the bounds' update rules and the tiny run above
@pytest.mark.slow
def test_bounds_follow_what_the_motor_can_hold(tmp_path):
    """2 Nm holds a light pole upright but not a heavy one: from [0.4, 0.6] kg the lower bound
    must reach the limit box's 0.2 kg, the upper one grow but stop well short of its 3 kg."""
    cfg = config_lib.load(TrainConfig, BALANCE + [
        f"out_dir={tmp_path}", "name=adr", "algo=adr", "total_steps=600_000", "progress=false", "tensorboard=false",
        "checkpoint_every=100", "seed=0", "algo_options.init_low=[0.4]", "algo_options.init_high=[0.6]",
        "algo_options.t_low=-300", "algo_options.t_high=-100", "algo_options.num_evals=16",
        "algo_options.buffer_size=8"])
    train(cfg)
    with np.load(tmp_path / "adr" / "arrays.npz") as f:
        low, high = f["adr_low"][0, :, 0], f["adr_high"][0, :, 0]
    assert low[-1] <= 0.25, low
    assert 0.9 <= high[-1] <= 2.4, high
    assert np.all(low <= high)
