"""Quadratic drag (``physics/kinds/drag.py``): the effect added as one plug-in file.

The truth here is MuJoCo's own quadratic damping (a joint's second ``damping`` coefficient,
force ``-(d0 + d1 |v|) v``), stepped by native ``mj_step``: an implementation independent of the
plug-in's, which simulates the drag as the damping ``c |v|`` inside MJX.
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

# a paddle pendulum on a motor shaft (masses from geoms, no <inertial>)
FAN = """<mujoco model="paddle">
  <option timestep="0.001" integrator="implicitfast"/>
  <worldbody>
    <body name="paddle">
      <joint name="shaft" type="hinge" axis="0 1 0" damping="{d0} {d1}"/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.01" mass="0.05"/>
      <geom type="box" pos="0 0 -0.3" size="0.06 0.005 0.04" mass="0.2"/>
    </body>
  </worldbody>
  <actuator><motor name="motor" joint="shaft" gear="1" ctrlrange="-1 1" ctrllimited="true"/></actuator>
</mujoco>"""


def _xml(tmp_path, name, d0=0.0, d1=0.0):
    p = tmp_path / name
    p.write_text(FAN.format(d0=d0, d1=d1))
    return str(p)


def _command(T, dt, seed):
    """Random steps of 0.1-0.4 s, amplitude up to 0.5 N m (swings of a few rad/s)."""
    rng = np.random.default_rng(seed)
    u, t = np.zeros(T), 0
    while t < T:
        n = int(rng.uniform(0.1, 0.4) / dt)
        u[t:t + n] = rng.uniform(-0.5, 0.5)
        t += n
    return u


def _native(xml, u, dt=0.005, noise=1e-4, seed=0):
    """Native MuJoCo, logged at ``dt``, command held between samples."""
    m = mujoco.MjModel.from_xml_path(xml)
    d = mujoco.MjData(m)
    k = int(round(dt / m.opt.timestep))
    q = np.empty(len(u))
    for i, ui in enumerate(u):
        q[i] = d.qpos[0]
        d.ctrl[0] = ui
        for _ in range(k):
            mujoco.mj_step(m, d)
    return q + np.random.default_rng(seed).normal(0, noise, len(q))


def test_drag_is_a_plugin_declared_on_every_joint():
    k = kinds.owner("drag")
    assert k is not None and k.attach == kinds.JOINT and k.effect == "quadratic_drag"
    assert "drag" in catalog.JOINT_EFFECTS
    from sim2real.sysid.candidates import ALL_EFFECTS, EFFECTS
    assert "quadratic_drag" in ALL_EFFECTS and "quadratic_drag" not in EFFECTS  # asked for, not default


def test_drag_matches_mujocos_own_quadratic_damping(tmp_path):
    c = 3e-3  # N m s^2/rad^2
    truth = mujoco.MjModel.from_xml_path(_xml(tmp_path, "t.xml", d1=c))
    nominal = mujoco.MjModel.from_xml_path(_xml(tmp_path, "n.xml"))
    spec = ParamSpec(catalog.effect_params(nominal, [0], [0], []))
    pm = PhysicsModel(nominal, spec)
    fx = Effects(pm.mj, spec, EffectsConfig())
    z = jnp.asarray(spec.vector({"drag:shaft": c}))
    model = pm.apply(z)
    data, es = mjx.make_data(pm.mx), fx.init_state()
    step = jax.jit(lambda d, e, u: stepper.advance(fx, model, z, d, e, u, 0.005, 5))
    d_native = mujoco.MjData(truth)
    u = _command(400, 0.005, 1)
    ours, native = [], []
    for ui in u:
        data, es = step(data, es, jnp.array([ui], jnp.float32))
        d_native.ctrl[0] = ui
        for _ in range(5):
            mujoco.mj_step(truth, d_native)
        ours.append(float(data.qvel[0]))
        native.append(d_native.qvel[0])
    ours, native = np.array(ours), np.array(native)
    top = np.abs(native).max()
    assert top > 5.0  # fast enough for the drag to matter
    assert np.abs(ours - native).max() < 0.02 * top
    # and without the drag the same commands give a clearly different motion
    free = jax.jit(lambda d, e, u: stepper.advance(fx, pm.apply(jnp.asarray(spec.default)), z * 0, d, e, u, 0.005, 5))
    data, es = mjx.make_data(pm.mx), fx.init_state()
    nodrag = []
    for ui in u:
        data, es = free(data, es, jnp.array([ui], jnp.float32))
        nodrag.append(float(data.qvel[0]))
    assert np.abs(np.array(nodrag) - native).max() > 0.1 * top


@pytest.mark.optimized  # runs long (see conftest.py)
def test_diagnosis_names_quadratic_drag_when_asked(tmp_path):
    c = 3e-3  # N m s^2/rad^2: 0.1-0.3 N m at the swings' top speeds, against 0.5 N m commands
    truth = _xml(tmp_path, "truth.xml", d1=c)
    dt, T = 0.005, 1600  # 8 s at 200 Hz
    files = []
    for i in range(2):
        u = _command(T, dt, seed=10 + i)
        q = _native(truth, u, dt, seed=i)
        files.append(str(tmp_path / f"run{i}.csv"))
        save_csv(files[-1], 3.0 + np.arange(T) * dt, {"qpos:shaft": q, "ctrl:motor": u})
    d = diagnose(DiagnoseConfig(model=_xml(tmp_path, "nominal.xml"), recordings=(files[0],), heldout=(files[1],),
                                out=str(tmp_path / "d"), plots=False, progress=False,
                                effects=("none", "coulomb_friction", "viscous_damping", "quadratic_drag")))
    assert [(s["effect"], s["target"]) for s in d["selected"]] == [("quadratic_drag", "shaft")]
    assert d["selected"][0]["params"]["drag:shaft"] == pytest.approx(c, rel=0.25)
    assert d["fit"]["after"] < 0.7 * d["fit"]["before"]  # on the held-out recording
    # written into fitted.xml as MuJoCo's own quadratic damping term
    fitted = mujoco.MjSpec.from_file(str(tmp_path / "d" / "fitted.xml"))
    assert float(np.ravel(fitted.joint("shaft").damping)[1]) == pytest.approx(c, rel=0.25)


def test_a_kind_without_a_plugin_is_refused(tmp_path):
    from sim2real.physics.params import Param

    m = mujoco.MjModel.from_xml_path(_xml(tmp_path, "n.xml"))
    with pytest.raises(ValueError, match="'wobble'.*no plug-in"):
        PhysicsModel(m, ParamSpec([Param("wobble:shaft", 0.0, 0.0, 1.0, "-", "?", "wobble", 0)]))
