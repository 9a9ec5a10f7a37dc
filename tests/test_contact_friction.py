"""The diagnosis' ``contact_friction`` (``physics/kinds/contact.py``): the effect added as one plug-in.

The truth is native MuJoCo with the friction written the way a user would, on the floor and the
box geoms (MuJoCo gives a contact the larger of its two geoms' frictions), not through the
plug-in's priority; the plug-in's model is run by MJX and by native MuJoCo alike.
"""
import mujoco
import numpy as np
import pytest
from mujoco import mjx

from sim2real.physics.kinds.contact import mixed_friction
from sim2real.physics.model_apply import to_mjmodel
from sim2real.sysid.candidates import EFFECTS, ALL_EFFECTS, Scales, library
from sim2real.sysid.export import write_fitted_mjcf
from sim2real.sysid.system import System

# a box pushed along a slide by a motor, resting on the floor (free to lift: its weight presses)
BOX = """<mujoco model="box">
  <option timestep="0.002"/>
  <worldbody>
    <geom name="floor" type="plane" size="2 2 0.1" {floor}/>
    <body name="box" pos="0 0 0.05">
      <joint name="x" type="slide" axis="1 0 0"/>
      <joint name="z" type="slide" axis="0 0 1"/>
      <geom type="box" size="0.05 0.05 0.05" mass="1" {box}/>
    </body>
  </worldbody>
  <actuator><motor name="push" joint="x" ctrlrange="-20 20"/></actuator>
</mujoco>"""


def _write(tmp_path, floor="", box=""):
    path = str(tmp_path / "box.xml")
    open(path, "w").write(BOX.format(floor=floor, box=box))
    return path


def _native(floor="", box=""):
    """The file as MuJoCo compiles it, with the solver's iterations the diagnosis' ``System`` caps."""
    m = mujoco.MjModel.from_xml_string(BOX.format(floor=floor, box=box))
    m.opt.iterations, m.opt.ls_iterations = 10, 10
    return m


def _slide(m, force=12.0, steps=300):
    """x [steps] of the box under a constant push (native MuJoCo, from rest on the floor)."""
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    out = np.empty(steps)
    for i in range(steps):
        d.ctrl[0] = force
        mujoco.mj_step(m, d)
        out[i] = d.qpos[0]
    return out


def test_contact_friction_is_neutral_by_default_and_sets_the_friction_of_the_bodys_contacts(tmp_path):
    system = System(_write(tmp_path), dt=0.002)
    p = system.spec["contact_friction:box"]
    assert p.default == 1.0  # the friction the box's contacts had (MuJoCo's default)
    # the plug-in's model (the box's priority raised) slides as the user's file does: exactly neutral
    user = _native()
    assert system.mj.geom_priority[1] > system.mj.geom_priority[0]
    np.testing.assert_array_equal(_slide(system.mj), _slide(user))
    # 0.3 as a user writes it (the floor and the box both) against the plug-in's 0.3 (its model in
    # float32, as every parameter vector: the same slide to a fraction of a percent)
    truth = _native(floor='friction="0.3"', box='friction="0.3"')
    z = system.spec.default.copy()
    z[system.spec.index("contact_friction:box")] = 0.3
    np.testing.assert_allclose(_slide(to_mjmodel(system.physics, z))[99::100], _slide(truth)[99::100], rtol=0.01)
    assert _slide(truth)[-1] > 2 * _slide(user)[-1]  # (a push of 12 N: much further on 0.3)
    # MJX: the contact's friction is the value the plug-in sets
    mx = system.physics.apply(np.asarray(z, np.float32))
    d = mjx.forward(mx, mjx.put_data(system.mj, mujoco.MjData(system.mj)))
    hit = np.asarray(d._impl.contact.dist) < 1e-3 if hasattr(d, "_impl") else np.asarray(d.contact.dist) < 1e-3
    fr = np.asarray(d._impl.contact.friction if hasattr(d, "_impl") else d.contact.friction)
    assert hit.any() and np.allclose(fr[hit, 0], 0.3)


def test_two_bodies_that_touch_each_other_both_get_the_parameter_and_stay_neutral(tmp_path):
    # a second box pushing the first: its contacts (with the box) mix to the same friction
    path = str(tmp_path / "two.xml")
    open(path, "w").write(BOX.format(floor="", box="").replace("</worldbody>", """  <body name="ram" pos="-0.11 0 0.05">
      <joint name="ram" type="slide" axis="1 0 0"/>
      <geom type="box" size="0.05 0.05 0.04" mass="0.5"/>
    </body>
  </worldbody>"""))
    system = System(path, dt=0.002)
    assert {"contact_friction:box", "contact_friction:ram"} <= set(system.spec.names)
    user = mujoco.MjModel.from_xml_path(path)
    # (each body's contacts read before either body's geoms change: a second body read after the
    # first's priority rose found no common friction, and its geoms got NaN)
    np.testing.assert_array_equal(system.mj.geom_friction, user.geom_friction)


def test_contact_friction_is_offered_only_where_the_contacts_mix_to_one_value(tmp_path):
    m = mujoco.MjModel.from_xml_string(BOX.format(floor="", box=""))
    assert np.allclose(mixed_friction(m, 1), [1.0, 0.005, 1e-4])
    # a priority already set by the user (the floor's) decides the contact: raising the box's
    # would not be neutral, so no parameter
    m = mujoco.MjModel.from_xml_string(BOX.format(floor='priority="1"', box=""))
    assert mixed_friction(m, 1) is None
    assert "contact_friction:box" not in System(_write(tmp_path, floor='priority="1"'), dt=0.002).spec


def test_contact_friction_is_a_candidate_when_asked_for_and_the_body_touches(tmp_path):
    system = System(_write(tmp_path), dt=0.002)
    assert "contact_friction" in ALL_EFFECTS and "contact_friction" not in EFFECTS  # asked for

    def scales(touch):
        one = np.ones(2)
        return Scales(one, one, one, np.ones(1), 0.002, 8, one, touch)

    labels = lambda sc, effects: [c.label for c in library(system, sc, effects)]  # noqa: E731
    assert "contact_friction@box" in labels(scales(np.array([False, True])), ALL_EFFECTS)
    assert "contact_friction@box" not in labels(scales(np.array([False, False])), ALL_EFFECTS)  # never touched
    assert "contact_friction@box" not in labels(scales(np.array([False, True])), EFFECTS)
    cand = next(c for c in library(system, scales(np.array([False, True])), ALL_EFFECTS) if c.effect == "contact_friction")
    assert cand.off == 1.0 and cand.is_off(1.0) and not cand.is_off(0.3)  # absent: the model's own friction


def test_a_fitted_contact_friction_is_written_into_mjcf_as_muJoCo_simulates_it(tmp_path):
    system = System(_write(tmp_path), dt=0.002)
    z = system.spec.default.copy()
    z[system.spec.index("contact_friction:box")] = 0.3
    out = str(tmp_path / "fitted.xml")
    write_fitted_mjcf(system.xml_path, system, z, {"contact_friction:box": 0.3}, out)
    fitted = mujoco.MjModel.from_xml_path(out)
    fitted.opt.iterations, fitted.opt.ls_iterations = 10, 10
    truth = _native(floor='friction="0.3"', box='friction="0.3"')
    np.testing.assert_allclose(_slide(fitted), _slide(truth), atol=1e-9)
    assert "written as the friction of the body's geoms" in open(out).read()


if __name__ == "__main__":
    pytest.main([__file__, "-q"])
