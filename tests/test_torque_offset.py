"""A constant joint torque (``physics/kinds/offset.py``): the effect added as one plug-in file.

The truth here is native ``mj_step`` with the torque in MuJoCo's own ``qfrc_applied``: an
implementation independent of the plug-in's path through ``effects.constant_force`` and MJX.
"""
import jax
import jax.numpy as jnp
import mujoco
import numpy as np
import pytest
from mujoco import mjx

from sim2real.physics import catalog, kinds, stepper
from sim2real.physics.effects import Effects, EffectsConfig
from sim2real.physics.model_apply import PhysicsModel
from sim2real.physics.params import ParamSpec
from sim2real.sysid.diagnose import DiagnoseConfig, diagnose
from sim2real.sysid.recordings import save_csv

# a short arm on a motor, swinging in a vertical plane (masses from geoms)
ARM = """<mujoco model="arm">
  <option timestep="0.001" integrator="implicitfast"/>
  <worldbody>
    <body name="link">
      <joint name="shoulder" type="hinge" axis="0 1 0" damping="0.03"/>
      <geom type="capsule" fromto="0 0 0 0.25 0 0" size="0.015" mass="0.3"/>
    </body>
  </worldbody>
  <actuator><motor name="motor" joint="shoulder" gear="1" ctrlrange="-2 2" ctrllimited="true"/></actuator>
</mujoco>"""
TAU = 0.12  # N m, about a sixth of the gravity torque at the horizontal


def _command(T, dt, seed):
    """Random steps of 0.2-0.5 s below the gravity torque (0.37 N m): swings about the bottom."""
    rng = np.random.default_rng(seed)
    u, t = np.zeros(T), 0
    while t < T:
        n = int(rng.uniform(0.2, 0.5) / dt)
        u[t:t + n] = rng.uniform(-0.3, 0.3)
        t += n
    return u


def _native(m, u, dt, tau, noise=1e-4, seed=0):
    """Native MuJoCo with ``tau`` in ``qfrc_applied``, logged at ``dt``, command held between samples."""
    d = mujoco.MjData(m)
    k = int(round(dt / m.opt.timestep))
    q = np.empty(len(u))
    for i, ui in enumerate(u):
        q[i] = d.qpos[0]
        d.ctrl[0], d.qfrc_applied[0] = ui, tau
        for _ in range(k):
            mujoco.mj_step(m, d)
    return q + np.random.default_rng(seed).normal(0, noise, len(q))


def test_torque_offset_is_a_plugin_declared_on_every_joint():
    k = kinds.owner("torque_offset")
    assert k is not None and k.attach == kinds.JOINT and k.effect == "torque_offset"
    assert "torque_offset" in catalog.JOINT_EFFECTS
    from sim2real.sysid.candidates import ALL_EFFECTS, EFFECTS
    assert "torque_offset" in ALL_EFFECTS and "torque_offset" not in EFFECTS  # asked for, not default


def test_torque_offset_matches_mujocos_applied_force():
    m = mujoco.MjModel.from_xml_string(ARM)
    spec = ParamSpec(catalog.effect_params(m, [0], [0], []))
    pm = PhysicsModel(m, spec)
    fx = Effects(pm.mj, spec, EffectsConfig())
    u = _command(400, 0.005, 1)

    def ours(z):
        z = jnp.asarray(z)
        step = jax.jit(lambda d, e, c: stepper.advance(fx, pm.apply(z), z, d, e, c, 0.005, 5))
        data, es, q = mjx.make_data(pm.mx), fx.init_state(), []
        for ui in u:
            q.append(float(data.qpos[0]))
            data, es = step(data, es, jnp.array([ui], jnp.float32))
        return np.array(q)

    native = _native(m, u, 0.005, TAU, noise=0.0)
    with_offset = ours(spec.vector({"torque_offset:shoulder": TAU}))
    assert np.ptp(native) > 1.0
    assert np.abs(with_offset - native).max() < 0.02 * np.ptp(native)
    assert np.abs(ours(spec.default) - native).max() > 0.1 * np.ptp(native)  # and it matters


@pytest.mark.optimized  # runs long (see conftest.py)
def test_diagnosis_names_a_torque_offset_when_asked(tmp_path):
    m = mujoco.MjModel.from_xml_string(ARM)
    model = tmp_path / "arm.xml"
    model.write_text(ARM)
    dt, T = 0.005, 1600  # 8 s at 200 Hz
    files = []
    for i in range(2):
        u = _command(T, dt, seed=10 + i)
        files.append(str(tmp_path / f"run{i}.csv"))
        save_csv(files[-1], 2.0 + np.arange(T) * dt, {"qpos:shoulder": _native(m, u, dt, TAU, seed=i), "ctrl:motor": u})
    d = diagnose(DiagnoseConfig(model=str(model), recordings=(files[0],), heldout=(files[1],), out=str(tmp_path / "d"),
                                plots=False, progress=False,
                                effects=("none", "coulomb_friction", "joint_stiffness", "torque_offset")))
    assert [(s["effect"], s["target"]) for s in d["selected"]] == [("torque_offset", "shoulder")]
    assert d["selected"][0]["params"]["torque_offset:shoulder"] == pytest.approx(TAU, rel=0.25)
    assert d["fit"]["after"] < 0.5 * d["fit"]["before"]  # on the held-out recording
    # written into fitted.xml as a bias-only actuator after the model's own
    fitted = mujoco.MjModel.from_xml_path(str(tmp_path / "d" / "fitted.xml"))
    a = mujoco.mj_name2id(fitted, mujoco.mjtObj.mjOBJ_ACTUATOR, "sim2real_torque_offset:shoulder")
    assert a == fitted.nu - 1 and fitted.actuator_gainprm[a, 0] == 0.0
    assert fitted.actuator_biasprm[a, 0] == pytest.approx(TAU, rel=0.25)
