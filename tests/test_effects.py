"""Effects library: exactly neutral when off, and each one changes the dynamics the way it should."""
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from mujoco import mjx

from conftest import T_ROLLOUT, env_for, run_rows, smooth_actions
from sim2real.physics.catalog import ACTUATOR_EFFECTS, BODY_EFFECTS, JOINT_EFFECTS

KEY = jax.random.PRNGKey(0)


def plain_mjx(env, z, actions):
    """Nominal physics with no effect code at all: clip the action, mjx.step frame_skip times."""
    m = env.physics.mx
    s0 = env.reset(KEY, jnp.asarray(z))

    def f(d, a):
        d = d.replace(ctrl=jnp.clip(a, env.ctrl_low, env.ctrl_high))
        d = jax.lax.fori_loop(0, env.config.frame_skip, lambda _, d: mjx.step(m, d), d)
        return d, d.qpos

    return np.asarray(jax.jit(lambda d, a: jax.lax.scan(f, d, a)[1])(s0.data, actions))


@pytest.mark.parametrize("name", ["pendulum", "arm2", "prismatic"])
def test_effects_off_is_bitwise_neutral(name):
    """At default z every effect function hands back its input bit for bit, and apply() the model."""
    env = env_for(name)
    z = jnp.asarray(env.default_z())
    fx = env.effects
    rng = np.random.default_rng(0)
    ctrl = jnp.asarray(rng.normal(size=env.action_size), jnp.float32)
    qpos = jnp.asarray(rng.normal(size=env.mj_model.nq), jnp.float32)
    qvel = jnp.asarray(rng.normal(size=env.mj_model.nv), jnp.float32)
    es = fx.init_state()
    n = env.config.frame_skip
    # (the backlash stage limits the command to its range, taking over MuJoCo's clamp: its own)
    limited = np.clip(np.asarray(ctrl), env.ctrl_low, env.ctrl_high)
    for _ in range(3):  # with a filled delay buffer too
        es = fx.push(es, ctrl)
        for j in range(n):
            u, es = fx.actuate(z, es, j, n, qpos, env.dt / n)
            np.testing.assert_array_equal(np.asarray(u), limited)
    _, extra = fx.velocity_damping(z, qvel)
    assert np.all(np.asarray(extra) == 0.0)
    np.testing.assert_array_equal(np.asarray(fx.sense(z, qpos, KEY)), np.asarray(qpos))
    m = env.physics.apply(z)
    for leaf_new, leaf_old in zip(jax.tree_util.tree_leaves(m), jax.tree_util.tree_leaves(env.physics.mx)):
        np.testing.assert_array_equal(np.asarray(leaf_new), np.asarray(leaf_old))


