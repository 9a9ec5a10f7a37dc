"""The diagnosis' ``rotor_inertia`` (``physics/kinds/armature.py``): a geared rotor's inertia a model
leaves out, added as one plug-in. The truth is native MuJoCo with ``armature`` written in the MJCF."""
import mujoco
import numpy as np
import pytest

from sim2real.physics.model_apply import to_mjmodel
from sim2real.sysid.candidates import ALL_EFFECTS, EFFECTS, Scales, library
from sim2real.sysid.export import write_fitted_mjcf
from sim2real.sysid.system import System

PENDULUM = """<mujoco model="pendulum">
  <option timestep="0.001"/>
  <worldbody>
    <body name="rod" pos="0 0 1">
      <joint name="hinge" axis="0 1 0" damping="0.01" {truth}/>
      <geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.02" mass="0.4"/>
    </body>
  </worldbody>
  <actuator><motor name="m" joint="hinge" ctrlrange="-2 2"/></actuator>
</mujoco>"""


def _swing(m, steps=1500):
    """The hinge angle [steps] under a 0.3 N m push from rest (native MuJoCo)."""
    d = mujoco.MjData(m)
    out = np.empty(steps)
    for i in range(steps):
        d.ctrl[0] = 0.3
        mujoco.mj_step(m, d)
        out[i] = d.qpos[0]
    return out


def test_rotor_inertia_is_muJoCos_armature_in_the_model_and_in_fitted_xml(tmp_path):
    path = str(tmp_path / "p.xml")
    open(path, "w").write(PENDULUM.format(truth=""))
    system = System(path)
    z = system.spec.default.copy()
    assert z[system.spec.index("armature:hinge")] == 0.0  # neutral
    z[system.spec.index("armature:hinge")] = 0.01
    truth = mujoco.MjModel.from_xml_string(PENDULUM.format(truth='armature="0.01"'))
    ours = to_mjmodel(system.physics, z)
    bare = _swing(mujoco.MjModel.from_xml_string(PENDULUM.format(truth="")))
    np.testing.assert_allclose(_swing(ours), _swing(truth), atol=1e-3 * np.ptp(bare))
    assert np.abs(_swing(truth) - bare).max() > 0.1 * np.ptp(bare)  # (the rotor slows the swing a lot)
    out = str(tmp_path / "fitted.xml")
    write_fitted_mjcf(path, system, z, {"armature:hinge": 0.01}, out)
    assert mujoco.MjModel.from_xml_path(out).dof_armature[0] == pytest.approx(0.01)


def test_rotor_inertia_is_asked_for_and_corrects_a_declared_armature_either_way(tmp_path):
    path = str(tmp_path / "p.xml")
    open(path, "w").write(PENDULUM.format(truth='armature="0.004"'))
    system = System(path)
    assert "rotor_inertia" in ALL_EFFECTS and "rotor_inertia" not in EFFECTS
    sc = Scales(force=np.ones(1), speed=np.ones(1), range=np.ones(1), act_force=np.ones(1), dt=0.01, max_delay=8,
                inertia=np.full(1, 0.02))
    (c,) = library(system, sc, ("rotor_inertia",))
    assert c.search[0] == (-0.004, 0.2)  # down to a total of 0, up to 10x the joint's inertia
    with pytest.raises(ValueError, match="armature:hinge"):
        system.spec.check_value("armature:hinge", -0.005)
