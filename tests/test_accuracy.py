"""The hopper's tuned MJX settings stay close to MuJoCo run with default settings.

Reference: native MuJoCo as Gymnasium runs Hopper-v5 (RK4, 2 ms x 4, 100 solver iterations).
Tuned: the env's defaults (Euler, 4 ms x 2, 2 Newton iterations, 4 line-search steps).
Open-loop random torques make the hopper tumble, so trajectories are compared over 0.2 s (25 control
steps) from 8 random initial states; the yardstick is the error of switching only the integrator
to Euler at 2 ms with default solver settings.
"""
import copy

import jax
import mujoco
import numpy as np
import pytest

from conftest import env_for, run_rows, smooth_actions

H = 25


def native(env, qpos0, qvel0, actions, dt, frame_skip, iterations, ls_iterations, integrator):
    m = copy.copy(env.mj_model)
    m.opt.timestep, m.opt.iterations, m.opt.ls_iterations = dt, iterations, ls_iterations
    m.opt.integrator = integrator
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:] = qpos0, qvel0
    out = []
    for a in np.asarray(actions)[:H]:
        d.ctrl[:] = a
        for _ in range(frame_skip):
            mujoco.mj_step(m, d)
        out.append(d.qpos.copy())
    return np.array(out)


@pytest.mark.optimized  # runs long (see conftest.py)
def test_tuned_hopper_close_to_default_mujoco():
    env = env_for("hopper")
    acts = smooth_actions(env, 40)
    tuned_err, euler_err = [], []
    for seed in range(8):
        key = jax.random.PRNGKey(seed)
        s0 = env.reset(key, env.default_z())
        q0, v0 = np.asarray(s0.data.qpos), np.asarray(s0.data.qvel)
        mjx_q = run_rows("hopper", env.default_z()[None], key)["qpos"][0][:H]
        ref = native(env, q0, v0, acts, 0.002, 4, 100, 50, mujoco.mjtIntegrator.mjINT_RK4)
        euler = native(env, q0, v0, acts, 0.002, 4, 100, 50, mujoco.mjtIntegrator.mjINT_EULER)
        tuned_err.append(np.abs(mjx_q - ref).max())
        euler_err.append(np.abs(euler - ref).max())
    tuned_err, euler_err = np.array(tuned_err), np.array(euler_err)
    # measured here: tuned median 0.025 / max 0.032, Euler-at-2ms median 0.012 (in a sweep with
    # other action sequences 1 solver iteration reached 0.29 and 8 ms single steps 0.46)
    assert np.median(tuned_err) < 0.06 and tuned_err.max() < 0.15, tuned_err
    assert np.median(tuned_err) < 4 * np.median(euler_err), (tuned_err, euler_err)