@pytest.mark.parametrize("name", ["pendulum", "arm2", "prismatic"])
def test_effects_off_matches_plain_mjx(name):
    """Whole trajectory vs a loop with no effect code (equal up to XLA's batch-vs-single rounding)."""
    env = env_for(name)
    out = run_rows(name, env.default_z()[None])
    ref = plain_mjx(env, env.default_z(), smooth_actions(env, T_ROLLOUT))
    np.testing.assert_allclose(out["qpos"][0], ref, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("name", ["pendulum", "cartpole", "arm2", "prismatic", "hopper", "halfcheetah"])
def test_every_env_exposes_every_effect(name):
    env = env_for(name)
    kinds = {p.kind for p in env.spec.params}
    assert set(JOINT_EFFECTS) | set(ACTUATOR_EFFECTS) | set(BODY_EFFECTS) <= kinds
    assert {"action_delay", "obs_noise", "gravity"} <= kinds


# --- pendulum: one torque motor with gear 1, so actuator_force is the applied command ------------
@pytest.fixture(scope="module")
def pend():
    env = env_for("pendulum")
    rows = {
        "nominal": {},
        "coulomb": {"coulomb:hinge": 3.0},
        "coulomb_pos": {"coulomb:hinge": 1.0, "coulomb_asym:hinge": 0.9},
        "coulomb_neg": {"coulomb:hinge": 1.0, "coulomb_asym:hinge": -0.9},
        "coulomb_soft": {"coulomb:hinge": 3.0, "coulomb_vel:hinge": 3.0},
        "coulomb_vel_eps": {"coulomb:hinge": 3.0, "coulomb_vel:hinge": 1e-3},
        "stribeck": {"coulomb:hinge": 1.5, "stribeck:hinge": 1.5, "stribeck_vel:hinge": 0.5},
        "viscous": {"viscous:hinge": 1.0},
        "stiffness": {"stiffness:hinge": 5.0},
        "backlash": {"backlash:motor": 0.3},
        "saturation": {"saturation:motor": 0.5},
        "motor_lag": {"motor_lag:motor": 0.2},
        "payload": {"payload:pole": 0.5},
        "delay1": {"action_delay": 1.0},
        "delay_half": {"action_delay": 0.5},
        "delay_0.9": {"action_delay": 0.9},
        "sensor_offset": {"sensor_offset:hinge": 0.3},
        "sensor_noise": {"sensor_noise:hinge": 0.05},
        "obs_noise": {"obs_noise": 0.1},
    }
    zs = np.stack([env.z_of(**v) for v in rows.values()])
    out = run_rows("pendulum", zs)
    res = {k: {f: out[f][i] for f in out} for i, k in enumerate(rows)}
    ctrl = np.clip(np.asarray(smooth_actions(env, T_ROLLOUT))[:, 0], -2, 2)
    return res, ctrl, env


def path_length(r):
    return np.abs(np.diff(r["qpos"][:, 0])).sum()


@pytest.mark.parametrize("kind", ["coulomb", "coulomb_pos", "stribeck", "viscous", "stiffness", "backlash",
                                  "saturation", "motor_lag", "payload", "delay1", "delay_half"])
def test_each_effect_changes_the_dynamics(pend, kind):
    res, _, _ = pend
    assert np.abs(res[kind]["qpos"] - res["nominal"]["qpos"]).max() > 1e-3


def test_dissipative_effects_reduce_motion(pend):
    res, _, _ = pend
    for kind in ("coulomb", "stribeck", "viscous"):
        assert path_length(res[kind]) < 0.9 * path_length(res["nominal"]), kind


def test_coulomb_asymmetry_acts_by_direction(pend):
    res, _, _ = pend
    a, b = res["coulomb_pos"]["qpos"], res["coulomb_neg"]["qpos"]
    assert np.abs(a - b).max() > 1e-2


def test_coulomb_onset_speed(pend):
    """``coulomb_vel``: the speed over which friction builds up. Left at 0 the plant's
    ``coulomb_eps`` (1e-3) serves, so setting it to that value changes nothing; a soft onset
    (3 rad/s, about the swing's speed) lets the pendulum move more than the same level with the
    default onset."""
    res, _, env = pend
    assert env.config.coulomb_eps == 1e-3
    np.testing.assert_allclose(res["coulomb_vel_eps"]["qpos"], res["coulomb"]["qpos"], atol=1e-6)
    assert path_length(res["coulomb"]) < 0.9 * path_length(res["coulomb_soft"])
    assert path_length(res["coulomb_soft"]) < path_length(res["nominal"])


def test_saturation_clamps_the_force(pend):
    res, ctrl, _ = pend
    assert np.abs(res["nominal"]["force"]).max() > 1.0
    assert np.abs(res["saturation"]["force"]).max() <= 0.5 + 1e-6


def test_delay_is_exact_whole_and_fractional(pend):
    """The pendulum runs 5 physics sub-steps per control step; ``force`` is the last sub-step's.
    A delay of 1 step applies the previous command; 0.5 step switches to the new command half
    way through the step (the last sub-step sees only the new one); 0.9 step puts the switch in
    the middle of the last sub-step, which then sees half of each."""
    res, ctrl, env = pend
    assert env.config.frame_skip == 5
    prev = np.concatenate([[0.0], ctrl[:-1]])
    np.testing.assert_allclose(res["delay1"]["force"][:, 0], prev, atol=1e-6)
    np.testing.assert_allclose(res["delay_half"]["force"][:, 0], ctrl, atol=1e-6)
    np.testing.assert_allclose(res["delay_0.9"]["force"][:, 0], 0.5 * ctrl + 0.5 * prev, atol=1e-6)


def test_motor_lag_is_first_order_filter(pend):
    res, ctrl, env = pend
    alpha = 1 - np.exp(-env.dt / 0.2)
    u, want = 0.0, []
    for c in ctrl:
        u = u + alpha * (c - u)
        want.append(u)
    np.testing.assert_allclose(res["motor_lag"]["force"][:, 0], want, atol=1e-5)


def test_backlash_withholds_torque_until_the_band_is_crossed(pend):
    res, ctrl, _ = pend
    assert res["nominal"]["force"][0, 0] != 0.0
    assert res["backlash"]["force"][0, 0] == 0.0           # first step: motor still inside the band
    assert (res["backlash"]["force"][:, 0] != 0).any()     # later the band is crossed


def test_a_backlash_motor_side_moves_with_its_joints_corrected_velocity():
    """``Effects.rebase``: the diagnosis replays the command path with estimated joint velocities
    and starts each prediction from refined ones; the backlash's motor side, dragged along by
    its joint, moves by as much (its gap does not), and the delay line and lag keep theirs."""
    env = env_for("arm2")
    fx = env.effects
    es = fx.init_state()
    es["backlash"] = (jnp.array([0.01, -0.02]), jnp.array([1.0, -2.0])) + tuple(es["backlash"][2:])
    dv = jnp.array([0.3, -0.5])  # shoulder, elbow: each motor drives its own joint
    out = fx.rebase(es, dv)
    np.testing.assert_allclose(out["backlash"][1], [1.3, -2.5], rtol=1e-6)
    np.testing.assert_array_equal(out["backlash"][0], es["backlash"][0])
    for name in set(es) - {"backlash"}:
        for a, b in zip(jax.tree_util.tree_leaves(out[name]), jax.tree_util.tree_leaves(es[name])):
            np.testing.assert_array_equal(a, b)


def test_sensor_effects_touch_measurements_not_physics(pend):
    res, _, _ = pend
    nominal = res["nominal"]
    for kind in ("sensor_offset", "sensor_noise", "obs_noise"):
        np.testing.assert_array_equal(res[kind]["qpos"], nominal["qpos"])
        assert np.abs(res[kind]["obs"] - nominal["obs"]).max() > 1e-3, kind
    # the offset is exact: the observed angle is the true one plus 0.3
    th_obs = np.arctan2(res["sensor_offset"]["obs"][:, 1], res["sensor_offset"]["obs"][:, 0])
    th = np.arctan2(np.sin(nominal["qpos"][:, 0] + 0.3), np.cos(nominal["qpos"][:, 0] + 0.3))
    np.testing.assert_allclose(th_obs, th, atol=1e-5)
    noise = res["obs_noise"]["obs"] - nominal["obs"]
    assert 0.05 < noise.std() < 0.2


def test_payload_adds_mass_at_the_body():
    env = env_for("arm2")
    m = env.physics.apply(jnp.asarray(env.z_of(**{"payload:lower": 0.4})))
    np.testing.assert_allclose(float(m.body_mass[2]), 1.0, rtol=1e-6)     # 0.6 + 0.4
    np.testing.assert_allclose(float(m.body_subtreemass[1]), 2.0, rtol=1e-6)


def test_servo_backlash_leaves_a_dead_band():
    """Prismatic servo: a target inside the band gets no spring force, so the carriage stays put."""
    env = env_for("prismatic")

    @jax.jit
    def final_q(z):
        s = env.reset(KEY, z)
        target = s.data.qpos + 0.001  # 1 mm away; the band is +-2 mm
        s = jax.lax.fori_loop(0, 30, lambda _, s: env.step(s, target, z), s)
        return s.data.qpos[0] - target[0]

    nominal = float(final_q(jnp.asarray(env.default_z())))
    with_band = float(final_q(jnp.asarray(env.z_of(**{"backlash:drive": 0.004}))))
    assert abs(nominal) < 1e-4          # the servo reaches the target
    assert abs(with_band) > 0.9e-3      # the target sits inside the band: no motion


def test_a_stage_left_out_while_off_gives_what_it_gives_off():
    """``Effects.actuate(skip=...)`` runs ``Kind.command_off`` in place of a stage that is off: the
    command it passes on is the stage's own at 0 (the backlash's limited to the command range),
    whatever the stage's memory holds (here filled with a band, a lag and a delay on)."""
    env = env_for("pendulum")
    fx, n = env.effects, env.config.frame_skip
    assert "backlash" in fx.skippable
    z_on = jnp.asarray(env.z_of(**{"backlash:motor": 0.05, "motor_lag:motor": 0.03, "action_delay": 1.5}))
    z_off = jnp.asarray(env.default_z())
    qpos, qvel = jnp.asarray([0.3]), jnp.asarray([-1.0])
    es = fx.init_state()
    for u in (0.7, -3.0, 2.5):   # the last beyond the command range
        es = fx.push(es, jnp.asarray([u * env.ctrl_high[0]], jnp.float32))
        for j in range(n):
            _, es = fx.actuate(z_on, es, j, n, qpos, env.dt / n, qvel)
    assert float(jnp.abs(es["backlash"][0]).max()) > 0            # the memory is not the rest state
    for j in range(n):
        full, _ = fx.actuate(z_off, es, j, n, qpos, env.dt / n, qvel)
        skipped, _ = fx.actuate(z_off, es, j, n, qpos, env.dt / n, qvel, skip=tuple(fx.stage_rows))
        np.testing.assert_array_equal(np.asarray(skipped), np.asarray(full))


def test_a_new_command_path_stage_is_one_plug_in(monkeypatch):
    """A kind with a ``command`` hook joins the command path at its ``command_order`` with nothing
    else changed: declared on every actuator, neutral at its default, acting after the delay line."""
    from sim2real.envs import make
    from sim2real.physics import catalog, kinds
    from sim2real.physics.kinds.base import ACTUATOR, Kind, rows, take

    class CommandBias(Kind):  # (a toy: a constant bias added to the command)
        owns = ("command_bias",)
        attach = ACTUATOR
        declares = {"command_bias": (0.0, -1.0, 1.0, "actuator units", "constant bias on the command")}
        order = 64
        command_order = 15  # after the delay line, before the motor lag

        def command_setup(self, m, spec, cfg):
            return {"rows": rows(spec, "command_bias", np.arange(m.nu))}

        def command(self, data, z, state, u, j, n, qpos, h, qvel=None):
            return u + take(z, data["rows"]), state

    plug = CommandBias()
    monkeypatch.setattr(kinds, "_REGISTRY", sorted(kinds.all_kinds() + [plug], key=lambda k: k.order))
    monkeypatch.setitem(kinds._OWNERS, "command_bias", plug)
    # (what importing the module would have done: its declaration in the catalog's table)
    monkeypatch.setitem(catalog.ACTUATOR_EFFECTS, "command_bias", plug.declares["command_bias"])
    env = make("pendulum")
    assert "command_bias:motor" in env.spec
    fx, qpos = env.effects, jnp.zeros(env.mj_model.nq)
    ctrl = jnp.asarray([0.3], jnp.float32)
    es = fx.push(fx.init_state(), ctrl)
    u, _ = fx.actuate(jnp.asarray(env.default_z()), es, 0, 1, qpos, env.dt)
    np.testing.assert_array_equal(np.asarray(u), np.asarray(ctrl))          # neutral by default
    z = env.z_of(**{"command_bias:motor": 0.25, "action_delay": 1.0})
    u, _ = fx.actuate(jnp.asarray(z), es, 0, 1, qpos, env.dt)
    assert float(u[0]) == pytest.approx(0.25)                               # the delayed command (0) + bias


def test_backlash_motor_side_crosses_the_band_then_drives_the_joint():
    """The backlash stage against hand-derived mechanics: a 0.1 Nm motor (motor side 1e-3 kg m^2)
    behind a 0.02 rad band drives a free 0.01 kg m^2 joint. Nothing reaches the joint while the
    motor side crosses half the band (sqrt(2 * 0.01 / 100) = 14.1 ms); a rigid mesh then passes
    its momentum on (the joint starts at J w / I); a compliant one (10 Nm/rad) settles at the
    deflection that accelerates the joint with the motor, tau I / ((I + J) k)."""
    from sim2real.physics.kinds.backlash import Backlash

    bk = Backlash()
    data = {"rows": np.array([0]), "inertia_rows": np.array([1]), "stiffness_rows": np.array([2]),
            "inertia": np.array([1e-3]), "gain_rows": np.array([-1]), "gain": np.array([1.0]),
            "k_per_gain": np.array([0.0]), "damp": np.array([0.0]), "qpos": np.array([0]), "dof": np.array([0]),
            "ctrl_lo": np.array([-np.inf]), "ctrl_hi": np.array([np.inf]), "integ": np.array([False]),
            "actadr": np.array([0]), "act_lo": np.array([-np.inf]), "act_hi": np.array([np.inf]), "gear": np.array([1.0])}
    I, J, tau, h = 0.01, 1e-3, 0.1, 1e-4

    def run(k, steps):
        z = jnp.array([0.02, J, k])

        def step(carry, _):
            state, q, v = carry
            u, state = bk.command(data, z, state, jnp.array([tau]), 0, 1, q[None], h, v[None])
            v = v + h * u[0] / I   # the joint under the torque that reached it (gain 1)
            return (state, q + h * v, v), jnp.stack([u[0], v, state[0][0]])

        init = (bk.command_state(data, jnp.zeros(1)), jnp.zeros(()), jnp.zeros(()))
        return np.asarray(jax.lax.scan(step, init, None, length=steps)[1], float)

    rigid = run(0.0, 300)
    cross = int(np.argmax(rigid[:, 0] != 0.0))
    assert cross * h == pytest.approx(np.sqrt(2 * 0.01 / (tau / J)), rel=0.02)
    assert (rigid[:cross, 0] == 0.0).all()
    w_motor = tau / J * cross * h
    assert rigid[cross, 1] == pytest.approx(J * w_motor / I + h * tau / I, rel=0.02)   # momentum passed on
    assert np.allclose(rigid[cross:, 2], 0.01)                                          # then at the edge
    compliant = run(10.0, 3000)
    assert (compliant[:cross, 0] == 0.0).all()
    settled = compliant[-500:, 2] - 0.01
    assert settled.mean() == pytest.approx(tau * I / ((I + J) * 10.0), rel=0.1)


def test_backlash_impact_reaches_the_joint_past_the_command_range():
    """MuJoCo clamps a command to its ``ctrlrange``; the backlash stage's output at an impact is not
    a motor command but the momentum the motor side hands over, and must reach the joint whole.
    Pendulum motor (gear 1, range +-2 N m), a 0.3 rad rigid band, the motor at its limit: at the
    impact the joint gets far more than 2 N m for a sub-step. A command past the range drives the
    motor side as the limit does (the same crossing), and with the band off is limited to 2 N m."""
    from sim2real.physics import stepper

    env = env_for("pendulum")
    h = env.dt / env.config.frame_skip

    @jax.jit
    def forces(z, u):
        z = jnp.asarray(z)
        model = env.physics.apply(z)
        d0 = env.reset(KEY, z).data.replace(qpos=jnp.zeros(1), qvel=jnp.zeros(1))

        def step(carry, _):
            d, es = carry
            d, es = stepper.advance(env.effects, model, z, d, es, jnp.asarray([u]), h, 1)
            return (d, es), d.actuator_force[0]

        return jax.lax.scan(step, (d0, env.effects.init_state()), None, length=400)[1]

    band = env.z_of(**{"backlash:motor": 0.3})
    at_limit, beyond = np.asarray(forces(band, 2.0)), np.asarray(forces(band, 5.0))
    hit = int(np.argmax(at_limit != 0.0))
    assert hit > 0 and (at_limit[:hit] == 0.0).all()      # nothing while the motor side crosses
    assert at_limit[hit] > 3 * 2.0                         # the impact: past the motor's range
    np.testing.assert_array_equal(beyond, at_limit)        # the motor's own command is limited
    free = np.asarray(forces(env.default_z(), 5.0))
    np.testing.assert_allclose(free, 2.0)
